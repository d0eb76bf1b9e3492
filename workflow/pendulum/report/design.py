"""The report's "What to film next" section, from the rule ``design``'s outputs (``results/design/<group>.json``
and ``.csv``: per candidate trial and coefficient, the predicted 95 % half-width;
:mod:`pendulum.design.next_trials`)."""

from __future__ import annotations

import re

import pandas as pd

from pendulum.design.next_trials import coefficient_words
from pendulum.report.data import ReportData, failure_text, is_ok, read_json, read_table
from pendulum.report.discovery import coefficient_label, sentence
from pendulum.report.figures import MPL_STYLE, figure_png, new_figure
from pendulum.report.format import PALETTE, esc, figure_html, fmt, is_finite

RIG_COLOURS = tuple(c for c in PALETTE if c != "#F0E442")


def design_figure(document: dict, table: pd.DataFrame) -> bytes | None:
    """One panel per target coefficient: predicted 95 % half-width against the release, one line per rig;
    today's half-width dashed, the part no trial removes (the tolerances) dotted, the target dash-dotted."""
    import matplotlib

    targets = [c for c in document.get("targets", []) if c in set(table.coefficient)]
    if not targets:
        return None
    with matplotlib.rc_context(MPL_STYLE):
        fig = new_figure(10, 0.6 + 2.4 * ((len(targets) + 1) // 2))
        axes = fig.subplots((len(targets) + 1) // 2, min(len(targets), 2), squeeze=False).ravel()
        for ax, name in zip(axes, targets, strict=False):
            if today_value(document["today"][name]) == "0 (at bound)":  # no share of zero to plot
                ax.set_title(coefficient_words(name), loc="left")
                ax.text(0.5, 0.5, "at its bound (0): no relative half-width", ha="center", transform=ax.transAxes)
                ax.set_axis_off()
                continue
            rows = table[table.coefficient == name]
            for i, (rig, r) in enumerate(rows.groupby("rig", sort=True)):
                r = r.sort_values("release_deg")
                style = "--o" if bool(r.described_rig.iloc[0]) else "-o"
                ax.plot(
                    r.release_deg,
                    100 * r.halfwidth95_predicted / abs(r.value),
                    style,
                    ms=3,
                    lw=1.0,
                    color=RIG_COLOURS[i % len(RIG_COLOURS)],
                    label=f"+1 trial on {rig}",
                )
            today = document["today"][name]
            ax.axhline(100 * today["relative_halfwidth95"], color="0.2", lw=0.9, ls="--", label="today")
            if today["floor_relative_halfwidth95"] > 0:
                floor = 100 * today["floor_relative_halfwidth95"]
                ax.axhline(floor, color="0.5", lw=0.9, ls=":", label="tolerances alone")
            target = document.get("target_relative_halfwidth95")
            if target:
                ax.axhline(100 * target, color="#009E73", lw=0.9, ls="-.", label="target")
            ax.set_ylim(bottom=0)
            ax.ticklabel_format(axis="y", useOffset=False)
            ax.set_title(coefficient_words(name), loc="left")
            ax.set_xlabel("release angle of the added trial (°)")
            ax.set_ylabel("95 % half-width (% of value)")
            ax.legend(fontsize=7, loc="best")
        for ax in axes[len(targets) :]:
            ax.set_visible(False)
        return figure_png(fig)


def today_value(entry: dict) -> str:
    """Today's estimate, "0 (at bound)" where it sits at zero (within 10⁻⁶ of its half-width, as the advice of
    :func:`pendulum.design.tolerances.measurement_advice` takes it)."""
    value = entry["value"]
    return "0 (at bound)" if abs(value) <= 1e-6 * abs(entry["halfwidth95"]) else fmt(value, 4)


def relative_text(entry: dict) -> str:
    """ " (11 %)": the half-width as a share of the value; nothing where the value cannot be told from zero."""
    relative = entry["relative_halfwidth95"]
    return f" ({fmt(100 * relative, 2)} %)" if is_finite(relative) and relative < 10 else " (not told from 0)"


def today_table(document: dict, caption) -> str:
    rows = []
    for name in document.get("targets", []):
        e = document["today"][name]
        target = document.get("to_target", {}).get(name, {})
        rows.append(
            "<tr>"
            f"<td>{coefficient_label(name) if name != 'drag_coefficient' else 'drag coefficient, C<sub>d</sub>'}</td>"
            f'<td class="num">{today_value(e)}</td>'
            f'<td class="num">±{fmt(e["halfwidth95"], 3)}{relative_text(e)}</td>'
            f'<td class="num">±{fmt(1.959963984540054 * e["stderr_systematic"], 3)}</td>'
            f"<td>{design_text(target.get('sentence', ''))}</td>"
            "</tr>"
        )
    head = (
        "<tr><th>coefficient</th><th>today</th><th>95 % half-width today</th>"
        "<th>of which no trial removes (tolerances)</th>"
        f"<th>to ±{fmt(100 * document.get('target_relative_halfwidth95', 0), 2)} %</th></tr>"
    )
    return (
        f"<table>{caption('Today’s intervals and what more trials can do')}"
        f"<thead>{head}</thead><tbody>{''.join(rows)}</tbody></table>"
    )


SYMBOL = re.compile(r"\b([A-Za-zτ])_([A-Za-z])\b")


def design_text(text: str) -> str:
    """A design sentence as HTML: capitalised, a full stop, symbols with subscripts (C_d → C<sub>d</sub>)."""
    text = sentence(text.strip())
    if text and text[-1] not in ".!?":
        text += "."
    return SYMBOL.sub(r"\1<sub>\2</sub>", esc(text))


def _informative(document: dict, table: pd.DataFrame) -> bool:
    """Whether some candidate narrows a target's interval by 1 % or more (else every line lies on today's)."""
    rows = table[table.coefficient.isin(document.get("targets", []))]
    return bool(len(rows)) and bool((rows.halfwidth95_predicted < 0.99 * rows.halfwidth95_today).any())


class DesignSections(ReportData):
    """What to film next: per group, the recommended trials, today's intervals and the predicted ones."""

    def design_section(self) -> str:
        groups = self.files.get("design") or {}
        if not groups:
            return "<p>No design: discovery did not run (config <code>discovery.baseline</code>).</p>"
        out = []
        for group, paths in sorted(groups.items()):
            document = read_json(paths["document"])
            head = f'<h3 id="design-{esc(group)}">Group {esc(group)}</h3>'
            if not is_ok(document):
                out.append(head + f'<p class="warn">{esc(sentence(failure_text(document)))}</p>')
                continue
            table = read_table(paths["table"])
            items = "".join(f"<li>{design_text(r['sentence'])}</li>" for r in document["recommendations"])
            items += "".join(f"<li>{design_text(r['sentence'])}</li>" for r in document.get("separating", []))
            model = document.get("model") or " + ".join(document.get("model_terms", []))
            next_label = "Next, if the model were right:" if document.get("model_misfit") else "Next:"
            fewer = f"<p>{design_text(document['fewer_recommended'])}</p>" if document.get("fewer_recommended") else ""
            out.append(
                head + f"<p>For discovery’s final model ({esc(model)}), fitted to {len(document.get('trials', []))} "
                "trial(s): the 95 % half-width each coefficient would have with one more trial, released at rest "
                "from the angle on the x-axis (the model assumed right; the tolerances’ part carried unchanged).</p>"
                + (
                    f'<p class="warn">{design_text(document["model_misfit"])}</p>'
                    if document.get("model_misfit")
                    else ""
                )
                + f'<div class="discovery-verdict design-next"><b>{next_label}</b><ol>{items}</ol>{fewer}</div>'
                + today_table(document, self.table_caption)
            )
            if document.get("warnings"):
                warned = "".join(f"<li>{design_text(w)}</li>" for w in document["warnings"])
                out.append(f'<p class="warn">The design’s warnings:</p><ul>{warned}</ul>')
            png = design_figure(document, table) if _informative(document, table) else None
            if png is None and not table.empty:
                out.append(
                    '<p class="table-note">No figure: every candidate trial leaves these intervals as they are '
                    "(within 1 %): the tolerances set them.</p>"
                )
            if png:
                out.append(
                    figure_html(
                        png,
                        self.figure_caption(
                            "Predicted 95 % half-width after one more trial, against its release angle (both signs)"
                        ),
                        f"predicted half-widths for group {group}",
                    )
                )
        return "".join(out)
