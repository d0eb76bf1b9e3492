"""Candidate trials and the information they add (the sandwich's B and M), for :mod:`pendulum.design.next_trials`."""

from __future__ import annotations

import math
from dataclasses import dataclass, replace

import numpy as np
from scipy import sparse

from pendulum.fit.group import GroupFit, GroupProblem
from pendulum.fit.uncertainty import Z95, ar_meat, fit_ar, normal_matrix, used_columns
from pendulum.model.physics import PendulumModel, simulate
from pendulum.model.rig import Rig

DRAG_AREA = "drag_area_m2"
DRAG_COEFFICIENT = "drag_coefficient"


@dataclass(frozen=True)
class Candidate:
    """A trial one could film: a rig (one of the group's, or a described one) and a release angle."""

    rig: str
    release_deg: float
    hypothetical: bool = False


@dataclass
class Information:
    """B and M of the sandwich over an extended parameter list (labels of the coefficients first)."""

    labels: list[str]  # coefficient labels (``parameter`` or ``parameter[rig]``)
    columns: list[tuple]  # (parameter, rig) per coefficient
    bread: np.ndarray
    meat: np.ndarray

    def covariance(self) -> np.ndarray:
        inverse = np.linalg.pinv(self.bread)
        return inverse @ self.meat @ inverse

    def coefficient_variances(self) -> np.ndarray:
        return np.diag(self.covariance())[: len(self.labels)]


def noise_models(fit: GroupFit, max_ar_order: int) -> list[tuple[np.ndarray, float]]:
    return [fit_ar(r, max_ar_order)[:2] for r in fit.residuals]


def today(fit: GroupFit, max_ar_order: int) -> tuple[Information, list[tuple[np.ndarray, float]], np.ndarray]:
    """Today's information (B, M over coefficients then nuisances), the trials' noise models, and each
    coefficient's ratio of the reported sandwich variance (bias-corrected) to the formula's."""
    problem = fit.problem
    jac = fit.jacobian
    rows = np.cumsum([0] + [r.size for r in fit.residuals])
    noise = noise_models(fit, max_ar_order)
    if sparse.issparse(jac):  # a large group: each trial's meat on the columns it touches
        meat = np.zeros((jac.shape[1], jac.shape[1]))
        for k, (phi, var) in enumerate(noise):
            used, part = used_columns(jac[rows[k] : rows[k + 1]])
            meat[np.ix_(used, used)] += ar_meat(part, phi, var)
    else:
        meat = sum(ar_meat(jac[rows[k] : rows[k + 1]], phi, var) for k, (phi, var) in enumerate(noise))
    info = Information(list(problem.labels), list(problem.columns), normal_matrix(jac), meat)
    reported, _, _ = fit.covariance(max_ar_order)
    formula = info.coefficient_variances()
    ratio = np.where(formula > 0, np.diag(reported)[: problem.n_phys] / np.where(formula > 0, formula, 1.0), 1.0)
    return info, noise, np.maximum(ratio, 1.0)


def candidate_record(fit: GroupFit, rig: str, rig_values: Rig | None, release_deg: float, skip_s: float):
    """A candidate's record (its rig, time grid and simulated θ) and its nuisance (θ0, θ̇0, δ = 0)."""
    problem = fit.problem
    members = [k for k, name in enumerate(problem.rig_of) if name == rig] or list(range(len(problem.records)))
    template = problem.records[members[0]]
    step = float(np.median([np.median(np.diff(problem.records[k].time_s)) for k in members]))
    end = float(np.median([problem.records[k].time_s[-1] for k in members]))
    times = np.arange(skip_s, end + 0.5 * step, step)
    phys_rig = rig if rig in problem.rigs else problem.rigs[0]
    base_rig = rig_values or template.rig
    params = problem.physical(fit.x, problem.rig_of.index(phys_rig) if phys_rig in problem.rig_of else 0)
    model = PendulumModel(base_rig, problem.terms)
    grid = np.concatenate([[0.0], times])
    theta, omega = simulate(model, params, math.radians(release_deg), 0.0, grid, max_step_s=problem.max_step_s)
    record = replace(template, trial="candidate", rig=base_rig, time_s=times, theta_rad=theta[1:])
    return record, (float(theta[1]), float(omega[1]), 0.0), params


def candidate_sensitivities(fit: GroupFit, candidate: Candidate, made: tuple):
    """The candidate's coefficient columns (parameter, rig) and its J_c (those columns, then θ0, θ̇0, δ);
    ``made``: its :func:`candidate_record`."""
    problem = fit.problem
    record, nuisance, params = made
    single = GroupProblem([record], [candidate.rig], problem.terms, None, problem.max_step_s)
    x = np.array([params.get(p, 0.0) for p, _ in single.columns] + list(nuisance))
    return list(single.columns), single.jacobian(x)


def with_trial(info: Information, columns: list[tuple], jac_c: np.ndarray, noise: tuple) -> Information:
    """``info`` with one more trial: its coefficient columns mapped onto (or appended to) info's, 3 new nuisances."""
    labels, all_columns = list(info.labels), list(info.columns)
    for column in columns:
        if column not in all_columns:
            all_columns.append(column)
            labels.append(f"{column[0]}[{column[1]}]")
    n_coef, n_old = len(all_columns), info.bread.shape[0]
    n_nuis_old = n_old - len(info.labels)
    size = n_coef + n_nuis_old + 3
    index = {c: i for i, c in enumerate(all_columns)}
    old_index = [index[c] for c in info.columns] + list(range(n_coef, n_coef + n_nuis_old))
    bread = np.zeros((size, size))
    meat = np.zeros((size, size))
    bread[np.ix_(old_index, old_index)] = info.bread
    meat[np.ix_(old_index, old_index)] = info.meat
    full = np.zeros((jac_c.shape[0], size))
    for j, column in enumerate(columns):
        full[:, index[column]] = jac_c[:, j]
    full[:, size - 3 :] = jac_c[:, len(columns) :]
    return Information(labels, all_columns, bread + full.T @ full, meat + ar_meat(full, *noise))


def median_noise(noise: list[tuple[np.ndarray, float]]) -> tuple[np.ndarray, float]:
    """The noise model of the trial with the median innovation variance."""
    order = np.argsort([var for _, var in noise])
    return noise[int(order[len(order) // 2])]


def half_widths(
    info: Information, ratio: np.ndarray, systematic: dict[str, float], values: dict[str, float], frontal_area: dict
) -> dict[str, dict]:
    """Predicted 95 % half-width per coefficient of today's labels (and C_d from the drag area)."""
    variances = info.coefficient_variances()
    out = {}
    for j, label in enumerate(info.labels):
        if label not in values:
            continue
        stat = math.sqrt(max(float(variances[j]) * float(ratio[j] if j < ratio.size else 1.0), 0.0))
        out[label] = _entry(values[label], stat, systematic.get(label, 0.0))
        if label == DRAG_AREA and frontal_area.get("m2"):
            area = frontal_area["m2"]
            out[DRAG_COEFFICIENT] = _entry(values[label] / area, stat / area, systematic.get(DRAG_COEFFICIENT, 0.0))
    return out


def _entry(value: float, stat: float, sys: float) -> dict:
    half = Z95 * math.hypot(stat, sys)
    return {
        "value": value,
        "stderr_statistical": stat,
        "stderr_systematic": sys,
        "halfwidth95": half,
        "relative_halfwidth95": half / abs(value) if value else math.inf,
        "floor_relative_halfwidth95": Z95 * sys / abs(value) if value else math.inf,
    }
