"""Lean output-error refits for discovery: one model fitted to a group of trials, one body on one or more rigs.

The least-squares problem of :mod:`pendulum.fit.output_error` (same simulator, residual,
finite-difference Jacobian and bounds), with the coefficients split by what
they describe. The body's coefficients are shared by every trial of the group,
in physical units: the added mass (kg), the drag area (m²), the history
coefficient K_h (kg/√s) and the restoring correction ε (a wrong mass or
buoyancy). The torques of a rig's bearing and arm, linear damping c (N·m·s)
and Coulomb friction τ_f (N·m), are one coefficient per rig. Each trial adds
θ0, θ̇0 and the rest offset δ. A group of one rig is exactly the joint fit's
problem, without its error budget (computed only for the model discovery
ends with: :func:`systematic_shifts`).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np
from scipy.optimize import least_squares

from pendulum.fit.output_error import on_bound, solve_stacked, stacked_jacobian, working_jacobian
from pendulum.fit.records import AngleRecord, FitSettings, added_mass_floor_kg, added_mass_lower_kg
from pendulum.fit.uncertainty import (
    coefficient_entry,
    drag_coefficient_entry,
    held_shifts,
    linear_response,
    normal_matrix,
    relaxed_bounds,
    sandwich_covariance,
    shared_frontal_area,
    systematic_perturbations,
    unclipped_shift,
    unmeasured_warning,
)
from pendulum.model.effects import ADDED_MASS, TERMS, unit_of
from pendulum.model.physics import PendulumModel, SimulationDiverged, simulate

RIG_LEVEL = ("linear_damping", "coulomb_friction")  # a rig's bearing and arm: one coefficient per rig
MAX_HELD_OUT_FOLDS = 10  # trials held out in at most this many folds (each a refit of the rest): one per trial up to 10


def typical_scale(parameter: str, rig) -> float:
    """A magnitude of a coefficient, for finite-difference steps only."""
    if parameter == ADDED_MASS:
        return 0.1 * rig.mass_kg
    return next(t.typical_scale(rig) for t in TERMS.values() if t.parameter == parameter)


@dataclass
class GroupFit:
    """A solved group problem: estimate ``x`` (coefficients by label, then θ0, θ̇0, δ per trial) and residuals."""

    problem: GroupProblem
    x: np.ndarray
    residuals: list[np.ndarray]  # per trial, on its mask
    active: np.ndarray
    converged: bool
    evaluations: int
    _jacobian: np.ndarray | None = field(default=None, repr=False)

    @property
    def rss(self) -> float:
        return float(sum(r @ r for r in self.residuals))

    @property
    def n(self) -> int:
        return int(sum(r.size for r in self.residuals))

    @property
    def rms_rad(self) -> float:
        return math.sqrt(self.rss / self.n)

    @property
    def coefficients(self) -> dict[str, float]:
        """Estimates by label (``parameter`` or ``parameter[rig]``)."""
        return dict(zip(self.problem.labels, self.x[: self.problem.n_phys].tolist(), strict=True))

    @property
    def values(self) -> dict[tuple, float]:
        """Estimates by (parameter, rig) column (rig None for the body's): starts of other problems."""
        return dict(zip(self.problem.columns, self.x[: self.problem.n_phys].tolist(), strict=True))

    def nuisance(self, k: int) -> np.ndarray:
        return self.x[self.problem.n_phys + 3 * k : self.problem.n_phys + 3 * k + 3]

    @property
    def jacobian(self):
        """At the estimate: sparse for a large group (:func:`pendulum.fit.output_error.working_jacobian`)."""
        if self._jacobian is None:
            self._jacobian = working_jacobian(self.problem, self.x)
        return self._jacobian

    def covariance(self, max_ar_order: int) -> tuple[np.ndarray, np.ndarray, dict]:
        """(sandwich covariance with the AR(p) noise model, white-noise covariance σ²(JᵀJ)⁻¹, noise-model info)."""
        jac = self.jacobian
        rows = np.cumsum([0] + [r.size for r in self.residuals])
        parts = [jac[rows[k] : rows[k + 1]] for k in range(len(self.residuals))]
        cov, info = sandwich_covariance(parts, self.residuals, max_ar_order)
        white = np.linalg.pinv(normal_matrix(jac)) * self.rss / max(self.n - self.x.size, 1)
        return cov, white, info

    def trial_curve(self, k: int) -> np.ndarray:
        """The model's θ at every sample of trial k (not only the fitted ones)."""
        return self.problem.simulate_trial(k, self.x)


class GroupProblem:
    """Stacked residuals of a group's trials for one list of terms; x = [coefficients, (θ0, θ̇0, δ) per trial]."""

    def __init__(self, records: list[AngleRecord], rigs: list[str], terms, masks=None, max_step_s: float = 0.02):
        self.records, self.rig_of, self.terms = list(records), list(rigs), tuple(terms)
        self.rigs = sorted(set(rigs))
        self.models = [PendulumModel(r.rig, self.terms) for r in records]
        body = [ADDED_MASS] + [TERMS[t].parameter for t in self.terms if t not in RIG_LEVEL]
        own = [TERMS[t].parameter for t in self.terms if t in RIG_LEVEL]
        self.columns = [(p, None) for p in body] + [(p, rig) for p in own for rig in self.rigs]
        self.labels = [parameter_label(p, rig, len(self.rigs)) for p, rig in self.columns]
        self.n_phys = len(self.columns)
        self.max_step_s = max_step_s
        self.masks = [
            np.ones(r.n_samples, bool) if masks is None else np.asarray(masks[k], bool) for k, r in enumerate(records)
        ]
        first = {rig: records[rigs.index(rig)].rig for rig in self.rigs}
        self.scales = np.array([typical_scale(p, first[rig] if rig else records[0].rig) for p, rig in self.columns])
        self.steps = np.concatenate([1e-6 * self.scales, np.full(2 * len(records), 1e-8)])

    def touches(self, j: int, k: int) -> bool:
        """Whether coefficient j enters trial k (a rig's own coefficients enter only its trials)."""
        rig = self.columns[j][1]
        return rig is None or rig == self.rig_of[k]

    def physical(self, x, k: int) -> dict:
        return {p: float(x[j]) for j, (p, rig) in enumerate(self.columns) if rig is None or rig == self.rig_of[k]}

    def simulate_trial(self, k: int, x) -> np.ndarray:
        nuis = x[self.n_phys + 3 * k : self.n_phys + 3 * k + 3]
        r = self.records[k]
        theta, _ = simulate(self.models[k], self.physical(x, k), nuis[0], nuis[1], r.time_s, max_step_s=self.max_step_s)
        return theta + nuis[2]

    def trial_residual(self, k: int, x) -> np.ndarray:
        return (self.simulate_trial(k, x) - self.records[k].theta_rad)[self.masks[k]]

    def residual_parts(self, x) -> list[np.ndarray]:
        return [self.trial_residual(k, x) for k in range(len(self.records))]

    def residuals(self, x) -> np.ndarray:
        key = x.tobytes()
        if key != getattr(self, "_key", None):
            self._parts, self._key = self.residual_parts(x), key
        return np.concatenate(self._parts)

    def jacobian_blocks(self, x):
        """The Jacobian's nonzero blocks ``(trial k, column j, ∂r_k/∂x_j)``: forward differences (a rig's coefficient
        only on its trials; a trial's θ0, θ̇0 only on it), the offset columns exact (∂r_k/∂δ_k = 1)."""
        self.residuals(x)
        base = self._parts
        for j in range(self.n_phys):
            step = max(1e-6 * abs(x[j]), self.steps[j])
            moved = x.copy()
            moved[j] += step
            for k in range(len(self.records)):
                if self.touches(j, k):
                    yield k, j, (self.trial_residual(k, moved) - base[k]) / step
        for k in range(len(self.records)):
            col = self.n_phys + 3 * k
            for i in range(2):
                step = max(1e-6 * abs(x[col + i]), 1e-8)
                moved = x.copy()
                moved[col + i] += step
                yield k, col + i, (self.trial_residual(k, moved) - base[k]) / step
            yield k, col + 2, np.ones(base[k].size)

    def jacobian(self, x) -> np.ndarray:
        """The Jacobian, dense (:meth:`jacobian_blocks`)."""
        return stacked_jacobian(self.jacobian_blocks(x), self.masks, x.size)

    def lower_bounds(self, settings: FitSettings) -> np.ndarray:
        floor = added_mass_lower_kg(self.records, settings)
        lower = [floor if p == ADDED_MASS else TERMS_BY_PARAMETER[p].lower_bound for p, _ in self.columns]
        return np.array(lower + [-np.inf] * (3 * len(self.records)))

    def start(self, values: dict, nuisance: list) -> np.ndarray:
        """x from coefficient values by (parameter, rig) column (a missing one starts at 0) and (θ0, θ̇0, δ) per trial.

        A rig's own coefficient may also be given by its parameter name alone (the same start on every rig).
        """
        phys = [float(values.get((p, rig), values.get(p, 0.0))) for p, rig in self.columns]
        return np.array(phys + [float(v) for nuis in nuisance for v in nuis])

    def solve(
        self, x0, settings: FitSettings, tolerance: float = 1e-10, max_evaluations: int = 200, lower=None
    ) -> GroupFit:
        """The least-squares estimate from ``x0`` within :meth:`lower_bounds` (or ``lower``, where given)."""
        self._key = None
        lower = self.lower_bounds(settings) if lower is None else lower
        x0 = np.maximum(np.asarray(x0, float), lower)
        sol = solve_stacked(self, x0, lower, tolerance, max_evaluations)
        active = on_bound(sol, lower)
        return GroupFit(self, sol.x, self.residual_parts(sol.x), active, bool(sol.success), int(sol.nfev))


TERMS_BY_PARAMETER = {t.parameter: t for t in TERMS.values()}


def parameter_label(parameter: str, rig: str | None, n_rigs: int) -> str:
    """A coefficient's name in a group: the parameter, with ``[rig]`` for a rig's own coefficient on several rigs."""
    return parameter if rig is None or n_rigs == 1 else f"{parameter}[{rig}]"


def solve_many(jobs: list[tuple]) -> list[GroupFit]:
    """Solve (problem, x0, settings, tolerance) jobs in turn (one process: the bytes do not depend on a pool)."""
    return [problem.solve(x0, settings, tolerance) for problem, x0, settings, tolerance in jobs]


def systematic_shifts(fit: GroupFit, settings: FitSettings, cov) -> tuple[dict[str, np.ndarray], np.ndarray]:
    """Shift of the estimate when each systematic input moves by 1σ, by a refit (as :mod:`pendulum.fit.output_error`;
    ``cov``: the estimate's covariance, for how far a coefficient held on its bound is let go).

    Inputs per rig (its values' tolerances, its pooled pivot): rigs are measured separately.
    """
    problem = fit.problem
    free = ~fit.active
    base = np.concatenate(fit.residuals)

    def jobs_for(sign: float) -> tuple[list[str], list[tuple]]:
        labels, jobs = [], []
        for rig in problem.rigs:
            members = [k for k, name in enumerate(problem.rig_of) if name == rig]
            subset = [problem.records[k] for k in members]
            for label, moved_subset in systematic_perturbations(subset, sign).items():
                records = list(problem.records)
                for k, rec in zip(members, moved_subset, strict=True):
                    records[k] = rec
                moved = GroupProblem(records, problem.rig_of, problem.terms, problem.masks, problem.max_step_s)
                start = fit.x + linear_response(fit.jacobian, free, moved.residuals(fit.x) - base)
                labels.append(label if len(problem.rigs) == 1 else f"{label}[{rig}]")
                jobs.append((moved, np.where(free, start, fit.x), settings, 1e-7))
        return labels, jobs

    labels, jobs = jobs_for(1.0)
    up = dict(zip(labels, solve_many(jobs), strict=True))
    down: dict[str, GroupFit] | None = None

    def turned(label: str):  # the −1σ refits (all at once, the first time a bound clips a +1σ one)
        nonlocal down
        if down is None:
            names, work = jobs_for(-1.0)
            down = dict(zip(names, solve_many(work), strict=True))
        return (down[label].x - fit.x, down[label].active) if label in down else None

    shifts = {
        label: unclipped_shift(up[label].x - fit.x, up[label].active, free, lambda k=label: turned(k))
        for label in labels
    }
    held = fit.active.copy()
    held[problem.n_phys :] = False
    if held.any() and shifts:
        stderr = np.sqrt(np.maximum(np.diag(cov), 0))
        typical = np.concatenate([problem.scales, np.zeros(stderr.size - problem.n_phys)])
        lower = problem.lower_bounds(settings)
        relaxed = relaxed_bounds(lower, held, np.maximum(stderr, typical), added_mass_floor_kg(problem.records))

        def solve(moved: GroupProblem, start, tolerance):
            found = moved.solve(start, settings, tolerance, lower=relaxed)
            return found.x, found.active

        moved = {label: job[0] for label, job in zip(labels, jobs, strict=True)}
        measured, unmeasured = held_shifts(held, solve, problem, fit.x, moved, SimulationDiverged)
        for label, shift in measured.items():
            shifts[label] = np.where(held & ~unmeasured, shift, shifts[label])
        return shifts, unmeasured
    return shifts, np.zeros(held.size, bool)


def leave_trials_out(fit: GroupFit, settings: FitSettings, max_folds: int = MAX_HELD_OUT_FOLDS) -> list[np.ndarray]:
    """Residuals of each trial predicted from a fit of the others, only its θ0, θ̇0 and offset refitted to it.

    Up to ``max_folds`` trials, each is left out alone; a larger group is split into ``max_folds`` folds, each
    predicted from a fit of the other folds: as many refits whatever the group's size. The trials are dealt out
    in turn, a rig's one after another, so that no fold holds all of a rig's (every rig of the group needs a
    second trial: its own coefficients come from the others).
    """
    problem, n = fit.problem, len(fit.problem.records)
    n_folds = min(n, max_folds)
    by_rig = sorted(range(n), key=lambda k: problem.rig_of[k])  # stable: one rig's trials in their order
    folds = [sorted(by_rig[f::n_folds]) for f in range(n_folds)]
    jobs = []
    for fold in folds:
        keep = [j for j in range(n) if j not in fold]
        rest = GroupProblem(
            [problem.records[j] for j in keep],
            [problem.rig_of[j] for j in keep],
            problem.terms,
            [problem.masks[j] for j in keep],
            problem.max_step_s,
        )
        jobs.append((rest, rest.start(fit.values, [fit.nuisance(j) for j in keep]), settings, 1e-8))
    predicted_from = {k: rest_fit for fold, rest_fit in zip(folds, solve_many(jobs), strict=True) for k in fold}
    out = []
    for k in range(n):
        single = GroupProblem(
            [problem.records[k]], [problem.rig_of[k]], problem.terms, [problem.masks[k]], problem.max_step_s
        )
        phys = single.start(predicted_from[k].values, [fit.nuisance(k)])[: single.n_phys]

        def residual(z, phys=phys, single=single):
            return single.trial_residual(0, np.concatenate([phys, z]))

        nuisance = least_squares(residual, fit.nuisance(k), x_scale="jac", xtol=1e-10).x
        out.append(residual(nuisance))
    return out


def forecast(fit: GroupFit, settings: FitSettings, held_out_fraction: float) -> list[np.ndarray]:
    """Residuals on the last ``held_out_fraction`` of each record, forecast from a fit to the rest (held-out cycles)."""
    problem = fit.problem
    early, late = [], []
    for k, r in enumerate(problem.records):
        split = r.time_s[0] + (1 - held_out_fraction) * (r.time_s[-1] - r.time_s[0])
        early.append(problem.masks[k] & (r.time_s < split))
        late.append(problem.masks[k] & (r.time_s >= split))
    fold = GroupProblem(problem.records, problem.rig_of, problem.terms, early, problem.max_step_s)
    fitted = fold.solve(fit.x, settings, 1e-8)
    return [(fold.simulate_trial(k, fitted.x) - r.theta_rad)[late[k]] for k, r in enumerate(problem.records)]


def ordered(terms) -> tuple[str, ...]:
    """Terms in library order (one model, one key)."""
    terms = set(terms)
    return tuple(t for t in TERMS if t in terms)


def start_values(records: list[AngleRecord], rigs: list[str], documents: list[dict]):
    """Start values by (parameter, rig), each trial's θ0, θ̇0, δ and kept samples, from fit documents.

    Each trial's values come from the first document holding it (a joint fit, else its own fit); a
    coefficient starts at the median over the documents used (of its rig, for a rig's own).
    """
    nuisance, masks, used = [], [], []
    for record in records:
        doc = next((d for d in documents if record.trial in d.get("trials", {})), None)
        if doc is None:
            raise ValueError(f"trial {record.trial}: no baseline fit holds it")
        entry = doc["trials"][record.trial]
        used.append(doc)
        nuisance.append([math.radians(entry[k]) for k in ("theta0_deg", "omega0_deg_s", "rest_offset_deg")])
        outliers = np.asarray(entry.get("outlier_times_s") or [], float)
        mask = np.ones(record.n_samples, bool)
        if outliers.size:
            mask &= np.min(np.abs(record.time_s[:, None] - outliers[None, :]), axis=1) > 1e-6
        masks.append(mask)
    values = {}
    for scope in [None, *sorted(set(rigs))]:
        docs = list({id(d): d for d, g in zip(used, rigs, strict=True) if scope in (None, g)}.values())
        for name in docs[0]["parameters"]:
            if name != "drag_coefficient":
                values[name if scope is None else (name, scope)] = float(
                    np.median([d["parameters"][name]["value"] for d in docs])
                )
    return values, nuisance, masks


def coefficient_entries(fit: GroupFit, settings: FitSettings) -> tuple[dict, list[str]]:
    """The fit's coefficients as the fit documents report them (:func:`pendulum.fit.uncertainty.coefficient_entry`):
    sandwich statistical error, systematic budget by refits, combined error and 95 % interval; plus C_d.
    Returns the entries and their warnings (at a bound, not identifiable)."""
    cov, _, _ = fit.covariance(settings.max_ar_order)
    shifts, unmeasured = systematic_shifts(fit, settings, cov)
    stderr = np.sqrt(np.maximum(np.diag(cov), 0))
    lower = fit.problem.lower_bounds(settings)
    warnings = [unmeasured_warning(label) for label, bad in zip(fit.problem.labels, unmeasured, strict=False) if bad]
    out = {}
    for j, ((parameter, _), label) in enumerate(zip(fit.problem.columns, fit.problem.labels, strict=True)):
        out[label] = coefficient_entry(
            label,
            unit_of(parameter),
            float(fit.x[j]),
            float(stderr[j]),
            {key: float(d[j]) for key, d in shifts.items()},
            float(lower[j]),
            bool(fit.active[j]),
            settings.identifiable_max_relative_stderr,
            warnings,
        )
        if parameter == "drag_area_m2":
            area, area_sigma, differ = shared_frontal_area(fit.problem.records)
            out["drag_coefficient"] = drag_coefficient_entry(out[label], area, area_sigma)
            warnings += [differ] if differ else []
    return out, warnings


def fit_body(records: list[AngleRecord], rigs: list[str], terms, documents: list[dict], settings: FitSettings) -> dict:
    """One model fitted jointly to every trial of one body swung on several rigs (config ``bodies``).

    The body's coefficients (added mass m_a in kg, drag area C_d·A in m², history
    coefficient K_h) are shared by all trials; linear damping c and Coulomb
    friction τ_f are each rig's own (``parameter[rig]``). Starts from the per-rig
    joint and per-trial ``documents``; coefficients are reported as the fit
    documents report them (statistical, systematic and combined error, 95 % interval).
    """
    values, nuisance, masks = start_values(records, rigs, documents)
    problem = GroupProblem(records, rigs, ordered(terms), masks, settings.max_step_s)
    fit = problem.solve(problem.start(values, nuisance), settings)
    entries, warnings = coefficient_entries(fit, settings)
    if not fit.converged:
        warnings.append("the body fit did not converge")
    trials = {}
    for k, record in enumerate(records):
        theta0, omega0, offset = fit.nuisance(k)
        trials[record.trial] = {
            "rig": rigs[k],
            "theta0_deg": math.degrees(theta0),
            "omega0_deg_s": math.degrees(omega0),
            "rest_offset_deg": math.degrees(offset),
            "rms_deg": math.degrees(math.sqrt(np.mean(fit.residuals[k] ** 2))),
            "n_samples": int(fit.residuals[k].size),
        }
    return {
        "terms": list(problem.terms),
        "rigs": problem.rigs,
        "parameters": entries,
        "trials": trials,
        "rms_deg": math.degrees(fit.rms_rad),
        "n_samples": fit.n,
        "converged": fit.converged,
        "evaluations": fit.evaluations,
        "warnings": warnings,
    }
