"""The library of candidate effects and the synthetic generator's hidden effects, against closed forms."""

import math
from dataclasses import replace

import numpy as np
import pytest
import yaml
from scipy.integrate import solve_ivp

from conftest import DEMO_SPEC, ROOT
from paper_rig import PAPER_RIG
from pendulum.fit.output_error import fit_trials
from pendulum.fit.records import FitSettings, load_record
from pendulum.model.effects import TERMS, effects_for, history_equivalent, lower_bound
from pendulum.model.physics import PendulumModel, simulate
from pendulum.model.rig import Rig
from pendulum.synthetic.experiment import load_specs, release_time_s, render_trial, true_angle_rad, truth_record
from pendulum.synthetic.records import hidden_effect_table, synthetic_angle_table
from pendulum.synthetic.specs import Camera, Disturbances, PeriodicTorque, TrialSpec
from pendulum.tracking.centroids import measure_marker
from pendulum.tracking.settings import TrackerSettings

RIG = Rig(**PAPER_RIG)
# Paper rig by hand (tests/test_physics_reference.py): K = (m g − ρ g V) L = 7.679268 N·m,
# I = m L² + m_a L² = 2.038928 + 2.5 · 0.5776 = 3.482928 kg·m² (m_a = 2.5 kg), ω₀ = √(K/I) = 1.48484 rad/s.
K_PAPER, L2, INERTIA = 7.679268, 0.5776, 3.482928
EFFECTS = ("linear_damping", "coulomb_friction", "quadratic_drag", "restoring_correction", "history_force")


def test_library_has_one_complete_entry_per_effect_and_the_config_schema_accepts_them():
    assert set(TERMS) == set(EFFECTS)
    schema = yaml.safe_load((ROOT / "workflow/schemas/config.schema.yaml").read_text())
    assert set(schema["properties"]["variants"]["additionalProperties"]["items"]["enum"]) == set(TERMS)
    for term in TERMS.values():
        assert term.unit and term.label and term.symbol and len(term.explanation) > 300, term.name
        assert term.period_signature and term.typical_scale(RIG) > 0
        dissipative = term.extinction_power is not None
        assert dissipative == (term.name != "restoring_correction")
        # coefficients of dissipative effects are ≥ 0; only the restoring correction is signed
        assert lower_bound(term.parameter) == (0.0 if dissipative else -0.5)
    assert effects_for({"added_mass_kg": 1, "friction_torque_nm": 1, "history_coefficient_kg_per_sqrt_s": 1}) == (
        "coulomb_friction",
        "history_force",
    )


def swing_peaks(theta):
    """|θ| at the swing extrema of a finely sampled record, refined by a parabola through three samples."""
    a = np.abs(theta)
    j = np.flatnonzero((a[1:-1] >= a[:-2]) & (a[1:-1] > a[2:])) + 1
    y0, y1, y2 = theta[j - 1], theta[j], theta[j + 1]
    shift = (y0 - y2) / (2 * (y0 - 2 * y1 + y2))
    return np.abs(y1 - 0.25 * (y0 - y2) * shift)


SIGNATURES = {
    # effect: (coefficient, tolerance, power of A in ΔA)
    "linear_damping": (0.05, 3e-3, 1),
    "coulomb_friction": (0.005, 3e-3, 0),
    "quadratic_drag": (0.01, 3e-3, 2),
    "history_force": (0.1, 1e-2, 1),
}


@pytest.mark.parametrize("name", sorted(SIGNATURES))
def test_extinction_signature_of_each_dissipative_effect(name):
    """Amplitude lost per cycle in a simulated 5° decay against the library's ΔA = p · per_unit · A^power.

    Full cycles (A_i − A_{i+2})/2 against the mean predicted loss of the two half cycles, so a slowly
    moving centre (the history force's non-oscillating tail) cancels. Small-damping energy balance:
    linear, Coulomb, quadratic to 0.3 % (measured 8e-4, 1.2e-3, 2.3e-4: errors O(ζ) and O(A²/16)).
    The history force is taken at its own frequency (ω and I including its equivalent added mass
    K_h √(π/2ω), iterated), from the second cycle on (the memory starts empty at the release): 1 %
    (measured 0.7 %; the single-frequency picture neglects the decay). The wrong power of A would
    be off by the ratio of the amplitudes, ≥ 30 % over these 14 half cycles.
    """
    value, tolerance, power = SIGNATURES[name]
    term = TERMS[name]
    assert term.extinction_power == power
    model = PendulumModel(RIG, (name,))
    inertia, omega = INERTIA, math.sqrt(K_PAPER / INERTIA)
    if term.memory:
        for _ in range(10):
            inertia = INERTIA + history_equivalent(RIG, value, omega)["added_mass_kg"] * L2
            omega = math.sqrt(K_PAPER / inertia)
    t = np.arange(0, 30, 1 / 600)
    theta, _ = simulate(model, {"added_mass_kg": 2.5, term.parameter: value}, math.radians(5.0), 0.0, t, substeps=1)
    peaks = swing_peaks(theta)[:14]
    predicted_half = term.half_cycle_loss_rad(RIG, inertia, omega, value, 0.5 * (peaks[:-1] + peaks[1:]))
    measured = (peaks[:-2] - peaks[2:]) / 2
    predicted = (predicted_half[:-1] + predicted_half[1:]) / 2
    first = 2 if term.memory else 0
    err = np.abs(measured / predicted - 1)[first:]
    assert err.max() < tolerance, err
    # the fast screen's inverse gives the coefficient back from the loss coefficient
    loss_coefficient = float(np.mean(measured[first:] / (peaks[1:-1][first:] ** power)))
    assert term.coefficient_from_loss(RIG, inertia, omega, loss_coefficient) == pytest.approx(value, rel=2 * tolerance)


def test_restoring_correction_scales_the_stiffness():
    """ε = 0.1: T₀ = 2π √(I / (1.1 K)) = 2π √(3.482928 / 8.4471948) = 4.03456 s; simulated at 0.5° to 2e-5.

    (At 0.5° the period is longer by A²/16 = 4.8e-6.) With ε applied to I instead (T ∝ √1.1) it would be 4.4381 s.
    """
    expected = 2 * math.pi * math.sqrt(INERTIA / (1.1 * K_PAPER))
    assert expected == pytest.approx(4.034561, rel=1e-6)
    model = PendulumModel(RIG, ("restoring_correction",))
    t = np.arange(0, 40, 1 / 120)
    theta, _ = simulate(model, {"added_mass_kg": 2.5, "restoring_torque_correction": 0.1}, math.radians(0.5), 0.0, t)
    i = np.flatnonzero((theta[1:] > 0) & (theta[:-1] <= 0))
    crossings = t[i] - theta[i] * (t[i + 1] - t[i]) / (theta[i + 1] - theta[i])
    assert (crossings[-1] - crossings[0]) / (len(crossings) - 1) == pytest.approx(expected, rel=2e-5)


def test_restoring_correction_is_indistinguishable_from_inertia_and_damping_on_one_rig():
    """(1+ε)K with I, C_dA, c, τ_f, K_h moves exactly as K with I/(1+ε) and every coefficient / (1+ε).

    ε = 0.1: I' = 3.482928/1.1 = 3.166298 kg·m², m_a' = (I' − m L²)/L² = 1.951818 kg. Trajectories agree
    to 1e-11 rad (measured 1e-16): one rig's free decay cannot measure ε, so the discovery must not name it there.
    """
    terms = ("quadratic_drag", "linear_damping", "coulomb_friction", "history_force")
    base = {
        "added_mass_kg": 2.5,
        "drag_area_m2": 0.02576,
        "linear_damping_nm_s": 0.15,
        "friction_torque_nm": 0.02,
        "history_coefficient_kg_per_sqrt_s": 0.2,
    }
    eps = 0.1
    corrected = PendulumModel(RIG, terms + ("restoring_correction",))
    scaled = {k: v / (1 + eps) for k, v in base.items()}
    scaled["added_mass_kg"] = (INERTIA / (1 + eps) - 2.038928) / L2
    t = np.arange(0, 20, 1 / 30)
    a, _ = simulate(corrected, {**base, "restoring_torque_correction": eps}, math.radians(30.0), 0.0, t)
    b, _ = simulate(PendulumModel(RIG, terms), scaled, math.radians(30.0), 0.0, t)
    assert np.abs(a - b).max() < 1e-11


@pytest.mark.slow
def test_fitter_accepts_a_restoring_correction_and_flags_it_unidentifiable_on_one_rig():
    truth = {"added_mass_kg": 2.5, "drag_area_m2": 0.02576, "restoring_torque_correction": 0.03}
    settings = FitSettings()
    record = load_record(hidden_effect_table(PAPER_RIG, truth, 20.0, seed=1), "eps", PAPER_RIG, settings)
    fit = fit_trials([record], ("quadratic_drag", "restoring_correction"), settings)
    entry = fit["parameters"]["restoring_torque_correction"]
    assert entry["unit"] == "1" and entry["lower_bound"] == -0.5 and not entry["identifiable"]


# --- the synthetic generator: effects in and outside the library


def forced_reference(p, t, theta0, drive):
    """I θ̈ = −(1+ε) K sin θ − c θ̇ + τ(t), typed in again; DOP853 at rtol 1e-12 (smooth: no reversal events)."""
    inertia = 2.038928 + p["added_mass_kg"] * L2
    stiffness = (1 + p["restoring_torque_correction"]) * K_PAPER
    c = p["linear_damping_nm_s"]
    a, period, phase = drive

    def rhs(time, y):
        torque = a * math.sin(2 * math.pi * time / period + phase)
        return [y[1], (-stiffness * math.sin(y[0]) - c * y[1] + torque) / inertia]

    sol = solve_ivp(rhs, (0, t[-1]), [theta0, 0.0], method="DOP853", rtol=1e-12, atol=1e-14, t_eval=t)
    return sol.y[0]


def test_angle_table_with_a_disturbance_and_a_drifting_zero_matches_an_independent_integration():
    """hidden_effect_table with a periodic torque (0.05 N·m, 1.3 s: off resonance, T₀ ≈ 4 s) and a 0.5° drift.

    θ_k − drift·t_k/22 s against DOP853 of the equation typed in above: to 1e-8 rad (RK4 at 1/240 s: ≈1e-10).
    Measured 7e-11 rad. The drift is exactly linear; without the torque θ differs by 2.7e-3 rad.
    """
    truth = {"added_mass_kg": 2.5, "linear_damping_nm_s": 0.15, "restoring_torque_correction": 0.02}
    drive = (0.05, 1.3, 0.4)
    table = hidden_effect_table(
        PAPER_RIG, truth, 15.0, zero_drift_deg=0.5, disturbance=PeriodicTorque(*drive), duration_s=22.0
    )
    t = table.time_s.to_numpy()
    reference = forced_reference(truth, np.concatenate([[0.0], t]), math.radians(15.0), drive)[1:]
    measured = table.theta_rad.to_numpy() - math.radians(0.5) * t / 22.0
    assert np.abs(measured - reference).max() < 1e-8, np.abs(measured - reference).max()
    quiet = hidden_effect_table(PAPER_RIG, truth, 15.0)
    assert np.abs(quiet.theta_rad.to_numpy() - reference).max() > 1e-3
    # the library effects to hide come from the truth's keys; same as naming them
    model = PendulumModel(RIG, ("linear_damping", "restoring_correction"))
    assert quiet.equals(synthetic_angle_table(model, truth, 15.0))


def test_disturbance_restarts_a_stuck_pendulum_when_it_exceeds_the_friction():
    """At rest at θ = 0 with τ_f = 0.02 N·m, the torque 0.05 sin(2πt/1.3 s) frees it when it reaches τ_f.

    Restart at t* = 1.3 asin(0.4)/2π = 0.085143 s. Then, until it stops again (θ ≤ 3.4e-4 rad: sin θ = θ to
    2e-8), I θ̈ + K θ = A sin Ωt − τ_f from rest at t*: θ = A sin(Ωt)/(K − IΩ²) − τ_f/K + c₁ cos ω₀(t−t*)
    + c₂ sin ω₀(t−t*), c₁, c₂ from θ(t*) = θ̇(t*) = 0. Before t* θ is exactly 0. Tolerance 1e-9 rad
    (measured 2e-14); restarting one sample (1/600 s) late would be off by 3e-8 rad.
    """
    a, period, tau = 0.05, 1.3, 0.02
    big_omega, w0 = 2 * math.pi / period, math.sqrt(K_PAPER / INERTIA)
    t_star = period * math.asin(tau / a) / (2 * math.pi)
    assert t_star == pytest.approx(0.085143, abs=1e-6)
    t = np.arange(0, 0.45, 1 / 600)
    model = PendulumModel(RIG, ("coulomb_friction",))
    theta, omega = simulate(
        model,
        {"added_mass_kg": 2.5, "friction_torque_nm": tau},
        0.0,
        0.0,
        t,
        external_torque_nm=PeriodicTorque(a, period),
    )
    before, after = t < t_star, t >= t_star
    assert np.all(theta[before] == 0.0) and np.all(omega[before] == 0.0)
    gain = a / (K_PAPER - INERTIA * big_omega**2)
    c1 = -(gain * math.sin(big_omega * t_star) - tau / K_PAPER)
    c2 = -gain * big_omega * math.cos(big_omega * t_star) / w0
    s = t[after] - t_star
    exact = gain * np.sin(big_omega * t[after]) - tau / K_PAPER + c1 * np.cos(w0 * s) + c2 * np.sin(w0 * s)
    assert np.all(omega[after][1:] > 0)  # still moving forward over the compared span
    assert np.abs(theta[after] - exact).max() < 1e-9, np.abs(theta[after] - exact).max()


def test_a_trial_spec_hides_the_history_force_in_the_video_truth():
    """A spec whose effects include history_force: the per-frame truth after the release is the decay with memory
    started at the release (θ̇ = 0 there, so no memory before), i.e. the angle table's θ shifted by the release time.
    Agreement to 1e-9 rad (the two use RK4 steps of 1/120 and 1/240 s: measured 4e-10); K_h = 0.3 kg/√s moves θ
    by 2.6e-2 rad.
    """
    base = load_specs(DEMO_SPEC)[1]  # demo_p20
    truth = {**base.truth, "history_coefficient_kg_per_sqrt_s": 0.3}
    spec = replace(base, truth=truth, effects=[*base.effects, "history_force"])
    t_release = release_time_s(spec)
    times = t_release + np.arange(1, 301) / 30
    video = true_angle_rad(spec, times)
    table = synthetic_angle_table(PendulumModel(RIG, tuple(spec.effects)), truth, spec.release_deg, duration_s=10.0)
    assert np.abs(video - table.theta_rad.to_numpy()).max() < 1e-9
    assert np.abs(video - true_angle_rad(base, times)).max() > 1e-3


def test_rendered_video_hides_a_drifting_pivot_and_records_it():
    """A 2 s clip whose pivot drifts by (6, −4) px: the marker, tracked in two held frames, moves with it.

    The pendulum is held still for the first second, so any motion of the marker there is the drift:
    (6, −4) px × 28/60 = (2.8, −1.867) px between frames 0 and 28, measured to 0.1 px (a threshold centroid
    on 3-grey-level noise is good to ≈ 0.03 px; measured 0.02 and 0.05 px). The truth file records the
    disturbance; the demo's does not.
    """
    base = load_specs(DEMO_SPEC)[0]
    camera = Camera(width_px=480, height_px=400, pivot_px=(240.3, 40.6), marker_arm_px=300.0, marker_radius_px=8.0)
    spec = replace(
        base,
        name="drift",
        release_deg=20.0,
        duration_s=2.0,
        camera=camera,
        disturbances=Disturbances(pivot_drift_px=(6.0, -4.0), torque_amplitude_nm=0.05, torque_period_s=1.3),
    )
    rendered = render_trial(spec)
    settings = TrackerSettings(marker_radius_px=8.0, centroid="threshold")
    truth = rendered.truth
    first, later = (
        measure_marker(rendered.frames[i], truth.marker_x_px[i], truth.marker_y_px[i], settings) for i in (0, 28)
    )
    assert later.x - first.x == pytest.approx(2.8, abs=0.1) and later.y - first.y == pytest.approx(-1.8667, abs=0.1)
    assert truth.pivot_x_px.iloc[-1] - truth.pivot_x_px.iloc[0] == pytest.approx(6.0 * 59 / 60)
    record = truth_record(spec)
    assert record["disturbances"]["pivot_drift_px"] == [6.0, -4.0]
    assert (
        TrialSpec.from_mapping(
            {k: v for k, v in record.items() if k not in ("trial", "release_time_s")} | {"name": "drift"}
        ).disturbances
        == spec.disturbances
    )
    assert "disturbances" not in truth_record(base)
