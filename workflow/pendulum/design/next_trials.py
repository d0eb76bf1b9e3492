"""What to film next: the 95 % half-width each coefficient would have if one more trial were added.

A group's least-squares estimate x̂ (coefficients, then θ0, θ̇0, δ per trial) has, trials independent,

    Cov = B⁻¹ M B⁻¹,   B = Σ_k J_kᵀ J_k,   M = Σ_k J_kᵀ Ω_k J_k,

J_k = ∂θ_k/∂x the sensitivities of trial k's kept samples and Ω_k its AR(p) residual-noise covariance
(the sandwich of :func:`pendulum.fit.uncertainty.sandwich_covariance`, whose bias correction is carried over
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
from dataclasses import dataclass

import pandas as pd

from pendulum.design.candidates import (
    DRAG_COEFFICIENT,
    Candidate,
    Information,
    candidate_record,
    candidate_sensitivities,
    half_widths,
    median_noise,
    today,
    with_trial,
)
from pendulum.design.separation import separations
from pendulum.design.tolerances import input_words, largest_input, measurement_advice
from pendulum.fit.group import GroupFit, GroupProblem, ordered, start_values
from pendulum.fit.uncertainty import shared_frontal_area
from pendulum.model.effects import ADDED_MASS, TERMS
from pendulum.model.physics import SimulationDiverged
from pendulum.model.rig import Rig

MIRROR_TIE = 0.005  # a release from the other side whose score is this close: either side is said
DEFAULT_RELEASES_DEG = (5.0, 10.0, 15.0, 20.0, 30.0, 45.0, 60.0, 75.0)
ROW_COLUMNS = [
    "rig",
    "described_rig",
    "release_deg",
    "coefficient",
    "value",
    "halfwidth95_today",
    "halfwidth95_predicted",
    "gain",
    "rank",
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


def coefficient_words(label: str) -> str:
    """``drag_coefficient`` → "the drag coefficient C_d"; a rig's own coefficient keeps its ``[rig]``."""
    base, _, rig = label.partition("[")
    words = COEFFICIENT_WORDS.get(base, base)
    return words + (f" of rig {rig.rstrip(']')}" if rig else "")


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


def _sentence(name: str, today_entry: dict, after: dict, cand: Candidate, either_side: bool = False) -> str:
    where = f"on the described rig {cand.rig}" if cand.hypothetical else f"on rig {cand.rig}"
    angle = f"±{abs(cand.release_deg):g}° (either side)" if either_side else f"{cand.release_deg:+g}°"
    return (
        f"release from {angle} {where}: {coefficient_words(name)} ±{_fmt(today_entry['halfwidth95'])}"
        f" → ±{_fmt(after['halfwidth95'])} (95 %)"
    )


def _fmt(value: float) -> str:
    return f"{value:.3g}"


class Designer:
    """Candidates' sensitivities computed once; information updated trial by trial."""

    def __init__(self, fit: GroupFit, parameters: dict, settings, options: DesignOptions, stated=None):
        problem = fit.problem
        self.fit, self.options, self.parameters = fit, options, parameters
        self.warnings: list[str] = []
        self.stated = dict(stated or {})
        self.tolerances = {rig: dict(problem.records[problem.rig_of.index(rig)].tolerances) for rig in problem.rigs}
        self.settings_max_ar, self.release_skip_s = settings.max_ar_order, settings.release_skip_s
        self.info, noise, self.ratio = today(fit, settings.max_ar_order)
        self.noise = median_noise(noise)
        self.values = {label: float(fit.x[j]) for j, label in enumerate(problem.labels)}
        self.systematic = {k: float(v.get("stderr_systematic", 0.0)) for k, v in parameters.items()}
        self.area = {"m2": shared_frontal_area(problem.records)[0]}  # the area C_d is divided by in the fits
        self.now = self.widths(self.info)
        self.targets = tuple(c for c in options.coefficients if c in self.now)
        for name in options.coefficients:
            if name not in self.now:
                self.warnings.append(
                    f"design.coefficients: {name} is not a coefficient of discovery's final model "
                    f"({' + '.join(problem.terms) or 'added mass only'}), so nothing is designed for it"
                )
        self.described = self._described(options, problem)
        self.sensitivities = {}
        self.records = {}  # candidate → its simulated record, nuisance and coefficients (candidate_record)
        for rig, hypothetical in [(r, False) for r in problem.rigs] + [(r, True) for r in self.described]:
            for release in options.releases_deg:
                for sign in (-1.0, 1.0):
                    cand = Candidate(rig, sign * release, hypothetical)
                    try:
                        made = candidate_record(
                            fit, rig, self.described.get(rig), cand.release_deg, self.release_skip_s
                        )
                    except SimulationDiverged:
                        continue
                    self.records[cand] = made
                    self.sensitivities[cand] = candidate_sensitivities(fit, cand, made)

    def _described(self, options: DesignOptions, problem) -> dict[str, Rig]:
        """The rigs of config ``design.rigs``: the group's first rig with the values given; one that is not a
        rig (not a pendulum, a group rig's name) is left out with a warning, the others are designed."""
        base = _rig_values(problem.records[0].rig)
        out = {}
        for name, vals in options.rigs:
            if name in problem.rigs:
                self.warnings.append(
                    f"design.rigs.{name}: a rig of the group has this name; give the described rig another name"
                )
                continue
            try:
                values = {**base, **vals}
                if "submerged_mass_kg" in vals and "displaced_volume_m3" not in vals:  # its own buoyancy, weighed
                    values.pop("displaced_volume_m3", None)
                out[name] = Rig.from_mapping(values)
            except ValueError as error:
                self.warnings.append(f"design.rigs.{name} ({problem.rigs[0]}'s values with {vals}): {error}; left out")
        return out

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
    fit: GroupFit,
    parameters: dict,
    settings,
    options: DesignOptions,
    indistinguishable: list[dict] | None = None,
    stated_tolerances: dict | None = None,
    misfit: str | None = None,
) -> tuple[dict, list[dict]]:
    """The design document and its table rows (one per candidate trial and coefficient).

    ``parameters``: the reported coefficient entries of this model (value, stderr_systematic, error_budget),
    as discovery's ``parameters`` for its final model. ``misfit``: discovery's verdict where its final model
    leaves structure (``unexplained``): the predictions assume the model right, so the document says they
    wait on the missing effect.
    """
    d = Designer(fit, parameters, settings, options, stated_tolerances)
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
    for name in {r["coefficient"] for r in rows}:  # 1: the candidate leaving this coefficient's narrowest interval
        mine = sorted((r for r in rows if r["coefficient"] == name), key=lambda r: r["halfwidth95_predicted"])
        for rank, row in enumerate(mine, start=1):
            row["rank"] = rank
    recommendations, info = [], d.info
    for _ in range(options.recommend if d.targets else 0):
        before, before_info = d.widths(info), info
        cand, after, widths = d.best(info, d.targets)
        if _score(before, d.targets) - _score(widths, d.targets) < MIN_GAIN * _widest(before, d.targets):
            break  # no candidate shrinks what the targets' widths are made of: their tolerances
        info = after
        widest = max(d.targets, key=lambda c: _reducible(before[c]))
        again = any((r["rig"], r["release_deg"]) == (cand.rig, cand.release_deg) for r in recommendations)
        mirror = Candidate(cand.rig, -cand.release_deg, cand.hypothetical)
        score = _score(widths, d.targets)  # the other side as good: the sign is no advice (a reviewer, 2026-12-02)
        either = (
            mirror in d.sensitivities
            and abs(_score(d.widths(d.added(before_info, mirror)), d.targets) - score) <= MIRROR_TIE * score
        )
        sentence = _sentence(widest, before[widest], widths[widest], cand, either) + (" (again)" if again else "")
        recommendations.append(
            {
                "rig": cand.rig,
                "described_rig": cand.hypothetical,
                "release_deg": cand.release_deg,
                "predicted": {c: widths[c]["halfwidth95"] for c in d.targets},
                "sentence": sentence,
            }
        )
    limits = sorted({input_words(largest_input(d.parameters.get(c, {}))[0]) for c in d.targets} - {""})
    fewer = None
    if d.targets and 0 < len(recommendations) < options.recommend:  # asked for more: say why not
        fewer = (
            f"{len(recommendations)} of the {options.recommend} trials asked for (design.recommend): a further "
            "trial would narrow "
            + " or ".join(coefficient_words(c) for c in d.targets)
            + " by less than 1 %; "
            + ("the rest of its interval is" if len(d.targets) == 1 else "the rest of their intervals is")
            + " set by the rig values' tolerances (largest: "
            + ", ".join(limits)
            + ")"
        )
    if d.targets and not recommendations:
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
        "fewer_recommended": fewer,
        "to_target": {c: _to_target(d, c) for c in d.targets},
        "separating": separations(d, indistinguishable or []),
        "warnings": d.warnings,
        "model_misfit": (
            f"discovery's final model does not fit these records: {misfit.removeprefix('unexplained: ')}. These "
            "predictions assume it right: find what it misses before filming for narrower intervals"
            if misfit
            else None
        ),
        "method": (
            "sandwich covariance (trials independent, AR(p) noise) with one more simulated trial per candidate; "
            "the systematic part carried unchanged; the model assumed right"
        ),
    }, rows


def _to_target(d: Designer, name: str) -> dict:
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
        advice = measurement_advice(
            name, coefficient_words(name), entry, d.parameters.get(name, {}), target, d.tolerances, d.stated
        )
        return {**out, "further_trials": None, "reachable": False, **advice}
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
