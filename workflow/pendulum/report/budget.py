"""The recommended coefficients' uncertainty budget: each source's share, and the coefficients' correlation."""

from __future__ import annotations

import math

import numpy as np

from pendulum.outcomes import MISFIT_MARK
from pendulum.report.data import ReportData, is_ok, record_problems
from pendulum.report.format import COEFFICIENTS, RIG_LABELS, esc, fmt, is_finite, table_html, td, with_minus_sign

PIVOT = "pivot_px"  # the error budget's pivot inputs: "pivot_px (axis 1)", "pivot_px[0] (axis 2)", ...
SYMBOLS = {  # a rig value's symbol as Table 1 names it (a column head; the whole name its tooltip)
    "mass_kg": "m",
    "length_m": "L",
    "frontal_area_m2": "A",
    "displaced_volume_m3": "V",
    "submerged_mass_kg": "m − ρV",
    "fluid_density_kg_m3": "ρ",
    "gravity_m_s2": "g",
    "body_inertia_kg_m2": "I<sub>p</sub>",
    PIVOT: "pivot",
}


def budget_sources(entries: dict) -> list[str]:
    """The budget's sources in the order shown: the rig values as Table 1 lists them, then the pivot, then any
    other (a source none of the coefficients moves is left out)."""
    keys = {k for e in entries.values() for k, v in (e.get("error_budget") or {}).items() if v}
    sources = [k for k in RIG_LABELS if k in keys]
    if any(k.startswith(PIVOT) for k in keys):
        sources.append(PIVOT)
    return sources + sorted(k for k in keys if k not in RIG_LABELS and not k.startswith(PIVOT))


def source_shift(entry: dict, source: str) -> float:
    """A coefficient's 1σ shift from one source: the signed refit shift of a rig value; for the pivot, its
    axes' shifts in quadrature (an estimated pivot's error ellipse: its axes have no sign a reader can use)."""
    budget = entry.get("error_budget") or {}
    if source == PIVOT:
        return math.sqrt(sum(v * v for k, v in budget.items() if k.startswith(PIVOT)))
    return float(budget.get(source, 0.0))


def correlation_of(covariance: dict, names: list[str]) -> tuple[list[str], np.ndarray]:
    """The correlation of ``names`` (those the fit document's ``covariance`` holds, in its order: coefficients, then
    rig values) from it."""
    quantities = covariance.get("quantities") or covariance["parameters"]
    index = {n: k for k, n in enumerate(quantities)}
    kept = [n for n in quantities if n in names]
    cov = np.asarray(covariance["matrix"], float)[np.ix_([index[n] for n in kept], [index[n] for n in kept])]
    scale = np.sqrt(np.clip(np.diag(cov), 0.0, None))
    with np.errstate(invalid="ignore", divide="ignore"):
        return kept, cov / np.outer(scale, scale)


def _percent(value: float, estimate: float) -> str:
    """A standard uncertainty or a shift as a signed percentage of the estimate ("−4.7 %"); "·" where none."""
    if not value or not estimate:
        return "·"
    return with_minus_sign(f"{100 * value / abs(estimate):.2g} %")


class BudgetSections(ReportData):
    """The uncertainty budget of each rig's recommended joint fit (the summary box's coefficients)."""

    def uncertainty_budget(self) -> str:
        """Per rig: where each recommended coefficient's uncertainty comes from (statistical, each rig value, the
        pivot) and how the coefficients' errors go together (their correlation, every error included)."""
        out = []
        for rig in self.rig_names:
            variant = self.recommended(rig)
            joint = self.joint.get((variant, rig)) if variant else None
            if not is_ok(joint) or record_problems(joint):
                continue
            entries = {
                n: e
                for n, e in joint["parameters"].items()
                if n in COEFFICIENTS and not e.get("at_bound") and e.get("identifiable", True) and e.get("stderr")
            }
            if not entries:
                continue
            sources = budget_sources(entries)
            labels = [
                RIG_LABELS[s][0] if s in RIG_LABELS else ("the estimated pivot" if s == PIVOT else s) for s in sources
            ]
            header = (
                ["coefficient", "estimate", "u (1σ)", "statistical"]
                + [
                    f'<span title="{esc(label)}">{SYMBOLS.get(source, esc(source))}</span>'
                    for source, label in zip(sources, labels, strict=True)
                ]
                + ["largest source"]
            )
            rows = []
            for name, e in entries.items():
                symbol, label, unit = COEFFICIENTS[name]
                statistical = float(e["stderr_statistical"]) * float(e.get("scale_factor") or 1.0)
                shifts = [source_shift(e, s) for s in sources]
                parts = {"statistical": statistical**2, **{lab: v * v for lab, v in zip(labels, shifts, strict=True)}}
                total = sum(parts.values())
                top = max(parts, key=parts.get)
                unit_text = "" if unit == "–" else f" {unit}"
                rows.append(
                    [td(f"{label}, {symbol}"), td(esc(fmt(e["value"], 4)) + esc(unit_text), "num")]
                    + [td(esc(f"{fmt(e['stderr'], 2)}{unit_text} ({_percent(e['stderr'], e['value'])})"), "num")]
                    + [td(esc(_percent(statistical, e["value"])), "num")]
                    + [
                        td(esc(("±" if source == PIVOT and v else "") + _percent(v, e["value"])), "num")
                        for source, v in zip(sources, shifts, strict=True)
                    ]
                    + [td(esc(f"{top} ({100 * parts[top] / total:.0f} % of u²)") if total else "·")]
                )
            misfit = any(MISFIT_MARK in w for w in joint.get("warnings") or [])
            caption = self.table_caption(
                "Uncertainty budget of the "
                + ("coefficients of the best of the variants tried" if misfit else "recommended coefficients")
                + f", rig {esc(rig)} (variant {esc(variant)}, joint fit; the summary's values"
                + (
                    '; <span class="warn">it misses its records by far more than their noise: its coefficients '
                    "absorb what it misses, and no line of this budget holds that</span>"
                    if misfit
                    else ""
                )
                + "): its standard uncertainty u and each source's 1σ part of it as a "
                "percentage of the estimate. Statistical: the fit's (widened by the consistency scale factor S "
                "where the trials disagree). Each rig value of Table 1 (m, L, A, V, ρ, ...): its stated 1σ "
                "tolerance, propagated by refitting with the value 1σ larger (the sign: the way the coefficient "
                "moves; one rig value moves every coefficient at once). Pivot: the estimated pivot's two error "
                "axes in quadrature (±: no one sign). u = √(sum of squares). The largest source is what to measure "
                "better first; more trials shrink only the statistical part (What to film next). u holds the "
                "statistics and the stated tolerances only, not the equation's own form (the header): nor a centre "
                "of buoyancy off the body's centre (the equation puts both at L: on the paper's rig a centimetre "
                "changes the restoring torque by 3 % and m<sub>a</sub> by about 8 %)."
            )
            out.append(table_html(header, rows, caption=caption, table_id=f"budget-{rig}"))
            out.append(self._correlation_table(rig, entries, joint))
        return "".join(out) or "<p>No recommended joint fit: no uncertainty budget.</p>"

    def _correlation_table(self, rig: str, entries: dict, joint: dict) -> str:
        """The recommended coefficients' correlation with each other and with the rig values, every error in it (the
        fit document's ``covariance``, :func:`pendulum.fit.summary.combined_covariance`)."""
        covariance = joint.get("covariance")
        if not covariance:
            return ""
        values = list(covariance.get("rig_values") or [])
        names, corr = correlation_of(covariance, list(entries) + values)
        coefficients = [n for n in names if n in entries]
        if len(coefficients) < 2:
            return ""
        head = [COEFFICIENTS[n][0] if n in COEFFICIENTS else SYMBOLS.get(n, esc(n)) for n in names]
        rows = [
            [td(head[a])]
            + [
                td(esc(with_minus_sign(f"{corr[a, b]:.3f}")) if is_finite(corr[a, b]) else "·", "num")
                for b in range(len(names))
            ]
            for a in range(len(coefficients))
        ]
        caption = self.table_caption(
            f"Correlation of the recommended coefficients with each other and with the rig values they were fitted "
            f"with, rig {esc(rig)} (columns after the coefficients: Table 1's m, L, A, V, ρ ...), every error in it: "
            "the statistical covariance (widened by S) plus each rig value's shifts in the budget above, taken "
            "together. What carrying the coefficients into a vehicle model needs, with the standard uncertainties, "
            "where the model uses the same rig values: a volume read too large lowers m<sub>a</sub> and raises the "
            "buoyancy at once, so a ratio such as (m − ρV)/(m + m<sub>a</sub>) is known far better than its parts "
            "taken apart. Correlations near ±1 here come from a rig value all the coefficients share (one scale, "
            "through the inertia), not from the records: whether the records tell two terms apart is their "
            "statistical correlation (the model comparison's rule). C<sub>d</sub> carries A's tolerance, "
            "C<sub>d</sub>A does not: a model using this A takes C<sub>d</sub>A. The covariance is in the fit's "
            "JSON (<code>covariance</code>; the statistical correlation alone: <code>correlation</code>)."
        )
        return table_html([""] + head, rows, caption=caption, table_id=f"correlation-{rig}")
