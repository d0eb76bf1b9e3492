"""Output-error identification of the pendulum's hydrodynamic coefficients.

The model is :class:`pendulum.model.physics.PendulumModel`, simulated by
:func:`pendulum.model.physics.simulate` (the same code that renders the synthetic
videos). For trial k the measured angle is modelled as

    θ_k(t) = x_k(t; p, θ0_k, θ̇0_k) + δ_k + noise,

where x_k is the simulated free decay started at the first sample used (t_k0)
from (θ0_k, θ̇0_k), p are the physical coefficients (added mass and one
coefficient per term) and δ_k is the rest-angle offset (camera not level).
The release transient is not modelled: the fit starts ``release_skip_s`` after
the release and the initial state there is fitted, so nothing depends on how
the hand let go.

Least squares (unweighted, as the paper) gives the estimate. Residuals of a
tracked decay are autocorrelated (tracking bias that follows the marker over
the background, vibration), so the white-noise covariance σ²(JᵀJ)⁻¹ is too
narrow. We use the sandwich (JᵀJ)⁻¹ (JᵀΩJ) (JᵀJ)⁻¹ with Ω the covariance of an
AR(p) noise model fitted to each trial's residuals (p ≤ 10 by AIC): JᵀΩJ is
σ_e² ZᵀZ with Z the Jacobian passed backwards through the inverse AR filter.
Why this and not a kernel (Newey–West) estimator or a bootstrap: the
sensitivities oscillate at the pendulum frequency, so what matters is the
noise spectrum at that frequency; a parametric AR spectrum estimates it from
all lags at once and costs nothing, whereas a Bartlett kernel with a data-
chosen bandwidth came out 2× too narrow on AR(0.9) noise, and a block
bootstrap needs hundreds of refits. Coverage measured on synthetic records
(tests/test_fitting.py) is 86–94 % for white and strongly coloured noise.
"""

from __future__ import annotations

import math

import numpy as np
from scipy import sparse
from scipy.optimize import least_squares

from pendulum.angles.swings import crossing_period
from pendulum.fit.checks import (
    added_mass_scale_warning,
    drag_checks,
    fastest_period_s,
    misfit_warning,
    record_checks,
    rig_checks,
    rig_period_problem,
    smooth_swing,
)
from pendulum.fit.decay import decay_analysis
from pendulum.fit.records import (
    AngleRecord,
    FitSettings,
    added_mass_floor_kg,
    added_mass_lower_kg,
    samples_digest,
    systematic_inputs,
    value_or_range,
)
from pendulum.fit.uncertainty import (
    Z95,
    coefficient_entry,
    compressed_rows,
    consistency_test,
    drag_coefficient_entry,
    held_shifts,
    interval95,
    jacobian_rank_warnings,
    lag1_autocorrelation,
    linear_response,
    normal_matrix,
    relaxed_bounds,
    sandwich_covariance,
    shared_frontal_area,
    systematic_perturbations,
    unclipped_shift,
    unmeasured_warning,
)
from pendulum.model.effects import ADDED_MASS, TERMS, lower_bound, unit_of
from pendulum.model.physics import PendulumModel, SimulationDiverged, fastest_swing, simulate

NUISANCE = ("theta0_rad", "omega0_rad_s", "rest_offset_rad")
# From this many trials a fit's steps are solved on its sparse Jacobian (LSMR), not by an SVD of the dense one (rows ×
# columns², the trials cubed: a joint fit of 20 trials 2.1 s, of 80 40 s; discovery on 40 115 s); below, as before.
SPARSE_FROM_TRIALS = 11


# ---------------------------------------------------------------------------
# The least-squares problem


def typical_scales(model: PendulumModel) -> dict:
    """Parameter magnitudes used for finite-difference steps (never for the answer)."""
    rig = model.rig
    return {
        ADDED_MASS: 0.1 * rig.mass_kg,
        **{term.parameter: term.typical_scale(rig) for term in TERMS.values()},  # the effects library's
        "theta0_rad": 1e-2,
        "omega0_rad_s": 1e-2,
    }


def bounded_least_squares(residuals, jacobian, x0, lower, tolerance=1e-10, max_evaluations=200, sparse=False):
    """min ½‖r(x)‖² subject to x ≥ lower (trust-region reflective, Jacobian-scaled): every fit here.

    ``sparse``: ``jacobian`` returns a sparse matrix and each step is solved iteratively (LSMR) instead of by
    an SVD of the whole Jacobian, whose cost grows as rows × columns² (a group's trials³)."""
    return least_squares(
        residuals,
        x0,
        jac=jacobian,
        bounds=(lower, np.full(x0.size, np.inf)),
        x_scale="jac",
        method="trf",
        xtol=tolerance,
        ftol=1e-2 * tolerance,
        gtol=tolerance,
        max_nfev=max_evaluations,
        **({"tr_solver": "lsmr", "tr_options": {"atol": 1e-12, "btol": 1e-12}} if sparse else {}),
    )


class _Problem:
    """Stacked residuals of N trials sharing the physical parameters; x = [p, (θ0, θ̇0, δ) per trial]."""

    def __init__(self, model_for, records, names, max_step_s):
        self.records = records
        self.model_for = model_for
        self.models = [model_for(r.rig) for r in records]
        self.names = list(names)
        self.n_phys = len(names)
        self.max_step_s = max_step_s
        self.masks = [np.ones(r.n_samples, bool) for r in records]
        scales = typical_scales(self.models[0])
        self.steps = np.array(
            [1e-6 * scales[n] for n in names]
            + [1e-6 * scales[k] for _ in records for k in ("theta0_rad", "omega0_rad_s")]
        )
        self._cache_key = None
        self._cache = None

    def split(self, x):
        phys = dict(zip(self.names, x[: self.n_phys], strict=True))
        nuis = x[self.n_phys :].reshape(len(self.records), 3)
        return phys, nuis

    def simulate_trial(self, k, phys, nuis_k):
        r = self.records[k]
        theta, _ = simulate(self.models[k], phys, nuis_k[0], nuis_k[1], r.time_s, max_step_s=self.max_step_s)
        return theta + nuis_k[2]

    def trial_residual(self, k, phys, nuis_k):
        """Simulated minus measured θ on trial k's samples in use."""
        return (self.simulate_trial(k, phys, nuis_k) - self.records[k].theta_rad)[self.masks[k]]

    def trial_residuals(self, x):
        phys, nuis = self.split(x)
        return [self.trial_residual(k, phys, nuis[k]) for k in range(len(self.records))]

    def residuals(self, x):
        key = x.tobytes()
        if key != self._cache_key:
            self._cache = self.trial_residuals(x)
            self._cache_key = key
        return np.concatenate(self._cache)

    def jacobian_blocks(self, x):
        """The Jacobian's nonzero blocks ``(trial k, column j, ∂r_k/∂x_j)``: forward differences, the offset
        columns exact (∂r/∂δ_k = 1 on trial k)."""
        self.residuals(x)
        base_parts = self._cache
        phys, nuis = self.split(x)
        for j, name in enumerate(self.names):
            step = max(1e-6 * abs(x[j]), self.steps[j])
            moved = dict(phys)
            moved[name] = x[j] + step
            for k in range(len(self.records)):
                yield k, j, (self.trial_residual(k, moved, nuis[k]) - base_parts[k]) / step
        for k in range(len(self.records)):
            col = self.n_phys + 3 * k
            for i in range(2):
                step = max(1e-6 * abs(nuis[k][i]), self.steps[self.n_phys + 2 * k + i])
                moved = nuis[k].copy()
                moved[i] += step
                yield k, col + i, (self.trial_residual(k, phys, moved) - base_parts[k]) / step
            yield k, col + 2, np.ones(base_parts[k].size)

    def jacobian(self, x):
        """The Jacobian, dense (:meth:`jacobian_blocks`)."""
        return stacked_jacobian(self.jacobian_blocks(x), self.masks, x.size)

    def solve(self, x0, lower, tolerance=1e-10):
        self._cache_key = None
        return solve_stacked(self, np.maximum(x0, lower), lower, tolerance)


def solve_stacked(problem, x0, lower, tolerance=1e-10, max_evaluations=200):
    """:func:`bounded_least_squares` of a problem of stacked trials (its ``residuals``, ``jacobian_blocks``,
    ``masks``, ``records``): on its sparse Jacobian from :data:`SPARSE_FROM_TRIALS` trials, else the dense one."""
    large = len(problem.records) >= SPARSE_FROM_TRIALS

    def jacobian(x):
        return working_jacobian(problem, x)

    return bounded_least_squares(problem.residuals, jacobian, x0, lower, tolerance, max_evaluations, sparse=large)


def working_jacobian(problem, x):
    """The Jacobian of a problem of stacked trials as its fit works with it (steps, covariance, systematic
    shifts, rank check): sparse from :data:`SPARSE_FROM_TRIALS` trials (its memory grows as the trials: 160
    trials' dense one and its products took 3.3 GB in discovery), else dense."""
    large = len(problem.records) >= SPARSE_FROM_TRIALS
    return stacked_jacobian(problem.jacobian_blocks(x), problem.masks, x.size, as_sparse=large)


def stacked_jacobian(blocks, masks: list[np.ndarray], n_columns: int, as_sparse: bool = False):
    """The Jacobian of stacked trials from its nonzero ``blocks`` ``(trial k, column j, ∂r_k/∂x_j)`` (trial k's rows
    are its samples in use, ``masks[k]``): dense, or sparse, whose nonzeros grow as the trials where the dense
    matrix grows as their square."""
    rows = np.cumsum([0] + [int(m.sum()) for m in masks])
    if not as_sparse:
        jac = np.zeros((int(rows[-1]), n_columns))
        for k, j, column in blocks:
            jac[rows[k] : rows[k + 1], j] = column
        return jac
    at, cols, values = [], [], []
    for k, j, column in blocks:
        at.append(np.arange(rows[k], rows[k + 1]))
        cols.append(np.full(column.size, j))
        values.append(column)
    shape = (int(rows[-1]), n_columns)
    return sparse.csr_matrix((np.concatenate(values), (np.concatenate(at), np.concatenate(cols))), shape=shape)


# ---------------------------------------------------------------------------
# Uncertainty


# ---------------------------------------------------------------------------
# Public entry points


def _model_factory(terms):
    return lambda rig: PendulumModel(rig, tuple(terms))


def _phys_start(model, starts):
    return {n: float(np.median([s["physical"][n] for s in starts])) for n in model.parameter_names}


class RigMismatch(ValueError):
    """A record swings faster than its rig's values allow at the least added mass: they are not its pendulum's.

    ``facts``: per such trial its small-amplitude period, its period as swung and the shortest (small-amplitude)
    its rig values allow, for the failed fit's document (:func:`pendulum.status.run_stage`) and the report."""

    def __init__(self, message: str, facts: dict):
        super().__init__(message)
        self.facts = facts


def fit_trials(records: list[AngleRecord], terms, settings: FitSettings | None = None) -> dict:
    """Fit one model variant to one or more trials (shared coefficients, per-trial nuisance).

    Raises :class:`RigMismatch` before fitting when a smooth record's period
    (:func:`~pendulum.fit.checks.smooth_swing`) is more than 2 % shorter than its rig values allow
    (:func:`~pendulum.fit.checks.rig_period_problem`; the usual cause on a new user's first clip: another rig's
    values): no coefficients can fit it, and before 2026-12-02 such a fit either diverged (a message that led
    with the simulation's start state) or ended at the bound with coefficients of nothing.
    """
    settings = settings or FitSettings()
    if not records:
        raise ValueError("no trials to fit")
    return _fit_trials(records, terms, settings)


def _fit_trials(records: list[AngleRecord], terms, settings: FitSettings) -> dict:
    model_for = _model_factory(terms)
    model = model_for(records[0].rig)
    names = model.parameter_names
    starts = [decay_analysis(model_for(r.rig), r) for r in records]
    lower_added_mass_kg = added_mass_lower_kg(records, settings)
    mismatched, periods = [], []
    for record, start in zip(records, starts, strict=True):
        # a record that hops between objects has no period to trust: its checks say so after the fit
        if smooth_swing(record) and rig_period_problem(record, start["period_s"], lower_added_mass_kg):
            found = crossing_period(record.time_s, record.theta_rad)  # as swung: the angles JSON's period_s
            swing_period_s = found[0] if found else None
            if swing_period_s and swing_period_s >= 0.98 * fastest_period_s(record, lower_added_mass_kg):
                continue  # its zero crossings give a period the rig allows: the extrema's period is the wrong one
            mismatched.append(rig_period_problem(record, start["period_s"], lower_added_mass_kg, swing_period_s))
            periods.append(
                {
                    "trial": record.trial,
                    "period_s": start["period_s"],
                    "swing_period_s": swing_period_s,
                    "fastest_period_s": fastest_period_s(record, lower_added_mass_kg),
                }
            )
    if mismatched:
        raise RigMismatch("; ".join(mismatched), {"rig_mismatch": periods})
    phys0 = _phys_start(model, starts)
    x0 = np.array([phys0[n] for n in names] + [s[k] for s in starts for k in NUISANCE])
    lower = np.array([lower_bound(n) for n in names] + [-np.inf] * (3 * len(records)))
    lower[0] = lower_added_mass_kg
    problem = _Problem(model_for, records, names, settings.max_step_s)
    for k, start in enumerate(starts):  # jumps in a record's first samples (decay analysis) are never fitted:
        problem.masks[k][start.get("start_outlier_samples", [])] = False  # least squares would chase them (θ̇0 → ∞)
    n_outliers = sum(len(s.get("start_outlier_samples", [])) for s in starts)
    sol = problem.solve(x0, lower)
    # one pass of outlier rejection (mis-tracked points), then refit from the solution
    n_rejected = 0
    parts = problem.trial_residuals(sol.x)
    for k, r in enumerate(parts):
        robust = 1.4826 * np.median(np.abs(r - np.median(r)))
        bad = np.abs(r - np.median(r)) > settings.outlier_sigmas * max(robust, 1e-12)
        if bad.any():
            problem.masks[k][np.flatnonzero(problem.masks[k])[bad]] = False
            n_rejected += int(bad.sum())
    n_outliers += n_rejected
    if n_rejected:
        sol = problem.solve(sol.x, lower)
    jac = working_jacobian(problem, sol.x)
    res_parts = problem.trial_residuals(sol.x)
    rows = np.cumsum([0] + [p.size for p in res_parts])
    jac_parts = [jac[rows[k] : rows[k + 1]] for k in range(len(records))]
    cov, hac_info = sandwich_covariance(jac_parts, res_parts, settings.max_ar_order)
    residual = np.concatenate(res_parts)
    n = residual.size
    white_cov = np.linalg.pinv(normal_matrix(jac)) * float(residual @ residual) / max(n - sol.x.size, 1)
    hac_info["systematic_shifts"] = _systematic_shifts(problem, sol, jac, lower, np.sqrt(np.maximum(np.diag(cov), 0)))
    labels = list(model.parameter_names) + [f"{k}[{r.trial}]" for r in records for k in NUISANCE]
    free = np.asarray(sol.active_mask) == 0
    ranked = compressed_rows(jac, rows) if sparse.issparse(jac) else jac  # the same singular values
    hac_info["jacobian_warnings"] = jacobian_rank_warnings(
        ranked[:, free], [n for n, f in zip(labels, free, strict=True) if f]
    )
    return _summarise(
        model, records, problem, sol, cov, white_cov, res_parts, starts, n_outliers, hac_info, settings, lower
    )


def _systematic_shifts(problem: _Problem, sol, jac, lower, stderr) -> tuple[dict[str, np.ndarray], np.ndarray]:
    """Shift of the estimate when each systematic input moves by 1σ: a real refit, not a linearisation (an input
    that changes the period moves the residuals far beyond their linear range over many cycles, although the
    estimate responds smoothly), started from the linearised answer δx = −J⁺ δr; the −1σ refit's, turned, where a
    bound stopped the +1σ one (:func:`~pendulum.fit.uncertainty.unclipped_shift`); a coefficient held on its bound,
    from refits with that bound relaxed (:func:`~pendulum.fit.uncertainty.held_shifts`; which of those got none: the
    second value)."""
    free = np.asarray(sol.active_mask) == 0
    base = problem.residuals(sol.x)

    def moved_problem(records):
        moved = _Problem(problem.model_for, records, problem.names, problem.max_step_s)
        moved.masks = [m.copy() for m in problem.masks]
        return moved

    def refit(records):
        moved = moved_problem(records)
        start = sol.x + linear_response(jac, free, moved.residuals(sol.x) - base)
        found = moved.solve(np.where(free, start, sol.x), lower, tolerance=1e-7)
        return found.x - sol.x, on_bound(found, lower)

    shifts, down, up = {}, None, systematic_perturbations(problem.records)
    for label, records in up.items():

        def turned(label=label):  # the −1σ refit, where a bound clipped the +1σ one
            nonlocal down
            down = systematic_perturbations(problem.records, sign=-1.0) if down is None else down
            return refit(down[label]) if label in down else None

        shifts[label] = unclipped_shift(*refit(records), free, turned)
    held = np.isfinite(lower) & (~free | (sol.x <= lower + 1e-9 * np.maximum(stderr, 1e-300)))
    held[problem.n_phys :] = False
    if held.any() and shifts:
        typical = typical_scales(problem.models[0])
        scale = np.maximum(stderr, [typical[n] for n in problem.names] + [0.0] * (stderr.size - problem.n_phys))
        relaxed = relaxed_bounds(lower, held, scale, added_mass_floor_kg(problem.records))

        def solve(moved, start, tolerance):
            found = moved.solve(start, relaxed, tolerance)
            return found.x, on_bound(found, relaxed)

        moved = {label: moved_problem(records) for label, records in up.items()}
        measured, unmeasured = held_shifts(held, solve, problem, sol.x, moved, SimulationDiverged)
        for label, shift in measured.items():
            shifts[label] = np.where(held & ~unmeasured, shift, shifts[label])
        return shifts, unmeasured
    return shifts, np.zeros(held.size, bool)


def on_bound(found, lower) -> np.ndarray:
    """Which coefficients a solution ended on their bound (the optimiser's active set, or within rounding of it)."""
    active = np.asarray(found.active_mask) != 0
    finite = np.isfinite(lower)
    active[finite] |= found.x[finite] <= lower[finite] + 1e-12 * np.maximum(1.0, np.abs(lower[finite]))
    return active


def _summarise(model, records, problem, sol, cov, white_cov, res_parts, starts, n_outliers, hac_info, settings, lower):
    names = list(model.parameter_names)
    x = sol.x
    stderr = np.sqrt(np.maximum(np.diag(cov), 0.0))
    shifts, unmeasured = hac_info.pop("systematic_shifts")
    active = np.asarray(sol.active_mask) != 0
    rig = records[0].rig
    warnings = [unmeasured_warning(name) for name, bad in zip(names, unmeasured, strict=False) if bad]
    if not sol.success:
        warnings.append(f"the optimiser stopped without converging: {sol.message}")
    warnings += hac_info.pop("jacobian_warnings")
    if n_outliers:
        warnings.append(f"{n_outliers} sample(s) beyond {settings.outlier_sigmas:g} robust σ were dropped as outliers")
    params = {}
    for j, name in enumerate(names):
        se = float(stderr[j])
        at_bound = bool(active[j] or x[j] <= lower[j] + 1e-9 * max(se, 1e-300))
        params[name] = coefficient_entry(
            name,
            unit_of(name),
            float(x[j]),
            se,
            {key: float(d[j]) for key, d in shifts.items()},
            float(lower[j]),
            at_bound,
            settings.identifiable_max_relative_stderr,
            warnings,
        )
        if name == "drag_area_m2":
            area, area_sigma, differ = shared_frontal_area(records)
            params["drag_coefficient"] = drag_coefficient_entry(params[name], area, area_sigma)
            warnings += [differ] if differ else []
    warnings += rig_checks(rig, params[ADDED_MASS], starts, [r.rig for r in records])
    warnings += drag_checks(rig, params["drag_coefficient"]) if "drag_coefficient" in params else []
    sd = np.sqrt(np.maximum(np.diag(cov), 1e-300))
    corr = cov / np.outer(sd, sd)
    labels = names + [f"{k}[{r.trial}]" for r in records for k in NUISANCE]
    high = [
        (labels[i], labels[j], corr[i, j])
        for i in range(len(names))
        for j in range(i + 1, len(names))
        if abs(corr[i, j]) > 0.99
    ]
    for a, b, c in high:
        warnings.append(f"{a} and {b} are {c:+.3f} correlated: the record hardly separates them")
    residual = np.concatenate(res_parts)
    n = residual.size
    k_params = x.size + 1  # plus the noise variance
    rss = float(residual @ residual)
    phys = dict(zip(names, x[: len(names)], strict=True))
    for name in names:
        phys[name] = params[name]["value"]
    trials = {}
    problems = []
    _, nuis = problem.split(x)
    for k, rec in enumerate(records):
        mdl = problem.models[k]
        dense_t = np.arange(rec.time_s[0], rec.time_s[-1], 0.01)
        theta_sim, omega = simulate(mdl, phys, nuis[k][0], nuis[k][1], dense_t, max_step_s=settings.max_step_s)
        peak_speed, period, kc = fastest_swing(mdl, phys, dense_t, theta_sim, omega, rec.characteristic_length_m)
        r = res_parts[k]
        warnings += misfit_warning(rec, r)
        checks = record_checks(rec, problem.masks[k], r, float(nuis[k][2]))
        problems += checks["problems"]
        trials[rec.trial] = {
            "n_samples": int(r.size),
            "fit_start_s": float(rec.time_s[0]),
            "fit_end_s": float(rec.time_s[-1]),
            "theta0_deg": math.degrees(nuis[k][0]),
            "omega0_deg_s": math.degrees(nuis[k][1]),
            "rest_offset_deg": math.degrees(nuis[k][2]),
            "rest_offset_ci95_deg": [
                math.degrees(nuis[k][2] - Z95 * stderr[len(names) + 3 * k + 2]),
                math.degrees(nuis[k][2] + Z95 * stderr[len(names) + 3 * k + 2]),
            ],
            "rms_deg": math.degrees(float(np.sqrt(np.mean(r**2)))),
            "residual_lag1_autocorrelation": lag1_autocorrelation(r),
            "peak_speed_m_s": peak_speed,
            "period_s": period,
            "keulegan_carpenter_number": kc,
            "measured_first_swing": rec.measured_first_swing(),
            "start_values": starts[k],
            "release_skip_s": rec.release_skip_s,
            "dropped_samples": rec.dropped,
            "outlier_times_s": [float(v) for v in rec.time_s[~problem.masks[k]]],
            "record_checks": checks,
        }
    if problems:  # garbage in: no coefficient is a measurement
        warnings += problems
        for entry in params.values():
            entry["reason"] = f"the angle record is unreliable: {problems[0]}" + (
                f"; also: {entry['reason']}" if not entry["identifiable"] and "reason" in entry else ""
            )
            entry["identifiable"] = False
    inflation = {
        name: float(math.sqrt(cov[j, j] / white_cov[j, j])) if white_cov[j, j] > 0 else None
        for j, name in enumerate(names)
    }
    return {
        "terms": list(model.terms),
        "parameters": params,
        "rms_rad": float(np.sqrt(rss / n)),
        "rms_deg": math.degrees(float(np.sqrt(rss / n))),
        "rms_arc_m": rig.length_m * float(np.sqrt(rss / n)),
        "aic": n * math.log(rss / n) + 2 * k_params,
        "bic": n * math.log(rss / n) + k_params * math.log(n),
        "n_samples": int(n),
        "samples_digest": samples_digest(records, problem.masks),
        "n_parameters": int(x.size),
        "correlation": {"parameters": names, "matrix": corr[: len(names), : len(names)].tolist()},
        "keulegan_carpenter_number": value_or_range([t["keulegan_carpenter_number"] for t in trials.values()]),
        "measured_keulegan_carpenter_number": value_or_range(
            [(t["measured_first_swing"] or {}).get("keulegan_carpenter_number") for t in trials.values()]
        ),
        "uncertainty": {
            "method": "statistical: least-squares sandwich covariance with an AR(p) model of the residual "
            "noise (p by AIC), its bias from fitting residuals corrected by a parametric bootstrap; systematic: "
            "each rig value's stated 1σ tolerance and the estimated pivot's covariance, each propagated by a "
            "refit (error_budget); combined in quadrature; normal 95 % intervals, one-sided at a bound",
            "systematic_inputs": systematic_inputs(records),
            "stderr_over_white_noise_stderr": inflation,
            **hac_info,
        },
        "optimiser": {"converged": bool(sol.success), "evaluations": int(sol.nfev), "message": sol.message},
        "trials": trials,
        "warnings": warnings,
        "reliable": not problems,
    }


def fit_joint(records: list[AngleRecord], terms, per_trial: dict[str, dict], settings: FitSettings | None = None):
    """Joint fit plus the consistency test. When the per-trial estimates scatter more than their statistical
    intervals allow (scale factor S > 1), the joint fit's statistical error is widened by S (the Particle Data
    Group's rule); the systematic part (rig values, pivot: one measurement shared by all trials) is added after,
    unscaled: σ = √((S σ_stat)² + σ_sys²)."""
    settings = settings or FitSettings()
    joint = fit_trials(records, terms, settings)
    rigs = [r.rig for r in records]  # the added mass's scale warning is judged again on a widened interval
    narrow = added_mass_scale_warning(rigs, joint["parameters"][ADDED_MASS])
    joint["consistency"] = consistency = consistency_test(per_trial, joint, settings.consistency_alpha)
    for name, entry in joint["parameters"].items():
        source = "drag_area_m2" if name == "drag_coefficient" else name
        scale = consistency["parameters"][source]["scale_factor"]
        entry["scale_factor"] = max(1.0, scale) if scale else 1.0
        if entry["scale_factor"] > 1.0:
            se = math.hypot(entry["stderr_statistical"] * entry["scale_factor"], entry["stderr_systematic"])
            entry["stderr"] = se
            entry["ci95"] = interval95(entry["value"], se, entry["lower_bound"], entry["at_bound"])
    if narrow in joint["warnings"] and added_mass_scale_warning(rigs, joint["parameters"][ADDED_MASS]) is None:
        joint["warnings"].remove(narrow)  # the widened interval reaches 3 × ρA^1.5: no longer said
    return joint
