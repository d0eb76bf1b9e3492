"""What to film next: the 95 % half-width each coefficient would have if one more trial were added.

A group's least-squares estimate x̂ (coefficients, then θ0, θ̇0, δ per trial) has, trials independent,

    Cov = B⁻¹ M B⁻¹,   B = Σ_k J_kᵀ J_k,   M = Σ_k J_kᵀ Ω_k J_k,

J_k = ∂θ_k/∂x the sensitivities of trial k's kept samples and Ω_k its AR(p) residual-noise covariance
(the sandwich of :func:`pendulum.uncertainty.sandwich_covariance`, whose bias correction is carried over
per coefficient as the ratio of the reported to the formula's variance). A candidate trial — released
at rest from θ_rel on one of the group's rigs, or on a rig the user describes (another arm length or
payload) — adds its own J_c, simulated with today's estimates and sampled as the group's records
(release transient left out), Ω_c (the median trial's noise model) and three nuisance columns; a new
rig adds its own rig-level coefficients. The systematic part (rig tolerances, pivot) is common to every
trial and carried unchanged: half-width = 1.96 √(σ_stat² + σ_sys²). A coefficient whose σ_sys dominates
does not shrink with more trials; the input behind it is named. The model is assumed right.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, replace

import numpy as np
import pandas as pd

from pendulum.effects import ADDED_MASS, TERMS
from pendulum.groupfit import GroupFit, GroupProblem, ordered, start_values
from pendulum.physics import PendulumModel, Rig, SimulationDiverged, simulate
from pendulum.uncertainty import Z95, _meat, fit_ar

DEFAULT_RELEASES_DEG = (5.0, 10.0, 15.0, 20.0, 30.0, 45.0, 60.0, 75.0)
DRAG_AREA = "drag_area_m2"
DRAG_COEFFICIENT = "drag_coefficient"
ROW_COLUMNS = [
    "rig",
    "described_rig",
    "release_deg",
    "coefficient",
    "value",
    "halfwidth95_today",
    "halfwidth95_predicted",
    "gain",
]


COEFFICIENT_WORDS = {
    ADDED_MASS: "the added mass m_a",
    DRAG_COEFFICIENT: "the drag coefficient C_d",
    "drag_area_m2": "the drag area C_d·A",
    "linear_damping_nm_s": "the linear damping c",
    "friction_torque_nm": "the bearing friction τ_f",
    "history_coefficient_kg_per_sqrt_s": "the history coefficient K_h",
    "restoring_torque_correction": "the restoring-torque correction ε",
}
INPUT_WORDS = {
    "mass_kg": "the rig's mass",
    "length_m": "the arm length",
    "frontal_area_m2": "the frontal area",
    "displaced_volume_m3": "the displaced volume",
    "fluid_density_kg_m3": "the water's density",
    "body_inertia_kg_m2": "the body's moment of inertia",
    "gravity_m_s2": "gravity",
}


def coefficient_words(label: str) -> str:
    """``drag_coefficient`` → "the drag coefficient C_d"; a rig's own coefficient keeps its ``[rig]``."""
    base, _, rig = label.partition("[")
    words = COEFFICIENT_WORDS.get(base, base)
    return words + (f" of rig {rig.rstrip(']')}" if rig else "")


def input_words(key: str) -> str:
    """An error-budget input in words (``pivot_px (axis 1)`` → "the pivot position")."""
    base = key.split("[")[0]
    if base.startswith("pivot"):
        return "the pivot position"
    return INPUT_WORDS.get(base, base)


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


def _noise_models(fit: GroupFit, max_ar_order: int) -> list[tuple[np.ndarray, float]]:
    return [fit_ar(r, max_ar_order)[:2] for r in fit.residuals]


def today(fit: GroupFit, max_ar_order: int) -> tuple[Information, list[tuple[np.ndarray, float]], np.ndarray]:
    """Today's information (B, M over coefficients then nuisances), the trials' noise models, and each
    coefficient's ratio of the reported sandwich variance (bias-corrected) to the formula's."""
    problem = fit.problem
    jac = fit.jacobian
    rows = np.cumsum([0] + [r.size for r in fit.residuals])
    noise = _noise_models(fit, max_ar_order)
    meat = sum(_meat(jac[rows[k] : rows[k + 1]], phi, var) for k, (phi, var) in enumerate(noise))
    info = Information(list(problem.labels), list(problem.columns), jac.T @ jac, meat)
    reported, _, _ = fit.covariance(max_ar_order)
    formula = info.coefficient_variances()
    ratio = np.where(formula > 0, np.diag(reported)[: problem.n_phys] / np.where(formula > 0, formula, 1.0), 1.0)
    return info, noise, np.maximum(ratio, 1.0)


def _record_for(fit: GroupFit, rig: str, rig_values: Rig | None, release_deg: float, skip_s: float):
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


def candidate_sensitivities(fit: GroupFit, candidate: Candidate, rig_values: Rig | None, skip_s: float):
    """The candidate's coefficient columns (parameter, rig) and its J_c (those columns, then θ0, θ̇0, δ)."""
    problem = fit.problem
    record, nuisance, params = _record_for(fit, candidate.rig, rig_values, candidate.release_deg, skip_s)
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
    return Information(labels, all_columns, bread + full.T @ full, meat + _meat(full, *noise))


def _median_noise(noise: list[tuple[np.ndarray, float]]) -> tuple[np.ndarray, float]:
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


@dataclass(frozen=True)
class DesignOptions:
    """Config ``design``: what to ask of the next trials."""

    coefficients: tuple[str, ...] = (ADDED_MASS, DRAG_COEFFICIENT)  # the ones the user cares about
    releases_deg: tuple[float, ...] = DEFAULT_RELEASES_DEG  # candidate releases (both signs)
    rigs: tuple[tuple[str, dict], ...] = ()  # described rigs: (name, rig values overriding the group's first)
    target_relative_halfwidth: float = 0.02  # 95 % half-width / value wanted for each coefficient above
    recommend: int = 3  # how many next trials to recommend
    max_trials: int = 50  # beyond this many further trials a target counts as out of reach

    @classmethod
    def from_config(cls, block: dict | None) -> DesignOptions:
        block = dict(block or {})
        return cls(
            coefficients=tuple(block.get("coefficients", cls.coefficients)),
            releases_deg=tuple(float(r) for r in block.get("releases_deg", cls.releases_deg)),
            rigs=tuple(sorted((name, dict(v)) for name, v in (block.get("rigs") or {}).items())),
            target_relative_halfwidth=float(block.get("target_relative_halfwidth", cls.target_relative_halfwidth)),
            recommend=int(block.get("recommend", cls.recommend)),
        )


def fit_final_model(group, discovery: dict, settings) -> GroupFit:
    """Discovery's final model refitted to the group (its nuisances and kept samples from the baseline fits)."""
    values, nuisance, masks = start_values(group.records, group.rigs, group.starts)
    problem = GroupProblem(group.records, group.rigs, ordered(discovery["final_terms"]), masks, settings.max_step_s)
    labels = dict(zip(problem.labels, problem.columns, strict=True))
    values.update({labels[k]: v["value"] for k, v in discovery["parameters"].items() if k in labels})
    return problem.solve(problem.start(values, nuisance), settings)


def design_table(rows: list[dict]) -> pd.DataFrame:
    return pd.DataFrame(rows, columns=ROW_COLUMNS)


def _largest_input(entry: dict) -> tuple[str, float]:
    budget = entry.get("error_budget") or {}
    if not budget:
        return "", 0.0
    key = max(budget, key=lambda k: abs(budget[k]))
    return key, abs(float(budget[key]))


MIN_GAIN = 0.01  # a recommended trial narrows the widest target interval by at least this share


def _reducible(entry: dict) -> float:
    return entry["relative_halfwidth95"] - entry["floor_relative_halfwidth95"]


def _widest(widths: dict, targets) -> float:
    return max(widths[c]["relative_halfwidth95"] for c in targets)


def _score(widths: dict, targets: tuple[str, ...]) -> float:
    """The widest reducible relative half-width among the targets (what a further trial can still shrink)."""
    parts = [_reducible(widths[c]) for c in targets if c in widths]
    return max(parts) if parts else 0.0


def _rig_values(rig: Rig) -> dict:
    return {name: getattr(rig, name) for name in rig.__dataclass_fields__}


def _sentence(name: str, today_entry: dict, after: dict, cand: Candidate) -> str:
    where = f"on the described rig {cand.rig}" if cand.hypothetical else f"on rig {cand.rig}"
    return (
        f"release from {cand.release_deg:+g}° {where}: {coefficient_words(name)} ±{_fmt(today_entry['halfwidth95'])}"
        f" → ±{_fmt(after['halfwidth95'])} (95 %)"
    )


def _fmt(value: float) -> str:
    return f"{value:.3g}"


class _Designer:
    """Candidates' sensitivities computed once; information updated trial by trial."""

    def __init__(self, fit: GroupFit, parameters: dict, settings, options: DesignOptions):
        problem = fit.problem
        self.fit, self.options, self.parameters = fit, options, parameters
        self.settings_max_ar, self.release_skip_s = settings.max_ar_order, settings.release_skip_s
        self.info, noise, self.ratio = today(fit, settings.max_ar_order)
        self.noise = _median_noise(noise)
        self.values = {label: float(fit.x[j]) for j, label in enumerate(problem.labels)}
        self.systematic = {k: float(v.get("stderr_systematic", 0.0)) for k, v in parameters.items()}
        self.area = {"m2": problem.records[0].rig.frontal_area_m2}
        self.now = self.widths(self.info)
        self.targets = tuple(c for c in options.coefficients if c in self.now)
        base = _rig_values(problem.records[0].rig)
        self.described = {name: Rig.from_mapping({**base, **vals}) for name, vals in options.rigs}
        self.sensitivities = {}
        for rig, hypothetical in [(r, False) for r in problem.rigs] + [(r, True) for r in self.described]:
            for release in options.releases_deg:
                for sign in (-1.0, 1.0):
                    cand = Candidate(rig, sign * release, hypothetical)
                    try:
                        self.sensitivities[cand] = candidate_sensitivities(
                            fit, cand, self.described.get(rig), settings.release_skip_s
                        )
                    except SimulationDiverged:
                        continue

    def widths(self, info: Information) -> dict:
        return half_widths(info, self.ratio, self.systematic, self.values, self.area)

    def added(self, info: Information, cand: Candidate) -> Information:
        columns, jac = self.sensitivities[cand]
        return with_trial(info, columns, jac, self.noise)

    def best(self, info: Information, targets) -> tuple[Candidate, Information, dict]:
        scored = []
        for cand in self.sensitivities:
            after = self.added(info, cand)
            widths = self.widths(after)
            scored.append((_score(widths, targets), abs(cand.release_deg), cand.rig, cand, after, widths))
        scored.sort(key=lambda s: s[:3])
        _, _, _, cand, after, widths = scored[0]
        return cand, after, widths


def design_group(
    fit: GroupFit, parameters: dict, settings, options: DesignOptions, indistinguishable: list[dict] | None = None
) -> tuple[dict, list[dict]]:
    """The design document and its table rows (one per candidate trial and coefficient).

    ``parameters``: the reported coefficient entries of this model (value, stderr_systematic, error_budget),
    as discovery's ``parameters`` for its final model.
    """
    d = _Designer(fit, parameters, settings, options)
    rows = []
    for cand in d.sensitivities:
        for name, entry in d.widths(d.added(d.info, cand)).items():
            today_half = d.now[name]["halfwidth95"]
            rows.append(
                {
                    "rig": cand.rig,
                    "described_rig": cand.hypothetical,
                    "release_deg": cand.release_deg,
                    "coefficient": name,
                    "value": entry["value"],
                    "halfwidth95_today": today_half,
                    "halfwidth95_predicted": entry["halfwidth95"],
                    "gain": today_half / entry["halfwidth95"] if entry["halfwidth95"] else math.inf,
                }
            )
    recommendations, info = [], d.info
    for _ in range(options.recommend if d.targets else 0):
        before = d.widths(info)
        cand, after, widths = d.best(info, d.targets)
        if _score(before, d.targets) - _score(widths, d.targets) < MIN_GAIN * _widest(before, d.targets):
            break  # no candidate shrinks what the targets' widths are made of: their tolerances
        info = after
        widest = max(d.targets, key=lambda c: _reducible(before[c]))
        recommendations.append(
            {
                "rig": cand.rig,
                "described_rig": cand.hypothetical,
                "release_deg": cand.release_deg,
                "predicted": {c: widths[c]["halfwidth95"] for c in d.targets},
                "sentence": _sentence(widest, before[widest], widths[widest], cand),
            }
        )
    if d.targets and not recommendations:
        limits = sorted({input_words(_largest_input(d.parameters.get(c, {}))[0]) for c in d.targets} - {""})
        recommendations.append(
            {
                "rig": None,
                "described_rig": False,
                "release_deg": None,
                "predicted": {c: d.now[c]["halfwidth95"] for c in d.targets},
                "sentence": (
                    "no further trial narrows "
                    + " or ".join(coefficient_words(c) for c in d.targets)
                    + " by 1 % or more: their intervals are set by the rig values' tolerances (largest: "
                    + ", ".join(limits)
                    + "); measure those more precisely"
                ),
            }
        )
    return {
        "model_terms": list(fit.problem.terms),
        "model": " + ".join(TERMS[t].label for t in fit.problem.terms) or "added mass only",
        "trials": [r.trial for r in fit.problem.records],
        "rigs": fit.problem.rigs,
        "described_rigs": dict(options.rigs),
        "targets": list(d.targets),
        "target_relative_halfwidth95": options.target_relative_halfwidth,
        "today": d.now,
        "recommendations": recommendations,
        "to_target": {c: _to_target(d, c) for c in d.targets},
        "separating": separations(d, indistinguishable or []),
        "method": (
            "sandwich covariance (trials independent, AR(p) noise) with one more simulated trial per candidate; "
            "the systematic part carried unchanged; the model assumed right"
        ),
    }, rows


def _to_target(d: _Designer, name: str) -> dict:
    """Further trials (each the best for this coefficient) until its relative half-width reaches the target."""
    target = d.options.target_relative_halfwidth
    entry = d.now[name]
    out = {"target_relative_halfwidth95": target, "relative_halfwidth95_today": entry["relative_halfwidth95"]}
    if entry["relative_halfwidth95"] <= target:
        return {
            **out,
            "further_trials": 0,
            "reachable": True,
            "sentence": f"{coefficient_words(name)} is already within ±{100 * target:g} %",
        }
    if entry["floor_relative_halfwidth95"] >= target:
        key, shift = _largest_input(d.parameters.get(name, {}))
        return {
            **out,
            "further_trials": None,
            "reachable": False,
            "limited_by": key,
            "sentence": (
                f"±{100 * target:g} % for {coefficient_words(name)} cannot be reached by more trials: it is limited "
                f"by {input_words(key)} ({key}; its tolerance alone moves it by ±{_fmt(shift)}, 1σ): measure "
                f"{input_words(key)} more precisely"
            ),
        }
    info = d.info
    for n in range(1, d.options.max_trials + 1):
        _, info, widths = d.best(info, (name,))
        if widths[name]["relative_halfwidth95"] <= target:
            return {
                **out,
                "further_trials": n,
                "reachable": True,
                "sentence": f"{n} further trial(s) bring {coefficient_words(name)} within ±{100 * target:g} %",
            }
    return {
        **out,
        "further_trials": None,
        "reachable": False,
        "sentence": f"{coefficient_words(name)} does not reach ±{100 * target:g} % within "
        f"{d.options.max_trials} further trials",
    }


# ---------------------------------------------------------------------------
# Telling two indistinguishable effects apart


def _unexplained(rows: list[tuple[np.ndarray, np.ndarray]]) -> float:
    """‖(I − P) s‖² of the stacked (J, s): the part of the signal no rival coefficient absorbs."""
    jac = np.vstack([j for j, _ in rows])
    signal = np.concatenate([s for _, s in rows])
    coef, *_ = np.linalg.lstsq(jac, signal, rcond=None)
    rest = signal - jac @ coef
    return float(rest @ rest)


def _signal_and_rival(problem: GroupProblem, rival: GroupProblem, x: np.ndarray, effect_column: int):
    """Per trial: the effect's signal θ(x) − θ(x with its coefficient 0), and the rival model's J at the same
    shared coefficients (its own at 0), columns as ``rival.columns`` then its nuisances."""
    off = x.copy()
    off[effect_column] = 0.0
    values = {c: float(v) for c, v in zip(problem.columns, x[: problem.n_phys], strict=True)}
    n_trials = len(problem.records)
    nuisance = [x[problem.n_phys + 3 * k : problem.n_phys + 3 * k + 3] for k in range(n_trials)]
    x_rival = rival.start({c: v for c, v in values.items() if c in rival.columns}, nuisance)
    for j, column in enumerate(rival.columns):
        if column not in values:
            x_rival[j] = 0.0
    jac = rival.jacobian(x_rival)
    rows = np.cumsum([0] + [m.sum() for m in rival.masks])
    out = []
    for k in range(n_trials):
        signal = (problem.simulate_trial(k, x) - problem.simulate_trial(k, off))[problem.masks[k]]
        out.append((jac[rows[k] : rows[k + 1]], signal))
    return out


def separations(d: _Designer, groups: list[dict]) -> list[dict]:
    """For each indistinguishable group of discovery (``effects``, the one ``carried_in_model`` first): how many
    σ apart its effects would be with each candidate trial added, and the trial that separates them most.

    Separation = √Λ with Λ = ‖(I − P_rival) s‖² / (κ² σ²), s the carried effect's signal in the records
    (θ with its coefficient less θ without), P_rival the projection on the rival model's sensitivities (the
    rival effect in its place), σ² = RSS/n of today's fit and κ² its residual-correlation factor: the
    likelihood ratio discovery compares with its threshold (n_eff ln(RSS_rival/RSS) ≈ Λ), linearised about
    today's fit. At one swing frequency the history force is an added mass plus a linear damping whatever
    the amplitude, so for that pair only a rig with another length or payload (config ``design.rigs``) counts.
    """
    fit, problem = d.fit, d.fit.problem
    cov, white, _ = fit.covariance(d.settings_max_ar)
    coefficients = range(problem.n_phys)
    kappa2 = max(float(np.mean([cov[j, j] / white[j, j] for j in coefficients if white[j, j] > 0] or [1.0])), 1.0)
    scale = 1.0 / math.sqrt(kappa2 * fit.rss / fit.n)
    out = []
    for group in groups:
        carried = group.get("carried_in_model") or group["effects"][0]
        if carried not in problem.terms:
            continue
        column = next(j for j, (p, _) in enumerate(problem.columns) if p == TERMS[carried].parameter)
        one_frequency = str(group.get("reason", "")).startswith("at one swing frequency")
        for other in [e for e in group["effects"] if e != carried]:
            terms = tuple(t for t in problem.terms if t != carried) + (other,)
            rival = GroupProblem(problem.records, problem.rig_of, ordered(terms), problem.masks, problem.max_step_s)
            today_rows = [(j * scale, s * scale) for j, s in _signal_and_rival(problem, rival, fit.x, column)]
            n_cols = today_rows[0][0].shape[1]
            today = math.sqrt(_unexplained(today_rows))
            best = None
            for cand in d.sensitivities:
                if one_frequency and not cand.hypothetical:
                    continue
                rows = _candidate_rows(d, cand, carried, rival, n_cols, scale)
                if rows is None:
                    continue
                width = rows[0].shape[1]
                padded = [(np.pad(j, ((0, 0), (0, width - n_cols))), s) for j, s in today_rows]
                separation = math.sqrt(_unexplained([*padded, rows]))
                if best is None or separation > best[0]:
                    best = (separation, cand)
            labels = f"{TERMS[carried].label} and {TERMS[other].label}"
            entry = {"effects": [carried, other], "separation_sigma_today": today}
            if best is None:
                entry["sentence"] = (
                    f"{labels} cannot be told apart at this arm length whatever the release: describe a rig with "
                    "another arm length or payload in config design.rigs to see the trial that would separate them"
                )
            else:
                separation, cand = best
                where = f"the described rig {cand.rig}" if cand.hypothetical else f"rig {cand.rig}"
                entry.update(
                    {
                        "rig": cand.rig,
                        "described_rig": cand.hypothetical,
                        "release_deg": cand.release_deg,
                        "separation_sigma": separation,
                        "sentence": (
                            f"to tell {labels} apart: one trial on {where}, released from {cand.release_deg:+g}°, "
                            f"would set them {separation:.1f}σ apart (today {today:.1f}σ"
                            + (
                                ", from the release transient alone, which discovery does not count: at one swing "
                                "frequency the two are one effect)"
                                if one_frequency
                                else ")"
                            )
                        ),
                    }
                )
            out.append(entry)
    return out


def _candidate_rows(d: _Designer, cand: Candidate, carried: str, rival: GroupProblem, n_cols: int, scale: float):
    """The candidate's rival sensitivities (columns: today's rival columns, any new rig's own, then its θ0, θ̇0,
    δ) and its signal of the carried effect, both times ``scale``; None if its simulation diverges."""
    fit, problem = d.fit, d.fit.problem
    try:
        record, nuisance, params = _record_for(
            fit, cand.rig, d.described.get(cand.rig), cand.release_deg, d.release_skip_s
        )
    except SimulationDiverged:
        return None
    final = GroupProblem([record], [cand.rig], problem.terms, None, problem.max_step_s)
    x = np.array([params.get(p, 0.0) for p, _ in final.columns] + list(nuisance))
    off = x.copy()
    off[next(j for j, (p, _) in enumerate(final.columns) if p == TERMS[carried].parameter)] = 0.0
    signal = final.simulate_trial(0, x) - final.simulate_trial(0, off)
    single = GroupProblem([record], [cand.rig], rival.terms, None, problem.max_step_s)
    jac = single.jacobian(np.array([params.get(p, 0.0) for p, _ in single.columns] + list(nuisance)))
    new = [c for c in single.columns if c not in rival.columns]
    total = n_cols + len(new) + 3
    full = np.zeros((jac.shape[0], total))
    for j, col in enumerate(single.columns):
        full[:, rival.columns.index(col) if col in rival.columns else n_cols + new.index(col)] = jac[:, j]
    full[:, total - 3 :] = jac[:, single.n_phys :]
    return full * scale, signal * scale
