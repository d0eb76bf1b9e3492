"""The Basset–Boussinesq history force: its memory in the simulator against closed forms.

The history torque is −K_h L² H(t), H(t) = ∫₀ᵗ θ̈(τ)/√(t−τ) dτ. pendulum.model.physics carries H as
c₀ θ̈ + Σ w_j z_j with z_j' = −λ_j z_j + θ̈ (HistoryKernel). The references here share none of that:
Fresnel integrals for prescribed accelerations, and the exact Laplace-transform solution of the
small-amplitude oscillator with the history force (residues plus the branch-cut integral).
"""

import math

import numpy as np
import pytest
from scipy.integrate import quad
from scipy.special import fresnel

from paper_rig import PAPER_RIG
from pendulum.fit.output_error import fit_trials
from pendulum.fit.records import FitSettings, load_record
from pendulum.model.effects import history_equivalent
from pendulum.model.history import HISTORY_KERNEL, history_integral
from pendulum.model.physics import PendulumModel, simulate
from pendulum.model.rig import Rig
from pendulum.synthetic.records import synthetic_angle_table

RIG = Rig(**PAPER_RIG)
# Paper rig by hand (tests/test_physics_reference.py): K = 7.679268 N·m, I = m L² + m_a L² = 3.482928 kg·m²
# with m_a = 2.5 kg, L² = 0.5776 m².
K_PAPER, L2, INERTIA = 7.679268, 0.5776, 3.482928
HISTORY = "history_coefficient_kg_per_sqrt_s"


def fresnel_history(omega, t):
    """∫₀ᵗ sin(ωτ)/√(t−τ) dτ and ∫₀ᵗ cos(ωτ)/√(t−τ) dτ.

    With s = t − τ: ∫₀ᵗ sin ω(t−s)/√s ds = sin ωt ∫₀ᵗ cos ωs/√s ds − cos ωt ∫₀ᵗ sin ωs/√s ds, and
    ωs = πu²/2 turns ∫₀ᵗ cos ωs/√s ds into √(2π/ω) C(z), z = √(2ωt/π) (S likewise), where
    C(z) = ∫₀^z cos(πu²/2) du and S(z) = ∫₀^z sin(πu²/2) du (scipy.special.fresnel returns S, C).
    """
    s, c = fresnel(np.sqrt(2 * omega * t / np.pi))
    scale = math.sqrt(2 * math.pi / omega)
    wt = omega * t
    return scale * (np.sin(wt) * c - np.cos(wt) * s), scale * (np.cos(wt) * c + np.sin(wt) * s)


@pytest.mark.parametrize("omega", [1.5, 2 * math.pi])
@pytest.mark.parametrize("step_s", [0.02, 1 / 240])
def test_history_integral_matches_fresnel_closed_forms(omega, step_s):
    """θ̈ = sin ωτ (starts smoothly) and cos ωτ (jumps to 1 at τ = 0), 60 s, at the fitter's step and a fine one.

    Tolerance 3e-4 of the steady amplitude √(π/ω) (measured 0.7–2.2e-4); for the jump only from 0.1 s
    on: the kernel's part faster than 10 ms is lumped into c₀ θ̈(t), so a jump's √t rise is smeared
    over the first ≈ 10 ms (error up to c₀ = 0.064 per unit jump there). A lost factor (2 in
    the weights, √π in c₀) or a wrong RK4 stage moves H by ≥ 1e-2.
    """
    t = np.arange(0, 60 + 1e-9, 1 / 30)
    exact_sin, exact_cos = fresnel_history(omega, t)
    amplitude = math.sqrt(math.pi / omega)
    got_sin = history_integral(lambda s: math.sin(omega * s), t, step_s)
    got_cos = history_integral(lambda s: math.cos(omega * s), t, step_s)
    err_sin = np.abs(got_sin - exact_sin) / amplitude
    err_cos = np.abs(got_cos - exact_cos)[t >= 0.1] / amplitude
    assert err_sin.max() < 3e-4, err_sin.max()
    assert err_cos.max() < 3e-4, err_cos.max()


@pytest.mark.slow
def test_history_integral_of_a_step_is_two_root_t():
    """θ̈ = 1 from τ = 0: H = ∫₀ᵗ dτ/√(t−τ) = 2√t. From 0.1 s to 1000 s to 1e-3 relative (measured 6e-4)."""
    t = np.concatenate([[0.0], np.geomspace(0.1, 1000.0, 60)])
    got = history_integral(lambda s: 1.0, t, 0.02)
    rel = np.abs(got[1:] / (2 * np.sqrt(t[1:])) - 1)
    assert rel.max() < 1e-3, rel.max()


def test_kernel_transfer_function_and_passivity():
    """c₀ + Σ w/(λ + iω) = √(π/(iω)) to 4e-4 relative for 1e-4 ≤ ω ≤ 30 rad/s; all weights ≥ 0 (dissipative)."""
    k = HISTORY_KERNEL
    omega = np.geomspace(1e-4, 30.0, 997)
    rel = np.abs(k.transfer(omega) / np.sqrt(np.pi / (1j * omega)) - 1)
    assert rel.max() < 4e-4, rel.max()
    assert np.all(k.weights > 0) and k.instantaneous_s05 >= 0
    assert k.rates_per_s.max() * 0.02 < 2.78  # RK4 stays stable at the fitter's 0.02 s step


CASES = {
    "drag, linear, friction, 20°": (("quadratic_drag", "linear_damping", "coulomb_friction"), 20.0, 0.0, None),
    "drag, friction, sticks, 8°": (("quadratic_drag", "coulomb_friction"), 8.0, 0.0, None),
    "drag, 75°, fitter step": (("quadratic_drag",), 75.0, 0.0, 0.02),
    "linear, moving start": (("linear_damping",), 10.0, -1.2, None),
}
VALUES = {"added_mass_kg": 2.5, "drag_area_m2": 0.02576, "linear_damping_nm_s": 0.15, "friction_torque_nm": 0.02}


@pytest.mark.parametrize("case", sorted(CASES))
def test_zero_history_coefficient_is_bit_identical_to_the_memoryless_simulator(case):
    """With K_h = 0 the memory path (extra states, stage moments, stick checks) reproduces today's θ, θ̇ exactly."""
    terms, release_deg, omega0, max_step = CASES[case]
    plain = PendulumModel(RIG, terms)
    params = {k: VALUES[k] for k in plain.parameter_names}
    if "sticks" in case:
        params["friction_torque_nm"] = 0.1
    times = np.arange(0, 30, 1 / 30)
    a = simulate(plain, params, math.radians(release_deg), omega0, times, max_step_s=max_step)
    b = simulate(plain.with_terms(terms + ("history_force",)), {**params, HISTORY: 0.0}, math.radians(release_deg),
                 omega0, times, max_step_s=max_step)  # fmt: skip
    assert np.array_equal(a[0], b[0]) and np.array_equal(a[1], b[1])
    if "sticks" in case:
        assert a[1][-1] == 0.0  # the stick branch was exercised


@pytest.mark.parametrize("case", sorted(CASES))
@pytest.mark.parametrize("friction_nm", [None, 0.1])
def test_the_compiled_memory_path_is_the_python_one(case, friction_nm):
    """The compiled loop with memory (pendulum.model.kernels) against the Python loop that serves external
    torques, given τ_ext ≡ 0 (it then adds 0/I to every stage): the same θ, θ̇ to 1e-12 with K_h = 0.3 kg/√s,
    through reversals, Coulomb stick and the memory setting the body moving again (τ_f = 0.1 N·m)."""
    terms, release_deg, omega0, max_step = CASES[case]
    terms = terms + (("coulomb_friction",) if friction_nm and "coulomb_friction" not in terms else ())
    model = PendulumModel(RIG, terms + ("history_force",))
    params = {**{k: VALUES[k] for k in model.parameter_names if k in VALUES}, HISTORY: 0.3}
    if friction_nm:
        params["friction_torque_nm"] = friction_nm
    times = np.arange(0, 30, 1 / 30)
    start = (math.radians(release_deg), omega0, times)
    compiled = simulate(model, params, *start, max_step_s=max_step)
    python = simulate(model, params, *start, max_step_s=max_step, external_torque_nm=lambda t: 0.0)
    assert np.abs(compiled[0] - python[0]).max() < 1e-12 and np.abs(compiled[1] - python[1]).max() < 1e-12
    if friction_nm:
        assert np.count_nonzero(compiled[1] == 0.0) > 10  # the stick branch was exercised


def test_tiny_history_coefficient_moves_events_and_stick_continuously():
    """K_h = 1e-6 and 2e-6 kg/√s beside friction that sticks: θ moves linearly in K_h through reversals and the stop.

    The change δθ(K_h) is of order 1e-8 rad (measured 4e-8 at 1e-6) and must double with K_h to 1 % of itself:
    a reversal or stick handled differently with memory (a missed event, a restart) is a jump, not a slope.
    """
    model = PendulumModel(RIG, ("quadratic_drag", "coulomb_friction", "history_force"))
    params = {"added_mass_kg": 2.5, "drag_area_m2": 0.02576, "friction_torque_nm": 0.1}
    times = np.arange(0, 40, 1 / 30)
    runs = [simulate(model, {**params, HISTORY: kh}, math.radians(8.0), 0.0, times) for kh in (0.0, 1e-6, 2e-6)]
    assert all(omega[-1] == 0.0 and np.all(theta[-100:] == theta[-1]) for theta, omega in runs)  # stuck for good
    d1, d2 = runs[1][0] - runs[0][0], runs[2][0] - runs[0][0]
    assert 1e-9 < np.abs(d1).max() < 1e-6, np.abs(d1).max()
    assert np.abs(d2 - 2 * d1).max() < 0.01 * np.abs(d1).max(), np.abs(d2 - 2 * d1).max() / np.abs(d1).max()


def test_memory_can_free_a_stuck_pendulum_and_does_so_smoothly():
    """A strong history force (K_h = 10 kg/√s) frees a pendulum that friction (0.2 N·m) had stopped.

    At rest the memory keeps decaying and its torque can exceed τ_f again; the simulator locates that
    instant (measured restarts after rests at 6.43 and 16.97 s of a 10° release). The trajectory stays
    a smooth function of K_h through the restarts: δθ doubles with δK_h to 1e-3 of itself (measured 2e-7).
    """
    model = PendulumModel(RIG, ("coulomb_friction", "history_force"))
    params = {"added_mass_kg": 2.5, "friction_torque_nm": 0.2}
    times = np.arange(0, 40, 1 / 30)
    runs = [
        simulate(model, {**params, HISTORY: kh}, math.radians(10.0), 0.0, times) for kh in (10.0, 10 + 1e-6, 10 + 2e-6)
    ]
    at_rest = runs[0][1] == 0.0
    restarts = times[1:][at_rest[:-1] & ~at_rest[1:]]  # first moving sample after a rest (the release is one)
    assert np.count_nonzero(restarts > 1.0) >= 2, restarts
    d1, d2 = runs[1][0] - runs[0][0], runs[2][0] - runs[0][0]
    assert 0 < np.abs(d1).max() < 1e-6
    assert np.abs(d2 - 2 * d1).max() < 1e-3 * np.abs(d1).max()


def exact_linear_history_oscillator(theta0, b, omega0_sq, t):
    """θ(t) of θ̈ + b ∫₀ᵗ θ̈(τ)/√(t−τ) dτ + ω₀² θ = 0, θ(0) = θ0, θ̇(0) = 0, by inverse Laplace transform.

    Θ(s) = θ0 (s + β√s)/D(s), D(s) = s² + β s^{3/2} + ω₀², β = b√π (L[∫θ̈/√(t−τ)] = √(π/s) L[θ̈]).
    With r = √s (Re r > 0 on the principal sheet), D = 0 is the quartic r⁴ + β r³ + ω₀² = 0: its two
    roots with Re r > 0 are the poles s_p = r², residues θ0 (s_p + β r) e^{s_p t}/D'(s_p) with
    D'(s) = 2s + (3/2)β√s. The branch cut along s < 0 adds −(1/π) ∫₀^∞ Im Θ(x e^{iπ}) e^{−xt} dx,
    with √s = i√x on its upper side: a non-oscillating tail ≈ −θ0 b/(2ω₀² t^{3/2}) at long times.
    """
    beta = b * math.sqrt(math.pi)
    r = np.roots([1.0, beta, 0.0, 0.0, omega0_sq])
    r = r[r.real > 0]
    poles = r**2
    theta = np.zeros_like(t)
    for sp, rp in zip(poles, r, strict=True):
        theta = theta + (theta0 * (sp + beta * rp) * np.exp(sp * t) / (2 * sp + 1.5 * beta * rp)).real

    def im_upper(x):
        sq = 1j * math.sqrt(x)
        return (theta0 * (-x + beta * sq) / (x * x - x * beta * sq + omega0_sq)).imag

    cut = np.array([quad(lambda x, tt=tt: im_upper(x) * math.exp(-x * tt), 0, np.inf, limit=400)[0] for tt in t])
    return theta - cut / math.pi, poles


def test_exact_reference_is_right_at_its_limits():
    """The reference: θ(0⁺) = θ0 (the poles and the cut together), and with b = 0 it is θ0 cos ω₀t."""
    w0sq = K_PAPER / INERTIA
    start, _ = exact_linear_history_oscillator(1.0, 0.166, w0sq, np.array([1e-7]))
    assert start[0] == pytest.approx(1.0, abs=1e-5)
    t = np.linspace(0.1, 20, 50)
    free, _ = exact_linear_history_oscillator(1.0, 0.0, w0sq, t)
    assert np.abs(free - np.cos(math.sqrt(w0sq) * t)).max() < 1e-10


@pytest.mark.parametrize("history_coefficient", [0.2, 1.0])
@pytest.mark.parametrize("max_step_s", [None, 0.02])
def test_small_amplitude_history_oscillator_matches_the_exact_solution(history_coefficient, max_step_s):
    """simulate() at θ0 = 1e-3 rad (sin θ = θ to 2e-7) against the Laplace solution, 30 s at 30 fps.

    Paper rig, point mass, m_a = 2.5 kg: b = K_h L²/I = 0.0332 and 0.166 √s; the history force shifts
    the frequency by 1.7 % and 8.4 % and decays the swing at 0.024 and 0.107 s⁻¹. Tolerance 2e-4 θ0
    (measured 5.6e-5 and 6.1e-5 θ0; 2.7e-6 without the history force, the nonlinearity): a 1 % error in
    the history torque moves θ by 5e-3 θ0 at K_h = 0.2.
    """
    theta0 = 1e-3
    t = np.arange(0, 30, 1 / 30)
    exact, _ = exact_linear_history_oscillator(theta0, history_coefficient * L2 / INERTIA, K_PAPER / INERTIA, t)
    model = PendulumModel(RIG, ("history_force",))
    params = {"added_mass_kg": 2.5, HISTORY: history_coefficient}
    theta, _ = simulate(model, params, theta0, 0.0, t, max_step_s=max_step_s)
    err = np.abs(theta - exact).max() / theta0
    assert err < 2e-4, err


def measured_period_and_decay_rate(t, theta):
    """Mean period from upward zero crossings; decay rate from the log of the swing peaks (least squares)."""
    i = np.flatnonzero((theta[1:] > 0) & (theta[:-1] <= 0))
    crossings = t[i] - theta[i] * (t[i + 1] - t[i]) / (theta[i + 1] - theta[i])
    period = (crossings[-1] - crossings[0]) / (len(crossings) - 1)
    j = np.flatnonzero((np.abs(theta[1:-1]) >= np.abs(theta[:-2])) & (np.abs(theta[1:-1]) > np.abs(theta[2:]))) + 1
    rate = -np.polyfit(t[j], np.log(np.abs(theta[j])), 1)[0]
    return period, rate


@pytest.mark.slow
def test_history_force_at_one_frequency_is_added_mass_plus_linear_damping():
    """Decay rate and period of a small swing with the history force, against two closed forms.

    K_h = 0.3 kg/√s on the paper rig, θ0 = 1e-3 rad, 5–40 s (the branch-cut tail is < 2e-3 of the swing there).
    (1) The exact pole s_p = −σ + iω_d of (I + K_h L²√(π/s)) s² + K = 0: period 2π/ω_d and σ to 1e-4 and
        2e-3 relative (measured 7e-6 and 6e-5).
    (2) pendulum.model.effects.history_equivalent at ω = ω_d: added mass m_h = K_h √(π/2ω), damping
        c_h = K_h L² √(πω/2); I' = I + m_h L², σ' = c_h/2I', ω' = √(K/I' − σ'²). The single-frequency
        picture neglects that the swing decays (s is not iω): period to 1e-3, rate to 3 % (measured 3e-4, 1.2 %).
    """
    kh, theta0 = 0.3, 1e-3
    t = np.arange(0, 40, 1 / 120)
    model = PendulumModel(RIG, ("history_force",))
    theta, _ = simulate(model, {"added_mass_kg": 2.5, HISTORY: kh}, theta0, 0.0, t)
    keep = t >= 5
    period, rate = measured_period_and_decay_rate(t[keep], theta[keep])

    b = kh * L2 / INERTIA
    _, poles = exact_linear_history_oscillator(theta0, b, K_PAPER / INERTIA, np.array([1.0]))
    pole = poles[poles.imag > 0][0]
    assert period == pytest.approx(2 * math.pi / pole.imag, rel=1e-4)
    assert rate == pytest.approx(-pole.real, rel=2e-3)

    omega = pole.imag
    for _ in range(20):  # ω' depends on the equivalent added mass at ω'
        eq = history_equivalent(RIG, kh, omega)
        inertia = INERTIA + eq["added_mass_kg"] * L2
        sigma = eq["linear_damping_nm_s"] / (2 * inertia)
        omega = math.sqrt(K_PAPER / inertia - sigma**2)
    assert period == pytest.approx(2 * math.pi / omega, rel=1e-3)
    assert rate == pytest.approx(sigma, rel=3e-2)


@pytest.mark.slow
def test_fitter_recovers_a_hidden_history_coefficient():
    """[quadratic_drag, history_force] fitted to a noise-free record made with K_h = 0.3 kg/√s, C_d = 0.8, m_a = 2.5 kg.

    Fitter and generator share pendulum.model.physics; what differs is the start: the generator runs the
    memory from the release, the fit starts 0.25 s later and assumes θ̇ grew linearly from rest since
    (history_origin_s = 0). Tolerance 2e-3 relative on K_h (measured 2.5e-4), 1e-3 on m_a and C_d
    (measured 3e-5, 1.1e-4).
    """
    terms = ("quadratic_drag", "history_force")
    truth = {"added_mass_kg": 2.5, "drag_area_m2": 0.02576, HISTORY: 0.3}
    settings = FitSettings()
    table = synthetic_angle_table(PendulumModel(RIG, terms), truth, 20.0)
    fit = fit_trials([load_record(table, "hidden_history", PAPER_RIG, settings)], terms, settings)
    p = fit["parameters"]
    assert p[HISTORY]["value"] == pytest.approx(0.3, rel=2e-3)
    assert p["added_mass_kg"]["value"] == pytest.approx(2.5, rel=1e-3)
    assert p["drag_coefficient"]["value"] == pytest.approx(0.8, rel=1e-3)
    assert p[HISTORY]["unit"] == "kg/√s" and not p[HISTORY]["at_bound"]
