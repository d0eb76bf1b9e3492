"""Tables 1–3 of the report: rig values, RMS residuals, coefficients per trial and variant.

Methods of :class:`TableSections`, one per notebook cell; the numbers are
written by :mod:`pendulum.report.format`.
"""

from __future__ import annotations

import math
from collections import Counter

from pendulum.fit.records import (
    RIG_DEFAULTS,
    WATER_KINEMATIC_VISCOSITY_M2_S,
    keulegan_carpenter_number,
    kinematic_viscosity_m2_s,
    rig_tolerances,
    with_rig_defaults,
)
from pendulum.model.rig import BUOYANCY_KEYS, Rig, tolerances_alike
from pendulum.report.data import (
    ReportData,
    failure_text,
    is_ok,
    problem_text,
    record_problems,
    short_warning,
    true_value,
)
from pendulum.report.format import (
    COEFFICIENTS,
    RIG_LABELS,
    UNRELIABLE_STYLE,
    esc,
    estimate_cell,
    fmt,
    garbage_badge,
    table_html,
    td,
)

NOISE_WORDS = "the record's noise"  # record_checks.misfit_warning's words for its noise
FIT_NOISE_NOTE = (
    "<p>“The record's noise” in these warnings is the record noise of Table 2 (σ from the fifth differences of the "
    "whole angle record, at least the quantisation step's for a record its tracker quantised), as everywhere in "
    "this report.</p>"
)


def camera_rig_note(rigs: dict) -> str:
    """The rig table's sentence on rigs filmed through a calibrated camera setup ("" without cameras)."""
    parts = [
        f"{esc(rig)} (camera setup {esc(str(info['values']['camera']))})"
        for rig, info in sorted(rigs.items())
        if info.get("values", {}).get("camera")
    ]
    if not parts:
        return ""
    return (
        f" Camera: {', '.join(parts)} — the pivot and marker coordinates of these rigs are swing-plane coordinates "
        "(marker centres undistorted by the lens model and mapped onto the swing plane by the plane board's "
        "homography, when the setup has one; the camera calibration table is under Tracking quality), not raw image "
        "pixels."
    )


UNSTATED_RIG_DEFAULTS = {  # rig values the model takes when a rig does not state them (Rig's and records' defaults)
    "displaced_volume_m3": Rig.__dataclass_fields__["displaced_volume_m3"].default,
    **RIG_DEFAULTS,
    "kinematic_viscosity_m2_s": WATER_KINEMATIC_VISCOSITY_M2_S,
}


class TableSections(ReportData):
    """Table 1 (rig values), Table 2 (RMS residuals) and Table 3 (coefficients) as HTML."""

    def rig_table(self) -> str:
        """Table: rig values with 1σ tolerances (stated or default) and per-trial overrides."""
        rigs = [r for r in self.rig_names if r in self.rigs]
        rows = []
        for key, (label, unit) in RIG_LABELS.items():
            if key == "submerged_mass_kg" and not any(self.rig_values_used(r)[0].get(key) for r in rigs):
                continue  # a row only where a rig is weighed in its fluid
            cells = []
            for rig in rigs:
                used, per_trial = self.rig_values_used(rig)
                if key in per_trial:
                    cells += [
                        td(esc("per trial (sidecars): " + ", ".join(fmt(v, 4) for v in per_trial[key]))),
                        td("", "na"),
                    ]
                    continue
                values = with_rig_defaults(used)  # as the fits take them
                stated, differ = self.rig_tolerances_used(rig)
                by_trials = used.get(key) != self.rigs[rig]["values"].get(key)  # every trial's sidecar gives it
                if key in differ:  # trials state different tolerances of one value: which (default: none stated)
                    text = fmt(values.get(key), 4) + (" (the sidecars of all its trials)" if by_trials else "")
                    listed = ["default" if v is None else f"± {fmt(v, 2)}" for v in differ[key]]
                    cells += [td(esc(text), "num"), td(esc("per trial (sidecars): " + ", ".join(listed)), "na")]
                    continue
                value = values.get(key)
                if key == "displaced_volume_m3" and used.get(key) is None and used.get("submerged_mass_kg"):
                    volume = Rig.from_mapping(values).displaced_volume_m3
                    cells += [td(esc(f"{fmt(volume, 4)} (from the submerged mass)"), "num"), td("derived", "na")]
                    continue
                if used.get(key) is None and key in UNSTATED_RIG_DEFAULTS:
                    default = UNSTATED_RIG_DEFAULTS[key]  # not stated: what the model uses
                    if key == "kinematic_viscosity_m2_s":  # water's, or air's for a gas (as the half cycles take it)
                        default = kinematic_viscosity_m2_s(values)
                    tol = rig_tolerances(values, stated).get(key) if key in RIG_DEFAULTS else None
                    tol_text = (
                        "not in the error budget"
                        if tol is None
                        else "0 (exact)"
                        if tol == 0
                        else f"± {fmt(tol, 2)} ({fmt(100 * tol / abs(default), 2)} %, default)"
                    )
                    cells += [td(esc(f"{fmt(default, 4)} (default)"), "num"), td(esc(tol_text), "num")]
                    continue
                if value is None and key not in ("body_inertia_kg_m2", "characteristic_length_m"):
                    cells += [td("—", "na"), td("", "na")]
                    continue
                if value is None:
                    text = "m L² (point mass)" if key == "body_inertia_kg_m2" else "√(4A/π) from A"
                    cells += [td(esc(text)), td("", "na")]
                    continue
                tol = rig_tolerances(values, stated).get(key)
                if tol is None:
                    tol_text = "—"
                elif tol == 0:
                    tol_text = "0 (exact)"
                else:
                    default = ", default" if key not in stated else ""
                    tol_text = f"± {fmt(tol, 2)} ({fmt(100 * tol / abs(value), 2)} %{default})"
                text = fmt(value, 4) + (" (the sidecars of all its trials)" if by_trials else "")
                cells += [td(esc(text), "num"), td(esc(tol_text), "num")]
            rows.append([td(esc(label)), td(esc(unit))] + cells)
        calibrated = any(self.rigs[rig]["values"].get("camera") for rig in rigs)
        for key, label, unit in (
            (
                "pivot_px",
                "pivot (swing-plane px where a camera setup is calibrated)" if calibrated else "pivot in the image",
                "px",
            ),
            ("vertical_deg", "image angle of the vertical", "°"),
        ):
            cells = []
            for rig in rigs:
                value = self.rigs[rig]["values"].get(key)
                text = (
                    self.estimated_geometry_text(rig, key)
                    if value is None
                    else ", ".join(fmt(x, 5) for x in value)
                    if isinstance(value, list)
                    else fmt(value, 3)
                )
                cells += [td(esc(text), "num" if value is not None else None), td("", "na")]
            rows.append([td(esc(label)), td(esc(unit))] + cells)
        for label, unit, f in (
            ("weight mg", "N", lambda r: r.mass_kg * r.gravity_m_s2),
            ("buoyancy B = ρgV", "N", lambda r: r.buoyancy_n),
            ("restoring torque (mg − B)L", "N·m", lambda r: r.restoring_torque_nm),
            ("pivot inertia I_p", "kg·m²", lambda r: r.pivot_inertia_kg_m2),
        ):
            cells = []
            for rig in rigs:
                used, per_trial = self.rig_values_used(rig)
                if per_trial:
                    cells += [td("per trial", "na"), td("derived", "na")]
                    continue
                try:
                    cells += [td(esc(fmt(f(Rig.from_mapping(used)), 4)), "num"), td("derived", "na")]
                except (TypeError, ValueError):
                    cells += [td("—", "na"), td("", "na")]
            rows.append([td(esc(label)), td(esc(unit))] + cells)
        header = ["quantity", "unit"] + [h for rig in rigs for h in (f"{esc(rig)}: value", "1σ tolerance")]
        overrides = {t: info.get("overrides") for t, info in self.trials.items() if info.get("overrides")}
        if overrides:
            items = "; ".join(
                f"{esc(t)}: " + ", ".join(f"{esc(k)} = {esc(str(v))}" for k, v in sorted(o.items()))
                for t, o in sorted(overrides.items())
            )
            note = f"Per-trial overrides (sidecars): {items}."
        else:
            note = "No per-trial overrides: every trial uses its rig's values."
        bad = self.failed_trials()
        failed = dict(zip(bad.trial, bad.stage, strict=True))  # named on their rig, not measured there

        def member(t: str) -> str:
            return esc(t) + (f" (failed at {esc(str(failed[t]))}: not in its fits)" if t in failed else "")

        trials_by_rig = "; ".join(f"{esc(r)}: {', '.join(member(t) for t in self.rig_trials(r))}" for r in rigs)
        note += f" Trials per rig (each trial's sidecar names its rig; without one, the default) — {trials_by_rig}."
        note += camera_rig_note({r: self.rigs[r] for r in rigs})
        caption = self.table_caption(
            "Rig values used (measured, not fitted) with their 1σ tolerances; a tolerance not stated in the "
            "configuration (or, for a value a sidecar gives, in that sidecar) takes the default fraction. They "
            "enter the fits' systematic error budget."
        )
        return table_html(header, rows, caption=caption, table_id="table1", note=note)

    def rig_values_used(self, rig: str) -> tuple[dict, dict]:
        """The rig's values as its trials use them: a value every trial overrides in its sidecar with one number
        is that number (Table 1 shows what the fits used, not the rig's); values the trials differ in, per trial
        (``key → sorted values``, the second dict)."""
        used, per_trial = dict(self.rigs[rig]["values"]), {}
        trials = self.rig_trials(rig)
        # every trial's own buoyancy (a volume or a weighing) replaces the rig's other one, as fitted
        for given, replaced in (BUOYANCY_KEYS, BUOYANCY_KEYS[::-1]):
            if trials and all(given in (self.trials[t].get("overrides") or {}) for t in trials):
                used.pop(replaced, None)
        for key in RIG_LABELS:
            values = [(self.trials[t].get("overrides") or {}).get(key) for t in trials]
            if trials and all(v is not None for v in values):
                if len(set(values)) == 1:
                    used[key] = values[0]
                else:
                    per_trial[key] = sorted(set(values))
        return used, per_trial

    def rig_tolerances_used(self, rig: str) -> tuple[dict, dict]:
        """The 1σ tolerances the rig's trials state (``trials[t]["tolerances"]``: the rig's, a sidecar's for the
        values it gives) where they all state them alike, and key → the values where they differ
        (:func:`pendulum.model.rig.tolerances_alike`). Without per-trial tolerances (an older build), the rig's."""
        trials = self.rig_trials(rig)
        if not trials or any("tolerances" not in self.trials[t] for t in trials):
            return dict(self.rigs[rig].get("tolerances") or {}), {}
        return tolerances_alike([self.trials[t]["tolerances"] for t in trials])

    def estimated_geometry_text(self, rig: str, key: str) -> str:
        """The pivot (± standard errors) or vertical a rig's angle records used when config gave none."""
        by_trial = {
            t: str(self.docs[(t, "angles")].get(key))
            for t in self.rig_trials(rig)
            if is_ok(self.docs.get((t, "angles"))) and self.docs[(t, "angles")].get(key) is not None
        }
        counts = Counter(by_trial.values()).most_common()
        suffix = ""
        if len(counts) > 1:  # its trials do not all use one pivot (their angles' notes say why)
            if counts[0][1] < 2 or counts[0][1] == counts[1][1]:
                return (
                    "not one for all trials: a trial whose path is off the rig's circle has its own (its notes say so)"
                )
            others = len(by_trial) - counts[0][1]  # the rig's pooled one, and a few trials their own
            suffix = f"; {others} other trial(s) their own (their notes say why)"
        for trial in self.rig_trials(rig):
            angles = self.docs.get((trial, "angles"))
            if trial not in by_trial or (counts and by_trial[trial] != counts[0][0]):
                continue
            if key == "vertical_deg":
                return f"{fmt(angles[key], 3)} (estimated from the swings{suffix})"
            covariance = angles.get("pivot_covariance_px2")
            if covariance is None:
                return ", ".join(fmt(x, 5) for x in angles[key]) + f" (the trial's own{suffix})"
            sigmas = [math.sqrt(max(float(covariance[i][i]), 0.0)) for i in (0, 1)]
            rod = f" and a rod's lines in {angles['pivot_rod_lines']} frames" if angles.get("pivot_rod_lines") else ""
            return (
                ", ".join(f"{fmt(x, 5)} ± {fmt(s, 2)}" for x, s in zip(angles[key], sigmas, strict=True))
                + f" (estimated from the tracked paths{rod}{suffix})"
            )
        return "not given: estimated from the tracked paths"

    def rms_table(self) -> str:
        """Table 2 (as the paper's): RMS residual per trial and variant in rad, degrees and arc millimetres."""
        order = self.order
        header = [
            ['<th rowspan="2">trial</th>', '<th rowspan="2">release</th>', '<th rowspan="2">record noise (°)</th>']
            + [f'<th colspan="3" class="group">{esc(v)}</th>' for v in order],
            [f'<th class="sub">{u}</th>' for _ in order for u in ("rad", "°", "arc mm")],
        ]
        rows, attrs = [], []
        for trial in self.trial_order():
            angles = self.docs.get((trial, "angles"), {})
            noise = angles.get("noise_deg") if is_ok(angles) else None
            problems = self.trial_problems(trial)
            badge = f" {garbage_badge(problems[0])}" if problems else ""
            row = [td(esc(trial) + badge), td(self.angle_label(trial), "num"), td(esc(fmt(noise, 2)), "num")]
            short = self.short_of_best(trial)
            for v in order:
                row += self._rms_cells(self.fits.get((v, trial)), "failed", short.get(v))
            rows.append(row)
            attrs.append({"data-trial": trial, **({"data-reliable": "false"} if problems else {})})
        for rig in self.rig_names:
            row = [td(f"<b>joint</b> {esc(rig)}"), td("all", "num"), td("", "na")]
            for v in order:
                row += self._rms_cells(self.joint.get((v, rig)), "—")
            rows.append(row)
            attrs.append({"data-trial": f"joint:{rig}", "class": "joint"})
        caption = self.table_caption(
            "RMS residual (fitted − measured angle over the fitted samples) per trial and model variant, in "
            "radians, degrees and metres of arc at the body (Lθ, here in mm). The record noise is the angle "
            "noise of the tracked record (σ from the fifth differences of the whole angle record as tracked, its "
            "hold before the release included, at least the "
            "quantisation step's for a record its tracker quantised): it sees the frame-to-frame noise, not the "
            "tracking's slow errors (a bias that follows the body across the wall), so a variant that captures the "
            "physics leaves an RMS of one to a few times it (the demo's ±5° swings: 3×), a variant that misses some "
            "far more. It is the one noise figure of this report: the tracking table's, the fits' warnings' and "
            "the model comparison's; discovery pools it over a group's trials." + self.dagger_note() + self.short_note()
        )
        return table_html(header, rows, caption=caption, table_id="table2", row_attrs=attrs, note=self.garbage_note())

    def short_note(self) -> str:
        """Table 2's note on fits marked ◊, naming them, when there is one."""
        found = [(t, v, p) for t in self.trial_order() for v, p in self.short_of_best(t).items()]
        if not found:
            return ""
        named = "; ".join(f"{esc(t)}: {esc(v)} ({esc(p[0])} leaves {fmt(p[1], 2)}°)" for t, v, p in found)
        return (
            " ◊ A fit that leaves more than a variant with one term fewer on the same samples stopped short of its "
            "best (that variant's solution is one of its own, the extra term 0): a local minimum, not the model's "
            f"failing; its coefficients are not that model's best: {named}."
        )

    def _rms_cells(self, fit: dict | None, missing: str, short: tuple | None = None) -> list[str]:
        """Three RMS cells (rad, °, arc mm) of one fit; grey with the problem as tooltip on an unreliable record;
        marked ◊ where ``short`` (:meth:`short_of_best`: the nested parent and its RMS) fits better."""
        if not is_ok(fit):
            if missing == "failed":
                return [td("failed", "na fail", span=3, title=failure_text(fit))]
            return [td(missing, "na", span=3)]
        values = (fit["rms_rad"], fit["rms_deg"], 1000 * fit["rms_arc_m"])
        problems = record_problems(fit)
        if not problems and short is not None:
            title = f"stopped short of its best fit: {short[0]}, one term fewer, leaves {fmt(short[1], 2)}°"
            return [td(esc(fmt(x, 2)) + "◊", "num", title=title) for x in values]
        if not problems:
            return [td(esc(fmt(x, 2)), "num") for x in values]
        return [
            f'<td class="num unreliable" style="{UNRELIABLE_STYLE}" title="{esc(problems[0])}">{esc(fmt(x, 2))}</td>'
            for x in values
        ]

    @staticmethod
    def _garbage_cell(problem: str, span: int) -> str:
        """A row-wide cell under an unreliable trial's fits: the badge and the record's first problem."""
        return td(
            f"{garbage_badge()} <b>not measurements</b> (struck through): {esc(problem)}.",
            "garbage-note",
            span=span,
        )

    def garbage_note(self) -> str | None:
        """The table note naming each trial whose record failed the garbage checks, with its first problem."""
        items = [(t, self.trial_problems(t)) for t in self.trial_order()]
        items = [(t, p) for t, p in items if p]
        if not items:
            return None
        return (
            f"{garbage_badge()} {len(items)} trial(s) rest on unreliable records (the garbage checks of the fit: "
            "usable fraction, rest angle, jumping residuals, record noise); their numbers are shown grey and "
            "their coefficients struck through, not measurements, and the joint fits leave them out: "
            + "; ".join(f"<b>{esc(t)}</b>: {esc(problem_text(t, p[0]))}" for t, p in items)
            + "."
        )

    def coefficient_table(self) -> str:
        """Table 3 (as the paper's, done right): coefficients per trial and variant with 95 % intervals."""
        names = [n for n in COEFFICIENTS if any(self._has(v, n) for v in self.order)]
        header = (
            ["trial", "release", "KC", "variant"]
            + [
                f"{COEFFICIENTS[n][0]}" + (f" ({COEFFICIENTS[n][2]})" if COEFFICIENTS[n][2] != "–" else "")
                for n in names
            ]
            + ["warnings"]
        )
        rows, attrs, notes = [], [], []

        def fit_row(label_cells, v, fit, kind, trial, above=None):
            if not is_ok(fit):  # the reason once a trial: a variant that failed for the same says so
                text = failure_text(fit)
                shown = "failed, as above" if text == above else text
                title = text if shown != text else None
                row = label_cells + [td(esc(v)), td(esc(shown), "na fail", span=len(names) + 1, title=title)]
            else:
                warnings = fit.get("warnings", [])
                problems = record_problems(fit)
                short = sorted({short_warning(w) for w in warnings if w not in problems})
                if warnings:
                    notes.append((kind, trial, v, warnings))
                row = label_cells + [td(esc(v), "vname")]
                row += [
                    estimate_cell(fit["parameters"].get(n), unreliable=bool(problems))
                    if self._has(v, n)
                    else td("—", "na")
                    for n in names
                ]
                badge = garbage_badge(problems[0]) + (" " if short else "") if problems else ""
                row.append(td(badge + esc(", ".join(short)), "warncell"))
            rows.append(row)
            attrs.append({"data-trial": trial, "data-variant": v, "data-kind": kind})

        for trial in self.trial_order():
            first, above = True, None
            shown_kc = None
            for v in self.order:
                kc = self.kc(v, trial)  # the record's, one per trial (a variant's own where the record lacks it)
                kc_text = fmt(kc, 2) if first or (kc is not None and fmt(kc, 2) != shown_kc) else ""
                label = [
                    td(esc(trial) if first else ""),
                    td(self.angle_label(trial) if first else "", "num"),
                    td(esc(kc_text), "num"),
                ]
                shown_kc = kc_text or shown_kc
                fit = self.fits.get((v, trial))
                fit_row(label, v, fit, "trial", trial, above)
                above = None if is_ok(fit) else failure_text(fit)
                first = False
            problems = self.trial_problems(trial)
            if problems:
                rows.append(
                    [td(""), td(""), td(""), self._garbage_cell(problem_text(trial, problems[0]), len(names) + 2)]
                )
                attrs.append({"data-trial": trial, "data-kind": "garbage"})
            if trial in self.truth:
                rows.append(
                    [td(""), td(""), td(""), td("truth", "truth")]
                    + [td(esc(fmt(true_value(self.truth[trial], n), 4)), "num truth") for n in names]
                    + [td("")]
                )
                attrs.append({"data-trial": trial, "data-kind": "truth", "class": "truth"})
            attrs[-1]["class"] = (attrs[-1].get("class", "") + " group-end").strip()
        for rig in self.rig_names:
            first, shown_joint_kc = True, None
            for v in self.order:
                joint = self.joint.get((v, rig))
                if joint is None:
                    continue
                kc = keulegan_carpenter_number(joint) if is_ok(joint) else None
                kc_text = f"{fmt(min(kc), 2)}–{fmt(max(kc), 2)}" if isinstance(kc, list) and kc else fmt(kc, 2)
                label = [
                    td(f"<b>joint</b> {esc(rig)}" if first else ""),
                    td("all" if first else "", "num"),
                    td(esc(kc_text) if first or kc_text != shown_joint_kc else "", "num"),
                ]
                shown_joint_kc = kc_text
                fit_row(label, v, joint, "joint", f"joint:{rig}")
                attrs[-1]["class"] = "joint"
                first = False
            left_out = self.left_out(rig)
            if left_out:
                items = "; ".join(
                    f"<b>{esc(', '.join(ts))}</b>"
                    + ("" if len(vs) == len(self.order) else f" ({esc(', '.join(vs))})")
                    + f": {esc(reason)}"
                    for ts, reason, vs in self.grouped(left_out)
                )
                rows.append(
                    [
                        td(""),
                        td(""),
                        td(""),
                        td(f"Left out of the joint fits: {items}.", "left-out", span=len(names) + 2),
                    ]
                )
                attrs.append({"data-trial": f"joint:{rig}", "data-kind": "left-out", "class": "joint"})
            trials = self.rig_trials(rig)
            if any(t in self.truth for t in trials):
                rows.append(
                    [td(""), td(""), td(""), td("truth", "truth")]
                    + [td(esc(self._truth_text(trials, n)), "num truth") for n in names]
                    + [td("")]
                )
                attrs.append({"data-trial": f"joint:{rig}", "data-kind": "truth", "class": "truth joint"})
        caption = self.table_caption(
            "Added mass m<sub>a</sub>, drag area C<sub>d</sub>A, drag coefficient C<sub>d</sub> = C<sub>d</sub>A/A "
            "and, where the variant has them, linear damping c and bearing friction torque τ<sub>f</sub>: "
            "estimate and 95 % interval per trial and variant, and the joint fit of each rig (shared "
            "coefficients, statistical part widened by the consistency scale factor S). KC: Keulegan–Carpenter "
            "number U<sub>max</sub>T/D of the trial's first fitted swing as its record shows it (U<sub>max</sub> = "
            "L × the largest |θ̇| from the fit's start to the end of the record's first whole cycle, T that cycle's "
            "period, from its first crossing of the vertical to its third, longer than the small-swing one for a "
            "wide release; the extinction figure's half cycles give the smaller KC of the later swings): the flow "
            "the trial made, one per trial whatever a variant fits (given on a variant's "
            "row only where the record shows too little of the swing and it comes from that variant's fitted "
            "curve); joint: the range. "
            + ("Rows ‘truth’: the synthetic trials' true values. " if self.truth else "")
            + "“at bound” marks a coefficient that ended on its lower bound: the data prefer an unphysical "
            "value, and only the one-sided 95 % upper limit is a result. Per-trial intervals of the damping "
            "terms are somewhat optimistic on tracked video (about 1.3× narrow in the coverage study); prefer "
            "the joint rows. Every interval holds the rig values' systematic part, which moves all the trials "
            "together (where it dominates, as a volume's tolerance does for m<sub>a</sub>, the trials' intervals "
            "look alike): to compare trials, read the consistency figure's statistical bars; the sources are in "
            "the uncertainty budget." + self.dagger_note()
        )
        out = table_html(header, rows, caption=caption, table_id="table3", row_attrs=attrs)
        if notes:
            items = "".join(
                f"<li><b>{esc(trial)}, {esc(v)}</b>: " + " | ".join(esc(w) for w in ws) + "</li>"
                for kind, trial, v, ws in notes
            )
            out += (
                f'<details class="fit-warnings"><summary>The fits\' warnings in full ({len(notes)} fits)</summary>'
                + (FIT_NOISE_NOTE if any(NOISE_WORDS in w for *_, ws in notes for w in ws) else "")
                + f"<ul>{items}</ul></details>"
            )
        return out
