"""Free-decay pendulum identification: camera → tracking → angles → fit (model) → discovery → report."""
