"""Comparing stage outputs with the synthetic truth."""

import numpy as np
import pandas as pd


def track_errors(track: pd.DataFrame, truth: pd.DataFrame) -> pd.DataFrame:
    merged = track.merge(truth, on="frame", suffixes=("", "_true"))
    merged["error_px"] = np.hypot(merged.x_px - merged.marker_x_px, merged.y_px - merged.marker_y_px)
    return merged
