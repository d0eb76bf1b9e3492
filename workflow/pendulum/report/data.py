"""The report's data: the results of one build, read once, and the look-ups its sections share.

Reads only what the rules wrote (fit documents, curve and half-cycle tables,
joint fits, the summary and status tables, tracking summaries, truth files of
synthetic trials); nothing is fitted. :class:`ReportData` is the base of every
group of sections (``tables``, ``figures``, ``comparison``,
``checks``), which :class:`pendulum.report.notebook.Report` puts together.
"""

from __future__ import annotations

import json
from dataclasses import dataclass, field
from pathlib import Path

import pandas as pd
import yaml

from pendulum.fit.records import keulegan_carpenter_number
from pendulum.model.effects import ADDED_MASS, TERMS
from pendulum.outcomes import MISFIT_MARK
from pendulum.report.format import MARKERS, PALETTE, TERM_LABELS, fmt, is_finite, with_minus_sign

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
        return cda / area if is_finite(area) and cda is not None else None
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


NESTED_RMS_SLACK = 1.01  # a fit that leaves over this × the RMS of a variant with one term fewer stopped short


def nested_parents(variants: dict, variant: str) -> list[str]:
    """The variants with exactly one term fewer whose terms all appear in ``variant``, simplest first: each pair
    tests one term (quadratic + friction → all three tests linear damping, linear + friction → all three the
    quadratic drag; the first alone hid the one a reviewer's variants were about)."""
    terms = set(variants[variant])
    return [v for v in variant_order(variants) if set(variants[v]) < terms and len(terms - set(variants[v])) == 1]


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
        basis = "AIC of the joint fits, every variant fitted to the same samples"
    else:
        per = summary[summary.fit.isin(trials) & summary.variant.isin(joint.variant)]
        common = sorted(
            t for t, g in per.groupby("fit") if set(g.variant) == set(joint.variant) and g.samples_digest.nunique() == 1
        )
        if common:
            chosen = per[per.fit.isin(common)].groupby("variant")
            aic, bic = chosen.aic.sum(), chosen.bic.sum()
            named = ", ".join(common) if len(common) <= 6 else f"{', '.join(common[:6])}, …"
            basis = (
                f"AIC summed over the per-trial fits of {len(common)} of the rig's {len(trials)} trial(s) ({named}), "
                "those every variant fitted to the same samples (the joint fits' samples differ, e.g. where a "
                "variant's outlier rejection left some out)"
            )
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


def record_problems(document: dict | None) -> list[str]:
    """The garbage-in sentences of a fit whose record failed the checks (``reliable: false``); [] otherwise.

    From ``trials.<name>.record_checks.problems`` (:func:`pendulum.fit.checks.record_checks`); a document
    marked unreliable without them gives one sentence saying so.
    """
    if not is_ok(document) or document.get("reliable", True) is not False:
        return []
    problems = [
        p
        for entry in (document.get("trials") or {}).values()
        for p in (entry.get("record_checks") or {}).get("problems", [])
    ]
    return problems or ["the fit marks its angle record unreliable (see its warnings)"]


def problem_text(trial: str, problem: str, first_clause: bool = False) -> str:
    """A garbage-in sentence shown next to its trial's name: without its leading "trial <name>: ";
    ``first_clause``: only up to the first colon (what was found, not the advice)."""
    text = problem.removeprefix(f"trial {trial}: ")
    return text.split(": ", 1)[0] if first_clause else text


def is_unreliable(document: dict | None) -> bool:
    """A fit that succeeded on a record that failed the garbage checks: its numbers are not measurements."""
    return bool(record_problems(document))


def short_warning(text: str) -> str:
    """A fit warning in two or three words (Table 3's warning column)."""
    lowered = text.lower()
    for key, short in (
        (MISFIT_MARK, "misfit"),
        ("lower bound", "at bound"),
        ("not identifiable", "not identifiable"),
        ("not converge", "not converged"),
        ("singular", "singular Jacobian"),
        ("inseparable", "inseparable parameters"),
        ("time base", "time base?"),
        ("correlated", "correlated parameters"),
        ("shorter than its rig values allow", "period vs rig values"),
    ):
        if key in lowered:
            return short
    return text if len(text) < 30 else text[:27] + "…"


# ---------------------------------------------------------------------------
# The results of one build


@dataclass
class ReportData:
    """Every result of one build, read once, and the look-ups the report's sections share.

    ``files``: the paths the rule declares as inputs (``summary``, ``status``,
    ``trials`` → per trial ``angles``/``frames``/``tracks``/``contact_sheet``/
    ``truth``, ``fits`` → variant → trial → ``fit``/``curve``/``cycles``,
    ``joint`` → variant → rig, ``calibration`` → camera setup, only when a rig has one). ``trials``: trial →
    ``rig``, ``kind``, ``source``, ``overrides``. ``rigs``: rig → ``values``, ``tolerances`` (as
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
        self.calibration = {setup: read_json(p) for setup, p in sorted(f.get("calibration", {}).items())}
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
        # one shape per trial in every figure that marks trials (the local C_d, the extinction curves)
        self.trial_marker = {t: MARKERS[i % len(MARKERS)] for i, t in enumerate(self._trial_order)}
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
        return is_ok(angles) and is_finite(angles.get("hold_angle_deg"))

    def release_deg(self, trial: str) -> float | None:
        """Release angle: the hold angle before release, else (no release in the record) the angle of its first
        swing extremum (as the paper's release, the swing's amplitude there), else the first fitted angle."""
        if self.release_detected(trial):
            return float(self.docs[(trial, "angles")]["hold_angle_deg"])
        first = (self.docs.get((trial, "angles")) or {}).get("first_extremum_deg")
        if is_finite(first):
            return float(first)
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

    def trial_problems(self, trial: str) -> list[str]:
        """Garbage-in sentences of a trial's record: those of its first per-trial fit (in variant order) marked
        unreliable; [] when every fit of it passed the checks."""
        for v in self.order:
            problems = record_problems(self.fits.get((v, trial)))
            if problems:
                return problems
        return []

    def short_of_best(self, trial: str) -> dict[str, tuple[str, float]]:
        """Variant → (nested parent, its RMS °) where this trial's fit of the variant leaves a larger RMS than the
        fit of a variant with one term fewer (:func:`nested_parents`) on the same samples: the parent's solution is
        one of its own (the extra term 0), so its fit stopped short of its best (a local minimum), not the model."""
        out = {}
        for v in self.order:
            fit = self.fits.get((v, trial))
            for parent in nested_parents(self.variants, v) if is_ok(fit) and not record_problems(fit) else []:
                other = self.fits.get((parent, trial))
                if is_ok(other) and other.get("samples_digest") == fit.get("samples_digest"):
                    if fit["rms_rad"] > NESTED_RMS_SLACK * other["rms_rad"]:
                        out[v] = (parent, other["rms_deg"])
                        break
        return out

    def unreliable_fits(self, trials: list[str]) -> tuple[list[tuple[str, str]], int]:
        """The (variant, trial) per-trial fits of ``trials`` on unreliable records, and how many fits succeeded."""
        fitted = [(v, t) for t in trials for v in self.order if is_ok(self.fits.get((v, t)))]
        return [(v, t) for v, t in fitted if record_problems(self.fits[(v, t)])], len(fitted)

    def left_out(self, rig: str) -> dict[str, tuple[str, list[str]]]:
        """Trials the rig's joint fits left out: trial → (reason, variants), from each joint's ``excluded_trials``."""
        out: dict[str, tuple[str, list[str]]] = {}
        for v in self.order:
            joint = self.joint.get((v, rig))
            if not is_ok(joint):
                continue
            for trial, reason in sorted((joint.get("excluded_trials") or {}).items()):
                reason = str(reason).replace(f": trial {trial}: ", ": ", 1)  # named already
                out.setdefault(trial, (reason, []))[1].append(v)
        return out

    @staticmethod
    def grouped(left_out: dict[str, tuple[str, list[str]]]) -> list[tuple[list[str], str, list[str]]]:
        """:meth:`left_out`'s trials with the same reason and variants together (a lab's copies of one clip, each
        left out as the same record as the first: one entry), in their order: (trials, reason, variants)."""
        groups: dict[tuple, list[str]] = {}
        for trial, (reason, variants) in left_out.items():
            groups.setdefault((reason, tuple(variants)), []).append(trial)
        return [(trials, reason, list(variants)) for (reason, variants), trials in groups.items()]

    def kc(self, variant: str, trial: str) -> float | None:
        fit = self.fits.get((variant, trial))
        return float(keulegan_carpenter_number(fit)) if is_ok(fit) else None

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
            table = self.status.astype(object).fillna("")
            return table[table.status == "failed"].sort_values("trial").reset_index(drop=True)
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

    def hidden_release(self, trial: str) -> bool:
        """A release by hand in view whose instant and angle the free swing could not tell (the hand hid the hold)."""
        angles = self.docs.get((trial, "angles"), {})
        return is_ok(angles) and bool(angles.get("release_detected")) and not self.release_detected(trial)

    def angle_label(self, trial: str) -> str:
        """Release angle, e.g. "+20°"; "+6°†" when the record holds no release (its first swing extremum); "+6°‡"
        when a hand hid its hold."""
        a = self.release_deg(trial)
        if a is None:
            return "—"
        mark = "" if self.release_detected(trial) else "‡" if self.hidden_release(trial) else "†"
        return with_minus_sign(f"{a:+.0f}°") + mark

    def dagger_note(self) -> str:
        """The notes for release angles marked † or ‡, when any trial has one."""
        marked = [t for t in self.trials if not self.release_detected(t) and self.release_deg(t) is not None]
        note = ""
        if any(not self.hidden_release(t) for t in marked):
            note += (
                " † No release in the record (a video or an angle table that starts mid-swing): the angle of its first "
                "turning point."
            )
        if any(self.hidden_release(t) for t in marked):
            note += (
                " ‡ Released by hand in view, the hand hiding the angle it held: the angle of the record's first "
                "turning point."
            )
        return note

    def _truth_text(self, trials: list[str], name: str) -> str:
        values = {true_value(self.truth.get(t), name) for t in trials if t in self.truth}
        values.discard(None)
        if not values:
            return "—"
        if len(values) == 1:
            return fmt(values.pop(), 4)
        return "varies by trial"

    def _has(self, variant: str, name: str) -> bool:
        if name in (ADDED_MASS,):
            return True
        if name == "drag_coefficient":
            name = "drag_area_m2"
        return any(TERMS[t].parameter == name for t in self.variants[variant] if t in TERMS)
