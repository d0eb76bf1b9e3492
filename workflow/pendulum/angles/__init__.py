"""Angles: tracks (or a Tracker table) in, angle records out: pivot, vertical and swing angle against time."""
