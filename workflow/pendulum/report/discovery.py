"""The report's discovery section: per group, the physics the baseline model misses, with its evidence.

Reads what the rule ``discovery`` wrote (``results/discovery/<group>.json`` and its residual and
extinction tables; see :mod:`pendulum.discovery.selection`) and shows, per group: the one-line verdict, each
forward step's evidence (Λ = n_eff ln(RSS₀/RSS₁) against its threshold, p, ΔBIC, the RMS residual
before → after in sample and held out), every candidate tested, the residuals of each model on
the path, the extinction curve measured and as each model predicts it, the honest endings
(unexplained structure, indistinguishable effects with the experiment that separates them), the
final coefficients with 95 % intervals and the trials left out. Nothing is fitted here.
"""

from __future__ import annotations

import math
import re
from functools import partial

from pendulum.discovery.findings import PATTERN_PLACE, part_name
from pendulum.model.effects import TERMS, term_for_parameter
from pendulum.report.data import ReportData, failure_text, is_ok, read_json, read_table
from pendulum.report.discovery_figures import figures_html, model_key, model_label
from pendulum.report.format import (
    COEFFICIENTS,
    esc,
    estimate_parts,
    fmt,
    is_finite,
    reaches_bound,
    table_html,
    td,
)

_PLAIN = lambda text: text  # noqa: E731  (a caption left unnumbered)


# ---------------------------------------------------------------------------
# Names and numbers


def sub(symbol: str) -> str:
    """A library symbol as HTML: ``τ_f`` → ``τ<sub>f</sub>``."""
    return re.sub(r"_(\w)", r"<sub>\1</sub>", esc(symbol))


def effect_name(effect: str) -> str:
    """An effect's physical name with its library name, e.g. ``bearing (Coulomb) friction (coulomb_friction)``."""
    term = TERMS.get(effect)
    return f"{esc(term.label)} <code>{esc(effect)}</code>" if term else f"<code>{esc(effect)}</code>"


def coefficient_label(key: str) -> str:
    """A coefficient of a discovery document (``friction_torque_nm[short_arm]`` for a rig's own) with unit."""
    base, _, rig = key.partition("[")
    term = term_for_parameter(base)
    if term is not None:
        symbol, label, unit = sub(term.symbol), esc(term.label), term.unit
    elif base in COEFFICIENTS:
        symbol, label, unit = COEFFICIENTS[base]
    else:
        symbol, label, unit = esc(base), esc(base), ""
    text = f"{label}, {symbol}" + (f" ({esc(unit)})" if unit not in ("", "1", "–") else "")
    return text + (f", rig {esc(rig.rstrip(']'))}" if rig else "")


def sentence(text: str) -> str:
    return text[:1].upper() + text[1:]


def prose(text: str) -> str:
    """Plain text of a document as HTML: `code` in code type, ω^−½ as a superscript."""
    text = re.sub(r"`([^`]+)`", r"<code>\1</code>", esc(text))
    return re.sub(r"\^([−-]?[\w½]+)", r"<sup>\1</sup>", text)


def p_text(p) -> str:
    """A p-value to two significant figures; below 10⁻¹⁰ only the bound (the tail is no better known)."""
    if not is_finite(p):
        return "—"
    return "< 10⁻¹⁰" if float(p) < 1e-10 else fmt(p, 2)


def deg(rad) -> str:
    return fmt(math.degrees(float(rad)), 2) if is_finite(rad) else "—"


def shrink_cell(before, after) -> str:
    """RMS before → after in degrees, with the factor it shrank by."""
    if not (is_finite(before) and is_finite(after)):
        return td("—", "na")
    factor = float(before) / float(after) if float(after) > 0 else math.inf
    note = f"{fmt(factor, 2)}× smaller" if factor >= 1 else f"{fmt(1 / factor, 2)}× larger"
    return td(f'<span class="v">{deg(before)} → {deg(after)}</span><span class="q">{note}</span>', "num")


def evidence_cells(ev: dict) -> list[str]:
    """Λ against its threshold, n_eff (of n), p (against α/m), ΔBIC."""
    if "likelihood_ratio" not in ev:
        return [td("—", "na")] * 4
    sign = "&gt;" if ev.get("significant") else "≤"
    n = f" of {ev['n_samples']}" if "n_samples" in ev else ""
    level = f'<span class="q">level {fmt(ev["level"], 2)}</span>' if is_finite(ev.get("level")) else ""
    statistic = ev["likelihood_ratio"] if abs(ev["likelihood_ratio"]) >= 1e-3 else 0.0  # no rounding noise
    return [
        td(f"{fmt(statistic, 3)} {sign} {fmt(ev['threshold'], 3)}", "num"),
        td(f"{fmt(ev['effective_sample_size'], 2)}{n}", "num"),
        td(f'<span class="v">{p_text(ev["p_value"])}</span>{level}', "num"),
        td(fmt(ev["delta_bic"], 3), "num"),
    ]


# ---------------------------------------------------------------------------
# Tables and text


def verdict_html(document: dict) -> str:
    return f'<p class="verdict discovery-verdict"><b>{esc(document.get("verdict", ""))}</b></p>'


def outcome_text(step: dict) -> str:
    if not step.get("kept_in_backward_step", True):
        return '<span class="warn">removed in the backward step</span>'
    if step.get("indistinguishable_from"):
        rivals = " or ".join(TERMS[e].label if e in TERMS else e for e in step["indistinguishable_from"])
        return f'<span class="warn">indistinguishable from {esc(rivals)}: not named</span>'
    return "<b>named</b>"


def steps_table(document: dict, caption=_PLAIN) -> str:
    """One row per forward step: the effect, its evidence, the RMS before → after in sample and held out."""
    header = ["step", "effect added", "Λ vs threshold", "n<sub>eff</sub>", "p", "ΔBIC"]
    header += ["RMS in sample (°)", "RMS held out (°)", "outcome"]
    rows = [
        [td(str(k)), td(effect_name(s["effect"]))]
        + evidence_cells(s)
        + [
            shrink_cell(s["rms_before_rad"], s["rms_after_rad"]),
            shrink_cell(s.get("held_out_rms_before_rad"), s.get("held_out_rms_after_rad")),
            td(outcome_text(s)),
        ]
        for k, s in enumerate(document["steps"], 1)
    ]
    return table_html(
        header,
        rows,
        caption=caption(
            "Discovery steps: each effect added to the model, with the likelihood ratio Λ = n<sub>eff</sub> "
            "ln(RSS₀/RSS₁) of the refits against its threshold, the effective sample size of the autocorrelated "
            "residuals, the p-value against the boundary mixture (level α/m) and ΔBIC; the RMS residual before → "
            f"after the step in sample and on held-out data ({esc(document.get('held_out_method', ''))})."
        ),
        table_id=f"discovery-steps-{document.get('group', '')}",
    )


def decision_text(candidate: dict, step: dict) -> str:
    """What the round decided about one candidate (``step``: the round's step, empty when none was taken)."""
    if candidate["effect"] == step.get("effect"):
        return "<b>taken</b>" if step.get("named", True) else "taken as the stand-in of an indistinguishable group"
    if candidate["effect"] in step.get("indistinguishable_from", []):
        return "as good as the one taken (indistinguishable)"
    if "error" in candidate:
        return esc(candidate["error"])
    if not candidate.get("significant"):
        return "not significant"
    if candidate.get("rejected_because"):
        return "significant, but " + prose("; ".join(candidate["rejected_because"]))
    return "significant; a better candidate was taken"


def candidates_table(document: dict, caption=_PLAIN) -> str:
    """Every candidate refitted in every forward round, with its evidence and what was decided."""
    rows, attrs = [], []
    steps = document["steps"]
    for r, round_ in enumerate(document["rounds"]):
        step = steps[r] if r < len(steps) else {}
        for i, c in enumerate(round_["candidates"]):
            first = i == 0
            rows.append(
                [td(f"{r + 1}: {esc(model_label(document, model_key(round_['model'])))}" if first else "")]
                + [td(effect_name(c["effect"]))]
                + evidence_cells(c)
                + [td(deg(c["rms_after_rad"]) if "rms_after_rad" in c else "—", "num")]
                + [td(decision_text(c, step))]
            )
            attrs.append({"class": "group-end"} if i == len(round_["candidates"]) - 1 else None)
    if not rows:
        return "<p>No candidate was tested (every candidate is already in the baseline).</p>"
    header = ["round: model before", "candidate", "Λ vs threshold", "n<sub>eff</sub>", "p", "ΔBIC"]
    header += ["RMS after (°)", "decision"]
    return table_html(
        header,
        rows,
        row_attrs=attrs,
        caption=caption(
            f"Every candidate refitted in each forward round (best fit first); α = {document['threshold']['alpha']:g}. "
            f"A candidate is taken when {esc(document['threshold']['rule'])}."
        ),
        table_id=f"discovery-candidates-{document.get('group', '')}",
    )


def residual_verdict(check: dict, threshold: dict) -> str:
    """The residual check in words; only residuals both white and near the noise read 'no structure left'
    (a new user's baseline at 3.5× the noise with Ljung–Box p < 10⁻¹⁰ read so, beside a named effect)."""
    if check["structured"]:
        return '<span class="warn">structure left</span>'
    not_white = check["whiteness"]["p_value"] < threshold["whiteness_alpha"]
    if not_white:
        return f"not white, but within {fmt(threshold['misfit_ratio'], 2)}× the noise"
    if check["rms_over_noise"] > threshold["misfit_ratio"]:
        return f"white, but above {fmt(threshold['misfit_ratio'], 2)}× the noise"
    return "no structure left"


def residual_check_table(document: dict, caption=_PLAIN) -> str:
    """Baseline and final residual against the noise floor, and the whiteness test."""
    rows = []
    for name, check in (("baseline", document["baseline"]["residual_check"]), ("final", document["residual_check"])):
        white = check["whiteness"]
        rows.append(
            [
                td(name),
                td(deg(check["rms_rad"]), "num"),
                td(deg(check["noise_floor_rad"]), "num"),
                td(fmt(check["rms_over_noise"], 3), "num"),
                td(f"{fmt(white['ljung_box_q'], 3)} / {white['dof']}", "num"),
                td(p_text(white["p_value"]), "num"),
                td(residual_verdict(check, document["threshold"])),
            ]
        )
    header = ["model", "RMS (°)", "pooled noise floor (°)", "RMS / noise", "Ljung–Box Q / dof", "p", "verdict"]
    th = document["threshold"]
    return table_html(
        header,
        rows,
        caption=caption(
            f"Residual check: structure is left when the RMS residual exceeds {fmt(th['misfit_ratio'], 2)}× the "
            "noise floor the angle records imply and the residuals (thinned to "
            f"{fmt(document['residual_check']['whiteness']['spacing_s'], 2)} s) are not white (Ljung–Box p < "
            f"{fmt(th['whiteness_alpha'], 2)}). The pooled noise floor: each trial's record noise (Table 2's), "
            "pooled over the group's fitted samples (RMS weighted by their number), so it can differ from a single "
            "trial's."
        ),
        table_id=f"discovery-check-{document.get('group', '')}",
    )


def endings_html(document: dict, harmonics: dict | None = None) -> str:
    """The honest endings: unexplained structure, indistinguishable groups, or nothing missing. ``harmonics``:
    trial → the second harmonic its angle record carries (present only), named where structure is left."""
    out = []
    check = document["residual_check"]
    if document["unexplained"]:
        seen = "; ".join(f"{esc(t)} {fmt(h['amplitude_deg'], 2)}°" for t, h in (harmonics or {}).items())
        found = (  # what the records themselves are measured to carry comes first, the guesses after
            f" Part of it is measured in the angle records themselves: they hold a second harmonic ({seen}), which "
            "no damping term makes and perspective does where the body's distance from the camera changes with the "
            "swing (Tracking quality: film square-on to the swing plane, from farther away)."
            if seen
            else ""
        )
        pattern = document.get("residual_pattern") or {}
        shares = {name: share * pattern.get("structured", 0.0) for name, share in (pattern.get("shares") or {}).items()}
        where = (
            " Where its power lies, against the swing's own frequency: "
            + "; ".join(
                f"{100 * shares[name]:.0f} % {PATTERN_PLACE[part_name(pattern, name)]}"
                for name in sorted(shares, key=lambda n: -shares[n])
                if shares[name] >= 0.05
            )
            + " (the verdict above says what the largest parts mean)."
            if pattern.get("dominant")
            else ""
        )
        guesses = (  # without a residual pattern (an older document, or mostly noise): what may be at work
            ""
            if where
            else " "
            + ("Beyond that, something" if seen else "Something")
            + " outside the library is at work: a disturbance, a drifting zero, frame times the motion could not "
            "check, wrong rig values?"
        )
        out.append(
            '<p class="warn discovery-ending">Unexplained: after the final model the residual is '
            f"{fmt(check['rms_over_noise'], 2)}× the noise floor ({deg(check['noise_floor_rad'])}°) and not white "
            f"(Ljung–Box p = {p_text(check['whiteness']['p_value'])}). No candidate in the library removes this "
            f"structure, so none is named for it.{found}{esc(where)}{guesses}</p>"
        )
    for group in document["indistinguishable"]:
        names = " or ".join(TERMS[e].label if e in TERMS else e for e in group["effects"])
        carried = group.get("carried_in_model")
        out.append(
            f'<p class="discovery-ending"><b>Indistinguishable: {esc(names)}.</b> {prose(sentence(group["reason"]))}'
            + (f"; the model carries {esc(TERMS[carried].label)} as their stand-in" if carried in TERMS else "")
            + f", but neither is named. What would separate them: {prose(group['experiment'])}.</p>"
        )
    if not out and not document["named_effects"]:
        out.append(
            f'<p class="discovery-ending">No missing effect: no candidate improves the baseline beyond the '
            f"threshold, and the residual is {fmt(check['rms_over_noise'], 2)}× the noise floor.</p>"
        )
    return "".join(out)


def parameters_table(document: dict, caption=_PLAIN, truth=None) -> str:
    """The final model's coefficients with 95 % intervals (a coefficient at its bound flagged)."""
    parameters = document.get("parameters") or {}
    truths = {k: truth(k.partition("[")[0]) for k in parameters} if truth else {}
    has_truth = any(v not in (None, "—") for v in truths.values())
    rows = []
    for key, entry in parameters.items():
        value, qualifier = estimate_parts(entry)
        flag = " flagged" if entry.get("at_bound") or entry.get("identifiable") is False else ""
        if reaches_bound(entry):  # not resolved from its bound: as the summary gives it, no bold
            value, qualifier = esc(value), f"{esc(qualifier)} (reaches {fmt(entry['lower_bound'], 3)})"
        else:
            value, qualifier = f"<b>{esc(value)}</b>", esc(qualifier)
        value, qualifier = f'<span class="v">{value}</span>', f'<span class="v">{qualifier}</span>'
        row = [td(coefficient_label(key)), td(value, "num" + flag), td(qualifier, "num" + flag)]
        row += [td(esc(truths[key] or "—"), "num truth")] if has_truth else []
        rows.append(row + [td(esc(entry.get("note") or entry.get("reason") or ""))])
    has_note = any(e.get("note") or e.get("reason") for e in parameters.values())
    rows = rows if has_note else [row[:-1] for row in rows]
    header = ["coefficient", "estimate", "95 % interval"] + ["truth (synthetic)"] * has_truth + ["note"] * has_note
    terms = ", ".join(TERMS[t].label for t in document["final_terms"]) or "added mass only"
    return table_html(
        header,
        rows,
        caption=caption(
            f"Final model ({esc(terms)}): coefficients with 95 % intervals (statistical and systematic parts "
            "combined, as in the fits, but not widened by the joint fits' consistency scale factor S: where the "
            "trials disagree beyond their intervals, the summary's joint-fit intervals are the wider, and they "
            "stand); a coefficient at its lower bound is given as the bound with its one-sided upper limit."
        ),
        table_id=f"discovery-parameters-{document.get('group', '')}",
    )


def excluded_html(document: dict) -> str:
    excluded = document.get("excluded_trials") or {}
    if not excluded:
        return f'<p class="table-note">Trials used: {esc(", ".join(document.get("trials", [])))}; none left out.</p>'
    by_reason = ReportData.grouped({t: (reason, []) for t, reason in sorted(excluded.items())})
    items = "".join(f"<li><b>{esc(', '.join(ts))}</b>: {esc(reason)}</li>" for ts, reason, _ in by_reason)
    return f'<p class="warn">Trials left out of discovery:</p><ul>{items}</ul>'


# ---------------------------------------------------------------------------
# The section


def group_html(
    document,
    residuals,
    extinction,
    table_caption=_PLAIN,
    figure_caption=_PLAIN,
    truth=None,
    harmonics=None,
    markers=None,
) -> str:
    """One group's discovery: verdict, steps, candidates, figures, endings, coefficients, trials left out."""
    group = esc(document.get("group", ""))
    rigs = document.get("rigs", [])
    head = f'<h3 id="discovery-{group}">Group {group} (rig{"s" if len(rigs) > 1 else ""} {esc(", ".join(rigs))})</h3>'
    if not is_ok(document):
        return head + f'<p class="warn">{esc(sentence(failure_text(document)))}</p>'
    residuals, extinction = (
        t.assign(model=t["model"].fillna("")) if "model" in t else t for t in (residuals, extinction)
    )
    candidates = ", ".join(TERMS[c].label for c in document.get("candidates", []))
    baseline = ", ".join(TERMS[t].label for t in document["baseline"]["terms"]) or "added mass only"
    out = [
        head,
        verdict_html(document),
        f"<p>From the baseline variant <b>{esc(document.get('baseline_variant', ''))}</b> "
        f"({esc(baseline)}) fitted jointly to "
        f"{len(document.get('trials', []))} trial(s), the candidates ({esc(candidates)}) are added one at a time by "
        "refitting; each chosen term is then refitted out of the final model and must still pass (backward step).</p>",
        endings_html(document, harmonics),
        steps_table(document, table_caption) if document["steps"] else "<p>No effect passed: no step was taken.</p>",
        candidates_table(document, table_caption),
        figures_html(document, residuals, extinction, figure_caption, markers),
        residual_check_table(document, table_caption),
        parameters_table(document, table_caption, truth),
        excluded_html(document),
    ]
    if document.get("warnings"):
        items = "".join(f"<li>{esc(w)}</li>" for w in document["warnings"])
        out.append(f'<p class="warn">Warnings of the final model:</p><ul>{items}</ul>')
    fit_warnings = document["baseline"].get("fit_warnings") or []
    if fit_warnings:
        items = "".join(f"<li>{esc(w)}</li>" for w in fit_warnings)
        summary = f"{len(fit_warnings)} warning(s) of the reused {esc(document.get('baseline_variant', ''))} fits"
        out.append(f'<details class="fit-warnings"><summary>{summary}</summary><ul>{items}</ul></details>')
    return "".join(out)


class DiscoverySections(ReportData):
    """The discovery section: one block per group (a body or a rig) from the rule ``discovery``'s outputs."""

    def discovery_section(self) -> str:
        """Per group: the verdict, its evidence and figures, the honest endings, the final coefficients."""
        groups = self.files.get("discovery") or {}
        if not groups:
            return (
                "<p>Discovery did not run: config <code>discovery.baseline</code> (default <code>quadratic</code>) "
                "is not one of the model variants.</p>"
            )
        out = []
        for group, paths in sorted(groups.items()):
            document = read_json(paths["document"])
            document.setdefault("group", group)
            truth = partial(self._truth_text, document.get("trials") or []) if self.truth else None
            residuals, extinction = read_table(paths["residuals"]), read_table(paths["extinction"])
            harmonics = {
                t: h
                for t in document.get("trials") or []
                if (h := (self.docs.get((t, "angles")) or {}).get("second_harmonic") or {}).get("present")
            }
            out.append(
                group_html(
                    document,
                    residuals,
                    extinction,
                    self.table_caption,
                    self.figure_caption,
                    truth,
                    harmonics,
                    self.trial_marker,
                )
            )
        return "".join(out)
