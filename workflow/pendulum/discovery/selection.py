"""Discovery: name the physics a baseline model misses, with evidence, or say honestly that it cannot.

From the baseline variant's fits of a group's trials (one body on one or more
rigs, :mod:`pendulum.fit.group`), the residuals are diagnosed
(:mod:`pendulum.discovery.diagnosis`: residual against time, angle and velocity, the
extinction curve, the period against amplitude, spectrum and autocorrelation)
and the candidate effects of the library ranked by the extinction-curve screen.
The decision is made by refitting the output-error model with each candidate
added (forward selection), then checking that every chosen term still earns its
place with the others in (backward step).

**Evidence** for adding d coefficients (one, or one per rig for a rig's own
torque) is the likelihood ratio of the two least-squares fits,
Λ = n_eff · ln(RSS₀/RSS₁), on the same samples. The residuals are
autocorrelated, so n samples carry the information of n_eff = n/κ² independent
ones, κ² the ratio of the added coefficients' sandwich variance (AR(p) noise
model of the larger fit's residuals, bias-corrected; :mod:`pendulum.fit.uncertainty`)
to their white-noise variance, at least 1 (never more than n); Λ is then the squared sandwich t-statistic to
first order. A dissipative coefficient is bounded at 0 (the truth can sit on
the boundary), so under "no effect" Λ follows the mixture Σ_k C(d,k)/2^d χ²_k
(½χ²₀ + ½χ²₁ for one coefficient); a signed one (the restoring correction) χ²_d.

**Threshold.** A candidate is accepted when (1) its p-value is below α/m, α =
0.01 the probability that a forward step names an effect that is not there and
m the candidates tested in that step (Bonferroni), and Λ also exceeds the BIC
penalty d·ln n_eff (ΔBIC > 0, which grows stricter than the test for long
records); (2) it lowers the RMS residual on data the fit did not use (every
trial left out in turn and predicted from the others with only its θ0, θ̇0 and
offset refitted; when a rig has one trial, the last 40 % of each record
forecast from a fit to the first 60 %); (3) while structure remains after it,
it removes at least half of the residual variance above the noise floor (an
effect outside the library tilts every candidate a little: a significant but
small gain is not a discovery). Why α = 0.01: the acceptance asks at most one
false naming in 20 effect-free groups (5 %); 1 % per step leaves room for the
approximations in n_eff (κ is estimated) while real effects give Λ in the
hundreds. Backward, each chosen term must still pass (1) with m the number of
chosen terms.

**Honest endings.** ``unexplained`` is true when the final residual RMS exceeds
``misfit_ratio`` (5, :data:`pendulum.fit.checks.MISFIT_RATIO`) times the noise
floor the angle records imply (their ``noise_deg``: fifth-difference σ) *and* the residuals are not
white (Ljung–Box, p < 0.01). Two candidates whose fits differ by less than the
threshold (n_eff ln(RSS_b/RSS_a)) are ``indistinguishable`` and neither is
named; at a single swing frequency the history force is always reported with
linear damping (its equivalent there, with an added mass), since what else
separates them on one rig is the tail of the fluid's memory of the start, which
the fit models only under an assumption (at rest at the release, θ̇ growing
linearly over the skipped transient): another pendulum length separates them.
Linear damping rests on no such assumption and is named alone where it wins.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from pendulum.discovery import diagnosis, findings
from pendulum.fit.checks import MISFIT_RATIO
from pendulum.fit.group import (
    MAX_HELD_OUT_FOLDS,
    GroupFit,
    GroupProblem,
    coefficient_entries,
    forecast,
    leave_trials_out,
    ordered,
    solve_many,
    start_values,
)
from pendulum.fit.output_error import fit_trials
from pendulum.fit.records import AngleRecord, FitSettings, record_noise_rad


def _fit_warning(document: dict, warning: str) -> str:
    """A baseline fit's warning headed by the fit it is of: a trial's own, or its rig's joint fit (a trial's residual
    differs between the two: a fresh-eyes user read demo_m05's 0.662° and 0.332° under one name, 2026-12-07)."""
    trial = document.get("trial")
    if trial:
        return f"fit of {trial}: {warning.removeprefix(f'trial {trial}: ')}"
    return f"joint fit of {(document.get('rig') or {}).get('name', 'its rig')}: {warning}"


@dataclass(frozen=True)
class DiscoveryOptions:
    """The decision rule (module docstring)."""

    alpha: float = 0.01
    misfit_ratio: float = MISFIT_RATIO
    material_fraction: float = 0.5
    held_out_fraction: float = 0.4
    frequency_spread: float = 0.05  # rigs whose swing frequencies differ by less are one frequency
    whiteness_alpha: float = 0.01
    max_steps: int = 5


class Discovery:
    """One group's discovery (a body, or a rig): fits are cached by their terms; :meth:`run` gives the document.

    ``baseline_fits``: the baseline variant's fit documents (joint fits of the group's rigs, then per-trial
    ones), reused as start values, per-trial θ0, θ̇0, offset and the samples they kept; None: fitted here
    (one joint fit per rig, as the workflow does). Each record's noise floor is its noise as the angles stage
    measured it (:func:`pendulum.fit.records.record_noise_rad`).
    """

    def __init__(
        self,
        records: list[AngleRecord],
        rigs: list[str],
        baseline_terms,
        candidates,
        settings: FitSettings | None = None,
        options: DiscoveryOptions | None = None,
        baseline_fits: list[dict] | None = None,
    ):
        self.records, self.rigs = list(records), list(rigs)
        self.settings, self.options = settings or FitSettings(), options or DiscoveryOptions()
        self.baseline_terms = ordered(baseline_terms)
        self.floors = np.array([record_noise_rad(r) for r in records])
        if baseline_fits is None:
            baseline_fits = [
                fit_trials(
                    [r for r, g in zip(records, rigs, strict=True) if g == rig], self.baseline_terms, self.settings
                )
                for rig in sorted(set(rigs))
            ]
        values, nuisance, self.masks = start_values(records, rigs, baseline_fits)
        self.baseline_warnings = list(
            dict.fromkeys(_fit_warning(doc, w) for doc in baseline_fits for w in doc.get("warnings", []))
        )
        problem = GroupProblem(records, rigs, self.baseline_terms, self.masks, self.settings.max_step_s)
        self._fits = {self.baseline_terms: problem.solve(problem.start(values, nuisance), self.settings)}
        self._held_out = {}
        self.loto = len(records) > 1 and all(rigs.count(r) >= 2 for r in set(rigs))
        n_rigs = len(set(rigs))
        self.candidates = [  # the restoring correction is a rescaled inertia on one rig: never a candidate there
            c
            for c in ordered(candidates)
            if c not in self.baseline_terms and (c != "restoring_correction" or n_rigs > 1)
        ]
        self.single_frequency = self._frequency_spread() < self.options.frequency_spread

    # --- fits, noise floor, held-out data ----------------------------------

    def fit(self, terms, start: GroupFit | None = None) -> GroupFit:
        return self.fit_many([terms], start)[0]

    def fit_many(self, models, start: GroupFit | None = None) -> list[GroupFit]:
        """Fits of several term lists (cached), each started from ``start`` (default the baseline)."""
        start = start or self._fits[self.baseline_terms]
        keys = [ordered(t) for t in models]
        jobs, todo = [], [k for k in dict.fromkeys(keys) if k not in self._fits]
        for key in todo:
            problem = GroupProblem(self.records, self.rigs, key, self.masks, self.settings.max_step_s)
            x0 = problem.start(start.values, [start.nuisance(k) for k in range(len(self.records))])
            jobs.append((problem, x0, self.settings, 1e-10))
        self._fits.update(zip(todo, solve_many(jobs), strict=True))
        return [self._fits[k] for k in keys]

    @property
    def fitted_models(self) -> list[tuple[str, ...]]:
        """The term lists fitted so far, each once."""
        return list(self._fits)

    def _frequency_spread(self) -> float:
        base = self._fits[self.baseline_terms]
        omega = [diagnosis.swing_omega(base, k) for k in range(len(self.records))]
        return max(omega) / min(omega) - 1

    def floor_rad(self, fit: GroupFit) -> float:
        """The noise floor pooled over the fitted samples."""
        n = np.array([r.size for r in fit.residuals])
        return float(np.sqrt(np.sum(n * self.floors**2) / n.sum()))

    def held_out_rms(self, terms) -> float:
        """RMS residual on data the fit did not use (rule 2): left-out trials, or forecast cycles."""
        key = ordered(terms)
        if key not in self._held_out:
            full = self.fit(key)
            if self.loto:
                parts = leave_trials_out(full, self.settings)
            else:
                parts = forecast(full, self.settings, self.options.held_out_fraction)
            self._held_out[key] = float(np.sqrt(np.mean(np.concatenate(parts) ** 2)))
        return self._held_out[key]

    # --- evidence -----------------------------------------------------------

    def evidence(self, before: GroupFit, after: GroupFit, m: int) -> dict:
        """Λ = n_eff ln(RSS₀/RSS₁) for the coefficients ``after`` adds, its p-value and the threshold (rule 1)."""
        new = [j for j, c in enumerate(after.problem.columns) if c not in before.problem.columns]
        cov, white, _ = after.covariance(self.settings.max_ar_order)
        # n_eff ≤ n: an AR fit that calls the residuals anti-correlated (κ² < 1) must not multiply the
        # evidence (a new user's record counted 1150 effective of 382 samples and named a history force
        # that was not there)
        kappa2 = max(float(np.mean([cov[j, j] / white[j, j] for j in new if white[j, j] > 0] or [1.0])), 1.0)
        n, d = after.n, len(new)
        white_ratio = n * math.log(before.rss / after.rss) if after.rss > 0 else math.inf
        statistic = white_ratio / kappa2
        bounded = all(after.problem.lower_bounds(self.settings)[j] == 0 for j in new)
        n_eff = n / kappa2
        level = self.options.alpha / max(m, 1)
        threshold = max(diagnosis.critical_value(level, d, bounded), d * math.log(n_eff))
        stderr = np.sqrt(np.maximum(np.diag(cov), 0))
        return {
            "likelihood_ratio": statistic,
            "likelihood_ratio_white_noise": white_ratio,
            "effective_sample_size": n_eff,
            "n_samples": n,
            "added_coefficients": d,
            "null_distribution": diagnosis.null_distribution(d, bounded),
            "p_value": diagnosis.mixture_p_value(statistic, d, bounded),
            "level": level,
            "delta_bic": statistic - d * math.log(n_eff),
            "threshold": threshold,
            "significant": bool(statistic > threshold),
            "coefficients": {
                after.problem.labels[j]: {"value": float(after.x[j]), "stderr_statistical": float(stderr[j])}
                for j in new
            },
            "model_before": "+".join(before.problem.terms),  # the `model` keys of the residual and extinction tables
            "model_after": "+".join(after.problem.terms),
            "converged": after.converged,
            "rms_before_rad": before.rms_rad,
            "rms_after_rad": after.rms_rad,
        }

    def residual_check(self, fit: GroupFit) -> dict:
        """Residual RMS against the noise floor, and the whiteness test: is structure left?"""
        floor = self.floor_rad(fit)
        white = diagnosis.whiteness(fit)
        ratio = fit.rms_rad / floor if floor > 0 else math.inf
        return {
            "rms_rad": fit.rms_rad,
            "noise_floor_rad": floor,
            "rms_over_noise": ratio,
            "whiteness": white,
            "structured": bool(ratio > self.options.misfit_ratio and white["p_value"] < self.options.whiteness_alpha),
        }

    # --- selection ----------------------------------------------------------

    def run(self) -> dict:
        """Forward selection, the backward step, the final model with its intervals: the discovery document."""
        current, steps, rounds, chosen, excluded = self._fits[self.baseline_terms], [], [], [], set()
        while len(steps) < self.options.max_steps:
            tested = [c for c in self.candidates if c not in current.problem.terms and c not in excluded]
            if not tested:
                break
            round_, step = self._round(current, tested)
            rounds.append(round_)
            if step is None:
                break
            steps.append(step)
            chosen.append(step["effect"])
            excluded |= set(step["indistinguishable_from"])
            current = self.fit(current.problem.terms + (step["effect"],), current)
        backward = self._backward(chosen)
        removed = {b["effect"] for b in backward if not b["kept"]}
        for step in steps:
            step["kept_in_backward_step"] = step["effect"] not in removed
        final = self.fit(self.baseline_terms + tuple(c for c in chosen if c not in removed))
        return self._document(final, steps, rounds, backward)

    def _round(self, current: GroupFit, tested: list[str]) -> tuple[dict, dict | None]:
        """One forward step: the screen ranks, every candidate is refitted, the best confirmed one is taken."""
        screen = diagnosis.extinction_screen(current, tested)
        fits, evidence = {}, {}
        for name in tested:
            try:
                fits[name] = self.fit(current.problem.terms + (name,), current)
            except (ValueError, RuntimeError, ArithmeticError, np.linalg.LinAlgError) as exc:
                evidence[name] = {"significant": False, "error": f"the refit failed: {exc}"}
                continue
            evidence[name] = self.evidence(current, fits[name], len(tested))
        ranked = sorted(fits, key=lambda c: fits[c].rss) + [c for c in tested if c not in fits]
        step = None
        for name in ranked:
            if evidence[name]["significant"]:
                evidence[name].update(self._confirm(current, fits[name]))
                if evidence[name]["confirmed"]:
                    rivals = self._rivals(name, ranked, fits, evidence)
                    step = {"effect": name, "named": not rivals, "indistinguishable_from": rivals, **evidence[name]}
                    break
        candidates = [{"effect": c, **evidence[c]} for c in ranked]
        return {"model": list(current.problem.terms), "screen": screen, "candidates": candidates}, step

    def _confirm(self, before: GroupFit, after: GroupFit) -> dict:
        """Rules 2 and 3: a lower held-out RMS, and a material gain while structure remains."""
        ho_before, ho_after = self.held_out_rms(before.problem.terms), self.held_out_rms(after.problem.terms)
        excess = before.rms_rad**2 - self.floor_rad(before) ** 2
        removed = before.rms_rad**2 - after.rms_rad**2
        material = not self.residual_check(after)["structured"] or removed >= self.options.material_fraction * excess
        reasons = []
        if not ho_after < ho_before:
            reasons.append("does not lower the held-out RMS")
        if not material:
            reasons.append(
                f"removes only {100 * removed / excess:.0f} % of the residual variance above the noise floor and "
                "leaves structure (an effect outside the library?)"
            )
        return {
            "held_out_rms_before_rad": ho_before,
            "held_out_rms_after_rad": ho_after,
            "excess_variance_removed": removed / excess if excess > 0 else None,
            "confirmed": not reasons,
            "rejected_because": reasons,
        }

    def _rivals(self, best: str, ranked: list[str], fits: dict, evidence: dict) -> list[str]:
        """Candidates that explain the data as well as ``best``: n_eff ln(RSS_b/RSS_best) below its threshold.

        At one swing frequency the history force always has linear damping as its rival (module docstring).
        """
        n_eff, threshold = evidence[best]["effective_sample_size"], evidence[best]["threshold"]
        rivals = [
            c
            for c in ranked
            if c != best and evidence[c]["significant"] and n_eff * math.log(fits[c].rss / fits[best].rss) < threshold
        ]
        if self.single_frequency and best == "history_force" and "linear_damping" not in rivals:
            rivals.append("linear_damping")
        return rivals

    def _backward(self, chosen: list[str]) -> list[dict]:
        """Each chosen term refitted out of the final model: does it still pass rule 1 (m = chosen terms)?"""
        kept, out = list(chosen), []
        while kept:
            full = self.fit(self.baseline_terms + tuple(kept))
            without = self.fit_many([[t for t in full.problem.terms if t != name] for name in kept], full)
            tests = {name: self.evidence(w, full, len(kept)) for name, w in zip(kept, without, strict=True)}
            failing = [n for n in kept if not tests[n]["significant"]]
            if not failing:
                return out + [{"effect": n, "kept": True, **_brief(tests[n])} for n in kept]
            worst = min(failing, key=lambda n: tests[n]["likelihood_ratio"])
            out.append({"effect": worst, "kept": False, **_brief(tests[worst])})
            kept.remove(worst)
        return out

    # --- the document -------------------------------------------------------

    def _document(self, final: GroupFit, steps, rounds, backward) -> dict:
        base = self._fits[self.baseline_terms]
        entries, warnings = self.coefficients(final)
        check = self.residual_check(final)
        named = [s["effect"] for s in steps if s["named"] and s["kept_in_backward_step"]]
        groups = [
            {
                "effects": [s["effect"], *s["indistinguishable_from"]],
                "carried_in_model": s["effect"],
                "reason": "at one swing frequency the history force is an added mass plus a linear damping"
                if s["effect"] == "history_force" and self.single_frequency
                else "their fits differ by less than the threshold",
                "separated_by": [
                    short for short, _ in findings.separating_experiments([s["effect"], *s["indistinguishable_from"]])
                ],
                "experiment": "; or ".join(
                    how for _, how in findings.separating_experiments([s["effect"], *s["indistinguishable_from"]])
                ),
            }
            for s in steps
            if not s["named"] and s["kept_in_backward_step"]
        ]
        document = {
            "baseline": {
                "terms": list(self.baseline_terms),
                "rms_rad": base.rms_rad,
                "rms_deg": math.degrees(base.rms_rad),
                "held_out_rms_rad": self.held_out_rms(self.baseline_terms),
                "coefficients": base.coefficients,
                "residual_check": self.residual_check(base),
                "diagnosis": diagnosis.residual_diagnostics(base),
                "period_drift": diagnosis.period_drift(base),
                "fit_warnings": self.baseline_warnings,
            },
            "held_out_method": (
                "leave one trial out (its θ0, θ̇0 and offset refitted)"
                if len(self.records) <= MAX_HELD_OUT_FOLDS
                else f"trials left out in {MAX_HELD_OUT_FOLDS} folds, each predicted from a fit of the others "
                "(its θ0, θ̇0 and offset refitted)"
            )
            if self.loto
            else f"held-out cycles: the last {100 * self.options.held_out_fraction:.0f} % of each record forecast",
            "single_swing_frequency": self.single_frequency,
            "candidates": self.candidates,
            "threshold": {
                "alpha": self.options.alpha,
                "rule": "p < alpha/m (m candidates in the step, boundary mixture null) and ΔBIC > 0 with n_eff; a "
                "lower held-out RMS; while structure remains, at least half the residual variance above the "
                "noise floor removed",
                "material_fraction": self.options.material_fraction,
                "misfit_ratio": self.options.misfit_ratio,
                "whiteness_alpha": self.options.whiteness_alpha,
            },
            "rounds": rounds,
            "steps": steps,
            "backward": backward,
            "named_effects": named,
            "final_terms": list(final.problem.terms),
            "parameters": entries,
            "rms_rad": final.rms_rad,
            "rms_deg": math.degrees(final.rms_rad),
            "held_out_rms_rad": self.held_out_rms(final.problem.terms),
            "residual_check": check,
            "unexplained": check["structured"],
            "residual_pattern": diagnosis.residual_pattern(final),
            "indistinguishable": groups,
            "warnings": warnings,
        }
        document["verdict"] = findings.verdict(document)
        return document

    def coefficients(self, fit: GroupFit) -> tuple[dict, list[str]]:
        """The fit's coefficients with statistical, systematic and combined errors and 95 % intervals; warnings."""
        return coefficient_entries(fit, self.settings)

    def tables(self, document: dict):
        """The residuals and extinction curves of the models on the path (:func:`.findings.tables`)."""
        return findings.tables(self, document)


def _brief(evidence: dict) -> dict:
    keys = ("likelihood_ratio", "effective_sample_size", "p_value", "threshold", "delta_bic", "significant")
    return {k: evidence[k] for k in keys}


def discover(records, rigs, baseline_terms, candidates, **options) -> dict:
    """Run discovery on one group of trials (:class:`Discovery`) and return its document."""
    return Discovery(records, rigs, baseline_terms, candidates, **options).run()
