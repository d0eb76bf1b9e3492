"""The synthetic experiment: byte-identical regeneration and truth consistency."""

import hashlib

import numpy as np
import pandas as pd
import pytest
import yaml

from conftest import DEMO_RAW, DEMO_SPEC, DEMO_TRUTH
from pendulum.synthetic.experiment import generate_trial, load_specs, marker_position_px


def sha(path):
    return hashlib.sha256(path.read_bytes()).hexdigest()


@pytest.mark.slow
def test_demo_trial_regenerates_byte_identically(tmp_path):
    spec = {s.name: s for s in load_specs(DEMO_SPEC)}["demo_p05"]
    generate_trial(spec, tmp_path, tmp_path, progress=None)
    for name in ("demo_p05.mp4", "demo_p05.csv", "demo_p05.yaml"):
        shipped = (DEMO_RAW if name.endswith(".mp4") else DEMO_TRUTH) / name
        assert sha(tmp_path / name) == sha(shipped), name


def test_demo_videos_are_small_and_truth_is_consistent():
    for spec in load_specs(DEMO_SPEC):
        assert (DEMO_RAW / f"{spec.name}.mp4").stat().st_size <= 5e6
        truth = pd.read_csv(DEMO_TRUTH / f"{spec.name}.csv")
        meta = yaml.safe_load((DEMO_TRUTH / f"{spec.name}.yaml").read_text())
        assert meta["truth"]["friction_torque_nm"] > 0 and "linear_damping" in meta["effects"]
        held = truth.time_s < meta["release_time_s"] - 0.02
        assert np.allclose(np.degrees(truth.theta_rad[held]), spec.release_deg)
        # the exposure-mean marker position lies within blur sag of the mid-exposure position
        x, y = marker_position_px(spec.camera, truth.theta_rad.to_numpy())
        assert np.hypot(x - truth.marker_x_px, y - truth.marker_y_px).max() < 0.2
