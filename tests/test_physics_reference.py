"""pendulum.model.physics against references that do not go through pendulum.model.physics.

The synthetic generator and the fitter share pendulum.model.physics, so a wrong term
there is invisible to a fit of synthetic data. These tests compare it with
closed forms (worked out here, with the arithmetic written down) and with the
equation of motion typed in again in tests/independent_eom.py, and fit records
made by that independent integrator.
"""

import math

import numpy as np
import pytest

from independent_eom import Pendulum, angle_table, integrate
from pendulum.fit.output_error import fit_trials
from pendulum.fit.records import FitSettings, load_record
from pendulum.model.physics import PendulumModel, fastest_swing, simulate, small_angle_period_s
from pendulum.model.rig import Rig

# The paper's Table 1 rig: m = 3.53 kg, L = 0.76 m, A = 0.0322 m², V = 0.0025 m³, ρ = 1000 kg/m³, g = 9.81 m/s².
#   weight    m g       = 3.53 · 9.81          = 34.6293 N
#   buoyancy  ρ g V     = 1000 · 9.81 · 0.0025 = 24.525 N
#   K = (m g − ρ g V) L = 10.1043 · 0.76       = 7.679268 N·m
#   L² = 0.5776 m²; point mass m L² = 3.53 · 0.5776 = 2.038928 kg·m²
K_PAPER = 7.679268
L2 = 0.5776


def model_and_params(p: Pendulum, terms):
    """The same pendulum as pendulum.model.physics spells it."""
    rig = Rig(
        mass_kg=p.mass,
        length_m=p.length,
        frontal_area_m2=p.area,
        displaced_volume_m3=p.volume,
        fluid_density_kg_m3=p.rho,
        gravity_m_s2=p.g,
        body_inertia_kg_m2=p.body_inertia,
    )
    values = {
        "added_mass_kg": p.added_mass,
        "drag_area_m2": p.drag_area,
        "linear_damping_nm_s": p.linear_damping,
        "friction_torque_nm": p.friction,
    }
    model = PendulumModel(rig, terms)
    return model, {k: values[k] for k in model.parameter_names}


def test_hand_arithmetic_of_the_paper_rig():
    """The literals the closed-form tests use, checked against the rig values once."""
    assert (3.53 * 9.81 - 1000 * 9.81 * 0.0025) * 0.76 == pytest.approx(K_PAPER, rel=1e-12)
    assert 0.76**2 == pytest.approx(L2, rel=1e-12)
    assert Pendulum().stiffness == pytest.approx(K_PAPER, rel=1e-12)


def test_small_amplitude_linear_damping_is_the_exact_damped_oscillator():
    """θ(t) = A e^{−ζω₀t} (cos ω_d t + ζω₀/ω_d sin ω_d t) for θ(0) = A, θ̇(0) = 0, sin θ → θ.

    Paper rig, point mass, m_a = 2.5 kg, c = 0.15 N·m·s:
      I  = m L² + m_a L² = 2.038928 + 2.5 · 0.5776 = 3.482928 kg·m²
      ω₀ = √(K/I) = √(7.679268 / 3.482928) = 1.48484… rad/s (T₀ = 4.2315 s)
      ζ  = c / (2√(K I)) = 0.15 / (2 · 5.17160…) = 0.014502…
    Neglected nonlinearity: sin θ = θ (1 − θ²/6 + …) lowers the frequency by
    A²/16 (relative) at amplitude A, so the phase drifts by at most ω₀ t A²/16 and
    |θ − θ_linear| ≤ A · ω₀ t A²/16 = 1.2e-6 rad (1.4e-4 A) at A = 0.5°, t = 20 s.
    Tolerance: twice that. Getting I or K wrong by 1 % shifts the phase by 0.15 rad.
    """
    inertia = 2.038928 + 2.5 * L2
    assert inertia == pytest.approx(3.482928, rel=1e-12)
    c = 0.15
    w0 = math.sqrt(K_PAPER / inertia)
    zeta = c / (2 * math.sqrt(K_PAPER * inertia))
    wd = w0 * math.sqrt(1 - zeta**2)
    amplitude, t_end = math.radians(0.5), 20.0
    times = np.arange(0, t_end, 1 / 30)
    exact = amplitude * np.exp(-zeta * w0 * times) * (np.cos(wd * times) + zeta * w0 / wd * np.sin(wd * times))

    model, params = model_and_params(Pendulum(linear_damping=c), ("linear_damping",))
    theta, _ = simulate(model, params, amplitude, 0.0, times)
    bound = amplitude * w0 * t_end * amplitude**2 / 16
    assert np.max(np.abs(theta - exact)) < 2 * bound, np.max(np.abs(theta - exact))


def test_small_amplitude_coulomb_friction_loses_2_tau_over_k_every_half_cycle():
    """Linear restoring + Coulomb friction: half cycles of exactly π/ω₀, amplitude falls by 2τ_f/K each.

    Paper rig, point mass, m_a = 2.5 kg (I = 3.482928 kg·m², ω₀ = 1.48484 rad/s), τ_f = 0.005 N·m:
      2τ_f/K = 0.01 / 7.679268 = 1.30221e-3 rad (0.0746°) per half cycle, 4τ_f/K per cycle.
    Half cycle k runs from t_k = kπ/ω₀ about the shifted centre ±τ_f/K:
      θ(t) = (−1)^k [τ_f/K + (a_k − τ_f/K) cos ω₀(t − t_k)],  a_k = A₀ − 2kτ_f/K,
    until a_k ≤ τ_f/K (stick). From A₀ = 1°: a_12 = 0.1048° > τ_f/K = 0.0373° ≥ a_13 = 0.0302°,
    so it sticks at θ = −a_13 after 13 half cycles.
    Neglected nonlinearity at A₀ = 1°: the loss per half cycle is 2τ_f/K / (1 − (a_k² + a_k+1²)/12),
    at most 5e-5 relative; the phase drifts by ≤ ω₀ t A₀²/16 = 7.8e-4 rad over 27.5 s, i.e.
    ≤ 1.4e-5 rad of θ. Tolerances: 1e-3 relative on each loss, 3e-5 rad on the trajectory.
    """
    inertia, tau = 3.482928, 0.005
    w0 = math.sqrt(K_PAPER / inertia)
    loss, centre = 2 * tau / K_PAPER, tau / K_PAPER
    a0 = math.radians(1.0)
    amplitudes = a0 - loss * np.arange(14)
    assert amplitudes[12] > centre >= amplitudes[13]

    def exact(t):
        k = np.minimum(np.floor(t * w0 / math.pi).astype(int), 13)
        sign = (-1.0) ** k
        moving = sign * (centre + (amplitudes[k] - centre) * np.cos(w0 * t - k * math.pi))
        return np.where(k < 13, moving, -amplitudes[13])

    model, params = model_and_params(Pendulum(friction=tau), ("coulomb_friction",))
    turning_times = np.append(np.arange(14) * math.pi / w0, 40.0)
    theta, omega = simulate(model, params, a0, 0.0, turning_times, substeps=400)
    losses = -np.diff(np.abs(theta[:14]))
    np.testing.assert_allclose(losses, loss, rtol=1e-3)
    np.testing.assert_allclose(np.abs(theta[:14]), amplitudes, rtol=0, atol=1e-6)
    assert omega[-1] == 0.0 and theta[-1] == pytest.approx(-amplitudes[13], abs=1e-6)  # stuck there

    times = np.arange(0, 35, 1 / 30)
    theta, _ = simulate(model, params, a0, 0.0, times)
    assert np.max(np.abs(theta - exact(times))) < 3e-5, np.max(np.abs(theta - exact(times)))


def test_period_with_buoyancy_and_body_inertia_by_hand():
    """T₀ = 2π √(I/K) with the paper rig's buoyancy and a stated body inertia I_p = 2.4 kg·m² (not m L²).

      K = (3.53 · 9.81 − 1000 · 9.81 · 0.0025) · 0.76 = 10.1043 · 0.76 = 7.679268 N·m
      I = I_p + m_a L² = 2.4 + 2.5 · 0.5776 = 2.4 + 1.444 = 3.844 kg·m²
      T₀ = 2π √(3.844 / 7.679268) = 2π √0.500568544 = 4.44540819 s
    (with m g + B instead: 1.837 s; with m_a L instead of m_a L²: 4.702 s; with m L² instead of I_p: 4.2315 s).
    Simulated at 0.5°, the period is longer by A²/16 = 4.8e-6 (relative): tolerance 2e-5.
    """
    expected = 4.445408193930251
    assert 2 * math.pi * math.sqrt(3.844 / 7.679268) == pytest.approx(expected, rel=1e-12)
    model, params = model_and_params(Pendulum(body_inertia=2.4), ())
    assert small_angle_period_s(model, params) == pytest.approx(expected, rel=1e-12)

    times = np.arange(0, 40, 1 / 120)
    theta, _ = simulate(model, params, math.radians(0.5), 0.0, times, substeps=2)
    i = np.flatnonzero((theta[1:] > 0) & (theta[:-1] <= 0))
    crossings = times[i] - theta[i] * (times[i + 1] - times[i]) / (theta[i + 1] - theta[i])
    assert len(crossings) >= 8
    period = (crossings[-1] - crossings[0]) / (len(crossings) - 1)
    assert period == pytest.approx(expected, rel=2e-5)


CASES = {
    # name: (pendulum, terms, release_deg, omega0_rad_s)
    "drag, buoyancy, point mass, 75°": (Pendulum(drag_area=0.02576), ("quadratic_drag",), 75.0, 0.0),
    "drag, buoyancy, point mass, -5°": (Pendulum(drag_area=0.02576), ("quadratic_drag",), -5.0, 0.0),
    "drag, no buoyancy, body inertia, 40°": (
        Pendulum(drag_area=0.02576, volume=0.0, body_inertia=2.4),
        ("quadratic_drag",),
        40.0,
        0.0,
    ),
    "drag, buoyancy, body inertia, moving start": (
        Pendulum(drag_area=0.05, body_inertia=2.4, added_mass=1.0),
        ("quadratic_drag",),
        10.0,
        -1.2,
    ),
    "linear only, buoyancy, 30°": (Pendulum(linear_damping=0.3), ("linear_damping",), 30.0, 0.0),
    "all terms, buoyancy, body inertia, 60°": (
        Pendulum(drag_area=0.02576, linear_damping=0.15, friction=0.02, body_inertia=2.4),
        ("quadratic_drag", "linear_damping", "coulomb_friction"),
        60.0,
        0.0,
    ),
    "drag and friction, buoyancy, point mass, sticks, 8°": (
        Pendulum(drag_area=0.02576, friction=0.1),
        ("quadratic_drag", "coulomb_friction"),
        8.0,
        0.0,
    ),
}


@pytest.mark.parametrize("case", sorted(CASES))
def test_simulator_matches_the_independently_written_equation_of_motion(case):
    """simulate() (RK4, 8 steps per 1/30 s) against DOP853 at rtol 1e-12 on the equation typed in separately.

    Measured agreement is 1e-11 to 4e-10 rad (tolerance 1e-8 rad, 1e-7 rad/s); any wrong factor in
    a term (L² for L³, a lost ½, m g + B, m_a L) changes θ by 1e-3 rad or more within 20 s.
    """
    p, terms, release_deg, omega0 = CASES[case]
    model, params = model_and_params(p, terms)
    times = np.arange(0, 20, 1 / 30)
    theta, omega = simulate(model, params, math.radians(release_deg), omega0, times)
    ref_theta, ref_omega = integrate(p, math.radians(release_deg), omega0, times)
    assert np.max(np.abs(theta - ref_theta)) < 1e-8, np.max(np.abs(theta - ref_theta))
    assert np.max(np.abs(omega - ref_omega)) < 1e-7, np.max(np.abs(omega - ref_omega))


@pytest.mark.parametrize(
    ("terms", "release_deg"),
    [(("quadratic_drag",), 40.0), (("quadratic_drag", "linear_damping", "coulomb_friction"), 60.0)],
)
def test_fitter_recovers_the_truth_from_an_independently_simulated_record(terms, release_deg):
    """No noise: a record from tests/independent_eom.py fits back to m_a = 2.5 kg and C_d = 0.8 to 0.1 %.

    The fitter simulates through pendulum.model.physics; if its equation were wrong, the best fit of a
    correct record would sit elsewhere (e.g. a lost ½ doubles C_d, m_a L for m_a L² gives m_a·L).
    The record has buoyancy and a stated body inertia (2.4 kg·m²). Noise-free, the estimates are
    off only by the two integrators' differences (< 1e-7 rad): 0.1 % is far wider than that and far
    narrower than any wrong factor. (Noisy records and their intervals: tests/test_fitting_statistics.py.)
    """
    truth = Pendulum(
        drag_area=0.8 * 0.0322,
        body_inertia=2.4,
        linear_damping=0.15 if "linear_damping" in terms else 0.0,
        friction=0.02 if "coulomb_friction" in terms else 0.0,
    )
    settings = FitSettings()
    rec = load_record(angle_table(truth, release_deg, None), "independent", truth.rig_mapping(), settings)
    fit = fit_trials([rec], terms, settings)
    assert fit["parameters"]["added_mass_kg"]["value"] == pytest.approx(2.5, rel=1e-3)
    assert fit["parameters"]["drag_coefficient"]["value"] == pytest.approx(0.8, rel=1e-3)
    if "linear_damping" in terms:
        assert fit["parameters"]["linear_damping_nm_s"]["value"] == pytest.approx(0.15, rel=1e-2)
        assert fit["parameters"]["friction_torque_nm"]["value"] == pytest.approx(0.02, rel=1e-2)


@pytest.mark.parametrize("release_deg", [5.0, 40.0, 75.0])
def test_the_fastest_swings_period_and_kc_take_its_amplitude(release_deg):
    """KC = U_max T / D of a record's fastest swing took the small-swing period T₀, 11 % short for a 75° release
    (a researcher's review, 2026-12-07). An undamped pendulum released at rest from θ₀ swings with the period
    T = (2/π) K(sin²(θ₀/2)) T₀ (the complete elliptic integral of the first kind, scipy.special.ellipk of
    m = k²) and U_max = L √(2 K_r (1 − cos θ₀) / I) (energy), K_r the restoring torque, I the inertia."""
    from scipy.special import ellipk

    model, params = model_and_params(Pendulum(), ())
    theta0 = math.radians(release_deg)
    times = np.arange(0, 12, 0.002)
    theta, omega = simulate(model, params, theta0, 0.0, times)
    small = small_angle_period_s(model, params)
    speed, period, kc = fastest_swing(model, params, times, theta, omega, 0.2)
    expected = 2 / math.pi * ellipk(math.sin(theta0 / 2) ** 2) * small
    assert period == pytest.approx(expected, rel=2e-4)
    inertia = float(model.inertia_kg_m2(params))
    restoring = model.rig.restoring_torque_nm
    u_max = model.rig.length_m * math.sqrt(2 * restoring * (1 - math.cos(theta0)) / inertia)
    assert speed == pytest.approx(u_max, rel=1e-3) and kc == pytest.approx(u_max * expected / 0.2, rel=2e-3)
    # a record with less than a cycle takes the small-swing period
    assert fastest_swing(model, params, times[:500], theta[:500], omega[:500], 0.2)[1] == small


@pytest.mark.parametrize("release_deg", [5.0, 20.0, 45.0, 75.0])
def test_the_records_own_first_swing_gives_the_flows_speed_and_period(release_deg):
    """The report's KC came from each variant's fitted curve: one trial read 5.1, 4.8 and 4.9 by variant, and a
    variant that misses the record moved it (an ROV engineer's review). Now it is measured on the record
    (``first_swing_rate``): the largest |θ̇| of its first cycle and that cycle's period, against the independent
    integrator's own state (the demo's damping: drag, linear damping and friction; at 75° the drag slows the swing
    by 40 % before the bottom, so |θ̇| at the crossing is not it), sampled from 0.25 s after the release at 15, 30
    and 60 fps with 0.005° of noise: within 0.5 % and 0.3 % in at least 19 of 20 seeds each."""
    from pendulum.angles.swings import first_swing_rate

    truth = Pendulum(drag_area=0.02576, linear_damping=0.15, friction=0.02)
    fine = np.arange(0.0, 12.0, 1e-4)
    theta, omega = integrate(truth, math.radians(release_deg), 0.0, fine)
    at = np.flatnonzero(np.signbit(theta[1:]) != np.signbit(theta[:-1]))
    crossings = fine[at] - theta[at] * (fine[at + 1] - fine[at]) / (theta[at + 1] - theta[at])
    first_cycle = (fine >= 0.25) & (fine <= crossings[2])
    true_rate, true_period = float(np.abs(omega[first_cycle]).max()), float(crossings[2] - crossings[0])
    for fps in (15.0, 30.0, 60.0):
        times = np.arange(0.25, 12.0, 1 / fps)
        clean = integrate(truth, math.radians(release_deg), 0.0, np.r_[0.0, times])[0][1:]
        good = 0
        for seed in range(20):
            noisy = clean + np.random.default_rng(seed).normal(0.0, math.radians(0.005), times.size)
            rate, period = first_swing_rate(times, noisy)
            good += abs(rate / true_rate - 1) < 0.005 and abs(period / true_period - 1) < 0.003
        assert good >= 19, (fps, good)


def test_a_record_that_crosses_the_vertical_once_gives_no_first_swing():
    from pendulum.angles.swings import first_swing_rate

    times = np.arange(0.0, 1.0, 1 / 30)
    assert first_swing_rate(times, np.cos(2 * np.pi * times / 2.0)) is None  # one crossing, at 0.5 s
    noisy = np.where(np.abs(times - 0.5) < 0.05, 1e-4 * (-1) ** np.arange(times.size), np.cos(np.pi * times))
    assert first_swing_rate(times, noisy) is None  # flickering about that one crossing is still one
