"""Free-decay pendulum identification: physics, synthetic experiment, video to angle."""
