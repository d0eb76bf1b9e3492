"""Which variant to trust: the summary box and the model comparison.

The summary box recommends, per rig, the joint fit of the best-supported variant with its consistency verdict and
the warnings that matter; the model comparison sets the variants side by side (RMS, ΔAIC/ΔBIC, consistency) and
weighs the evidence for each added term."""

from __future__ import annotations

import re

import numpy as np

from pendulum.design.tolerances import input_words, largest_input, split_key
from pendulum.model.effects import TERMS, term_for_parameter
from pendulum.outcomes import MISFIT_MARK
from pendulum.report.checks import MANY_TRIALS, misfits_together
from pendulum.report.data import ReportData, failure_text, is_ok, nested_parents, problem_text, record_problems
from pendulum.report.format import (
    COEFFICIENTS,
    TERM_LABELS,
    UNRELIABLE_STYLE,
    esc,
    estimate_cell,
    estimate_parts,
    fmt,
    garbage_badge,
    is_finite,
    reaches_bound,
    table_html,
    td,
)
from pendulum.report.track_notes import tracking_note

TRADED = re.compile(r"(\w+) and (\w+) are (-?[0-9.]+) correlated")
TRADED_LIMIT = 0.99  # |correlation| of two coefficients in a joint fit at which the records cannot tell them apart


def _traded_against(name: str, warnings: list[str]) -> tuple[str, float] | None:
    """The coefficient that ``name`` trades against in a fit (its warning "a and b are r correlated", |r| ≥
    :data:`TRADED_LIMIT`), and r; None. The apple clip in air (22° to 18°): linear damping at its bound, −1.000
    correlated with C_dA, was called "not supported" where the record cannot tell the two laws apart (2026-12-02)."""
    for warning in warnings:
        found = TRADED.search(warning)
        if found and name in found.group(1, 2) and abs(float(found.group(3))) >= TRADED_LIMIT:
            other = found.group(2) if found.group(1) == name else found.group(1)
            return other, float(found.group(3))
    return None


def unresolved_sentence(label: str, entry: dict) -> str:
    """Why a coefficient is not resolved from its bound, naming the largest input where the rig values'
    tolerances dominate its uncertainty (more trials do not help then)."""
    bound = fmt(entry["lower_bound"], 3)
    text = f"{label[:1].upper()}{label[1:]} is not resolved from {bound}: its 95 % interval reaches {bound}"
    largest = largest_input(entry)[0]
    if largest and (entry.get("stderr_systematic") or 0) > (entry.get("stderr_statistical") or 0):
        text += (
            f"; most of its uncertainty is the rig values' (largest: {input_words(largest)}), which more trials "
            "do not reduce (What to film next)"
        )
    return text + "."


def default_tolerance_sentence(label: str, entry: dict, stated: dict, rig: str) -> str:
    """Where a coefficient's interval rests mostly on a rig value whose tolerance nobody stated (the default
    share of its value), a sentence saying so ('' otherwise): the apple in air with L = 1.05 m gave m_a
    0.00088 kg [0.00015, 0.00161] on the arm length's default 0.2 % (a reviewer, 2026-12-02)."""
    largest = largest_input(entry, rig_values_only=True)[0]
    if not largest or not (entry.get("stderr_systematic") or 0) > (entry.get("stderr_statistical") or 0):
        return ""
    if split_key(largest)[0] in stated:
        return ""
    return (
        f" {label[:1].upper()}{label[1:]}'s interval rests mostly on {input_words(largest)}'s tolerance, the "
        f"default share of its value, not one stated for the rig: state yours (rigs.{rig}.tolerances in "
        "config.yaml, or tolerances in the sidecar that gives the value)."
    )


class ComparisonSections(ReportData):
    """The summary box (recommended coefficients per rig) and the model comparison with term-by-term evidence."""

    def _rig_mismatch_note(self, trials: list[str]) -> str:
        """Where the rig's values cannot give its trials' periods (their fits refused: ``rig_mismatch``), one
        sentence that says so with the numbers and what to give; empty otherwise."""
        found = {}
        for trial in trials:
            for variant in self.order:
                for entry in (self.fits.get((variant, trial)) or {}).get("rig_mismatch", []):
                    found.setdefault(entry["trial"], entry)
        if not found:
            return ""
        periods = [e.get("swing_period_s") or e["period_s"] for e in found.values()]
        fastest = min(e["fastest_period_s"] for e in found.values())
        span = (
            f"its period {min(periods):.4g} s"
            if len(periods) == 1
            else f"their periods {min(periods):.4g}–{max(periods):.4g} s"
        )
        lengths = [9.81 * e["period_s"] ** 2 / (4 * np.pi**2) for e in found.values()]  # simple: L = g T₀²/4π²
        simple = f"{min(lengths):.3g}" if len(lengths) == 1 else f"{min(lengths):.3g}–{max(lengths):.3g}"
        return (
            f" The rig's values cannot give the swing of {len(found)} of its {len(trials)} trial(s): "
            f"{span} as swung, where these values allow {fastest:.4g} s at the least (at small amplitude); "
            f"they are another pendulum's (a simple pendulum of that period is {simple} m long). "
            "Give each pendulum its own rig in the trials' sidecars (<code>rig</code>, "
            "<code>mass_kg</code>, <code>length_m</code>, <code>frontal_area_m2</code>, "
            "<code>displaced_volume_m3</code> and <code>fluid_density_kg_m3</code>: 1.2 in air, where water's 1000 "
            "is the default; docs/your-data.md); their tracks and angle records stand (Tracking quality)."
        )

    def summary_box(self) -> str:
        """Recommended coefficients per rig (joint fit of the best-supported variant), verdict, warnings."""
        boxes = []
        for rig in self.rig_names:
            trials = self.rig_trials(rig)
            if not trials:
                continue
            best = self.best.get(rig)
            if best is None:
                boxes.append(
                    f'<section class="summary-box"><h3>Rig {esc(rig)}</h3><p class="warn">No joint fit succeeded: '
                    f"no coefficients can be recommended.{self._rig_mismatch_note(trials)} See the failed trials "
                    "below.</p></section>"
                )
                continue
            variant = best["variant"]
            joint = self.joint.get((variant, rig), {})
            truths = [self.truth.get(t) for t in trials if t in self.truth]
            header = ["coefficient", "estimate", "95 % interval"] + (["truth (synthetic)"] if truths else [])
            rows = []
            joint_problems = record_problems(joint)
            # a model that misses the record by far more than its noise: the best of the variants tried, not a
            # recommendation (its coefficients absorb what it misses; their intervals do not cover that): no bold
            misfit = any(MISFIT_MARK in w for w in joint.get("warnings") or [])
            for name, entry in joint.get("parameters", {}).items():
                symbol, label, unit = COEFFICIENTS.get(name, (esc(name), name, ""))
                value, qualifier = estimate_parts(entry)
                row = [td(f"{label}, {symbol} ({unit})" if unit != "–" else f"{label}, {symbol}")]
                if joint_problems:  # garbage in: struck, grey, never a plain number
                    row += [
                        f'<td class="num unreliable" style="{UNRELIABLE_STYLE}"><s>{esc(value)}</s></td>',
                        f'<td class="num unreliable" style="{UNRELIABLE_STYLE}"><s>{esc(qualifier)}</s> '
                        f"{garbage_badge(joint_problems[0])}</td>",
                    ]
                elif reaches_bound(entry):  # not a measurement to recommend: no bold
                    row += [
                        td(esc(value), "num"),
                        td(f"{esc(qualifier)} (reaches {fmt(entry['lower_bound'], 3)})", "num"),
                    ]
                else:
                    row += [td(esc(value) if misfit else f"<b>{esc(value)}</b>", "num"), td(esc(qualifier), "num")]
                if truths:
                    row.append(td(esc(self._truth_text(trials, name)), "num"))
                rows.append(row)
            table = table_html(header, rows, caption="", table_id=f"recommended-{rig}")
            others = [v for v in self.order if v != variant and (v, rig) in self.joint and is_ok(self.joint[(v, rig)])]
            delta = "; ".join(f"{esc(v)} +{fmt(best['delta_aic'].get(v), 3)}" for v in others if v in best["delta_aic"])
            tie, choice = self._choice_note(rig, variant, best)
            bic_note = "BIC agrees" if best["bic_best"] == variant else f"BIC prefers {esc(best['bic_best'])}"
            bic_note = "" if tie else f"; {bic_note}"  # a tie: BIC's difference is only the penalty too
            basis = f"Chosen by the lowest {esc(best['basis'])}" + (f" (ΔAIC: {delta}{bic_note})." if delta else ".")
            basis += choice
            warnings = self._summary_warnings(rig, variant, joint, best)
            warn_html = (
                '<ul class="warnings">' + "".join(f"<li>{w}</li>" for w in warnings) + "</ul>"
                if warnings
                else "<p>No warnings.</p>"
            )
            title = (
                "Best of the variants tried, none fits within the record's noise"
                if misfit
                else "Recommended coefficients"
            )
            boxes.append(
                f'<section class="summary-box" id="summary-{esc(rig)}">'
                f"<h3>{title} — rig {esc(rig)}: joint fit of {len(joint.get('trials', {}))} "
                f"trial(s), variant {esc(self.variant_label(variant))}</h3>{table}"
                f'<p class="basis">{basis}</p>'
                f'<p class="verdict"><b>Consistency:</b> {self._verdict_sentence(rig, variant)}</p>'
                f"<p><b>Warnings that matter:</b></p>{warn_html}</section>"
            )
        return "".join(boxes) or '<p class="warn">No trials: nothing to report.</p>'

    def _choice_note(self, rig: str, variant: str, best: dict) -> tuple[bool, str]:
        """What the choice rests on where the richer variants fit no better (every added coefficient at its bound,
        the RMS within 0.1 %): their ΔAIC is only their parameter penalty, so the variants tie and the simplest is
        given; and where an added term trades against one of the chosen variant's (the rig's evidence table, linked:
        its number is not known yet, the summary comes first), the records cannot
        tell those laws apart. The apple in air (2026-12-02): "chosen by ΔAIC 2 and 4" said neither. (tie, text)"""
        chosen = self.joint.get((variant, rig)) or {}
        richer = [
            v
            for v in self.order
            if set(self.variants[variant]) < set(self.variants[v]) and is_ok(self.joint.get((v, rig)))
        ]
        if not richer or not is_finite(chosen.get("rms_deg")) or not chosen["rms_deg"]:
            return False, ""
        out = ""
        added = {t for v in richer for t in set(self.variants[v]) - set(self.variants[variant])}
        tie = all(
            abs(self.joint[(v, rig)]["rms_deg"] / chosen["rms_deg"] - 1) < 1e-3
            and all(
                (self.joint[(v, rig)]["parameters"].get(TERMS[t].parameter) or {}).get("at_bound")
                for t in set(self.variants[v]) - set(self.variants[variant])
            )
            for v in richer
        )
        if tie:
            terms = ", ".join(esc(TERM_LABELS.get(t, t)) for t in sorted(added, key=list(TERMS).index))
            out += (
                f" The richer variants fit no better: their added terms ({terms}) end at their bound of 0 and the RMS "
                "is unchanged, so their higher AIC and BIC are only the penalty for their extra parameters, not "
                "evidence for the chosen law: the variants tie, and the simplest is given."
            )
        said = set()  # a term tested by two pairs of variants (each one term apart) is said once
        for e in self.term_evidence_rows(rig, best):
            rival = term_for_parameter(e["rival"][0]) if e.get("rival") else None
            if rival and rival.name in self.variants[variant] and (e["term"], rival.name) not in said:
                said.add((e["term"], rival.name))
                out += (
                    f" These records cannot tell {esc(TERM_LABELS.get(e['term'], e['term']))} from "
                    f'{esc(TERM_LABELS.get(rival.name, rival.name))} (<a href="#term-evidence-{esc(rig)}">the '
                    f"evidence for each added term, rig {esc(rig)}</a>: the two trade one for the other, "
                    f"correlation {fmt(e['rival'][1], 3)}): the coefficients above give the swing's whole damping as "
                    f"if it were all {esc(TERM_LABELS.get(rival.name, rival.name))}; releases over a wider range of "
                    "amplitudes would separate the two laws."
                )
        return tie, out

    def _verdict_sentence(self, rig: str, variant: str) -> str:
        joint = self.joint.get((variant, rig), {})
        consistency = joint.get("consistency") or {}
        verdict = consistency.get("verdict", "not tested")
        n = len(joint.get("trials", {}))
        scale = {
            name: p.get("scale_factor")
            for name, p in (consistency.get("parameters") or {}).items()
            if is_finite(p.get("scale_factor"))
        }
        worst = max(scale, key=scale.get) if scale else None
        others = [
            f"{esc(v)}: {esc((self.joint[(v, rig)].get('consistency') or {}).get('verdict', 'not tested'))}"
            for v in self.order
            if v != variant and is_ok(self.joint.get((v, rig)))
        ]
        sentence = (
            f"under the {esc(variant)} model the {n} trial(s) are <b>{esc(verdict)}</b> "
            f"({esc(_in_words(consistency.get('explanation', '')))}"
            + (
                f"; largest scale factor S = {fmt(scale[worst], 2)} for {esc(COEFFICIENTS.get(worst, ('', worst))[1])}"
                if worst
                else ""
            )
            + ")"
            + (f"; for comparison, {'; '.join(others)}" if others else "")
            + "."
        )
        return sentence[0].upper() + sentence[1:]

    def _summary_warnings(self, rig: str, variant: str, joint: dict, best: dict) -> list[str]:
        out = []
        failed = self.failed_trials()
        failed = failed[failed.trial.isin(self.rig_trials(rig))]
        if len(failed):
            names = ", ".join(esc(t) for t in failed.trial)
            out.append(
                f'<span class="warn">{len(failed)} trial(s) failed and are not in the fit: {names}</span> '
                '(see <a href="#failed-trials">Failed trials</a>).' + self._rig_mismatch_note(self.rig_trials(rig))
            )
        joint_problems = record_problems(joint)
        if joint_problems:
            out.append(
                f'{garbage_badge()} <span class="warn">The recommended joint fit itself rests on an unreliable '
                f"record: its coefficients are not measurements</span> ({esc(joint_problems[0])})."
            )
        unreliable, n_fits = self.unreliable_fits(self.rig_trials(rig))
        if unreliable:
            trials = sorted({t for _, t in unreliable}, key=self.rig_trials(rig).index)
            items = "; ".join(f"<b>{esc(t)}</b>: {esc(problem_text(t, self.trial_problems(t)[0]))}" for t in trials)
            out.append(
                f'{garbage_badge()} <span class="warn">{len(unreliable)} of {n_fits} fits rest on unreliable '
                f"records</span> (garbage in; coefficients struck through in Table 3, the joint fits leave these "
                f"trials out): {items}."
            )
        said = set(failed.trial) | {t for _, t in unreliable}
        left_out = {
            t: r
            for t, r in self.left_out(rig).items()
            if not (t in said and (r[0].startswith("unreliable record") or t in set(failed.trial)))
        }
        if left_out:
            items = "; ".join(
                esc(", ".join(ts))
                + ("" if len(vs) == len(self.order) else f" (by {esc(', '.join(vs))})")
                + f" — {esc(r)}"
                for ts, r, vs in self.grouped(left_out)
            )
            out.append(f"Left out of the joint fits: {items}.")
        if not best["comparable"]:
            out.append("The variants' joint fits used different samples: their AIC values are not strictly comparable.")
        stated = self.rig_tolerances_used(rig)[0] if hasattr(self, "rig_tolerances_used") else {}
        for name, entry in joint.get("parameters", {}).items():
            unstated = default_tolerance_sentence(COEFFICIENTS.get(name, ("", name))[1], entry, stated, rig)
            if reaches_bound(entry):
                out.append(esc(unresolved_sentence(COEFFICIENTS.get(name, ("", name))[1], entry)) + esc(unstated))
            elif entry.get("at_bound"):
                out.append(
                    f"{esc(COEFFICIENTS.get(name, ('', name))[1])} is at its lower bound: "
                    "an upper limit, not a measurement."
                )
            elif entry.get("identifiable") is False:
                out.append(f"{esc(COEFFICIENTS.get(name, ('', name))[1])} is not identifiable from these records.")
            elif unstated:
                out.append(esc(unstated.strip()))
        if (joint.get("consistency") or {}).get("verdict") == "inconsistent":
            out.append(
                "The per-trial estimates disagree beyond their intervals: the joint interval is widened by S, "
                "but the model may miss physics."
            )
        for w in misfits_together([w for w in joint.get("warnings", []) if "lower bound" not in w]):
            if "not identifiable" not in w:  # said above, in words
                out.append(esc(w))
        per_trial = [  # other than the garbage-in problems, said above
            t
            for t in self.rig_trials(rig)
            if is_ok(self.fits.get((variant, t)))
            and set(self.fits[(variant, t)].get("warnings", [])) - set(record_problems(self.fits[(variant, t)]))
        ]
        if per_trial:
            out.append(
                f"Per-trial {esc(variant)} fits with warnings: {', '.join(esc(t) for t in per_trial)} (Table 3)."
            )
        fitted = set(joint["trials"] if "trials" in joint else self.rig_trials(rig))  # not a failed trial's record
        tracking = [
            f"<b>{esc(t)}</b>: {esc(n)}"
            for t in self.rig_trials(rig)
            if t in fitted and (n := tracking_note(self.docs.get((t, "tracks")), self.docs.get((t, "angles"))))
        ]
        said = "What the fitted videos' records carry (Tracking quality)"
        if len(tracking) > MANY_TRIALS:  # a lab's many trials: folded, not a page of text in the summary
            out.append(f"<details><summary>{said}: {len(tracking)} trials</summary>{'; '.join(tracking)}.</details>")
        elif tracking:
            out.append(f"{said}: " + "; ".join(tracking) + ".")
        if not self.provenance.get("commit"):
            out.append("Not built from a git commit: the code version of these results is not recorded.")
        elif self.provenance.get("dirty"):
            out.append("The work tree had uncommitted changes: the commit does not fully identify the code.")
        return out

    def model_comparison(self) -> str:
        """Per rig: RMS, AIC/BIC and consistency per variant, and the evidence for each added term."""
        out = []
        for rig in self.rig_names:
            best = self.best.get(rig)
            trials = self.rig_trials(rig)
            rows, attrs = [], []
            for v in self.order:
                joint = self.joint.get((v, rig))
                if not is_ok(joint):
                    rows.append([td(esc(v)), td(esc(failure_text(joint)), "na fail", span=8)])
                    attrs.append({"data-variant": v})
                    continue
                clean = [t for t in trials if is_ok(self.fits.get((v, t))) and not record_problems(self.fits[(v, t)])]
                lag1 = [self.fits[(v, t)]["trials"][t].get("residual_lag1_autocorrelation") for t in clean]
                lag1 = [x for x in lag1 if is_finite(x)]
                ratio = [
                    self.fits[(v, t)]["rms_deg"] / self.docs[(t, "angles")]["noise_deg"]
                    for t in clean
                    if is_ok(self.fits.get((v, t)))
                    and is_ok(self.docs.get((t, "angles")))
                    and is_finite(self.docs[(t, "angles")].get("noise_deg"))
                    and self.docs[(t, "angles")]["noise_deg"] > 0
                ]
                consistency = joint.get("consistency") or {}
                s_max = max(
                    (
                        p.get("scale_factor")
                        for p in (consistency.get("parameters") or {}).values()
                        if is_finite(p.get("scale_factor"))
                    ),
                    default=None,
                )
                problems = record_problems(joint)
                rows.append(
                    [
                        td(
                            (f"<b>{esc(v)}</b>" if best and v == best["variant"] else esc(v))
                            + (f" {garbage_badge(problems[0])}" if problems else "")
                        ),
                        td(esc(", ".join(TERM_LABELS.get(t, t) for t in self.variants[v]) or "—")),
                        td(str(joint.get("n_parameters", "—")), "num"),
                        td(esc(fmt(joint["rms_deg"], 2)), "num"),
                        td(esc(fmt(float(np.median(ratio)), 2)) if ratio else "—", "num"),
                        td(esc(fmt(float(np.median(lag1)), 2)) if lag1 else "—", "num"),
                        td(esc(fmt(best["delta_aic"].get(v), 3)) if best and v in best["delta_aic"] else "—", "num"),
                        td(esc(fmt(best["delta_bic"].get(v), 3)) if best and v in best["delta_bic"] else "—", "num"),
                        td(
                            esc(consistency.get("verdict", "—"))
                            + (f" (S<sub>max</sub> = {esc(fmt(s_max, 2))})" if s_max else "")
                        ),
                    ]
                )
                attrs.append({"data-variant": v})
            unreliable = sorted({t for _, t in self.unreliable_fits(trials)[0]}, key=trials.index)
            header = [
                "variant",
                "damping terms",
                "parameters",
                "joint RMS (°)",
                "RMS / noise (median)",
                "residual lag-1 autocorr. (median)",
                "ΔAIC",
                "ΔBIC",
                "consistency",
            ]
            caption = self.table_caption(
                f"Model comparison, rig {esc(rig)}: per variant the joint fit's RMS residual, the per-trial RMS over "
                "the record's noise (Table 2's; the RMS of each trial's own fit, the median over the trials), the "
                "lag-1 autocorrelation of the per-trial residuals, ΔAIC and ΔBIC against "
                f"the best variant ({esc(best['basis']) if best else 'no fits'}), and the consistency of the per-trial "
                "estimates. Caveat: AIC and BIC treat the samples as independent; the residuals are autocorrelated "
                "(lag-1 up to the value shown), so the effective number of samples is smaller and the differences "
                "overstate the evidence. Read them with the RMS against the noise and the consistency across trials."
                + (
                    f" The medians leave out the per-trial fits on unreliable records ({esc(', '.join(unreliable))}), "
                    "as the joint fits do."
                    if unreliable
                    else ""
                )
            )
            out.append(table_html(header, rows, caption=caption, table_id=f"model-comparison-{rig}", row_attrs=attrs))
            out.append(self._term_evidence(rig, best))
        return "".join(out)

    def term_evidence_rows(self, rig: str, best: dict | None) -> list[dict]:
        """Each added term: nested variant pair, ΔAIC, ΔBIC, RMS ratio, the joint coefficient, a verdict."""
        rows = []
        pairs = [(variant, parent) for variant in self.order for parent in nested_parents(self.variants, variant)]
        for v, parent in pairs:
            child, base = self.joint.get((v, rig)), self.joint.get((parent, rig))
            if not (is_ok(child) and is_ok(base)):
                continue
            term = (set(self.variants[v]) - set(self.variants[parent])).pop()
            name = TERMS[term].parameter
            entry = child["parameters"].get(name, {})
            same = child.get("samples_digest") == base.get("samples_digest")
            d_aic, d_bic = base["aic"] - child["aic"], base["bic"] - child["bic"]
            rms_ratio = base["rms_deg"] / child["rms_deg"] if child["rms_deg"] else float("inf")
            rival = _traded_against(name, child.get("warnings") or [])
            if not same:
                verdict = "not comparable: the two fits used different samples"
            elif rival:
                verdict = (
                    f"indistinguishable on these records: its coefficient trades against {rival[0]} (correlation "
                    f"{fmt(rival[1], 3)}); a wider range of amplitudes would separate them"
                )
            elif entry.get("at_bound"):
                verdict = "not supported: the coefficient stays at its bound"
            elif entry.get("identifiable") is False:
                verdict = "not supported: the coefficient is not identifiable"
            elif d_bic > 10 and rms_ratio > 1.2:
                verdict = f"supported: the RMS falls {fmt(rms_ratio, 2)}× and ΔBIC > 10"
            elif d_bic > 10:
                verdict = "weak: ΔBIC > 10 but the RMS hardly changes (autocorrelated residuals inflate ΔBIC)"
            else:
                verdict = "not supported"
            rows.append(
                {
                    "term": term,
                    "parent": parent,
                    "variant": v,
                    "delta_aic": d_aic,
                    "delta_bic": d_bic,
                    "rms_ratio": rms_ratio,
                    "entry": entry,
                    "verdict": verdict,
                    "rival": rival if same else None,
                }
            )
        return rows

    def _no_term_evidence(self) -> str:
        """Why no term is tested on its own: the fits of the pairs one term apart failed, or no pair is one apart."""
        wider = [
            (base, v, sorted(set(self.variants[v]) - set(self.variants[base])))
            for v in self.order
            for base in self.order
            if set(self.variants[base]) < set(self.variants[v])
        ]
        if not wider:
            return "No variant holds every term of another, so no term is compared on its own."
        single = [f"{esc(base)} → {esc(v)}" for base, v, extra in wider if len(extra) == 1]
        if single:  # pairs one term apart whose joint fits did not both succeed here
            pairs = ", ".join(single)
            return f"No term is compared on its own: the joint fits of {pairs} (one term apart) did not both succeed."
        base, v, extra = min(wider, key=lambda w: len(w[2]))
        names = " and ".join(esc(TERM_LABELS.get(t, t)) for t in extra)
        return (
            f"No two variants differ by one term, so no term is tested on its own: {esc(base)} → {esc(v)} adds "
            f"{len(extra)} at once ({names}). A variant with one of them added to {esc(base)} (config "
            "<code>variants</code>) tests each."
        )

    def _term_evidence(self, rig: str, best: dict | None) -> str:
        evidence = self.term_evidence_rows(rig, best)
        if not evidence:
            return f"<p>{self._no_term_evidence()}</p>"
        rows = [
            [
                td(esc(TERM_LABELS.get(e["term"], e["term"]))),
                td(f"{esc(e['parent'])} → {esc(e['variant'])}"),
                td(esc(fmt(e["delta_aic"], 3)), "num"),
                td(esc(fmt(e["delta_bic"], 3)), "num"),
                td(esc(fmt(e["rms_ratio"], 3)), "num"),
                estimate_cell(e["entry"]),
                td(esc(e["verdict"])),
            ]
            for e in evidence
        ]
        header = [
            "added term",
            "variants",
            "AIC drop",
            "BIC drop",
            "RMS ratio (before/after)",
            "coefficient (joint, 95 %)",
            "evidence",
        ]
        caption = self.table_caption(
            f"Evidence for each added term, rig {esc(rig)}: the drop of the joint fits' AIC and BIC when the term "
            "is added to the nested simpler variant, the ratio of their RMS residuals and the term's joint "
            "coefficient. "
            "A term is called supported when its coefficient is clear of its bound, the RMS falls by more than 20 % "
            "and BIC drops by more than 10."
        )
        return table_html(header, rows, caption=caption, table_id=f"term-evidence-{rig}")


def _in_words(text: str) -> str:
    """A fit's sentence with its coefficients' field names (``added_mass_kg``) as the report names them."""
    for name, (_, words, _) in COEFFICIENTS.items():
        text = re.sub(rf"\b{name}\b", words, text)
    return text
