"""The results report: its tables, figures and the deterministic notebook → HTML conversion.

``notebooks/report.ipynb`` calls :class:`Report` section by section; the
Snakemake rule ``report`` runs it with papermill (:func:`build_report`) and
converts it to one self-contained HTML file. Everything here only *reads* what
the rules wrote (fit documents, curve and half-cycle tables, joint fits, the
summary and status tables, tracking summaries, truth files of synthetic
trials): nothing is fitted. Identical inputs give identical bytes: figures are
PNG without a software stamp, the executed notebook carries no timestamps and
fixed cell ids.
"""

from __future__ import annotations

import base64
import html
import io
import json
import math
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
import pandas as pd
import yaml

from pendulum.physics import ADDED_MASS, TERMS, Rig
from pendulum.records import rig_tolerances

# ---------------------------------------------------------------------------
# Names, symbols and units

COEFFICIENTS = {  # parameter → (symbol as HTML, name, unit)
    ADDED_MASS: ("m<sub>a</sub>", "added mass", "kg"),
    "drag_area_m2": ("C<sub>d</sub>A", "drag area", "m²"),
    "drag_coefficient": ("C<sub>d</sub>", "drag coefficient", "–"),
    "linear_damping_nm_s": ("c", "linear damping", "N·m·s"),
    "friction_torque_nm": ("τ<sub>f</sub>", "friction torque", "N·m"),
}
PLAIN_SYMBOLS = {  # axis labels (matplotlib mathtext)
    ADDED_MASS: "$m_a$ (kg)",
    "drag_area_m2": "$C_dA$ (m²)",
    "drag_coefficient": "$C_d$",
    "linear_damping_nm_s": "$c$ (N·m·s)",
    "friction_torque_nm": "$\\tau_f$ (N·m)",
}
TERM_LABELS = {
    "quadratic_drag": "quadratic drag",
    "linear_damping": "linear damping",
    "coulomb_friction": "Coulomb friction",
}
RIG_LABELS = {  # rig value → (label, unit)
    "mass_kg": ("mass m", "kg"),
    "length_m": ("length L (pivot to body centre)", "m"),
    "frontal_area_m2": ("frontal area A", "m²"),
    "displaced_volume_m3": ("displaced volume V", "m³"),
    "fluid_density_kg_m3": ("fluid density ρ", "kg/m³"),
    "gravity_m_s2": ("gravity g", "m/s²"),
    "body_inertia_kg_m2": ("body inertia about the pivot I_p", "kg·m²"),
    "characteristic_length_m": ("characteristic length D (KC)", "m"),
    "kinematic_viscosity_m2_s": ("kinematic viscosity ν", "m²/s"),
}
# Okabe–Ito colours (distinct for colour-blind readers and in greyscale print by marker)
PALETTE = ("#D55E00", "#E69F00", "#0072B2", "#009E73", "#CC79A7", "#56B4E9", "#F0E442", "#000000")
MARKERS = ("s", "^", "o", "D", "v", "P", "X", "*")
FIGURE_DPI = 110
MINUS = "\u2212"


# ---------------------------------------------------------------------------
# Numbers as a reader wants them

_SUPERSCRIPT = str.maketrans("-0123456789", "⁻⁰¹²³⁴⁵⁶⁷⁸⁹")


def _finite(value) -> bool:
    try:
        return value is not None and math.isfinite(float(value))
    except (TypeError, ValueError):
        return False


def _minus(text: str) -> str:
    return text.replace("-", MINUS)


def _scientific(value: float, sig: int) -> str:
    mantissa, exponent = f"{value:.{sig - 1}e}".split("e")
    return _minus(f"{mantissa}×10{str(int(exponent)).translate(_SUPERSCRIPT)}")


def fmt(value, sig: int = 3) -> str:
    """``value`` to ``sig`` significant figures; ×10ⁿ outside 0.001–99 999; "—" when missing."""
    if not _finite(value):
        return "—"
    value = float(value)
    if value == 0:
        return "0"
    if not 1e-3 <= abs(value) < 1e5:
        return _scientific(value, sig)
    decimals = max(0, sig - 1 - math.floor(math.log10(abs(value))))
    return _minus(f"{value:.{decimals}f}")


def decimals_for(uncertainty: float, digits: int = 2) -> int:
    """Decimal places that keep ``digits`` significant figures of ``uncertainty`` (≥ 0)."""
    return max(0, digits - 1 - math.floor(math.log10(abs(uncertainty))))


def fmt_at(value: float, decimals: int) -> str:
    return _minus(f"{value:.{decimals}f}")


def estimate_parts(entry: dict | None) -> tuple[str, str]:
    """(value, qualifier) of one coefficient of a fit document, rounded to its uncertainty.

    The value keeps two significant figures of the 95 % interval's half-width;
    the qualifier is the interval ``[low, high]``, or for a coefficient at its
    bound ``(at bound; < upper)`` with the one-sided 95 % upper limit, plus
    ``not identifiable`` when flagged. Never prints a bound's rounding noise
    (4.3e-14) as a measurement.
    """
    if not entry or not _finite(entry.get("value")):
        return "—", ""
    value = float(entry["value"])
    low, high = (entry.get("ci95") or [None, None])[:2]
    if entry.get("at_bound"):
        bound = entry.get("lower_bound", value)
        upper = f"< {fmt(high, 2)}" if _finite(high) else "no upper limit"
        return fmt(bound if _finite(bound) else value, 3), f"(at bound; {upper})"
    qualifier = ""
    if _finite(low) and _finite(high) and high > low:
        half = (float(high) - float(low)) / 2
        decimals = decimals_for(half)
        scale = max(abs(value), abs(float(low)), abs(float(high)))
        if decimals > 6 or scale >= 1e5:
            text, qualifier = fmt(value, 3), f"[{fmt(low, 3)}, {fmt(high, 3)}]"
        else:
            text = fmt_at(value, decimals)
            qualifier = f"[{fmt_at(float(low), decimals)}, {fmt_at(float(high), decimals)}]"
    else:
        text = fmt(value, 3)
    if entry.get("identifiable") is False:
        qualifier = f"{qualifier} not identifiable".strip()
    return text, qualifier


def format_estimate(entry: dict | None) -> str:
    """One coefficient as text, e.g. ``2.50 [2.26, 2.74]`` or ``0 (at bound; < 0.035)``."""
    return " ".join(p for p in estimate_parts(entry) if p)


# ---------------------------------------------------------------------------
# HTML pieces

esc = html.escape


def table_html(header: list, rows: list[list[str]], *, caption: str, table_id: str, row_attrs=None, note=None):
    """A table with its numbered caption above and a note below; cells are HTML (escape text first).

    ``header``: one row of header texts, or several rows of ready ``<th>`` cells.
    """
    if header and isinstance(header[0], list):
        head = "</tr><tr>".join("".join(row) for row in header)
    else:
        head = "".join(f"<th>{h}</th>" for h in header)
    body = []
    for i, row in enumerate(rows):
        attrs = (row_attrs[i] if row_attrs else None) or {}
        attr_text = "".join(f' {k}="{esc(str(v))}"' for k, v in attrs.items())
        body.append(f"<tr{attr_text}>" + "".join(row) + "</tr>")
    note_html = f'<p class="table-note">{note}</p>' if note else ""
    caption_html = f'<p class="caption">{caption}</p>' if caption else ""
    return (
        f'<div class="table-block">{caption_html}<div class="table-wrap"><table id="{table_id}">'
        f"<thead><tr>{head}</tr></thead><tbody>{''.join(body)}</tbody></table></div>{note_html}</div>"
    )


def td(content: str, cls: str | None = None, span: int = 1, title: str | None = None) -> str:
    attrs = f' class="{cls}"' if cls else ""
    attrs += f' colspan="{span}"' if span > 1 else ""
    attrs += f' title="{esc(title)}"' if title else ""
    return f"<td{attrs}>{content}</td>"


def estimate_cell(entry: dict | None, missing: str = "—") -> str:
    if entry is None:
        return td(missing, "na", title="not a parameter of this variant")
    value, qualifier = estimate_parts(entry)
    flag = " flagged" if entry.get("at_bound") or entry.get("identifiable") is False else ""
    title = entry.get("note") or entry.get("reason")
    return td(f'<span class="v">{esc(value)}</span><span class="q">{esc(qualifier)}</span>', "num" + flag, title=title)


def png_data_uri(data: bytes) -> str:
    return "data:image/png;base64," + base64.b64encode(data).decode("ascii")


def figure_html(png: bytes, caption: str, alt: str, cls: str = "") -> str:
    return (
        f'<figure class="{("fig " + cls).strip()}"><img src="{png_data_uri(png)}" alt="{esc(alt)}">'
        f"<figcaption>{caption}</figcaption></figure>"
    )


def figure_png(fig) -> bytes:
    """A matplotlib figure as PNG bytes (no software or date stamp: identical bytes for identical input)."""
    buffer = io.BytesIO()
    fig.savefig(buffer, format="png", dpi=FIGURE_DPI, metadata={"Software": None})
    return buffer.getvalue()


def log_ticks(axis) -> None:
    """Ticks at 1, 2, 5 × 10ⁿ labelled as plain numbers (no crowded minor labels)."""
    from matplotlib.ticker import FuncFormatter, LogLocator, NullFormatter

    axis.set_major_locator(LogLocator(subs=(1.0, 2.0, 5.0)))
    axis.set_major_formatter(FuncFormatter(lambda v, _: f"{v:g}"))
    axis.set_minor_formatter(NullFormatter())


def new_figure(width_in: float, height_in: float):
    """A figure outside pyplot (no global state, nothing shown twice in the notebook)."""
    from matplotlib.figure import Figure

    return Figure(figsize=(width_in, height_in), layout="constrained")


MPL_STYLE = {
    "font.size": 9,
    "axes.titlesize": 10,
    "axes.labelsize": 9,
    "legend.fontsize": 8,
    "xtick.labelsize": 8,
    "ytick.labelsize": 8,
    "axes.grid": True,
    "grid.alpha": 0.3,
    "axes.spines.top": False,
    "axes.spines.right": False,
    "svg.hashsalt": "pendulum",
    "path.simplify": False,
}


# ---------------------------------------------------------------------------
# Reading the results


def read_json(path) -> dict:
    """A JSON document; a missing or unreadable file becomes a failed document naming it."""
    try:
        return json.loads(Path(path).read_text())
    except (OSError, ValueError) as exc:
        return {"status": "failed", "failed_stage": "report", "error": f"{path}: cannot be read ({exc})"}


def read_table(path) -> pd.DataFrame:
    """A CSV table; missing or header-only gives an empty frame."""
    try:
        return pd.read_csv(path)
    except (OSError, ValueError, pd.errors.EmptyDataError):
        return pd.DataFrame()


def is_ok(document: dict | None) -> bool:
    return bool(document) and document.get("status", "ok") != "failed"


def failure_text(document: dict | None) -> str:
    if not document:
        return "no result"
    stage = document.get("failed_stage")
    error = document.get("error") or "failed"
    return f"{stage} failed: {error}" if stage else error


def true_value(truth: dict | None, name: str) -> float | None:
    """A coefficient's true value from a synthetic trial's truth file (C_d from C_dA / A)."""
    if not truth:
        return None
    values = truth.get("truth") or {}
    if name == "drag_coefficient":
        area, cda = (truth.get("rig") or {}).get("frontal_area_m2"), true_value(truth, "drag_area_m2")
        return cda / area if _finite(area) and cda is not None else None
    if name in values:
        return float(values[name])
    effects = truth.get("effects")
    term = next((t for t, spec in TERMS.items() if spec.parameter == name), None)
    if effects is not None and term is not None and term not in effects:
        return 0.0
    return None


def variant_order(variants: dict) -> list[str]:
    """Simplest first (fewest terms), then by name: nested variants read as added terms."""
    return sorted(variants, key=lambda v: (len(variants[v]), v))


def nested_parent(variants: dict, variant: str) -> str | None:
    """The variant with exactly one term fewer whose terms all appear in ``variant`` (None if there is none)."""
    terms = set(variants[variant])
    parents = [v for v in variant_order(variants) if set(variants[v]) < terms and len(terms - set(variants[v])) == 1]
    return parents[0] if parents else None


def best_variant(summary: pd.DataFrame, fit_label: str, trials: list[str]) -> dict | None:
    """The best-supported variant of one rig: lowest AIC among fits of the same samples.

    Basis, in order: the joint fits' AIC when every variant's joint fit used the
    same samples; else the AIC summed over the per-trial fits of the trials that
    every variant fitted to the same samples; else the joint AIC with a warning.
    Returns ``variant``, ``basis``, ``delta_aic`` and ``delta_bic`` (variant →
    difference to the best), ``bic_best`` and ``comparable``. None without fits.
    """
    if summary.empty or "fit" not in summary:
        return None
    joint = summary[summary.fit == fit_label].sort_values("variant")
    if joint.empty:
        return None
    comparable = True
    if joint.samples_digest.nunique() == 1:
        aic, bic = joint.set_index("variant").aic, joint.set_index("variant").bic
        basis = "AIC of the joint fits (every variant fitted to the same samples)"
    else:
        per = summary[summary.fit.isin(trials) & summary.variant.isin(joint.variant)]
        common = sorted(
            t for t, g in per.groupby("fit") if set(g.variant) == set(joint.variant) and g.samples_digest.nunique() == 1
        )
        if common:
            chosen = per[per.fit.isin(common)].groupby("variant")
            aic, bic = chosen.aic.sum(), chosen.bic.sum()
            basis = f"AIC summed over the {len(common)} per-trial fits every variant made to the same samples"
        else:
            aic, bic = joint.set_index("variant").aic, joint.set_index("variant").bic
            basis = "AIC of the joint fits, although they used different samples (not strictly comparable)"
            comparable = False
    aic, bic = aic.sort_index(), bic.sort_index()
    best = str(aic.idxmin())
    return {
        "variant": best,
        "basis": basis,
        "delta_aic": {str(k): float(v - aic.min()) for k, v in aic.items()},
        "delta_bic": {str(k): float(v - bic.min()) for k, v in bic.items()},
        "bic_best": str(bic.idxmin()),
        "comparable": comparable,
    }


def short_warning(text: str) -> str:
    """A fit warning in two or three words (Table 3's warning column)."""
    lowered = text.lower()
    for key, short in (
        ("misses a systematic effect", "misfit"),
        ("lower bound", "at bound"),
        ("not identifiable", "not identifiable"),
        ("not converge", "not converged"),
        ("singular", "singular Jacobian"),
        ("inseparable", "inseparable parameters"),
        ("time base", "time base?"),
        ("correlated", "correlated parameters"),
        ("small-amplitude period", "period vs rig values"),
    ):
        if key in lowered:
            return short
    return text if len(text) < 30 else text[:27] + "…"


# ---------------------------------------------------------------------------
# The report


@dataclass
class Report:
    """Every result of one build, read once, and the report's sections as HTML.

    ``files``: the paths the rule declares as inputs (``summary``, ``status``,
    ``trials`` → per trial ``angles``/``frames``/``tracks``/``contact_sheet``/
    ``truth``, ``fits`` → variant → trial → ``fit``/``curve``/``cycles``,
    ``joint`` → variant → rig). ``trials``: trial → ``rig``, ``kind``,
    ``source``, ``overrides``. ``rigs``: rig → ``values``, ``tolerances`` (as
    stated). ``variants``: variant → terms.
    """

    files: dict
    trials: dict
    rigs: dict
    variants: dict
    provenance: dict = field(default_factory=dict)
    fitting: dict = field(default_factory=dict)
    n_tables: int = 0
    n_figures: int = 0

    def __post_init__(self):
        f = self.files
        self.summary = read_table(f["summary"]) if f.get("summary") else pd.DataFrame()
        self.status = read_table(f["status"]) if f.get("status") else None
        self.fits = {
            (v, t): read_json(p["fit"]) for v, by_trial in f.get("fits", {}).items() for t, p in by_trial.items()
        }
        self.joint = {(v, r): read_json(p) for v, by_rig in f.get("joint", {}).items() for r, p in by_rig.items()}
        trial_files = f.get("trials", {})
        self.docs = {
            (t, kind): read_json(p)
            for t, paths in trial_files.items()
            for kind, p in paths.items()
            if kind in ("angles", "frames", "tracks")
        }
        self.truth = {t: yaml.safe_load(Path(p["truth"]).read_text()) for t, p in trial_files.items() if p.get("truth")}
        self.order = variant_order(self.variants)
        self.colour = {v: PALETTE[i % len(PALETTE)] for i, v in enumerate(self.order)}
        self.marker = {v: MARKERS[i % len(MARKERS)] for i, v in enumerate(self.order)}
        n_trials = {r: sum(info["rig"] == r for info in self.trials.values()) for r in self.rigs}
        n_trials.update(
            {info["rig"]: sum(i["rig"] == info["rig"] for i in self.trials.values()) for info in self.trials.values()}
        )
        # rigs with most trials first; trials by rig, then largest release first
        self.rig_names = sorted(n_trials, key=lambda r: (-n_trials[r], r))
        self._trial_order = sorted(self.trials, key=self._trial_key)
        self.best = {
            rig: best_variant(self.summary, f"joint:{rig}", self.rig_trials(rig))
            for rig in self.rig_names
            if self.rig_trials(rig)
        }
        self._tables: dict = {}

    # -- look-ups ---------------------------------------------------------

    def rig_trials(self, rig: str) -> list[str]:
        return [t for t in self.trial_order() if self.trials[t]["rig"] == rig]

    def release_detected(self, trial: str) -> bool:
        angles = self.docs.get((trial, "angles"), {})
        return is_ok(angles) and _finite(angles.get("hold_angle_deg"))

    def release_deg(self, trial: str) -> float | None:
        """Release angle: the hold angle before release, else (no release in the record) the first fitted angle."""
        if self.release_detected(trial):
            return float(self.docs[(trial, "angles")]["hold_angle_deg"])
        for v in self.order:
            fit = self.fits.get((v, trial))
            if is_ok(fit) and fit.get("trials", {}).get(trial):
                return float(fit["trials"][trial]["theta0_deg"])
        return None

    def _trial_key(self, trial: str):
        angle = self.release_deg(trial)
        rig = self.rig_names.index(self.trials[trial]["rig"])
        return (rig, angle is None, -abs(angle) if angle is not None else 0.0, -(angle or 0.0), trial)

    def trial_order(self) -> list[str]:
        """By rig, then largest release first (as the paper's tables), then by name; trials without an angle last."""
        return list(self._trial_order)

    def kc(self, variant: str, trial: str) -> float | None:
        fit = self.fits.get((variant, trial))
        return float(fit["keulegan_carpenter_number"]) if is_ok(fit) else None

    def curve(self, variant: str, trial: str) -> pd.DataFrame:
        key = ("curve", variant, trial)
        if key not in self._tables:
            self._tables[key] = read_table(self.files["fits"][variant][trial]["curve"])
        return self._tables[key]

    def cycles(self, variant: str, trial: str) -> pd.DataFrame:
        key = ("cycles", variant, trial)
        if key not in self._tables:
            self._tables[key] = read_table(self.files["fits"][variant][trial]["cycles"])
        return self._tables[key]

    def recommended(self, rig: str) -> str | None:
        best = self.best.get(rig)
        return best["variant"] if best else None

    def failed_trials(self) -> pd.DataFrame:
        """Failed trials (status table when present, else from the documents)."""
        if self.status is not None and not self.status.empty:
            table = self.status.fillna("")
            return table[table.status != "ok"].sort_values("trial").reset_index(drop=True)
        rows = []
        for t in sorted(self.trials):
            for stage in ("frames", "tracks", "angles"):
                doc = self.docs.get((t, stage))
                if doc is not None and not is_ok(doc):
                    rows.append(
                        {"trial": t, "stage": doc.get("failed_stage", stage), "reason": doc.get("error", ""), "log": ""}
                    )
                    break
        return pd.DataFrame(rows, columns=["trial", "stage", "reason", "log"])

    def table_caption(self, text: str) -> str:
        self.n_tables += 1
        return f"<b>Table {self.n_tables}.</b> {text}"

    def figure_caption(self, text: str) -> str:
        self.n_figures += 1
        return f"<b>Figure {self.n_figures}.</b> {text}"

    def variant_label(self, variant: str) -> str:
        terms = " + ".join(TERM_LABELS.get(t, t) for t in self.variants[variant]) or "added mass only"
        return f"{variant} ({terms})"

    def angle_label(self, trial: str) -> str:
        """Release angle, e.g. "+20°"; "+6°†" when the record holds no release (the first fitted angle)."""
        a = self.release_deg(trial)
        if a is None:
            return "—"
        return _minus(f"{a:+.0f}°") + ("" if self.release_detected(trial) else "†")

    def dagger_note(self) -> str:
        """The note for release angles marked †, when any trial has one."""
        if all(self.release_detected(t) or self.release_deg(t) is None for t in self.trials):
            return ""
        return " † No release in the record (e.g. an angle table that starts mid-swing): the first fitted angle."

    # -- sections -----------------------------------------------------------

    def header(self) -> str:
        p = self.provenance
        commit = p.get("commit")
        built = (
            f"Code: commit <code>{esc(commit[:12])}</code> of {esc(str(p.get('commit_time_utc')))}"
            + (' <span class="warn">with uncommitted changes</span>' if p.get("dirty") else "")
            if commit
            else 'Code: <span class="warn">version not recorded (not built from a git commit)</span>'
        )
        n_failed = len(self.failed_trials())
        return (
            "<header><h1>Free-decay pendulum: added mass and drag coefficient</h1>"
            f'<p class="subtitle">{len(self.trials)} trial(s) on {len(self.rig_names)} rig(s), '
            f"{len(self.variants)} model variant(s) fitted side by side"
            + (f', <span class="warn">{n_failed} trial(s) failed</span>' if n_failed else "")
            + f". {built}.</p>"
            '<p class="subtitle">Equation of motion: (I<sub>p</sub> + m<sub>a</sub>L²) θ̈ = −(mg − B) L sin θ '
            "− ½ρC<sub>d</sub>AL³ θ̇|θ̇| − c θ̇ − τ<sub>f</sub> sgn θ̇; each variant keeps a subset of the "
            "damping terms. Intervals are 95 % (statistical and rig-value systematic errors combined).</p></header>"
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
                    "no coefficients can be recommended. See the failed trials below.</p></section>"
                )
                continue
            variant = best["variant"]
            joint = self.joint.get((variant, rig), {})
            truths = [self.truth.get(t) for t in trials if t in self.truth]
            header = ["coefficient", "estimate", "95 % interval"] + (["truth (synthetic)"] if truths else [])
            rows = []
            for name, entry in joint.get("parameters", {}).items():
                symbol, label, unit = COEFFICIENTS.get(name, (esc(name), name, ""))
                value, qualifier = estimate_parts(entry)
                row = [
                    td(f"{label}, {symbol} ({unit})" if unit != "–" else f"{label}, {symbol}"),
                    td(f"<b>{esc(value)}</b>", "num"),
                    td(esc(qualifier), "num"),
                ]
                if truths:
                    row.append(td(esc(self._truth_text(trials, name)), "num"))
                rows.append(row)
            table = table_html(header, rows, caption="", table_id=f"recommended-{rig}")
            others = [v for v in self.order if v != variant and (v, rig) in self.joint and is_ok(self.joint[(v, rig)])]
            delta = "; ".join(f"{esc(v)} +{fmt(best['delta_aic'].get(v), 3)}" for v in others if v in best["delta_aic"])
            bic_note = "BIC agrees" if best["bic_best"] == variant else f"BIC prefers {esc(best['bic_best'])}"
            basis = f"Chosen by the lowest {esc(best['basis'])}" + (f" (ΔAIC: {delta}; {bic_note})." if delta else ".")
            warnings = self._summary_warnings(rig, variant, joint, best)
            warn_html = (
                '<ul class="warnings">' + "".join(f"<li>{w}</li>" for w in warnings) + "</ul>"
                if warnings
                else "<p>No warnings.</p>"
            )
            boxes.append(
                f'<section class="summary-box" id="summary-{esc(rig)}">'
                f"<h3>Recommended coefficients — rig {esc(rig)}: joint fit of {len(joint.get('trials', {}))} "
                f"trial(s), variant {esc(self.variant_label(variant))}</h3>{table}"
                f'<p class="basis">{basis}</p>'
                f'<p class="verdict"><b>Consistency:</b> {self._verdict_sentence(rig, variant)}</p>'
                f"<p><b>Warnings that matter:</b></p>{warn_html}</section>"
            )
        return "".join(boxes) or '<p class="warn">No trials: nothing to report.</p>'

    def _truth_text(self, trials: list[str], name: str) -> str:
        values = {true_value(self.truth.get(t), name) for t in trials if t in self.truth}
        values.discard(None)
        if not values:
            return "—"
        if len(values) == 1:
            return fmt(values.pop(), 4)
        return "varies by trial"

    def _verdict_sentence(self, rig: str, variant: str) -> str:
        joint = self.joint.get((variant, rig), {})
        consistency = joint.get("consistency") or {}
        verdict = consistency.get("verdict", "not tested")
        n = len(joint.get("trials", {}))
        scale = {
            name: p.get("scale_factor")
            for name, p in (consistency.get("parameters") or {}).items()
            if _finite(p.get("scale_factor"))
        }
        worst = max(scale, key=scale.get) if scale else None
        others = [
            f"{esc(v)}: {esc((self.joint[(v, rig)].get('consistency') or {}).get('verdict', 'not tested'))}"
            for v in self.order
            if v != variant and is_ok(self.joint.get((v, rig)))
        ]
        sentence = (
            f"under the {esc(variant)} model the {n} trial(s) are <b>{esc(verdict)}</b> "
            f"({esc(consistency.get('explanation', ''))}"
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
                '(see <a href="#failed-trials">Failed trials</a>).'
            )
        if not best["comparable"]:
            out.append("The variants' joint fits used different samples: their AIC values are not strictly comparable.")
        for name, entry in joint.get("parameters", {}).items():
            if entry.get("at_bound"):
                out.append(
                    f"{esc(COEFFICIENTS.get(name, ('', name))[1])} is at its lower bound: "
                    "an upper limit, not a measurement."
                )
            elif entry.get("identifiable") is False:
                out.append(f"{esc(COEFFICIENTS.get(name, ('', name))[1])} is not identifiable from these records.")
        if (joint.get("consistency") or {}).get("verdict") == "inconsistent":
            out.append(
                "The per-trial estimates disagree beyond their intervals: the joint interval is widened by S, "
                "but the model may miss physics."
            )
        for w in joint.get("warnings", []):
            if "lower bound" not in w and "not identifiable" not in w:  # said above, in words
                out.append(esc(w))
        per_trial = [
            t
            for t in self.rig_trials(rig)
            if is_ok(self.fits.get((variant, t))) and self.fits[(variant, t)].get("warnings")
        ]
        if per_trial:
            out.append(
                f"Per-trial {esc(variant)} fits with warnings: {', '.join(esc(t) for t in per_trial)} (Table 3)."
            )
        if not self.provenance.get("commit"):
            out.append("Not built from a git commit: the code version of these results is not recorded.")
        elif self.provenance.get("dirty"):
            out.append("The work tree had uncommitted changes: the commit does not fully identify the code.")
        return out

    def rig_table(self) -> str:
        """Table: rig values with 1σ tolerances (stated or default) and per-trial overrides."""
        rigs = [r for r in self.rig_names if r in self.rigs]
        rows = []
        for key, (label, unit) in RIG_LABELS.items():
            cells = []
            for rig in rigs:
                values = self.rigs[rig]["values"]
                stated = self.rigs[rig].get("tolerances") or {}
                value = values.get(key)
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
                cells += [td(esc(fmt(value, 4)), "num"), td(esc(tol_text), "num")]
            rows.append([td(esc(label)), td(esc(unit))] + cells)
        for key, label, unit in (
            ("pivot_px", "pivot in the image", "px"),
            ("vertical_deg", "image angle of the vertical", "°"),
        ):
            cells = []
            for rig in rigs:
                value = self.rigs[rig]["values"].get(key)
                text = (
                    "not given: estimated from the marker paths"
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
                try:
                    cells += [
                        td(esc(fmt(f(Rig.from_mapping(self.rigs[rig]["values"])), 4)), "num"),
                        td("derived", "na"),
                    ]
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
        trials_by_rig = "; ".join(f"{esc(r)}: {', '.join(esc(t) for t in self.rig_trials(r))}" for r in rigs)
        note += f" Trials per rig — {trials_by_rig}."
        caption = self.table_caption(
            "Rig values used (measured, not fitted) with their 1σ tolerances; a tolerance not stated in the "
            "configuration takes the default fraction. They enter the fits' systematic error budget."
        )
        return table_html(header, rows, caption=caption, table_id="table1", note=note)

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
            row = [td(esc(trial)), td(self.angle_label(trial), "num"), td(esc(fmt(noise, 2)), "num")]
            for v in order:
                fit = self.fits.get((v, trial))
                if is_ok(fit):
                    row += [
                        td(esc(fmt(fit["rms_rad"], 2)), "num"),
                        td(esc(fmt(fit["rms_deg"], 2)), "num"),
                        td(esc(fmt(1000 * fit["rms_arc_m"], 2)), "num"),
                    ]
                else:
                    row.append(td("failed", "na fail", span=3, title=failure_text(fit)))
            rows.append(row)
            attrs.append({"data-trial": trial})
        for rig in self.rig_names:
            row = [td(f"<b>joint</b> {esc(rig)}"), td("all", "num"), td("", "na")]
            for v in order:
                joint = self.joint.get((v, rig))
                if is_ok(joint):
                    row += [
                        td(esc(fmt(joint["rms_rad"], 2)), "num"),
                        td(esc(fmt(joint["rms_deg"], 2)), "num"),
                        td(esc(fmt(1000 * joint["rms_arc_m"], 2)), "num"),
                    ]
                else:
                    row.append(td("—", "na", span=3))
            rows.append(row)
            attrs.append({"data-trial": f"joint:{rig}", "class": "joint"})
        caption = self.table_caption(
            "RMS residual (fitted − measured angle over the fitted samples) per trial and model variant, in "
            "radians, degrees and metres of arc at the body (Lθ, here in mm). The record noise is the angle "
            "noise of the tracked record: a variant that captures the physics leaves an RMS close to it."
            + self.dagger_note()
        )
        return table_html(header, rows, caption=caption, table_id="table2", row_attrs=attrs)

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

        def fit_row(label_cells, v, fit, kind, trial):
            if not is_ok(fit):
                row = label_cells + [td(esc(v)), td(esc(failure_text(fit)), "na fail", span=len(names) + 1)]
            else:
                warnings = fit.get("warnings", [])
                short = sorted({short_warning(w) for w in warnings})
                if warnings:
                    notes.append((kind, trial, v, warnings))
                row = label_cells + [td(esc(v), "vname")]
                row += [estimate_cell(fit["parameters"].get(n)) if self._has(v, n) else td("—", "na") for n in names]
                row.append(td(esc(", ".join(short)) or "", "warncell"))
            rows.append(row)
            attrs.append({"data-trial": trial, "data-variant": v, "data-kind": kind})

        for trial in self.trial_order():
            first = True
            for v in self.order:
                kc = self.kc(v, trial)
                label = [
                    td(esc(trial) if first else ""),
                    td(self.angle_label(trial) if first else "", "num"),
                    td(esc(fmt(kc, 2)), "num"),
                ]
                fit_row(label, v, self.fits.get((v, trial)), "trial", trial)
                first = False
            if trial in self.truth:
                rows.append(
                    [td(""), td(""), td(""), td("truth", "truth")]
                    + [td(esc(fmt(true_value(self.truth[trial], n), 4)), "num truth") for n in names]
                    + [td("")]
                )
                attrs.append({"data-trial": trial, "data-kind": "truth", "class": "truth"})
            attrs[-1]["class"] = (attrs[-1].get("class", "") + " group-end").strip()
        for rig in self.rig_names:
            first = True
            for v in self.order:
                joint = self.joint.get((v, rig))
                if joint is None:
                    continue
                kc = joint.get("keulegan_carpenter_number") if is_ok(joint) else None
                kc_text = f"{fmt(min(kc), 2)}–{fmt(max(kc), 2)}" if isinstance(kc, list) and kc else fmt(kc, 2)
                label = [
                    td(f"<b>joint</b> {esc(rig)}" if first else ""),
                    td("all" if first else "", "num"),
                    td(esc(kc_text), "num"),
                ]
                fit_row(label, v, joint, "joint", f"joint:{rig}")
                attrs[-1]["class"] = "joint"
                first = False
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
            "number of the trial's first fitted swing (joint: range). "
            + ("Rows ‘truth’: the synthetic trials' true values. " if self.truth else "")
            + "“at bound” marks a coefficient that ended on its lower bound: the data prefer an unphysical "
            "value, and only the one-sided 95 % upper limit is a result. Per-trial intervals of the damping "
            "terms are somewhat optimistic on tracked video (about 1.3× narrow in the coverage study); prefer "
            "the joint rows." + self.dagger_note()
        )
        out = table_html(header, rows, caption=caption, table_id="table3", row_attrs=attrs)
        if notes:
            items = "".join(
                f"<li><b>{esc(trial)}, {esc(v)}</b>: " + " | ".join(esc(w) for w in ws) + "</li>"
                for kind, trial, v, ws in notes
            )
            out += (
                f'<details class="fit-warnings"><summary>The fits\' warnings in full ({len(notes)} fits)</summary>'
                f"<ul>{items}</ul></details>"
            )
        return out

    def _has(self, variant: str, name: str) -> bool:
        if name in (ADDED_MASS,):
            return True
        if name == "drag_coefficient":
            name = "drag_area_m2"
        return any(TERMS[t].parameter == name for t in self.variants[variant] if t in TERMS)

    # -- figures --------------------------------------------------------------

    def trial_figures(self) -> str:
        """Per trial: measured θ(t) with each variant's fit, and each variant's residual beneath."""
        import matplotlib

        out = []
        for trial in self.trial_order():
            curves = {v: self.curve(v, trial) for v in self.order if is_ok(self.fits.get((v, trial)))}
            curves = {v: c for v, c in curves.items() if not c.empty}
            if not curves:
                continue
            with matplotlib.rc_context(MPL_STYLE):
                fig = new_figure(10, 3.0 + 1.05 * len(curves))
                grid = fig.add_gridspec(1 + len(curves), 1, height_ratios=[3.0] + [1.0] * len(curves))
                ax = fig.add_subplot(grid[0])
                base = next(iter(curves.values()))
                t = base.time_s.to_numpy(float)
                measured = np.degrees(base.theta_measured_rad.to_numpy(float))
                used = base.flag.isin(["fitted", "release_transient"]).to_numpy()
                ax.plot(t[used], measured[used], ".", ms=2.2, color="0.25", label="measured", zorder=3)
                bad = ~used & np.isfinite(measured)
                if bad.any():
                    ax.plot(t[bad], measured[bad], "x", ms=4, color="#C00000", label="outlier / flagged", zorder=4)
                start = self.fits[(next(iter(curves)), trial)]["trials"][trial]["fit_start_s"]
                for v, c in curves.items():
                    ax.plot(
                        c.time_s, np.degrees(c.theta_fitted_rad), "-", lw=1.0, color=self.colour[v], label=f"{v} fit"
                    )
                ax.axvspan(min(0.0, float(np.nanmin(t))), start, color="0.85", lw=0, zorder=0)
                ax.set_ylabel("θ (°)")
                ax.set_title(f"{trial}: release {self.angle_label(trial)}", loc="left")
                ax.legend(loc="upper right", ncol=len(curves) + 2, frameon=False)
                for i, (v, c) in enumerate(curves.items()):
                    rax = fig.add_subplot(grid[1 + i], sharex=ax)
                    fitted = c.flag == "fitted"
                    r = np.degrees(c.residual_rad.to_numpy(float))
                    rax.plot(c.time_s[fitted], r[fitted.to_numpy()], "-", lw=0.6, color=self.colour[v])
                    rax.axhline(0, color="0.3", lw=0.6)
                    lim = float(np.nanmax(np.abs(r[fitted.to_numpy()]))) if fitted.any() else 1.0
                    rax.set_ylim(-1.15 * lim, 1.15 * lim)
                    rms = self.fits[(v, trial)]["rms_deg"]
                    rax.text(
                        0.995,
                        0.92,
                        f"{v}: RMS {fmt(rms, 2)}°",
                        transform=rax.transAxes,
                        ha="right",
                        va="top",
                        fontsize=8,
                    )
                    rax.set_ylabel("resid. (°)")
                    if i < len(curves) - 1:
                        rax.tick_params(labelbottom=False)
                rax.set_xlabel("time since release (s)")
                ax.tick_params(labelbottom=False)
                png = figure_png(fig)
            caption = self.figure_caption(
                f"Trial <b>{esc(trial)}</b> (release {self.angle_label(trial)}, KC "
                f"{fmt(self.kc(next(iter(curves)), trial), 2)}). Top: measured angle (dots) and each variant's fitted "
                "θ(t); grey band: release transient, not fitted. Below: residual (fitted − measured) of each "
                "variant on its own scale — structure that repeats with the swing is physics the variant misses."
            )
            out.append(figure_html(png, caption, alt=f"measured and fitted angle of {trial}"))
        return "".join(out) or "<p>No fitted curves to show.</p>"

    def consistency_figure(self) -> str:
        """Each coefficient against release angle and against KC, per variant, joint fit as a band."""
        import matplotlib

        names = [
            n
            for n in (ADDED_MASS, "drag_coefficient", "linear_damping_nm_s", "friction_torque_nm")
            if any(self._has(v, n) for v in self.order)
        ]
        out = []
        for rig in self.rig_names:
            trials = [t for t in self.rig_trials(rig) if any(is_ok(self.fits.get((v, t))) for v in self.order)]
            if len(trials) < 2:
                out.append(f"<p>Rig {esc(rig)}: {len(trials)} fitted trial(s), nothing to compare across releases.</p>")
                continue
            with matplotlib.rc_context(MPL_STYLE):
                fig = new_figure(10, 2.3 * len(names) + 0.5)
                axes = fig.subplots(len(names), 2, squeeze=False, sharex="col")
                for row, name in enumerate(names):
                    for col, xkind in enumerate(("release", "kc")):
                        ax = axes[row][col]
                        variants = [v for v in self.order if self._has(v, name)]
                        for k, v in enumerate(variants):
                            xs, ys, lo, hi, hollow = [], [], [], [], []
                            for t in trials:
                                fit = self.fits.get((v, t))
                                if not is_ok(fit) or name not in fit["parameters"]:
                                    continue
                                e = fit["parameters"][name]
                                x = self.release_deg(t) if xkind == "release" else self.kc(v, t)
                                if x is None:
                                    continue
                                offset = k - (len(variants) - 1) / 2
                                xs.append(x + 1.2 * offset if xkind == "release" else x * 1.03**offset)
                                half = 1.96 * float(e.get("stderr_statistical") or 0.0)
                                ys.append(e["value"])
                                lo.append(half if not e.get("at_bound") else 0.0)
                                hi.append(half)
                                hollow.append(bool(e.get("at_bound")))
                            if not xs:
                                continue
                            xs, ys, lo, hi, hollow = map(np.asarray, (xs, ys, lo, hi, hollow))
                            colour = self.colour[v]
                            ax.errorbar(xs, ys, yerr=[lo, hi], fmt="none", ecolor=colour, elinewidth=1, capsize=2)
                            ax.scatter(
                                xs[~hollow], ys[~hollow], marker=self.marker[v], s=22, color=colour, label=v, zorder=3
                            )
                            if hollow.any():
                                ax.scatter(
                                    xs[hollow],
                                    ys[hollow],
                                    marker=self.marker[v],
                                    s=22,
                                    facecolor="white",
                                    edgecolor=colour,
                                    zorder=3,
                                    label=f"{v} (at bound)",
                                )
                            joint = self.joint.get((v, rig))
                            if is_ok(joint) and name in joint["parameters"]:
                                je = joint["parameters"][name]
                                scale = max(1.0, float(je.get("scale_factor") or 1.0))
                                half = 1.96 * scale * float(je.get("stderr_statistical") or 0.0)
                                bound = je.get("lower_bound")
                                low = je["value"] - half
                                low = max(low, float(bound)) if _finite(bound) else low
                                ax.axhspan(low, je["value"] + half, color=colour, alpha=0.18, lw=0)
                                ax.axhline(je["value"], color=colour, lw=0.8, alpha=0.9)
                        truth = {true_value(self.truth.get(t), name) for t in trials if t in self.truth} - {None}
                        if len(truth) == 1:
                            ax.axhline(truth.pop(), color="black", ls="--", lw=1, label="truth")
                        if xkind == "kc":
                            ax.set_xscale("log")
                            log_ticks(ax.xaxis)
                        if row == 0:
                            ax.set_title(
                                "against release angle" if xkind == "release" else "against Keulegan–Carpenter number",
                                loc="left",
                            )
                        if row == len(names) - 1:
                            ax.set_xlabel("release angle (°)" if xkind == "release" else "KC of the first fitted swing")
                        if col == 0:
                            ax.set_ylabel(PLAIN_SYMBOLS[name])
                handles = {}
                for ax in axes.flat:
                    for h, label in zip(*ax.get_legend_handles_labels(), strict=True):
                        handles.setdefault(label, h)
                fig.legend(
                    handles.values(),
                    handles.keys(),
                    loc="outside upper center",
                    ncol=min(len(handles), 7),
                    frameon=False,
                )
                png = figure_png(fig)
            caption = self.figure_caption(
                f"Consistency across the trials of rig {esc(rig)}: each coefficient of each trial's fit against the "
                "release angle (left) and the Keulegan–Carpenter number (right), per variant (markers slightly "
                "offset sideways). Error bars: 95 % statistical intervals — what the consistency test compares; the "
                "rig values' systematic error moves all trials together and is left out here (it is in Table 3). "
                "Line and band: each variant's joint fit with its statistical 95 % interval widened by the scale "
                "factor S. Hollow markers: at the lower bound"
                + ("; dashed: truth." if self.truth else ".")
                + " A model that captures the physics gives the same value at every release."
            )
            out.append(figure_html(png, caption, alt=f"coefficients against release angle and KC, rig {rig}"))
        return "".join(out) or "<p>No per-trial fits to compare.</p>"

    def extinction_figure(self) -> str:
        """Amplitude loss per half cycle against amplitude (each variant's prediction) and local C_d against KC."""
        import matplotlib

        out = []
        for rig in self.rig_names:
            variant = self.recommended(rig)
            trials = [t for t in self.rig_trials(rig) if variant and is_ok(self.fits.get((variant, t)))]
            if not trials:
                continue
            with matplotlib.rc_context(MPL_STYLE):
                fig = new_figure(10, 4.2)
                ax, bx = fig.subplots(1, 2)
                grey = ("0.1", "0.35", "0.55", "0.7", "0.45")
                for i, t in enumerate(trials):
                    c = self.cycles(variant, t)
                    if c.empty:
                        continue
                    ax.plot(
                        c.amplitude_deg,
                        np.degrees(c.amplitude_loss_rad),
                        MARKERS[i % len(MARKERS)],
                        ms=4,
                        mfc="none",
                        mec=grey[i % len(grey)],
                        label=f"{t} (measured)",
                    )
                    bx.plot(
                        c.keulegan_carpenter_number,
                        c.local_drag_coefficient,
                        MARKERS[i % len(MARKERS)],
                        ms=4,
                        mfc="none",
                        mec=grey[i % len(grey)],
                        label=t,
                    )
                for v in self.order:
                    first = True
                    for t in trials:
                        if not is_ok(self.fits.get((v, t))):
                            continue
                        c = self.cycles(v, t)
                        if c.empty or "predicted_amplitude_loss_rad" not in c:
                            continue
                        c = c.sort_values("amplitude_deg")
                        ax.plot(
                            c.amplitude_deg,
                            np.degrees(c.predicted_amplitude_loss_rad),
                            "-",
                            lw=1.1,
                            color=self.colour[v],
                            alpha=0.85,
                            label=f"{v} prediction" if first else None,
                        )
                        first = False
                ax.set_xscale("log")
                ax.set_yscale("log")
                log_ticks(ax.xaxis)
                log_ticks(ax.yaxis)
                ax.set_xlabel("amplitude A at the half cycle's start (°)")
                ax.set_ylabel("amplitude loss per half cycle ΔA (°)")
                ax.set_title("extinction curve", loc="left")
                ax.legend(frameon=False, fontsize=7)
                joint = self.joint.get((variant, rig), {})
                cd = joint.get("parameters", {}).get("drag_coefficient") if is_ok(joint) else None
                if cd:
                    bx.axhspan(cd["ci95"][0], cd["ci95"][1], color=self.colour[variant], alpha=0.15, lw=0)
                    bx.axhline(cd["value"], color=self.colour[variant], lw=1, label=f"{variant} joint $C_d$")
                truth = {true_value(self.truth.get(t), "drag_coefficient") for t in trials if t in self.truth} - {None}
                if len(truth) == 1:
                    bx.axhline(truth.pop(), color="black", ls="--", lw=1, label="truth")
                bx.set_xscale("log")
                bx.set_yscale("log")
                log_ticks(bx.xaxis)
                log_ticks(bx.yaxis)
                bx.set_xlabel("Keulegan–Carpenter number of the half cycle")
                bx.set_ylabel("local $C_d$ (all loss charged to drag)")
                bx.set_title("local drag coefficient", loc="left")
                bx.legend(frameon=False, fontsize=7)
                png = figure_png(fig)
            caption = self.figure_caption(
                f"Rig {esc(rig)}. Left: the extinction curve — loss of amplitude over each half cycle against the "
                f"amplitude at its start, measured (open markers, one per trial; amplitudes about the {esc(variant)} "
                "fit's rest angle) and as each variant's fitted curve predicts it. On these log axes Coulomb friction "
                "gives a constant loss, linear damping a slope 1 and quadratic drag a slope 2: a variant that lacks a "
                "term misses one end of the curve. Right: the local drag coefficient of each half cycle, charging all "
                "of its loss to quadratic drag, against its KC number"
                + (f"; band: the {esc(variant)} joint C<sub>d</sub> (95 %)" if cd else "")
                + ". Where the local value climbs at small KC, the loss there is not quadratic drag."
            )
            out.append(figure_html(png, caption, alt=f"extinction curve and local drag coefficient, rig {rig}"))
        return "".join(out) or "<p>No half-cycle tables to show.</p>"

    # -- comparisons ------------------------------------------------------

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
                    continue
                lag1 = [
                    self.fits[(v, t)]["trials"][t].get("residual_lag1_autocorrelation")
                    for t in trials
                    if is_ok(self.fits.get((v, t)))
                ]
                lag1 = [x for x in lag1 if _finite(x)]
                ratio = [
                    self.fits[(v, t)]["rms_deg"] / self.docs[(t, "angles")]["noise_deg"]
                    for t in trials
                    if is_ok(self.fits.get((v, t)))
                    and is_ok(self.docs.get((t, "angles")))
                    and _finite(self.docs[(t, "angles")].get("noise_deg"))
                    and self.docs[(t, "angles")]["noise_deg"] > 0
                ]
                consistency = joint.get("consistency") or {}
                s_max = max(
                    (
                        p.get("scale_factor")
                        for p in (consistency.get("parameters") or {}).values()
                        if _finite(p.get("scale_factor"))
                    ),
                    default=None,
                )
                rows.append(
                    [
                        td(f"<b>{esc(v)}</b>" if best and v == best["variant"] else esc(v)),
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
                "the record's noise, the lag-1 autocorrelation of the per-trial residuals, ΔAIC and ΔBIC against "
                f"the best variant ({esc(best['basis']) if best else 'no fits'}), and the consistency of the per-trial "
                "estimates. Caveat: AIC and BIC treat the samples as independent; the residuals are autocorrelated "
                "(lag-1 up to the value shown), so the effective number of samples is smaller and the differences "
                "overstate the evidence. Read them with the RMS against the noise and the consistency across trials."
            )
            out.append(table_html(header, rows, caption=caption, table_id=f"model-comparison-{rig}", row_attrs=attrs))
            out.append(self._term_evidence(rig, best))
        return "".join(out)

    def term_evidence_rows(self, rig: str, best: dict | None) -> list[dict]:
        """Each added term: nested variant pair, ΔAIC, ΔBIC, RMS ratio, the joint coefficient, a verdict."""
        rows = []
        for v in self.order:
            parent = nested_parent(self.variants, v)
            if parent is None:
                continue
            child, base = self.joint.get((v, rig)), self.joint.get((parent, rig))
            if not (is_ok(child) and is_ok(base)):
                continue
            term = (set(self.variants[v]) - set(self.variants[parent])).pop()
            name = TERMS[term].parameter
            entry = child["parameters"].get(name, {})
            same = child.get("samples_digest") == base.get("samples_digest")
            d_aic, d_bic = base["aic"] - child["aic"], base["bic"] - child["bic"]
            rms_ratio = base["rms_deg"] / child["rms_deg"] if child["rms_deg"] else float("inf")
            if not same:
                verdict = "not comparable: the two fits used different samples"
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
                }
            )
        return rows

    def _term_evidence(self, rig: str, best: dict | None) -> str:
        evidence = self.term_evidence_rows(rig, best)
        if not evidence:
            return "<p>No nested variants to compare term by term.</p>"
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

    def truth_section(self) -> str:
        """Joint estimates against the synthetic truth: error in standard errors, coverage of the 95 % intervals."""
        if not self.truth:
            return (
                "<p>No truth files (<code>truth_dir</code>): these are real records, so the estimates cannot be "
                "checked against known values.</p>"
            )
        rows, seen = [], set()
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
                    inside = entry["ci95"][0] <= true <= entry["ci95"][1]
                    covered = sum(
                        1
                        for t in trials
                        if is_ok(self.fits.get((v, t)))
                        and name in self.fits[(v, t)]["parameters"]
                        and self.fits[(v, t)]["parameters"][name]["ci95"][0]
                        <= true
                        <= self.fits[(v, t)]["parameters"][name]["ci95"][1]
                    )
                    n_fit = sum(1 for t in trials if is_ok(self.fits.get((v, t))))
                    first = (rig, v) not in seen
                    seen.add((rig, v))
                    rows.append(
                        [
                            td(esc(rig) if first else ""),
                            td(esc(v) if first else "", "vname"),
                            td(f"{COEFFICIENTS[name][1]}, {COEFFICIENTS[name][0]}"),
                            td(esc(truth), "num"),
                            estimate_cell(entry),
                            td(esc(_minus(f"{z:+.2f}" if abs(z) >= 0.005 else "0.00")) if _finite(z) else "—", "num"),
                            td("yes" if inside else '<span class="warn">no</span>'),
                            td(f"{covered} of {n_fit}", "num"),
                        ]
                    )
        header = [
            "rig",
            "variant",
            "coefficient",
            "truth",
            "joint estimate (95 %)",
            "(estimate − truth)/σ",
            "truth inside",
            "per-trial intervals covering truth",
        ]
        caption = self.table_caption(
            "The synthetic experiment: each variant's joint estimate against the true value the videos were "
            "rendered with, the error in units of the estimate's combined standard error σ, and how many of the "
            "per-trial 95 % intervals cover the truth. Only a variant that contains every effect of the simulation "
            "can be expected to cover it."
        )
        return table_html(header, rows, caption=caption, table_id="truth-table")

    def tracking_section(self) -> str:
        """Per trial: frames, flags by kind, samples used; then the contact sheets."""
        rows, sheets = [], []
        variant_for = {t: self.recommended(self.trials[t]["rig"]) for t in self.trials}
        for trial in self.trial_order():
            frames, tracks, angles = (self.docs.get((trial, k)) for k in ("frames", "tracks", "angles"))
            kind = self.trials[trial].get("kind", "video")
            if kind != "video":
                frame_cells = [td("angle table (no video)", "na", span=4)]
            elif not is_ok(frames):
                frame_cells = [td(esc(failure_text(frames)), "na fail", span=4)]
            else:
                frame_cells = [
                    td(str(frames.get("n_frames", "—")), "num"),
                    td(esc(fmt(frames.get("nominal_fps"), 3)), "num"),
                    td(str(frames.get("dropped_frames", "—")), "num"),
                    td(str(frames.get("duplicate_timestamps", "—")), "num"),
                ]
            if kind != "video":
                flag_cell = td("—", "na")
            elif is_ok(tracks):
                flags = tracks.get("flags") or {}
                bad = {k: n for k, n in sorted(flags.items()) if k != "ok" and n}
                flag_cell = td(f"ok {flags.get('ok', 0)}" + "".join(f", {esc(k)} {n}" for k, n in bad.items()))
            else:
                flag_cell = td(esc(failure_text(tracks)), "na fail")
            if is_ok(angles):
                angle_cells = [
                    td(str(angles.get("n_samples", "—")), "num"),
                    td(str(angles.get("n_flagged", "—")), "num"),
                    td(esc(fmt(angles.get("noise_deg"), 2)), "num"),
                ]
            else:
                angle_cells = [td(esc(failure_text(angles)), "na fail", span=3)]
            fit = self.fits.get((variant_for[trial], trial)) if variant_for[trial] else None
            fitted = td(str(fit["n_samples"]), "num") if is_ok(fit) else td("—", "na")
            rows.append(
                [td(esc(trial)), td(self.angle_label(trial), "num")]
                + frame_cells
                + [flag_cell]
                + angle_cells
                + [fitted]
            )
            sheet = self.files.get("trials", {}).get(trial, {}).get("contact_sheet")
            if sheet and Path(sheet).is_file():
                sheets.append((trial, Path(sheet).read_bytes(), is_ok(frames)))
        header = [
            "trial",
            "release",
            "frames",
            "fps",
            "dropped",
            "duplicate time stamps",
            "tracker flags by kind",
            "angle samples",
            "flagged",
            "angle noise (°)",
            "samples fitted",
        ]
        caption = self.table_caption(
            "Tracking quality per trial: frames in the video (from the container: dropped frames and duplicate time "
            "stamps), the tracker's flags by kind (flagged frames are never interpolated), the angle samples from "
            "release to rest and how many of them are flagged, the angle record's noise, and the samples the "
            "recommended variant's fit used (after the release transient and outliers)."
        )
        out = table_html(header, rows, caption=caption, table_id="tracking-table")
        if sheets:
            caption = self.figure_caption(
                "Contact sheets: key frames of each video, for a visual check of the scene, marker and lighting."
            )
            items = "".join(
                f'<figure class="sheet"><img src="{png_data_uri(data)}" alt="contact sheet of {esc(t)}">'
                f"<figcaption>{esc(t)}{'' if ok else ' (failed)'}</figcaption></figure>"
                for t, data, ok in sheets
            )
            out += f'<div class="sheets">{items}</div><p class="figcaption">{caption}</p>'
        return out

    def failures_section(self) -> str:
        """Failed or skipped trials with the stage, the reason and the log to read."""
        failed = self.failed_trials()
        n = len(self.trials)
        if failed.empty:
            return f"<p>All {n} trial(s) succeeded at every stage (<code>results/status/trials.csv</code>).</p>"
        rows = [
            [
                td(esc(str(r.trial))),
                td(esc(str(r.stage))),
                td(esc(str(r.reason))),
                td(f"<code>{esc(str(r.log))}</code>"),
            ]
            for r in failed.itertuples()
        ]
        caption = self.table_caption(
            f"{len(failed)} of {n} trial(s) failed and are missing from the tables and the joint fits above: the "
            "stage where each failed, the reason and the log to read."
        )
        return table_html(["trial", "stage", "reason", "log"], rows, caption=caption, table_id="failed-table")

    def provenance_section(self) -> str:
        """Commit, configuration digest, fit settings and package versions."""
        p = self.provenance
        items = [
            ("commit", f"<code>{esc(str(p.get('commit') or 'not a git work tree'))}</code>"),
            ("commit time (UTC)", esc(str(p.get("commit_time_utc") or "—"))),
            ("uncommitted changes", esc({True: "yes", False: "no"}.get(p.get("dirty"), "unknown"))),
            ("configuration SHA-256", f"<code>{esc(str(p.get('config_sha256') or '—'))}</code>"),
            ("Python", esc(str(p.get("python") or "—"))),
        ]
        items += [(f"{esc(k)}", esc(str(v or "not installed"))) for k, v in sorted((p.get("packages") or {}).items())]
        items += [(f"fitting.{esc(k)}", esc(str(v))) for k, v in sorted(self.fitting.items())]
        rows = [[td(k), td(v)] for k, v in items]
        caption = self.table_caption(
            "Provenance: the code version, the digest of the configuration as used, the fit settings and the "
            "versions of the packages the results depend on."
        )
        return table_html(["item", "value"], rows, caption=caption, table_id="provenance-table")


def show(html_text: str) -> None:
    """Display an HTML fragment as the cell's output (in the notebook)."""
    from IPython.display import HTML, display

    display(HTML(html_text))


# ---------------------------------------------------------------------------
# Executing the notebook and writing the HTML

PAGE_CSS = """
:root { --ink: #1b1b1b; --muted: #5a5a5a; --rule: #c9c9c9; --band: #f4f6f8; --warn: #a33a00; }
html { font-size: 15px; }
body { margin: 0; color: var(--ink); background: #fff;
  font-family: "Source Sans Pro", "Segoe UI", "Helvetica Neue", Arial, "DejaVu Sans", sans-serif; line-height: 1.45; }
main { max-width: 1120px; margin: 0 auto; padding: 24px 28px 60px; }
h1 { font-size: 1.7rem; margin: 0.2em 0 0.3em; }
h2 { font-size: 1.3rem; margin: 1.8em 0 0.5em; padding-bottom: 0.2em; border-bottom: 2px solid var(--ink); }
h3 { font-size: 1.05rem; margin: 0.4em 0 0.5em; }
p { margin: 0.45em 0; }
.subtitle { color: var(--muted); margin: 0.2em 0; }
a.anchor-link { display: none; }
code { font-size: 0.9em; }
.warn { color: var(--warn); font-weight: 600; }
.summary-box { border: 2px solid #0072B2; border-radius: 6px; padding: 10px 16px 12px; margin: 12px 0 18px;
  background: #f3f8fc; }
.summary-box table { width: auto; }
.summary-box ul.warnings { margin: 0.2em 0 0.2em 1.2em; padding: 0; }
.table-block { margin: 14px 0 20px; }
.table-wrap { overflow-x: auto; }
p.caption { font-size: 0.9rem; margin: 0 0 6px; max-width: 1060px; }
table { border-collapse: collapse; font-size: 0.86rem; font-variant-numeric: tabular-nums; }
th { text-align: left; vertical-align: bottom; padding: 4px 8px; font-weight: 600;
  border-bottom: 1.5px solid var(--ink); border-top: 1.5px solid var(--ink); }
th.group { text-align: center; border-bottom: 1px solid var(--rule); }
th.sub { border-top: none; text-align: right; font-weight: 500; }
td { padding: 3px 8px; vertical-align: top; border-bottom: 1px solid #eee; }
td.num { text-align: right; white-space: nowrap; }
td.num .v { display: block; }
td.num .q { display: block; color: var(--muted); font-size: 0.8rem; }
td.flagged .v, td.flagged .q { color: var(--warn); }
td.na { color: #9a9a9a; }
td.fail { color: var(--warn); white-space: normal; }
td.truth, tr.truth td { color: #333; font-style: italic; background: #fbfbf3; }
tr.joint td { background: var(--band); }
tr.group-end td { border-bottom: 1px solid var(--rule); }
td.warncell { color: var(--warn); font-size: 0.8rem; min-width: 8em; max-width: 12em; }
.table-note { font-size: 0.85rem; color: var(--muted); max-width: 1060px; }
figure { margin: 16px 0 22px; break-inside: avoid; }
figure.fig img { width: 100%; max-width: 1100px; height: auto; display: block; }
figcaption, p.figcaption { font-size: 0.88rem; max-width: 1060px; margin-top: 4px; }
.sheets { display: grid; grid-template-columns: repeat(2, minmax(0, 1fr)); gap: 10px 16px; }
figure.sheet { margin: 0; }
figure.sheet img { width: 100%; height: auto; display: block; border: 1px solid var(--rule); }
figure.sheet figcaption { text-align: center; }
details.fit-warnings { font-size: 0.82rem; color: var(--muted); margin: -8px 0 16px; }
details.fit-warnings li { margin: 2px 0; }
@media print {
  html { font-size: 10pt; }
  main { max-width: none; padding: 0; }
  h2 { break-after: avoid; }
  .table-wrap { overflow: visible; }
  figure, .summary-box, .table-block { break-inside: avoid; }
  .sheets { grid-template-columns: repeat(3, minmax(0, 1fr)); }
  details.fit-warnings { display: none; }
  @page { size: A4; margin: 14mm 12mm; }
}
"""


def page_html(body: str, title: str) -> str:
    """One self-contained HTML page: the notebook's outputs, the report's CSS, no scripts, no external files."""
    return (
        '<!DOCTYPE html>\n<html lang="en">\n<head>\n<meta charset="utf-8">\n'
        '<meta name="viewport" content="width=device-width, initial-scale=1">\n'
        f"<title>{esc(title)}</title>\n<style>{PAGE_CSS}</style>\n</head>\n<body>\n<main>\n{body}\n</main>\n</body>\n</html>\n"
    )


def normalise_notebook(nb) -> list[str]:
    """Make an executed notebook depend on its inputs only; returns the stderr texts it removed.

    Drops papermill's and nbclient's timing metadata (start and end times,
    durations, input and output paths), numbers the cells (``cell-00``, …) and
    moves text written to stderr out of the notebook (the rule logs it).
    """
    nb.metadata.pop("papermill", None)
    stderr = []
    for i, cell in enumerate(nb.cells):
        cell["id"] = f"cell-{i:02d}"
        for key in ("papermill", "execution", "collapsed", "scrolled"):
            cell.metadata.pop(key, None)
        if cell.cell_type == "code":
            kept = []
            for output in cell.get("outputs", []):
                if output.get("output_type") == "stream" and output.get("name") == "stderr":
                    stderr.append(output.get("text", ""))
                else:
                    kept.append(output)
            cell["outputs"] = kept
    return stderr


def notebook_body(nb) -> str:
    """The notebook's outputs and markdown as HTML (code hidden), via nbconvert's basic template."""
    from nbconvert import HTMLExporter

    exporter = HTMLExporter(
        template_name="basic", exclude_input=True, exclude_input_prompt=True, exclude_output_prompt=True
    )
    body, _ = exporter.from_notebook_node(nb)
    return body


def build_report(notebook, html_path, executed_path, parameters: dict, cwd=".", log=None) -> None:
    """Execute the report notebook with papermill (same interpreter), write it normalised and as HTML."""
    import matplotlib.font_manager  # noqa: F401  (builds the font cache here, not in the notebook's output)
    import nbformat
    import papermill

    from pendulum.io import write_text

    nb = papermill.execute_notebook(
        str(notebook),
        None,
        parameters=parameters,
        kernel_name="python3",
        cwd=str(cwd),
        progress_bar=False,
        log_output=False,
        request_save_on_cell_execute=False,
    )
    for text in normalise_notebook(nb):
        if log:
            log.warning("notebook stderr: %s", text.strip())
    write_text(nbformat.writes(nb) + "\n", executed_path)
    title = "Free-decay pendulum: added mass and drag coefficient"
    write_text(page_html(notebook_body(nb), title), html_path)
