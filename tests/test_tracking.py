"""Marker tracking against the rendered truth (demo set, dark marker, occlusions)."""

import numpy as np
import pandas as pd
import pytest

from conftest import DEMO_RAW, DEMO_TRUTH, demo_trials
from pendulum.tracking import TrackerSettings, track_video
from truth import track_errors


@pytest.fixture(scope="module")
def demo_tracks():
    return {name: track_video(DEMO_RAW / f"{name}.mp4", TrackerSettings()) for name in demo_trials()}


@pytest.mark.parametrize("trial", demo_trials())
def test_demo_marker_centre_is_subpixel(demo_tracks, trial):
    errors = track_errors(demo_tracks[trial], pd.read_csv(DEMO_TRUTH / f"{trial}.csv"))
    ok = errors.flag == "ok"
    assert ok.mean() > 0.98
    assert np.sqrt(np.mean(errors.error_px[ok] ** 2)) <= 0.15
    assert errors.error_px[ok].max() <= 2.0


def test_dark_marker_on_bright_scene(hard_videos):
    track = track_video(hard_videos / "dark_marker.mp4", TrackerSettings(polarity="dark"))
    errors = track_errors(track, pd.read_csv(hard_videos / "dark_marker.csv"))
    ok = errors.flag == "ok"
    assert ok.mean() > 0.98
    assert np.sqrt(np.mean(errors.error_px[ok] ** 2)) <= 0.15
    assert errors.error_px[ok].max() <= 2.0


def test_occluded_frames_are_flagged_not_interpolated(hard_videos):
    track = track_video(hard_videos / "occluded.mp4", TrackerSettings())
    truth = pd.read_csv(hard_videos / "occluded.csv")
    errors = track_errors(track, truth)
    occluded = errors.occluded_fraction > 0
    assert 0.04 <= occluded.mean() <= 0.07  # the video really has ~5 % occluded frames
    ok = errors.flag == "ok"
    # every substantially covered frame is flagged; lost frames carry no invented position
    assert not (ok & (errors.occluded_fraction >= 0.2)).any()
    assert errors.loc[errors.flag == "lost", ["x_px", "y_px"]].isna().all().all()
    assert np.sqrt(np.mean(errors.error_px[ok] ** 2)) <= 0.15
    assert errors.error_px[ok].max() <= 2.0
    assert (~ok).sum() <= 2 * occluded.sum()  # flags are not sprayed over clean frames
