"""Synthetic: a trial specification in, rendered videos (or angle tables) and their truth out, for the tests."""
