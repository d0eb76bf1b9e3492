"""The synthetic truth: each variant's joint estimate against the values the renders were made with."""

from __future__ import annotations

from pendulum.fit.uncertainty import Z95, Z95_ONE_SIDED
from pendulum.report.data import ReportData, is_ok, record_problems, true_value
from pendulum.report.format import COEFFICIENTS, esc, estimate_cell, is_finite, table_html, td, with_minus_sign


class TruthSections(ReportData):
    """The report's table against the truth (synthetic trials only)."""

    def truth_section(self) -> str:
        """Joint estimates against the synthetic truth: error in standard errors, coverage of the 95 % intervals."""
        if not self.truth:
            return (
                "<p>No trial has a truth file (<code>truth_dir</code>, written only for synthetic renders), so "
                "the estimates are not checked against known values here.</p>"
            )
        rows, seen = [], set()
        garbage = [t for t in self.trial_order() if t in self.truth and self.trial_problems(t)]
        for rig in self.rig_names:
            trials = [t for t in self.rig_trials(rig) if t in self.truth]
            if not trials:
                continue
            for v in self.order:
                joint = self.joint.get((v, rig))
                if not is_ok(joint):
                    continue
                for name, entry in joint["parameters"].items():
                    truth = self._truth_text(trials, name)
                    values = {true_value(self.truth[t], name) for t in trials} - {None}
                    if len(values) != 1:
                        continue
                    true = values.pop()
                    z = (entry["value"] - true) / entry["stderr"] if entry.get("stderr") else float("nan")
                    z_stat = _statistical_z(entry, true)
                    inside = entry["ci95"][0] <= true <= entry["ci95"][1]
                    clean = [t for t in trials if not record_problems(self.fits.get((v, t)))]
                    own = [
                        self.fits[(v, t)]["parameters"][name]
                        for t in clean
                        if is_ok(self.fits.get((v, t))) and name in self.fits[(v, t)]["parameters"]
                    ]
                    covered = sum(1 for e in own if e["ci95"][0] <= true <= e["ci95"][1])
                    covered_stat = sum(1 for e in own if _within_statistical(e, true))
                    n_fit = sum(1 for t in clean if is_ok(self.fits.get((v, t))))
                    first = (rig, v) not in seen
                    seen.add((rig, v))
                    rows.append(
                        [
                            td(esc(rig) if first else ""),
                            td(esc(v) if first else "", "vname"),
                            td(f"{COEFFICIENTS[name][1]}, {COEFFICIENTS[name][0]}"),
                            td(esc(truth), "num"),
                            estimate_cell(entry),
                            td(_z_text(z), "num"),
                            td(_z_text(z_stat), "num"),
                            td("yes" if inside else '<span class="warn">no</span>'),
                            td(f"{covered} of {n_fit}", "num"),
                            td(f"{covered_stat} of {n_fit}", "num"),
                        ]
                    )
        header = [
            "rig",
            "variant",
            "coefficient",
            "truth",
            "joint estimate (95 %)",
            "(estimate − truth)/σ",
            "(estimate − truth)/σ<sub>stat</sub>",
            "truth inside",
            "per-trial intervals covering truth",
            "per-trial within 1.96 σ<sub>stat</sub>",
        ]
        caption = self.table_caption(
            "The synthetic experiment: each variant's joint estimate against the true value the videos were "
            "rendered with, the error in units of the estimate's combined standard error σ, and how many of the "
            "per-trial 95 % intervals cover the truth. Only a variant that contains every effect of the simulation "
            "can be expected to cover it. Renders are made with the rig's stated values exactly, so the systematic "
            "part of σ (the rig values' tolerances) has no error to cover here and can make any estimate look "
            "right: the σ<sub>stat</sub> columns (the statistical error alone, widened by the joint fit's scale "
            "factor) are the test of the fit itself."
            + (
                f" The per-trial fits on unreliable records ({esc(', '.join(garbage))}) are not counted."
                if garbage
                else ""
            )
            + (
                f" {len(untold)} trial(s) have no truth file (<code>truth_dir</code>) and are not counted: "
                f"{esc(', '.join(untold[:5]) + (', …' if len(untold) > 5 else '.'))}"
                if (untold := [t for t in self.trial_order() if t not in self.truth])
                else ""
            )
        )
        return table_html(header, rows, caption=caption, table_id="truth-table")


def _statistical_z(entry: dict, true: float) -> float:
    """(estimate − truth) in units of the statistical error alone (a joint fit's widened by its scale factor)."""
    se = (entry.get("stderr_statistical") or 0.0) * max(entry.get("scale_factor") or 1.0, 1.0)
    return (entry["value"] - true) / se if se > 0 else float("nan")


def _z_text(z: float) -> str:
    return esc(with_minus_sign(f"{z:+.2f}" if abs(z) >= 0.005 else "0.00")) if is_finite(z) else "—"


def _within_statistical(entry: dict, true: float) -> bool:
    """Whether the truth lies within the statistical 95 % interval alone: ±1.96 σ_stat, or for a coefficient held on
    its bound the one-sided [b, b + 1.645 σ_stat] (as its reported limit)."""
    z = _statistical_z(entry, true)
    if entry.get("at_bound"):
        return is_finite(z) and -Z95_ONE_SIDED <= z <= 0.0  # b ≤ truth ≤ b + 1.645 σ_stat
    return is_finite(z) and abs(z) <= Z95
