"""The fitter's start state (decay analysis): θ0, θ̇0 and the rest offset, robust to jumps and to high frame rates.

Truth: the simulated swing (``simulate`` from the release, 400 RK4 substeps per
sample) at the record's first fitted sample, and the synthetic rest offset.
"""

import math

import numpy as np
import pytest

from pendulum.fit.decay import decay_analysis, start_state
from pendulum.fit.records import FitSettings, load_record
from pendulum.model.physics import PendulumModel, simulate
from pendulum.model.rig import Rig
from pendulum.synthetic.records import synthetic_angle_table

PAPER = {"mass_kg": 3.53, "length_m": 0.76, "frontal_area_m2": 0.0322, "displaced_volume_m3": 0.0025}
TRUTH = {"added_mass_kg": 2.5, "drag_area_m2": 0.02576, "linear_damping_nm_s": 0.15, "friction_torque_nm": 0.02}
MODEL = PendulumModel(Rig.from_mapping(PAPER), ("quadratic_drag", "linear_damping", "coulomb_friction"))
OFFSET_DEG = 0.4


def record(release_deg, fps, seed, duration_s=8.0, jump_deg=0.0):
    """A noisy record (0.01° white noise, 0.4° rest offset); ``jump_deg`` added to its first 3 fitted samples."""
    table = synthetic_angle_table(
        MODEL,
        TRUTH,
        release_deg,
        fps=fps,
        duration_s=duration_s,
        rest_offset_deg=OFFSET_DEG,
        rng=np.random.default_rng(seed),
        white_deg=0.01,
    )
    first = np.flatnonzero(table.time_s >= FitSettings().release_skip_s)[:3]
    table.loc[first, "theta_rad"] += math.radians(jump_deg)
    return load_record(table, "x", PAPER, FitSettings())


def true_state_deg(release_deg, t0_s):
    theta, omega = simulate(MODEL, TRUTH, math.radians(release_deg), 0.0, np.array([0.0, t0_s]), substeps=400)
    return math.degrees(theta[1]), math.degrees(omega[1])


def start_errors_deg(start, rec, release_deg):
    theta_true, omega_true = true_state_deg(release_deg, rec.time_s[0])
    theta = math.degrees(start["theta0_rad"] + start["rest_offset_rad"]) - OFFSET_DEG
    return theta - theta_true, math.degrees(start["omega0_rad_s"]) - omega_true


@pytest.mark.parametrize("fps", [30.0, 240.0])
def test_clean_records_start_near_the_truth_with_no_sample_called_a_jump(fps):
    """Releases −5°, 20°, 75°, seeds 0–2: offline (10 seeds) |Δθ0| ≤ 0.024°, |Δθ̇0| ≤ 0.56°/s, and no
    sample rejected (on 72 clean records the largest residual is ≤ 4 robust σ against the 8 σ cut)."""
    for release in (-5.0, 20.0, 75.0):
        for seed in range(3):
            rec = record(release, fps, seed)
            start = decay_analysis(MODEL, rec)
            d_theta, d_omega = start_errors_deg(start, rec, release)
            assert start["start_outlier_samples"] == [], (release, seed)
            assert start["start_method"] == "local cubic"
            assert abs(d_theta) < 0.05 and abs(d_omega) < 1.0, (release, seed, d_theta, d_omega)


def test_the_rest_offset_start_is_right_at_240_fps():
    """The fitter's start rest offset (the swing centre of the whole record) at 240 fps: the old estimator
    (extremum triplets of a 3-sample running mean) found no centre or −10.8° for a true 0.4°; now within
    0.01° of it (offline, releases 5°, 20°, 75°, 5 seeds each, 22 s: 0.393–0.403°)."""
    for release in (5.0, 20.0, 75.0):
        rec = record(release, 240.0, seed=int(release), duration_s=22.0)
        offset_deg = math.degrees(decay_analysis(MODEL, rec)["rest_offset_rad"])
        assert offset_deg == pytest.approx(OFFSET_DEG, abs=0.02), release


@pytest.mark.parametrize("jump_deg", [170.0, -40.0, 5.0])
def test_a_jump_in_the_first_samples_is_rejected_and_does_not_move_the_start(jump_deg):
    """The real record's failure: a jump in the first 3 samples gave θ̇0 = −4727°/s from the old 7-sample
    quadratic. Now the 3 samples are found as jumps and the start stays within 0.1°, 2°/s of the truth
    (offline, jumps ±5°, −40°, 170° on −5°/20°/75° releases at 30 and 240 fps, 4 seeds: the 3 samples and
    no other found every time; ≤ 0.086°, ≤ 1.35°/s). A 1° jump on a 75° swing (below 8 robust σ of the
    sinusoid) is not found: the start then moves by 1.2°, 12°/s, still far inside the speed bound."""
    for release, fps in ((20.0, 30.0), (75.0, 30.0), (20.0, 240.0)):
        rec = record(release, fps, seed=1, jump_deg=jump_deg)
        start = decay_analysis(MODEL, rec)
        assert start["start_outlier_samples"] == [0, 1, 2], (release, fps)
        d_theta, d_omega = start_errors_deg(start, rec, release)
        assert abs(d_theta) < 0.1 and abs(d_omega) < 2.0, (release, fps, d_theta, d_omega)


def test_a_start_speed_no_release_could_give_is_refused():
    """Jumps the outlier test did not catch (here: none passed in): the cubic's θ̇0 (thousands of °/s) exceeds
    1.5 × 2√(K/I) sin(θ_max/2) and is refused; the decaying sinusoid's θ̇0, clipped to that bound, is used."""
    rec = record(20.0, 30.0, seed=1, jump_deg=170.0)
    x = rec.theta_rad - math.radians(OFFSET_DEG)
    natural_rad_s = math.sqrt(MODEL.rig.restoring_torque_nm / float(MODEL.inertia_kg_m2(TRUTH)))
    state = start_state(rec.time_s, x, 4.2, natural_rad_s, np.zeros(rec.n_samples, bool))
    limit = state["start_speed_limit_rad_s"]
    # θ_max is the jumped sample (188.7°, nothing rejected), capped at 180°: the bound is loose but finite
    assert limit == pytest.approx(1.5 * 2 * natural_rad_s, rel=1e-12)
    assert abs(math.degrees(state["refused_start"]["omega0_rad_s"])) > 1000
    assert state["start_method"] == "decaying sinusoid"
    assert abs(state["omega0_rad_s"]) <= limit
