"""Where a fitted model and the measured swing disagree: residual structure, noise floor, extinction-curve screen.

Plain functions on a :class:`pendulum.fit.group.GroupFit`; :mod:`pendulum.discovery.selection` turns them into a ranked
list of candidate effects and decides by refitting, with the null distribution of its likelihood ratio
(the boundary mixture, at the end of this module).
"""

from __future__ import annotations

import math

import numpy as np
import pandas as pd
from scipy import stats
from scipy.optimize import brentq, nnls

from pendulum.angles.swings import swing_centre_track
from pendulum.fit.decay import half_cycles
from pendulum.fit.group import GroupFit
from pendulum.model.effects import TERMS

WHITENESS_SPACING_S = 0.2  # residuals thinned to this spacing before the whiteness test (tracker noise decorrelates)
WHITENESS_MAX_LAGS = 20


def whiteness(fit: GroupFit, spacing_s: float = WHITENESS_SPACING_S, max_lags: int = WHITENESS_MAX_LAGS) -> dict:
    """Ljung–Box test of the residuals thinned to ``spacing_s``, summed over trials (χ² with Σ lags dof).

    Thinning to 0.2 s leaves tracker noise (correlated over a few frames) nearly white while a
    model error, smooth over a swing, stays strongly autocorrelated.
    """
    q, dof = 0.0, 0
    for k, r in enumerate(fit.residuals):
        t = fit.problem.records[k].time_s[fit.problem.masks[k]]
        step = max(1, int(round(spacing_s / max(float(np.median(np.diff(t))), 1e-9))))
        x = r[::step] - r[::step].mean()
        n = x.size
        lags = min(max_lags, n // 5)
        if lags < 1 or not np.any(x):
            continue
        denom = float(x @ x)
        acf = np.array([float(x[h:] @ x[:-h]) / denom for h in range(1, lags + 1)])
        q += float(n * (n + 2) * np.sum(acf**2 / (n - np.arange(1, lags + 1))))
        dof += lags
    p = float(stats.chi2.sf(q, dof)) if dof else 1.0
    return {"ljung_box_q": q, "dof": dof, "p_value": p, "spacing_s": spacing_s}


def _lag_correlation(r: np.ndarray, lag: int) -> float:
    r = r - r.mean()
    if lag <= 0 or lag >= r.size or not np.any(r):
        return 0.0
    return float(r[lag:] @ r[:-lag] / (r @ r))


def residual_diagnostics(fit: GroupFit) -> dict:
    """Residual against time, angle and velocity; its spectrum and autocorrelation (pooled over trials).

    ``against``: correlation of the residual with the shapes the candidate torques leave
    (sgn θ̇, θ̇, θ̇|θ̇|, θ) and the residual RMS by quarter of the record and by third of |θ| and
    |θ̇|; ``spectrum``: frequency of the residual's strongest periodogram peak over the swing
    frequency; ``autocorrelation``: at one sample and at half a swing period.
    """
    shapes = {"sign_velocity": [], "velocity": [], "velocity_squared": [], "angle": []}
    pooled, time_bins, angle_bins, speed_bins, peaks, lag1, lag_half = [], [], [], [], [], [], []
    for k, r in enumerate(fit.residuals):
        record, mask = fit.problem.records[k], fit.problem.masks[k]
        t = record.time_s[mask]
        theta = fit.trial_curve(k)[mask] - fit.nuisance(k)[2]
        omega = np.gradient(theta, t)
        for key, shape in zip(shapes, (np.sign(omega), omega, omega * np.abs(omega), theta), strict=True):
            shapes[key].append(shape)
        pooled.append(r)
        time_bins.append(np.minimum((4 * (t - t[0]) / max(t[-1] - t[0], 1e-9)).astype(int), 3))
        angle_bins.append(_terciles(np.abs(theta)))
        speed_bins.append(_terciles(np.abs(omega)))
        dt = float(np.median(np.diff(t)))
        period = 2 * math.pi / swing_omega(fit, k)
        spectrum = np.abs(np.fft.rfft(r - r.mean())) ** 2
        freq = np.fft.rfftfreq(r.size, dt)
        peaks.append(float(freq[1:][np.argmax(spectrum[1:])] * period) if r.size > 4 else math.nan)
        lag1.append(_lag_correlation(r, 1))
        lag_half.append(_lag_correlation(r, int(round(period / 2 / dt))))
    residual = np.concatenate(pooled)

    def binned(bins):
        b = np.concatenate(bins)
        return [float(np.sqrt(np.mean(residual[b == i] ** 2))) if np.any(b == i) else None for i in range(b.max() + 1)]

    against = {}
    for key, parts in shapes.items():
        s = np.concatenate(parts)
        against[key] = float(np.corrcoef(s, residual)[0, 1]) if np.std(s) > 0 and np.std(residual) > 0 else 0.0
    return {
        "correlation_with": against,
        "rms_by_time_quarter_rad": binned(time_bins),
        "rms_by_angle_tercile_rad": binned(angle_bins),
        "rms_by_speed_tercile_rad": binned(speed_bins),
        "spectrum_peak_over_swing_frequency": peaks,
        "autocorrelation_lag1": lag1,
        "autocorrelation_half_period": lag_half,
    }


def _terciles(values: np.ndarray) -> np.ndarray:
    edges = np.quantile(values, [1 / 3, 2 / 3])
    return np.searchsorted(edges, values, side="right")


def _model_and_params(fit: GroupFit, k: int):
    return fit.problem.models[k], fit.problem.physical(fit.x, k)


def swing_omega(fit: GroupFit, k: int) -> float:
    """Trial ``k``'s small-amplitude angular frequency in the fit, ω = √(restoring torque / inertia) (rad/s)."""
    model, params = _model_and_params(fit, k)
    return math.sqrt(fit.problem.records[k].rig.restoring_torque_nm / float(model.inertia_kg_m2(params)))


def measured_half_cycles(fit: GroupFit) -> pd.DataFrame:
    """Half cycles of every trial's measured record about its own swing centre
    (:func:`pendulum.angles.swings.swing_centre_track`; the fit's rest offset where it has none), with the
    trial's name."""
    tables = []
    for k, record in enumerate(fit.problem.records):
        model, params = _model_and_params(fit, k)
        mask = fit.problem.masks[k]
        # the samples the fit left out as gaps, not closed up (the extrema are refined over neighbouring samples)
        centre = swing_centre_track(record.time_s, np.where(mask, record.theta_rad, np.nan))
        centre = None if centre is None else centre[mask]
        table = half_cycles(
            record.time_s[mask],
            record.theta_rad[mask],
            fit.nuisance(k)[2] if centre is None else centre,
            model,
            params,
            record.characteristic_length_m,
            1e-6,
        )
        table.insert(0, "trial", record.trial)
        tables.append(table)
    return pd.concat(tables, ignore_index=True)


def predicted_half_cycles(fit: GroupFit) -> pd.DataFrame:
    """The same half-cycle analysis on the fitted (noise-free) curves: the model's extinction curve."""
    tables = []
    for k, record in enumerate(fit.problem.records):
        model, params = _model_and_params(fit, k)
        curve = fit.trial_curve(k)
        table = half_cycles(
            record.time_s, curve, fit.nuisance(k)[2], model, params, record.characteristic_length_m, 1e-6, 1e-5
        )
        table.insert(0, "trial", record.trial)
        tables.append(table)
    return pd.concat(tables, ignore_index=True)


def extinction_screen(fit: GroupFit, candidates) -> list[dict]:
    """Fast screen: how much each candidate's extinction signature improves a fit of the measured ΔA(A).

    The pooled half cycles (ΔA against Ā, each trial about its own swing centre) are fitted by
    non-negative least squares with the baseline terms' powers of Ā (0: Coulomb, 1: linear or
    history, 2: quadratic), then with the candidate's power added; the score is the fraction of
    the remaining sum of squares the candidate removes, and the implied coefficient is its
    library inverse (:meth:`Term.coefficient_from_loss`). Terms with the same power tie: the
    screen only ranks, the refits decide. Conservative terms (restoring correction) have no
    extinction signature and rank last.
    """
    cycles = measured_half_cycles(fit)
    if len(cycles) < 3:
        return [{"effect": c, "score": None, "reason": "fewer than 3 half cycles"} for c in candidates]
    amp = cycles.mean_amplitude_rad.to_numpy()
    loss = cycles.amplitude_loss_rad.to_numpy()
    base_powers = sorted(
        {TERMS[t].extinction_power for t in fit.problem.terms if TERMS[t].extinction_power is not None}
    )

    def residual_ss(powers):
        if not powers:
            return float(loss @ loss), np.zeros(0)
        design = np.column_stack([amp**p for p in powers])
        scale = np.abs(design).max(axis=0)
        solution, norm = nnls(design / scale, loss)
        return float(norm**2), solution / scale

    ss0, _ = residual_ss(base_powers)
    k0 = 0
    model, params = _model_and_params(fit, k0)
    rig = fit.problem.records[k0].rig
    inertia = float(model.inertia_kg_m2(params))
    omega0 = swing_omega(fit, k0)
    out = []
    for name in candidates:
        term = TERMS[name]
        if term.extinction_power is None:
            out.append({"effect": name, "score": 0.0, "reason": "no extinction signature (conservative)"})
            continue
        powers = sorted(set(base_powers) | {term.extinction_power})
        ss1, solution = residual_ss(powers)
        loss_coefficient = float(solution[powers.index(term.extinction_power)])
        out.append(
            {
                "effect": name,
                "score": 1 - ss1 / ss0 if ss0 > 0 else 0.0,
                "extinction_power": term.extinction_power,
                "implied_coefficient": term.coefficient_from_loss(rig, inertia, omega0, loss_coefficient),
            }
        )
    return sorted(out, key=lambda e: -(e["score"] or 0.0))


def period_drift(fit: GroupFit) -> dict:
    """Half period against amplitude, measured and as the fitted model has it: slope and mean difference.

    A missing conservative effect (a wrong restoring torque, an added mass changing with the
    frequency) shows as a period the model gets wrong at every amplitude or as a wrong slope.
    """
    measured, predicted = measured_half_cycles(fit), predicted_half_cycles(fit)
    out = {}
    for label, table in (("measured", measured), ("model", predicted)):
        if len(table) >= 3:
            slope = np.polyfit(table.mean_amplitude_rad**2, table.half_period_s, 1)[0]
            out[f"{label}_slope_s_per_rad2"] = float(slope)
            out[f"{label}_mean_half_period_s"] = float(table.half_period_s.mean())
    return out


# What an unexplained residual looks like: its power by harmonic of the swing (pendulum.discovery.findings names it)
PATTERN_BANDS = (  # (name, lowest, highest) frequency in cycles per swing of the residual's phase-domain spectrum
    ("slow", 0.0, 0.5),
    ("swing", 0.5, 1.5),  # split into steady (within STEADY_BINS of 1) and wobble (side bands)
    ("even_harmonic", 1.5, 2.5),
    ("odd_harmonic", 2.5, 3.5),
)
STEADY_BINS = 2.5  # a line at the swing frequency, Hann-windowed, spreads over ±2 bins of 1/N cycles per swing
PATTERN_SHARE = 0.5  # a pattern named alone when it holds at least this share of the residual's power below 3.5 ...
SECOND_SHARE = 0.15  # ... and the next holds less than this (else the two are named)
PATTERNS = ("slow", "swing_steady", "swing_wobble", "even_harmonic", "odd_harmonic")


def swing_phase(time_s: np.ndarray, theta_rad: np.ndarray, omega: float) -> tuple[np.ndarray, np.ndarray]:
    """The swing's phase φ = atan2(−θ̇/ω, θ) and amplitude A = √(θ² + (θ̇/ω)²) of a smooth (fitted) curve θ(t), φ
    unwrapped with the advance ω Δt expected between samples, so that a gap in the record (frames left out) keeps
    its whole swings; θ̇ by differences within each run of evenly spaced samples (not across a gap)."""
    t = np.asarray(time_s, float)
    theta = np.asarray(theta_rad, float)
    step = float(np.median(np.diff(t))) if t.size > 1 else 1.0
    runs = np.split(np.arange(t.size), np.flatnonzero(np.diff(t) > 1.5 * step) + 1)
    speed = np.zeros_like(theta)
    for run in runs:
        if run.size >= 2:
            speed[run] = np.gradient(theta[run], t[run])
    raw = np.arctan2(-speed / omega, theta)
    expected = omega * np.diff(t)
    turned = (np.diff(raw) - expected + math.pi) % (2 * math.pi) - math.pi + expected
    return np.concatenate([raw[:1], raw[0] + np.cumsum(turned)]), np.hypot(theta, speed / omega)


def _timing_part(grid, residual, amplitude, omega: float, swings: float) -> tuple[float, float, float, int]:
    """The residual's steady part at the swing frequency (its spectrum within :data:`STEADY_BINS`/N of one cycle per
    swing, the rest of it zeroed) split into the swing's amplitude and its timing: with θ = A cos φ, a residual
    a cos φ + b sin φ is an amplitude error a and a timing error δ with |δ| = |b| / (A ω) (θ(t + δ) − θ(t) = θ̇ δ =
    −A ω sin φ δ). Demodulated, z = r e^(−iφ) averaged over one swing is (a − i b) / 2. Returns Σ b², Σ (a² + b²)
    (in z) and Σ δ² over the samples where the swing is at least a quarter of its largest, and their number."""
    spectrum = np.fft.rfft(residual - residual.mean())
    nu = np.fft.rfftfreq(grid.size, (grid[1] - grid[0]) / (2 * math.pi))
    steady = np.fft.irfft(np.where(np.abs(nu - 1) <= STEADY_BINS / swings, spectrum, 0), grid.size)
    per_swing = max(1, int(round(grid.size / swings)))
    smooth = np.ones(per_swing) / per_swing
    z = np.convolve(steady * np.exp(-1j * grid), smooth, mode="valid")
    a = np.convolve(amplitude, smooth, mode="valid")
    swinging = a >= 0.25 * a.max() if a.size else np.zeros(0, bool)  # δ = b / (A ω) is no measure as A → 0
    delay = 2 * z.imag[swinging] / (a[swinging] * omega)
    return float(np.sum(z.imag**2)), float(np.sum(np.abs(z) ** 2)), float(np.sum(delay**2)), int(delay.size)


def residual_pattern(fit: GroupFit) -> dict:
    """The residual's power by harmonic of the swing, pooled over trials.

    Each trial's residual r is taken onto its swing's own phase φ (unwrapped; φ = atan2(−θ̇/ω, θ) of the fitted
    curve, ω its small-amplitude angular frequency: :func:`swing_phase`; up to where the fitted swing comes to rest),
    resampled evenly over its N swings (at least 3), Hann-windowed (the record's two ends weigh less), and its
    periodogram, scaled to the trial's Σr² (trials weighed as the fit weighs them), split by ν, cycles per swing
    (Parseval: shares that add up): ``slow`` (ν < ½: a drifting zero),
    ``swing_steady`` (|ν − 1| ≤ :data:`STEADY_BINS`/N: a decay or period that departs steadily), ``swing_wobble``
    (½ ≤ ν < 1½ otherwise: side bands, the swing's amplitude or phase wobbling), ``even_harmonic`` (ν ≈ 2: which an
    equation symmetric in θ cannot make) and ``odd_harmonic`` (ν ≈ 3: the swing's shape). Shares are of the power
    below ν = 3½ (``structured``: that power's share of the whole; above is noise). ``dominant``: the pattern
    holding :data:`PATTERN_SHARE` of it where the next holds under :data:`SECOND_SHARE`, else the two largest
    (none where most of the residual's power lies above: noise).
    ``wobble_period_s``: 1 / (|ν − 1| f₀) at the strongest side band, where the wobble is among ``dominant`` and
    at least two such wobbles fit in the records (else None). ``steady_in_timing``: the share of the slow part at the
    swing frequency that lies in the swing's timing rather than its amplitude (:func:`_timing_part`; 1: the swing
    runs ahead of and behind the model, 0: its amplitude departs; pooled, each trial by its steady part's power), and
    ``timing_wander_ms``, that timing error's RMS over the records' samples."""
    power = dict.fromkeys(PATTERNS, 0.0)
    total, wobbles, timing = 0.0, [], []
    for k, r in enumerate(fit.residuals):
        record, mask = fit.problem.records[k], fit.problem.masks[k]
        t = record.time_s[mask]
        theta = fit.trial_curve(k)[mask] - fit.nuisance(k)[2]
        omega = swing_omega(fit, k)
        phase, amplitude = swing_phase(t, theta, omega)
        stalled = np.flatnonzero(np.diff(phase) <= 0)  # the model's swing at rest (friction): its phase stands still
        moving = slice(0, stalled[0] + 1 if stalled.size else phase.size)
        phase, amplitude, r = phase[moving], amplitude[moving], r[moving]
        swings = (phase[-1] - phase[0]) / (2 * math.pi) if phase.size else 0.0
        if r.size < 16 or swings < 3 or not np.all(np.isfinite(r)):
            continue
        grid = np.linspace(phase[0], phase[-1], r.size)
        on_phase = np.interp(grid, phase, r)
        timing.append(_timing_part(grid, on_phase, np.interp(grid, phase, amplitude), omega, swings))
        on_phase = (on_phase - on_phase.mean()) * np.hanning(r.size)
        spectrum = np.abs(np.fft.rfft(on_phase)) ** 2
        spectrum *= float(r @ r) / max(float(spectrum.sum()), 1e-300)  # each trial weighed by its residual's Σr²
        nu = np.fft.rfftfreq(r.size, (grid[1] - grid[0]) / (2 * math.pi))  # cycles per swing
        total += float(spectrum.sum())
        for name, low, high in PATTERN_BANDS:
            band = (nu >= low) & (nu < high)
            if name != "swing":
                power[name] += float(spectrum[band].sum())
                continue
            steady = band & (np.abs(nu - 1) <= STEADY_BINS / swings)
            side = band & ~steady
            power["swing_steady"] += float(spectrum[steady].sum())
            power["swing_wobble"] += float(spectrum[side].sum())
            if np.any(side):
                peak = int(np.argmax(spectrum[side]))
                offset = abs(float(nu[side][peak]) - 1)
                wobbles.append((float(spectrum[side][peak]), offset, swings, omega / (2 * math.pi)))
    structured = sum(power.values())
    if structured <= 0 or total <= 0:
        return {
            "shares": None,
            "structured": 0.0,
            "dominant": [],
            "steady_in_timing": None,
            "timing_wander_ms": None,
            "wobble_period_s": None,
        }
    shares = {name: value / structured for name, value in power.items()}
    ranked = sorted(PATTERNS, key=lambda name: -shares[name])
    dominant = ranked[:1] if shares[ranked[0]] >= PATTERN_SHARE and shares[ranked[1]] < SECOND_SHARE else ranked[:2]
    if structured < 0.5 * total:  # mostly noise: no part of it to name
        dominant = []
    _, offset, swings, frequency = max(wobbles) if wobbles else (0.0, 0.0, 0.0, 0.0)  # the strongest side band
    in_b, in_z, delay2, samples = (sum(part) for part in zip(*timing, strict=True)) if timing else (0, 0, 0, 0)
    in_timing = in_b / in_z if in_z > 0 else None  # pooled: each trial by its own steady part
    wander_ms = 1e3 * math.sqrt(delay2 / samples) if samples else None
    return {
        "shares": {name: round(value, 4) for name, value in shares.items()},
        "structured": round(structured / total, 4),
        "dominant": dominant,
        "steady_in_timing": None if in_timing is None else round(in_timing, 3),
        "timing_wander_ms": None if wander_ms is None else round(wander_ms, 2),
        "wobble_period_s": round(1 / (offset * frequency), 2)
        if "swing_wobble" in dominant and offset * swings >= 2
        else None,
    }


# ---------------------------------------------------------------------------
# The statistics of the evidence (pendulum.discovery.selection)


def mixture_p_value(statistic: float, d: int, bounded: bool) -> float:
    """P(Λ ≥ statistic) under no effect: Σ_k C(d,k)/2^d χ²_k for d coefficients at a bound 0, else χ²_d."""
    if statistic <= 0:
        return 1.0
    if not bounded:
        return float(stats.chi2.sf(statistic, d))
    return float(sum(math.comb(d, k) / 2**d * stats.chi2.sf(statistic, k) for k in range(1, d + 1)))


def critical_value(level: float, d: int, bounded: bool) -> float:
    """The Λ whose p-value is ``level``."""
    return brentq(lambda x: mixture_p_value(x, d, bounded) - level, 1e-9, 1e4)


def null_distribution(d: int, bounded: bool) -> str:
    """The name of the null distribution of Λ."""
    if not bounded:
        return f"χ²_{d}"
    return "½χ²_0 + ½χ²_1" if d == 1 else f"Σ_k C({d},k)/2^{d} χ²_k"
