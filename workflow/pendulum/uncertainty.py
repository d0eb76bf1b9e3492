"""Uncertainty of the fitted coefficients: residual noise model, sandwich covariance, consistency test."""

from __future__ import annotations

import math

import numpy as np
from scipy import stats
from scipy.signal import lfilter

Z95 = stats.norm.ppf(0.975)


def fit_ar(r: np.ndarray, max_order: int = 10) -> tuple[np.ndarray, float, int]:
    """AR(p) model of a residual series by least squares, p ≤ max_order chosen by AIC: (φ, σ_e², p)."""
    r = r - r.mean()
    n = r.size
    best = (np.zeros(0), float(r @ r) / n, 0)
    best_aic = n * math.log(best[1])
    if max_order < 1:
        return best
    lags = np.column_stack([r[max_order - i - 1 : n - i - 1] for i in range(max_order)])
    target = r[max_order:]
    for order in range(1, max_order + 1):
        phi, *_ = np.linalg.lstsq(lags[:, :order], target, rcond=None)
        e = target - lags[:, :order] @ phi
        var = float(e @ e) / e.size
        aic = n * math.log(var) + 2 * order
        roots = np.abs(np.roots(np.concatenate([[1.0], -phi])))
        if aic < best_aic and (roots.size == 0 or roots.max() < 0.995):
            best, best_aic = (phi, var, order), aic
    return best


def ar_meat(jac: np.ndarray, r: np.ndarray, max_order: int = 10) -> tuple[np.ndarray, dict]:
    """Jᵀ Ω J for AR(p) noise: Ω = σ_e² Φ⁻¹ Φ⁻ᵀ, Φ the whitening filter, so Jᵀ Ω J = σ_e² ZᵀZ, Z = Φ⁻ᵀ J."""
    phi, var, order = fit_ar(r, max_order)
    z = lfilter([1.0], np.concatenate([[1.0], -phi]), jac[::-1], axis=0)[::-1]
    return var * (z.T @ z), {"ar_order": order, "ar_coefficients": phi.tolist()}


def sandwich_covariance(jac_parts, res_parts, max_ar_order: int = 10) -> tuple[np.ndarray, dict]:
    """(JᵀJ)⁻¹ (Σ_k J_kᵀ Ω_k J_k) (JᵀJ)⁻¹ with Ω_k the AR(p) noise covariance of trial k (trials independent)."""
    p = jac_parts[0].shape[1]
    bread = np.zeros((p, p))
    meat = np.zeros((p, p))
    details = []
    for jk, rk in zip(jac_parts, res_parts, strict=True):
        bread += jk.T @ jk
        used = np.flatnonzero(np.any(jk != 0, axis=0))
        s_k, info = ar_meat(jk[:, used], rk, max_ar_order)
        meat[np.ix_(used, used)] += s_k
        details.append(info)
    n_total = sum(r.size for r in res_parts)
    meat *= n_total / max(n_total - p, 1)  # degrees-of-freedom correction
    inv = np.linalg.pinv(bread)
    return inv @ meat @ inv, {"noise_models": details}


def _lag1(r: np.ndarray) -> float:
    r = r - r.mean()
    return float(np.dot(r[1:], r[:-1]) / np.dot(r, r)) if np.dot(r, r) > 0 else 0.0


def consistency_test(per_trial: dict[str, dict], joint: dict, alpha: float = 0.05) -> dict:
    """χ² test of the per-trial estimates against the joint one, per physical parameter.

    χ²_j = Σ_k ((p̂_kj − p̂_j)/σ_kj)² over the N_j trials where parameter j is
    identifiable and not at a bound, N_j − 1 degrees of freedom. Bonferroni
    over parameters: the set is consistent if every p-value exceeds α / (number
    tested). The scale factor S_j = √(χ²_j / (N_j − 1)) (the Particle Data
    Group's, or Birge ratio) says how much wider the per-trial intervals would
    have to be for the estimates to agree.
    """
    result = {}
    names = [n for n in joint["parameters"] if n != "drag_coefficient"]
    tested = []
    for name in names:
        ref = joint["parameters"][name]["value"]
        used, excluded, chi2 = [], {}, 0.0
        values = []
        for trial, fit in sorted(per_trial.items()):
            entry = fit["parameters"][name]
            if entry["at_bound"]:
                excluded[trial] = "at bound"
            elif not entry["identifiable"]:
                excluded[trial] = "not identifiable"
            elif not entry["stderr"] or not math.isfinite(entry["stderr"]):
                excluded[trial] = "no standard error"
            else:
                used.append(trial)
                values.append(entry["value"])
                chi2 += ((entry["value"] - ref) / entry["stderr"]) ** 2
        dof = len(used) - 1
        item = {"trials_used": used, "trials_excluded": excluded, "dof": dof}
        if dof > 0:
            item.update(
                chi2=chi2,
                p_value=float(stats.chi2.sf(chi2, dof)),
                scale_factor=math.sqrt(chi2 / dof),
                relative_spread=float(np.std(values, ddof=1) / abs(ref)) if ref else None,
            )
            tested.append(name)
        else:
            item.update(chi2=None, p_value=None, scale_factor=None, relative_spread=None)
        result[name] = item
    threshold = alpha / max(len(tested), 1)
    inconsistent = [n for n in tested if result[n]["p_value"] < threshold]
    if not tested:
        verdict, explanation = "not testable", "fewer than two trials determine any parameter"
    elif inconsistent:
        worst = max(inconsistent, key=lambda n: result[n]["scale_factor"])
        verdict = "inconsistent"
        explanation = (
            f"per-trial estimates of {', '.join(inconsistent)} disagree beyond their own intervals "
            f"(worst: {worst}, scatter {result[worst]['scale_factor']:.1f}× what the intervals allow, "
            f"{100 * result[worst]['relative_spread']:.1f} % relative spread): the model misses physics "
            "that changes between trials, or the angle records carry systematic errors"
        )
    else:
        verdict = "consistent"
        explanation = "per-trial estimates agree with the joint estimate within their uncertainties"
    return {
        "verdict": verdict,
        "alpha": alpha,
        "per_parameter_threshold": threshold,
        "inconsistent_parameters": inconsistent,
        "parameters": result,
        "explanation": explanation,
    }
