"""Fit: angle records in, fitted coefficients out: output-error fits per trial, rig and body, uncertainty, summary."""
