"""Classical decay analysis: swing extrema, period, extinction curve.

Used for the fitter's starting values, the per-half-cycle table the report and
discovery read, and (later) the discovery's fast screen of candidate effects.
"""

from __future__ import annotations

import math

import numpy as np
import pandas as pd
from scipy.optimize import least_squares, nnls

from pendulum.angles.swings import noise_level, swing_centre_rad, swing_extrema
from pendulum.fit.records import AngleRecord
from pendulum.model.effects import ADDED_MASS, TERMS
from pendulum.model.physics import PendulumModel

PEAK_DROP_SIGMAS = 4.0  # a peak's refining window reaches where the swing has come back by this many noise σ
MAX_PEAK_HALF_WIDTH = 64  # ... at most this many samples each side


def extrema(t, theta, noise_rad: float = 0.0):
    """Times and signed values of the swing extrema (:func:`~pendulum.angles.swings.swing_extrema`: one
    per swing, however noisy its flat peak), each refined by a parabola through 2k + 1 samples about it: k = 2, or
    wider where the angle comes back from the peak by less than :data:`PEAK_DROP_SIGMAS` × ``noise_rad`` within k
    samples (a slow swing sampled fast: its peak is flat within the noise, and 5 samples place it anywhere on it).
    A peak clipped flat (3 of its 5 samples at one value: a sensor's or a frame edge's limit) gives none."""
    smooth = pd.Series(theta).rolling(3, center=True, min_periods=1).mean().to_numpy()
    times, values = [], []
    for i in swing_extrema(theta):
        if np.count_nonzero(theta[max(i - 2, 0) : i + 3] == theta[i]) >= 3:  # a clipped, flat peak: no extremum
            continue
        k = 2
        while (
            k < MAX_PEAK_HALF_WIDTH
            and i - 2 * k >= 0
            and i + 2 * k < t.size
            and min(abs(smooth[i] - smooth[i - k]), abs(smooth[i] - smooth[i + k])) < PEAK_DROP_SIGMAS * noise_rad
        ):
            k *= 2
        if i < k or i > t.size - k - 1:
            continue
        tt, yy = t[i - k : i + k + 1] - t[i], theta[i - k : i + k + 1]
        a, b, c = np.polyfit(tt, yy, 2)
        if a == 0 or abs(-b / (2 * a)) > 2 * (tt[-1] - tt[0]):
            continue
        tv = -b / (2 * a)
        times.append(t[i] + tv)
        values.append(c - b * b / (4 * a))
    return np.array(times), np.array(values)


def decay_analysis(model: PendulumModel, record: AngleRecord) -> dict:
    """Starting values: period → inertia → added mass; extinction curve → damping coefficients.

    With A the swing amplitude, the small-damping energy balance over one half
    cycle gives the amplitude loss ΔA = 2τ_f/K + (π c / 2Iω₀) A + (4 D / 3I) A²,
    K = (mg − B)L, D = ½ρ C_dA L³. The large-amplitude period is
    T = T₀ (1 + A²/16 + 11A⁴/3072), T₀ = 2π √(I/K). The rest offset is the
    swing centre (:func:`~pendulum.angles.swings.swing_centre_rad`, right at any frame
    rate), else the median of the last fifth; θ0, θ̇0 come from :func:`start_state`
    without the jumps of :func:`_start_outliers` (``start_outlier_samples``, left
    out of the extinction curve too).
    """
    rig = model.rig
    t, th = record.time_s, record.theta_rad
    sigma = noise_level(th)
    found = swing_centre_rad(th)
    centre = found[0] if found is not None else float(np.median(th[-max(10, th.size // 5) :]))
    x = th - centre
    K = rig.restoring_torque_nm
    _, a0, a1, half_t = _half_cycle_pairs(t, x, max(20 * sigma, 1e-4))
    outliers = _start_outliers(t, x, _start_period_s(half_t, rig), sigma)
    if outliers.any():  # jumps at the start would add false extrema to the extinction curve
        _, a0, a1, half_t = _half_cycle_pairs(t[~outliers], x[~outliers], max(20 * sigma, 1e-4))
    mean_amp, loss = 0.5 * (a0 + a1), a0 - a1
    start = {}
    if half_t.size >= 1:
        correction = 1 + mean_amp**2 / 16 + 11 * mean_amp**4 / 3072
        period0 = float(np.median(2 * half_t / correction))
        inertia = K * (period0 / (2 * math.pi)) ** 2
    else:  # less than half a swing: assume the added mass equals the displaced mass
        inertia = rig.pivot_inertia_kg_m2 + rig.fluid_density_kg_m3 * rig.displaced_volume_m3 * rig.length_m**2
        period0 = 2 * math.pi * math.sqrt(inertia / K)
    added_mass = (inertia - rig.pivot_inertia_kg_m2) / rig.length_m**2
    start[ADDED_MASS] = added_mass
    inertia = rig.pivot_inertia_kg_m2 + start[ADDED_MASS] * rig.length_m**2
    omega0 = 2 * math.pi / period0
    columns = {
        "coulomb_friction": np.ones_like(mean_amp),
        "linear_damping": mean_amp,
        "quadratic_drag": mean_amp**2,
    }
    to_coefficient = {
        "coulomb_friction": K / 2,
        "linear_damping": 2 * inertia * omega0 / math.pi,
        "quadratic_drag": 3 * inertia / 4 / (0.5 * rig.fluid_density_kg_m3 * rig.length_m**3),
    }
    terms = [name for name in model.terms if name in columns]  # the others (history, restoring) start at 0
    coefficients = np.zeros(len(terms))
    if loss.size >= len(terms) + 1:
        a = np.column_stack([columns[name] for name in terms])
        scale = np.abs(a).max(axis=0)
        scale[scale == 0] = 1.0
        solution, _ = nnls(a / scale, loss)
        coefficients = solution / scale
    for name, value in zip(terms, coefficients, strict=True):
        start[TERMS[name].parameter] = float(value * to_coefficient[name])
    for name in model.terms:
        start.setdefault(TERMS[name].parameter, 0.0)
    state = start_state(t, x, _start_period_s(half_t, rig), math.sqrt(K / inertia), outliers)
    return {
        "physical": start,
        "theta0_rad": state.pop("theta0_rad"),
        "omega0_rad_s": state.pop("omega0_rad_s"),
        "rest_offset_rad": float(centre),
        "period_s": period0,
        "n_half_cycles": int(half_t.size),
        "start_outlier_samples": np.flatnonzero(outliers).tolist(),
        **state,
    }


START_WINDOW_PERIODS = 0.75  # the robust decaying sinusoid is fitted to the record's first 3/4 period
LOCAL_WINDOW_PERIODS = 1 / 8  # the local cubic spans the first 1/8 period (at least LOCAL_MIN_SAMPLES)
LOCAL_MIN_SAMPLES = 9
START_OUTLIER_SIGMAS = 8.0  # a sample further than this (robust σ of the sinusoid's residuals) is a jump
SPEED_MARGIN = 1.5  # |θ̇0| up to 1.5 × the largest speed a release from the record's largest swing gives


def _start_period_s(half_t, rig) -> float:
    """Period at the record's start: twice the median of its first three half periods (else with m_a = ρV)."""
    if half_t.size:
        return float(2 * np.median(half_t[:3]))
    inertia = rig.pivot_inertia_kg_m2 + rig.fluid_density_kg_m3 * rig.displaced_volume_m3 * rig.length_m**2
    return 2 * math.pi * math.sqrt(inertia / rig.restoring_torque_nm)


def _start_window(t, period_s) -> np.ndarray:
    return (t - t[0]) <= START_WINDOW_PERIODS * period_s


def _fit_decaying_sinusoid(tau, x, omega_rad_s, robust_scale=None):
    """Least squares x ≈ e^{−λτ}(a cos ωτ + b sin ωτ) + c, ω within a factor 2 and 0 ≤ λ ≤ ω/5 free; (a, b, ω, λ, c).

    ``robust_scale``: Cauchy loss with that scale (a few wild samples barely pull the fit), else plain.
    """
    basis = np.column_stack([np.cos(omega_rad_s * tau), np.sin(omega_rad_s * tau), np.ones_like(tau)])
    (a, b, c), *_ = np.linalg.lstsq(basis, x, rcond=None)

    def residual(p):
        return np.exp(-p[3] * tau) * (p[0] * np.cos(p[2] * tau) + p[1] * np.sin(p[2] * tau)) + p[4] - x

    lower = [-np.inf, -np.inf, 0.5 * omega_rad_s, 0.0, -np.inf]
    upper = [np.inf, np.inf, 2.0 * omega_rad_s, 0.2 * omega_rad_s, np.inf]
    loss = {} if robust_scale is None else {"loss": "cauchy", "f_scale": robust_scale}
    sol = least_squares(residual, [a, b, omega_rad_s, 0.0, c], bounds=(lower, upper), x_scale="jac", **loss)
    return sol.x


def _sinusoid(p, tau):
    a, b, w, lam, c = p
    return np.exp(-lam * tau) * (a * np.cos(w * tau) + b * np.sin(w * tau)) + c


def _start_outliers(t, x, period_s, sigma) -> np.ndarray:
    """Samples of the first 3/4 period that jump off a decaying sinusoid fitted to it (mis-tracked frames).

    Fitted with a Cauchy loss (scale: the robust σ of a first linear fit), then
    by least squares without the samples whose residual exceeds
    max(8 robust σ, 8 σ_noise), robust σ = 1.4826 × median |residual|, until
    the set is stable (on clean records the largest residual is ≤ 4 robust σ,
    also at 75° swings). Samples outside the window are never outliers.
    """
    out = np.zeros(t.size, bool)
    window = np.flatnonzero(_start_window(t, period_s))
    if window.size < 12:
        return out
    tau, xw = t[window] - t[0], x[window]
    omega = 2 * math.pi / period_s
    basis = np.column_stack([np.cos(omega * tau), np.sin(omega * tau), np.ones_like(tau)])
    first = xw - basis @ np.linalg.lstsq(basis, xw, rcond=None)[0]
    params = _fit_decaying_sinusoid(tau, xw, omega, max(1.4826 * float(np.median(np.abs(first))), sigma, 1e-9))
    keep = np.ones(window.size, bool)
    for _ in range(5):
        r = _sinusoid(params, tau) - xw
        scale = 1.4826 * float(np.median(np.abs(r[keep])))
        new = np.abs(r) <= START_OUTLIER_SIGMAS * max(scale, sigma, 1e-12)
        if (new == keep).all() or new.sum() < 12:
            break
        keep = new
        params = _fit_decaying_sinusoid(tau[keep], xw[keep], omega)
    out[window[~keep]] = True
    return out


def start_state(t, x, period_s, natural_rad_s, outliers) -> dict:
    """θ0, θ̇0 of a record (θ about the rest offset) at its first sample, robust to jumps there.

    A cubic through the samples of the first 1/8 period that are not ``outliers``
    (at least 9), evaluated at t0. A θ̇0 no release could give, beyond
    1.5 ω_max with ω_max = 2 ω_n sin(θ_max/2) (energy from rest at the record's
    largest inlying |θ|, θ_max, over the first 3/4 period; ω_n = √(K/I)), or a
    θ0 beyond 1.5 θ_max, is refused: the decaying sinusoid fitted to the first
    3/4 period (inliers) gives θ(t0), θ̇(t0) instead (biased by up to 20 % at
    75° swings, never wild), clipped to those bounds.
    """
    good = ~outliers & np.isfinite(x)
    window = _start_window(t, period_s) & good
    theta_max = float(min(np.max(np.abs(x[window])), math.pi)) if window.any() else float(np.nanmax(np.abs(x)))
    speed_limit = SPEED_MARGIN * 2 * natural_rad_s * math.sin(theta_max / 2)
    idx = np.flatnonzero(good)
    n_local = max(LOCAL_MIN_SAMPLES, int(np.sum(t[idx] - t[0] <= LOCAL_WINDOW_PERIODS * period_s)))
    idx = idx[: min(n_local, idx.size)]
    poly = np.polyfit(t[idx] - t[0], x[idx], min(3, idx.size - 1))
    theta0, omega0 = float(poly[-1]), float(poly[-2])
    state = {"start_method": "local cubic", "start_speed_limit_rad_s": speed_limit}
    if abs(omega0) <= speed_limit and abs(theta0) <= SPEED_MARGIN * theta_max:
        return state | {"theta0_rad": theta0, "omega0_rad_s": omega0}
    state["refused_start"] = {"theta0_rad": theta0, "omega0_rad_s": omega0}
    in_window = np.flatnonzero(window)
    if in_window.size >= 8:
        a, b, w, lam, c = _fit_decaying_sinusoid(t[in_window] - t[0], x[in_window], 2 * math.pi / period_s)
        theta0, omega0 = float(a + c), float(-lam * a + w * b)  # θ(0), θ̇(0) of the sinusoid
        state["start_method"] = "decaying sinusoid"
    theta0 = float(np.clip(theta0, -SPEED_MARGIN * theta_max, SPEED_MARGIN * theta_max))
    omega0 = float(np.clip(omega0, -speed_limit, speed_limit))
    return state | {"theta0_rad": theta0, "omega0_rad_s": omega0}


def _half_cycle_pairs(t, x, min_amplitude_rad):
    """Half cycles of x (θ minus the rest offset): consecutive refined extrema above ``min_amplitude_rad``
    of opposite sign, as (peak time, amplitude, next amplitude, half period)."""
    good = np.isfinite(t) & np.isfinite(x)
    t, x = np.asarray(t, float)[good], np.asarray(x, float)[good]
    if t.size < 5:
        return (np.array([]),) * 4
    ext_t, ext_v = extrema(t, x, noise_level(x))
    keep = np.abs(ext_v) > min_amplitude_rad
    ext_t, ext_v = ext_t[keep], ext_v[keep]
    pairs = np.flatnonzero(np.sign(ext_v[1:]) != np.sign(ext_v[:-1])) if ext_v.size > 1 else np.array([], int)
    amp = np.abs(ext_v)
    return ext_t[pairs], amp[pairs], amp[pairs + 1], ext_t[pairs + 1] - ext_t[pairs]


HALF_CYCLE_COLUMNS = (
    "peak_time_s",
    "next_peak_time_s",
    "amplitude_rad",
    "amplitude_deg",
    "next_amplitude_rad",
    "amplitude_loss_rad",
    "mean_amplitude_rad",
    "mean_amplitude_deg",
    "half_period_s",
    "period_s",
    "peak_speed_m_s",
    "keulegan_carpenter_number",
    "reynolds_number",
    "equivalent_linear_damping_nm_s",
    "local_drag_coefficient",
    "equivalent_friction_torque_nm",
)


def half_cycles(
    time_s,
    theta_rad,
    rest_offset_rad: float,
    model: PendulumModel,
    params: dict,
    characteristic_length_m: float,
    kinematic_viscosity_m2_s: float,
    min_amplitude_rad: float | None = None,
) -> pd.DataFrame:
    """One row per half cycle (swing extremum to the next, opposite extremum) of a decay record.

    Extrema are the parabola-refined turning points of θ − δ (δ the rest offset);
    those smaller than ``min_amplitude_rad`` (default max(20 σ_noise, 10⁻⁴ rad))
    are noise, and only consecutive extrema of opposite sign form a half cycle.
    With A_i = |θ_i − δ| at the peak (time t_i) and A_{i+1} at the next:

    * amplitude loss ΔA = A_i − A_{i+1}, mean amplitude Ā = (A_i + A_{i+1})/2,
      half period t_{i+1} − t_i, period T = 2 (t_{i+1} − t_i), ω = 2π/T;
    * peak speed at the bottom of the swing from the energy at Ā (the bottom is
      passed half-way, so its energy is that of the mean amplitude to first
      order in the loss): U = L √(2K(1 − cos Ā)/I), K = (mg − B)L, I = I_p + m_a L²
      (from ``params``, the variant's fitted inertia);
    * Keulegan–Carpenter number KC = U T / D, Reynolds number Re = U D / ν;
    * equivalent linearisation (energy balance over the half cycle, small
      damping, small angle), each charging all of the loss to one mechanism:
      linear damping ΔA = π c Ā / (2 I ω) → c_eq = 2 I ω ΔA / (π Ā);
      quadratic drag ΔA = (4 D_q / 3I) Ā², D_q = ½ ρ C_d A_f L³ → C_d,local = 3 I ΔA / (2 ρ A_f L³ Ā²);
      Coulomb friction ΔA = 2 τ_f / K → τ_eq = K ΔA / 2.

    Errors of the approximations (measured on noise-free records, tests/test_fit_outputs.py):
    for pure linear damping c_eq = 2Iω_d tanh(δ/2)·2/π with δ the log decrement per half
    cycle, i.e. exact to δ²/12 (≈0.1 % at δ = 0.1); the small-angle energy balance adds
    O(Ā²/16) (≈0.8 % at 20°) for the linear and quadratic terms.
    """
    t = np.asarray(time_s, float)
    x = np.asarray(theta_rad, float) - rest_offset_rad
    if min_amplitude_rad is None:
        min_amplitude_rad = max(20 * noise_level(x[np.isfinite(x)]), 1e-4)
    peak_t, a0, a1, half = _half_cycle_pairs(t, x, min_amplitude_rad)
    rig = model.rig
    K = rig.restoring_torque_nm
    inertia = float(model.inertia_kg_m2(params))
    loss = a0 - a1
    mean = 0.5 * (a0 + a1)
    period = 2 * half
    omega = 2 * math.pi / period
    speed = rig.length_m * np.sqrt(2 * K * (1 - np.cos(mean)) / inertia)
    D = float(characteristic_length_m)
    return pd.DataFrame(
        {
            "peak_time_s": peak_t,
            "next_peak_time_s": peak_t + half,
            "amplitude_rad": a0,
            "amplitude_deg": np.degrees(a0),
            "next_amplitude_rad": a1,
            "amplitude_loss_rad": loss,
            "mean_amplitude_rad": mean,
            "mean_amplitude_deg": np.degrees(mean),
            "half_period_s": half,
            "period_s": period,
            "peak_speed_m_s": speed,
            "keulegan_carpenter_number": speed * period / D,
            "reynolds_number": speed * D / float(kinematic_viscosity_m2_s),
            "equivalent_linear_damping_nm_s": 2 * inertia * omega * loss / (math.pi * mean),
            "local_drag_coefficient": 3
            * inertia
            * loss
            / (2 * rig.fluid_density_kg_m3 * rig.frontal_area_m2 * rig.length_m**3 * mean**2),
            "equivalent_friction_torque_nm": K * loss / 2,
        },
        columns=list(HALF_CYCLE_COLUMNS),
    )


def loss_at_amplitude(cycles: pd.DataFrame, amplitude_rad) -> np.ndarray:
    """Amplitude loss of the half cycle starting at ``amplitude_rad``, interpolated in a half-cycle table.

    Linear in the peak amplitude between the table's half cycles; beyond its
    largest or smallest amplitude by less than that half cycle's loss, the end
    value (a fitted curve's peaks differ slightly from the measured ones); NaN further out.
    """
    amplitude_rad = np.asarray(amplitude_rad, float)
    if cycles.empty:
        return np.full(amplitude_rad.shape, np.nan)
    order = np.argsort(cycles.amplitude_rad.to_numpy())
    a = cycles.amplitude_rad.to_numpy()[order]
    loss = cycles.amplitude_loss_rad.to_numpy()[order]
    out = np.interp(amplitude_rad, a, loss)
    out[(amplitude_rad < a[0] - abs(loss[0])) | (amplitude_rad > a[-1] + abs(loss[-1]))] = np.nan
    return out
