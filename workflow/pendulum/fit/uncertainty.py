"""Uncertainty of the fitted coefficients: residual noise model, sandwich covariance, consistency test."""

from __future__ import annotations

import math
from dataclasses import replace

import numpy as np
from scipy import sparse
from scipy.linalg import solve_banded
from scipy.special import chdtrc, ndtri

from pendulum.model.rig import Rig

Z95 = float(ndtri(0.975))  # the standard normal's 97.5 % quantile (as scipy.stats, which costs 0.7 s to import)


def fit_ar(r: np.ndarray, max_order: int = 10) -> tuple[np.ndarray, float, int]:
    """AR(p) model of a residual series by least squares, p ≤ max_order chosen by AIC: (φ, σ_e², p).

    Every order regresses the same target on the first p of the same lags, so one QR factorisation of
    [lags | target] = Q R gives them all: φ_p solves R[:p, :p] φ = R[:p, m], and the residual sum of
    squares is Σ_{j ≥ p} R[j, m]² (m = max_order, the target's column)."""
    r = r - r.mean()
    n = r.size
    best = (np.zeros(0), float(r @ r) / n, 0)
    best_aic = n * math.log(best[1])
    m = min(max_order, (n - 1) // 2)  # at least as many equations as unknowns
    if m < 1:
        return best
    system = np.column_stack([*(r[m - i - 1 : n - i - 1] for i in range(m)), r[m:]])
    upper = np.linalg.qr(system, mode="r")
    rhs = upper[:, m]
    rss = np.cumsum((rhs**2)[::-1])[::-1]  # rss[p] = Σ_{j ≥ p} rhs_j²
    size = n - m
    var = rss[1:] / size
    aic = np.where(var > 0, n * np.log(np.where(var > 0, var, 1.0)) + 2 * np.arange(1, m + 1), np.inf)
    for order in np.argsort(aic, kind="stable") + 1:  # the lowest AIC among the stationary orders
        if not aic[order - 1] < best_aic:
            break
        phi = np.linalg.solve(upper[:order, :order], rhs[:order])
        if np.abs(np.roots(np.concatenate([[1.0], -phi]))).max() < 0.995:
            return phi, float(var[order - 1]), int(order)
    return best


def all_pole(phi: np.ndarray, x: np.ndarray) -> np.ndarray:
    """y with y_t = x_t + Σ_i φ_i y_{t−i} along axis 0 (y_t = 0 before the start): the AR(p) recursion, as
    ``lfilter([1], [1, −φ], x, axis=0)`` of scipy.signal, solved as the banded lower-triangular system
    Φ y = x (scipy.linalg, which the fit imports anyway; scipy.signal costs 0.6 s to import in every job)."""
    x = np.asarray(x, dtype=float)
    phi = np.asarray(phi, dtype=float).ravel()
    order, n = phi.size, x.shape[0]
    if order == 0 or n == 0:
        return x.copy()
    bands = np.zeros((order + 1, n))
    bands[0] = 1.0
    for i, coefficient in enumerate(phi, start=1):
        bands[i, : n - i] = -coefficient
    return solve_banded((order, 0), bands, x)


def _ar_noise(rng, phi: np.ndarray, var: float, n: int) -> np.ndarray:
    """A realisation of the AR(p) process e_t = Σ φ_i e_{t−i} + w_t, w ~ N(0, σ²), after a burn-in."""
    burn = 20 * max(phi.size, 1)
    w = rng.standard_normal(n + burn) * math.sqrt(var)
    return all_pole(phi, w)[burn:]


def sandwich_covariance(
    jac_parts, res_parts, max_ar_order: int = 10, replicates: int = 24, seed: int = 0
) -> tuple[np.ndarray, dict]:
    """(JᵀJ)⁻¹ (Σ_k J_kᵀ Ω_k J_k) (JᵀJ)⁻¹ with Ω_k the AR(p) noise covariance of trial k (trials independent).

    An AR model fitted to *residuals* underestimates the noise where the fit
    absorbs it, which is exactly at the swing frequency where the sensitivities
    live (10–15 % too narrow on 15–20 s records, more on short ones). The
    bias is measured for this very design and corrected: ``replicates``
    realisations of the fitted AR noise are passed through the fit's linear
    residual maker (I − J J⁺), the AR model is re-estimated from each (p by AIC,
    as for the data) and the mean of the resulting covariances is compared with
    the covariance the fitted model implies. Each parameter's variance is
    multiplied by that ratio (never below 1): a parametric bootstrap of the
    variance estimator, with no refits.
    """
    p = jac_parts[0].shape[1]
    bread = np.zeros((p, p))
    meat = np.zeros((p, p))
    meat_recovered = np.zeros((p, p))
    details = []
    rng = np.random.default_rng(seed)
    for jk, rk in zip(jac_parts, res_parts, strict=True):
        if sparse.issparse(jk):  # a large group's (its memory grows as the trials, the dense one's as their square)
            used, ju = used_columns(jk)
            bread[np.ix_(used, used)] += ju.T @ ju
        else:
            bread += jk.T @ jk
            used = np.flatnonzero(np.any(jk != 0, axis=0))
            ju = jk[:, used]
        phi, var, order = fit_ar(rk, max_ar_order)
        s_k = ar_meat(ju, phi, var)
        meat[np.ix_(used, used)] += s_k
        pinv = np.linalg.pinv(ju)
        recovered = np.zeros_like(s_k)
        for _ in range(replicates):
            u = _ar_noise(rng, phi, var, rk.size)
            u = u - ju @ (pinv @ u)
            recovered += ar_meat(ju, *fit_ar(u, max_ar_order)[:2]) / replicates
        meat_recovered[np.ix_(used, used)] += recovered
        details.append({"ar_order": order, "ar_coefficients": phi.tolist()})
    inv = np.linalg.pinv(bread)
    cov = inv @ meat @ inv
    ratio = np.ones(p)
    if replicates:
        implied = np.diag(cov)
        recovered = np.diag(inv @ meat_recovered @ inv)
        ratio = np.where(recovered > 0, implied / np.where(recovered > 0, recovered, 1.0), 1.0)
        ratio = np.maximum(ratio, 1.0)
    scale = np.sqrt(ratio)
    return cov * np.outer(scale, scale), {
        "noise_models": details,
        "residual_noise_bias_correction": scale.tolist(),
    }


def used_columns(part) -> tuple[np.ndarray, np.ndarray]:
    """The columns one trial's rows of a sparse Jacobian touch (any nonzero), and those columns, dense."""
    part = sparse.csc_matrix(part)
    used = np.flatnonzero(np.asarray(abs(part).sum(axis=0)).ravel() > 0)
    return used, part[:, used].toarray()


def normal_matrix(jac) -> np.ndarray:
    """JᵀJ, dense, of a dense or a sparse Jacobian."""
    product = jac.T @ jac
    return product.toarray() if sparse.issparse(product) else product


def compressed_rows(jac, rows) -> np.ndarray:
    """R with RᵀR = JᵀJ and J's singular values, from a sparse J whose trial k holds rows ``rows[k]:rows[k+1]``:
    each trial's touched columns reduced by a QR to as many rows (J = diag(Q_k) R). What the rank check needs of
    J in memory that grows as the trials (Σ_k m_k × p, m_k the columns trial k touches), J's as their square."""
    blocks = []
    for k in range(len(rows) - 1):
        used, ju = used_columns(jac[rows[k] : rows[k + 1]])
        block = np.zeros((min(ju.shape), jac.shape[1]))
        block[:, used] = np.linalg.qr(ju, mode="r")
        blocks.append(block)
    return np.vstack(blocks)


def ar_meat(jac: np.ndarray, phi: np.ndarray, var: float) -> np.ndarray:
    """Jᵀ Ω J for AR(p) noise: Ω = σ_e² Φ⁻¹ Φ⁻ᵀ, Φ the whitening filter, so Jᵀ Ω J = σ_e² ZᵀZ, Z = Φ⁻ᵀ J."""
    z = all_pole(phi, jac[::-1])[::-1]
    return var * (z.T @ z)


def lag1_autocorrelation(r: np.ndarray) -> float:
    r = r - r.mean()
    return float(np.dot(r[1:], r[:-1]) / np.dot(r, r)) if np.dot(r, r) > 0 else 0.0


def consistency_test(per_trial: dict[str, dict], joint: dict, alpha: float = 0.05) -> dict:
    """χ² test of the per-trial estimates against each other, per physical parameter.

    χ²_j = Σ_k ((p̂_kj − p̄_j)/σ_kj)² over the N_j trials where parameter j is
    identifiable and not at a bound, p̄_j their inverse-variance weighted mean,
    N_j − 1 degrees of freedom (one mean fitted). σ_kj is the *statistical*
    standard error: the systematic part (rig values, pivot) is one measurement
    shared by every trial of the rig and moves them together, so it cannot make
    them disagree. Bonferroni over parameters: the set is consistent if every
    p-value exceeds α / (number tested). The scale factor S_j = √(χ²_j / (N_j − 1))
    (the Particle Data Group's, or Birge ratio) says how much wider the per-trial
    intervals would have to be for the estimates to agree. The joint estimate
    is reported beside the weighted mean.
    """
    result = {}
    names = [n for n in joint["parameters"] if n != "drag_coefficient"]
    tested = []
    for name in names:
        used, excluded, values, errors = [], {}, [], []
        for trial, fit in sorted(per_trial.items()):
            entry = (fit.get("parameters") or {}).get(name)
            se = None if entry is None else entry.get("stderr_statistical", entry.get("stderr"))
            if entry is None or entry.get("value") is None:
                excluded[trial] = "no estimate"
            elif entry.get("at_bound"):
                excluded[trial] = "at bound"
            elif not entry.get("identifiable", True):
                excluded[trial] = "not identifiable"
            elif not se or not math.isfinite(se):
                excluded[trial] = "no standard error"
            else:
                used.append(trial)
                values.append(float(entry["value"]))
                errors.append(float(se))
        dof = len(used) - 1
        item = {
            "trials_used": used,
            "trials_excluded": excluded,
            "dof": dof,
            "joint_value": joint["parameters"][name].get("value"),
        }
        if dof > 0:
            v, w = np.array(values), 1.0 / np.array(errors) ** 2
            mean = float(np.sum(w * v) / np.sum(w))
            chi2 = float(np.sum(w * (v - mean) ** 2))
            item.update(
                weighted_mean=mean,
                chi2=chi2,
                p_value=float(chdtrc(dof, chi2)),  # χ² survival function
                scale_factor=math.sqrt(chi2 / dof),
                relative_spread=float(np.std(v, ddof=1) / abs(mean)) if mean else None,
            )
            tested.append(name)
        else:
            item.update(weighted_mean=None, chi2=None, p_value=None, scale_factor=None, relative_spread=None)
        result[name] = item
    threshold = alpha / max(len(tested), 1)
    inconsistent = [n for n in tested if result[n]["p_value"] < threshold]
    if not tested:
        verdict, explanation = "not testable", "fewer than two trials determine any parameter"
    elif inconsistent:
        worst = max(inconsistent, key=lambda n: result[n]["scale_factor"])
        spread = result[worst]["relative_spread"]
        spread_text = f", {100 * spread:.1f} % relative spread" if spread is not None else ""
        verdict = "inconsistent"
        explanation = (
            f"per-trial estimates of {', '.join(inconsistent)} disagree beyond their own intervals "
            f"(worst: {worst}, scatter {result[worst]['scale_factor']:.1f}× what the intervals allow{spread_text}): "
            "the model misses physics that changes between trials, or the angle records carry systematic errors"
        )
    else:
        verdict = "consistent"
        explanation = (
            f"per-trial estimates of {', '.join(tested)} agree with each other within their statistical uncertainties"
        )
    untested = [
        f"{name} ({len(result[name]['trials_excluded'])} of {len(per_trial)} trials "
        f"{' or '.join(sorted(set(result[name]['trials_excluded'].values())))})"
        for name in names
        if name not in tested and result[name]["trials_excluded"]
    ]
    if tested and untested:  # what the verdict does not speak for
        explanation += "; not tested: " + ", ".join(untested)
    return {
        "verdict": verdict,
        "alpha": alpha,
        "per_parameter_threshold": threshold,
        "inconsistent_parameters": inconsistent,
        "parameters": result,
        "explanation": explanation,
    }


# ---------------------------------------------------------------------------
# Intervals, reported coefficients, and the systematic inputs (rig values, estimated pivot)

Z95_ONE_SIDED = float(ndtri(0.95))


def interval95(value: float, stderr: float, lower: float, at_bound: bool) -> list[float]:
    """Normal 95 % interval value ± 1.96σ, cut at the lower bound.

    A coefficient that ends on its bound gets the one-sided 95 % upper limit
    [b, b + 1.645σ] instead (the estimate is censored there: P(truth ≤ b + 1.645σ) = 0.95
    for a normal estimator that the bound would have clipped).
    """
    if at_bound:
        return [lower, lower + Z95_ONE_SIDED * stderr]
    return [max(value - Z95 * stderr, lower), value + Z95 * stderr]


def coefficient_entry(
    name: str,
    unit: str,
    value: float,
    stderr_statistical: float,
    error_budget: dict,
    lower: float,
    at_bound: bool,
    max_relative_stderr: float,
    warnings: list,
) -> dict:
    """One fitted coefficient as reported: the value (the bound itself when it ends there), the statistical,
    systematic (quadrature sum of the ``error_budget`` shifts) and combined standard errors, the 95 % interval
    of the combined error, and the at-bound and identifiability flags (warnings appended to ``warnings``)."""
    if at_bound:
        value = lower
        # held on its bound, it moves with no input: what the refits leave is rounding (1e-10), not an error
        error_budget = {k: (v if abs(v) > 1e-6 * stderr_statistical else 0.0) for k, v in error_budget.items()}
    systematic = math.sqrt(sum(v * v for v in error_budget.values()))
    combined = math.hypot(stderr_statistical, systematic)
    entry = {
        "value": value,
        "stderr": combined,
        "ci95": interval95(value, combined, lower, at_bound),
        "stderr_statistical": stderr_statistical,
        "stderr_systematic": systematic,
        "error_budget": error_budget,
        "lower_bound": lower,
        "at_bound": at_bound,
        "identifiable": True,
        "unit": unit,
    }
    if at_bound:
        entry["note"] = f"at its lower bound {lower:g}: the data prefer a smaller (unphysical) value"
        warnings.append(f"{name} is at its lower bound ({lower:g}); its estimate is not a measurement")
    rel = stderr_statistical / abs(value) if value != 0 else math.inf
    if not at_bound and rel > max_relative_stderr:
        entry["identifiable"] = False
        entry["reason"] = (
            f"standard error {stderr_statistical:.3g} is {_share_of_estimate(rel)}: this term's torque is "
            "too small against the noise and the other terms over this record (amplitude or duration too small)"
        )
        warnings.append(f"{name} is not identifiable from this record (standard error {_share_of_estimate(rel)})")
    return entry


def _share_of_estimate(relative: float) -> str:
    """A standard error relative to its estimate in words: '212 % of the estimate', '4.5e+04 times the estimate'."""
    if not math.isfinite(relative):
        return "finite while the estimate is 0"
    return f"{relative * 100:.0f} % of the estimate" if relative < 10 else f"{relative:.2g} times the estimate"


def shared_frontal_area(records) -> tuple[float, float, str | None]:
    """The frontal area A (m²) and its 1σ that C_d = C_dA / A of a fit over ``records`` uses, and a warning.

    Records that state one area (one rig, or one body on several rigs): that, with the largest tolerance they
    state. Records that state different areas (a sidecar's own): their mean, with a 1σ of the largest stated
    tolerance and half their range added in quadrature (one drag area fitted to all, divided by an area they
    disagree on), and a warning naming the trials' values."""
    stated = [(float(r.rig.frontal_area_m2), float(r.tolerances.get("frontal_area_m2", 0.0))) for r in records]
    areas = np.array([a for a, _ in stated])
    if np.ptp(areas) == 0:  # one area (its tolerance, where trials state it differently: the largest)
        return stated[0][0], max(s for _, s in stated), None
    area = float(areas.mean())
    sigma = math.hypot(max(s for _, s in stated), 0.5 * float(np.ptp(areas)))
    given = ", ".join(f"{r.trial} {a:.6g} ± {s:.2g}" for r, (a, s) in zip(records, stated, strict=True))
    warning = (
        f"the trials state different frontal areas ({given} m²): C_d is the drag area over their mean, "
        f"{area:.6g} ± {sigma:.2g} m² (half their range added to the tolerance)"
    )
    return area, sigma, warning


def drag_coefficient_entry(drag_area: dict, frontal_area_m2: float, frontal_area_sigma_m2: float) -> dict:
    """C_d = C_dA / A: every input of the drag area's budget divided by A, plus A's own tolerance (−C_d σ_A / A)."""
    area = frontal_area_m2
    value = drag_area["value"] / area
    budget = {key: shift / area for key, shift in drag_area["error_budget"].items()}
    if frontal_area_sigma_m2:
        budget["frontal_area_m2"] = -value * frontal_area_sigma_m2 / area + 0.0  # + 0.0: no "-0.0" at a bound
    systematic = math.sqrt(sum(v * v for v in budget.values()))
    combined = math.hypot(drag_area["stderr_statistical"] / area, systematic)
    return {
        **drag_area,
        "value": value,
        "stderr": combined,
        "ci95": interval95(value, combined, drag_area["lower_bound"] / area, drag_area["at_bound"]),
        "stderr_statistical": drag_area["stderr_statistical"] / area,
        "stderr_systematic": systematic,
        "error_budget": budget,
        "lower_bound": drag_area["lower_bound"] / area,
        "unit": "1",
        "derived_from": "drag_area_m2 / frontal_area_m2",
    }


def linear_response(jac, free: np.ndarray, delta_residual: np.ndarray) -> np.ndarray:
    """Shift of the least-squares estimate when the residuals move by δr: δx = −J⁺ δr (parameters at a bound stay);
    of a sparse J by its column-scaled normal equations (a refit's start: their squared condition number is no
    matter there)."""
    dx = np.zeros(jac.shape[1])
    if not sparse.issparse(jac):
        dx[free] = np.linalg.lstsq(jac[:, free], -delta_residual, rcond=None)[0]
        return dx
    jf = sparse.csc_matrix(jac)[:, np.flatnonzero(free)]
    normal, gradient = normal_matrix(jf), jf.T @ delta_residual
    diagonal = np.diag(normal)
    scale = np.where(diagonal > 0, 1.0 / np.sqrt(np.where(diagonal > 0, diagonal, 1.0)), 0.0)
    step = np.linalg.lstsq(normal * np.outer(scale, scale), -gradient * scale, rcond=None)[0]
    dx[free] = scale * step
    return dx


def pivot_angle_gradient(theta_image_rad: np.ndarray, arm_radius_px: float) -> np.ndarray:
    """∂θ/∂(x_p, y_p) for θ = atan2(x − x_p, y − y_p): (−cos θ, sin θ) / R, one row per sample."""
    return np.column_stack([-np.cos(theta_image_rad), np.sin(theta_image_rad)]) / arm_radius_px


def systematic_perturbations(records, sign: float = 1.0) -> dict[str, list]:
    """Each systematic input moved by its 1σ (by −1σ with ``sign`` −1, an input whose −1σ values make no rig left
    out): input name → the records as they would then be.

    Rig values: every record's value moved by its stated 1σ tolerance (one
    input for all records of a fit: one rig, one measurement). The estimated
    pivot: its covariance C = Σ λ_i v_i v_iᵀ gives independent inputs √λ_i v_i,
    which move the measured angles by δθ = ∇θ · √λ_i v_i (records sharing one
    pooled pivot move together). A wrong vertical only adds a constant to θ,
    which the fitted rest offset absorbs exactly: it is no input.
    """
    out: dict[str, list] = {}
    for key in sorted(set().union(*(r.tolerances for r in records))):
        moved, changed = [], False
        for rec in records:
            sigma = rec.tolerances.get(key, 0.0)
            if sigma and rec.rig_values.get(key) is not None:
                values = dict(rec.rig_values, **{key: float(rec.rig_values[key]) + sign * sigma})
                try:
                    rec = replace(rec, rig=Rig.from_mapping(values), rig_values=values)
                except ValueError:
                    if sign > 0:
                        raise
                    moved = None  # −1σ makes no pendulum (a body then lighter than the water it displaces)
                    break
                changed = True
            moved.append(rec)
        if moved is not None and changed and key != "frontal_area_m2":  # A enters only C_d = C_dA / A, not the fit
            out[key] = moved
    groups: dict[tuple, list[int]] = {}
    for k, rec in enumerate(records):
        if rec.pivot_covariance_px2 is not None and rec.arm_radius_px:
            groups.setdefault(tuple(np.ravel(rec.pivot_covariance_px2)), []).append(k)
    for g, (cov_key, members) in enumerate(sorted(groups.items())):
        lam, vec = np.linalg.eigh(np.reshape(cov_key, (2, 2)))
        for i in range(2):
            if lam[i] <= 0:
                continue
            step = sign * math.sqrt(lam[i]) * vec[:, i]
            moved = []
            for k, rec in enumerate(records):
                if k in members:
                    grad = pivot_angle_gradient(rec.theta_rad + rec.vertical_rad, rec.arm_radius_px)
                    rec = replace(rec, theta_rad=rec.theta_rad + grad @ step)
                moved.append(rec)
            label = "pivot_px" if len(groups) == 1 else f"pivot_px[{g}]"
            out[f"{label} (axis {i + 1})"] = moved
    return out


def unclipped_shift(up: np.ndarray, up_active: np.ndarray, free: np.ndarray, down) -> np.ndarray:
    """An input's 1σ shift of the estimate: the +1σ refit's (``up``), or where a coefficient the fit left ``free``
    stopped at its bound in that refit (``up_active``) the −1σ refit's turned (``down()``: its shift and which
    coefficients it stopped at their bound; None where the −1σ values are no rig): a bound clipped that shift, and
    every other coefficient then took up what the bound held back. The whole −1σ shift where that refit reaches no
    bound; else each coefficient the +1σ refit clipped from it, the rest as they were (both clipped: the +1σ
    refit's, an underestimate). An apple's added mass (0.0004 kg) with its string's length +1σ refitted to the
    bound 0: a shift of −0.0004 kg, where −1σ moves it by +0.009 kg, and the drag area by −9.2e-4 m² against the
    −1σ refit's −1.9e-4 m² (a helper's run of the apple clip, 2026-12-05)."""
    clipped = np.asarray(up_active, bool) & np.asarray(free, bool)
    if not clipped.any():
        return up
    found = down()
    if found is None:
        return up
    down_shift, down_active = found
    below = np.asarray(down_active, bool) & np.asarray(free, bool)
    return -down_shift if not below.any() else np.where(clipped & ~below, -down_shift, up)


RELAXED_BOUND_SPREAD = 100.0  # a held coefficient is let go this many of its scales below its bound (held_shifts)


def relaxed_bounds(lower: np.ndarray, held: np.ndarray, scale: np.ndarray, added_mass_floor_kg: float) -> np.ndarray:
    """``lower`` with each coefficient the fit holds on its bound (``held``) let go :data:`RELAXED_BOUND_SPREAD` ×
    its ``scale`` (the larger of its standard error and its typical magnitude) below it: the added mass (column 0)
    no further than the floor that leaves a pendulum."""
    relaxed = np.array(lower, float)
    relaxed[held] -= RELAXED_BOUND_SPREAD * np.asarray(scale)[held]
    relaxed[0] = max(relaxed[0], min(lower[0], added_mass_floor_kg))
    return relaxed


def held_shifts(
    held: np.ndarray, solve, base, x0: np.ndarray, moved: dict, failure: type[Exception]
) -> tuple[dict[str, np.ndarray], np.ndarray]:
    """Each input's 1σ shift of the coefficients a fit holds on their bound (``held``), measured where no bound
    holds them: ``base`` (the problem) and ``moved`` (input → the problem with that input moved by 1σ) solved with
    those bounds relaxed (``solve(problem, start, tolerance)`` → estimate, which coefficients ended on a bound),
    the moved ones from the relaxed base's estimate. Held on its bound, a coefficient's refits stay there, and its
    one-sided limit was statistical only: the wooden bob in air's added mass < 6.4e-5 kg, where its inertia's 2 %
    moves the unbounded estimate by 3.0e-4 kg. Returns the shifts and which held coefficients got none: those the
    relaxed base still stops on their relaxed bound (the data want them far past it, :data:`RELAXED_BOUND_SPREAD`),
    or every one where a relaxed fit raised ``failure`` (a simulation that ran away)."""
    try:
        start, active = solve(base, x0, 1e-10)
        shifts = {label: solve(problem, start, 1e-10)[0] - start for label, problem in moved.items()}
    except failure:
        return {}, held.copy()
    return shifts, held & np.asarray(active, bool)


def unmeasured_warning(name: str) -> str:
    """The warning of a coefficient held on its bound whose systematic part :func:`held_shifts` could not measure."""
    return (
        f"{name} is held on its bound, and how the rig values move its unbounded estimate could not be measured "
        f"(that estimate lies beyond {RELAXED_BOUND_SPREAD:g} of its scales below the bound, or its simulation ran "
        "away there): its upper limit leaves the rig values' tolerances out"
    )


def jacobian_rank_warnings(jac: np.ndarray, labels: list[str], tolerance: float = 1e-8) -> list[str]:
    """Warnings for combinations of parameters the record cannot determine (a (near-)singular Jacobian).

    Columns are scaled to unit norm, so the test is on the sensitivities' shapes,
    not their units; a singular value below ``tolerance`` × the largest means that
    direction in parameter space leaves every residual unchanged. The warning
    names the parameters that carry that direction.
    """
    norms = np.linalg.norm(jac, axis=0)
    out = [f"{labels[j]} has no effect on the fitted record (zero sensitivity)" for j in np.flatnonzero(norms == 0)]
    live = norms > 0
    if live.sum() < 2:
        return out
    _, sv, vt = np.linalg.svd(jac[:, live] / norms[live], full_matrices=False)
    names = [label for label, keep in zip(labels, live, strict=True) if keep]
    for s, v in zip(sv, vt, strict=True):
        if s < tolerance * sv[0]:
            carried = [names[i] for i in sorted(np.argsort(-np.abs(v))[:3]) if abs(v[i]) > 0.2]
            out.append(
                f"singular Jacobian: {' and '.join(carried)} cannot be told apart by this record "
                f"(relative singular value {s / sv[0]:.1e})"
            )
    return out
