"""Each trial's outcome, where a user reads it: the status table (results/status/trials.csv), the terminal's
last lines, the report's list of failed and skipped trials and those no model variant fits.

Kept apart from :mod:`pendulum.status` (the stages' failure documents, which every stage imports): editing
how outcomes are tabulated reruns only the status table, the check and the report, not every stage.
"""

from __future__ import annotations

import re
import sys
from pathlib import Path

import pandas as pd

from pendulum.status import copies_of, is_failed, same_record, says_rig_mismatch

STATUS_COLUMNS = [
    "trial",
    "source",
    "rig",
    "status",
    "stage",
    "ok_frames_pct",
    "period_s",
    "reason",
    "log",
    "n_warnings",
    "warnings",
]
MISFIT_MARK = "misses a systematic effect"  # the fits' warning that the model is wrong for the record
# the fits' notes on the model itself (pendulum.fit: misfit, a coefficient at its bound, not identifiable, traded
# against another): what a variant too simple or too rich says on every trial
MODEL_NOTE_MARKS = (
    MISFIT_MARK,
    "its estimate is not a measurement",
    "is not identifiable from this record",
    "the record hardly separates them",
)
EVERY_VARIANT = "fit (every variant): "


def for_the_terminal(warning: str) -> bool:
    """Whether a fit's warning goes to the terminal as well as its log: not a note on the model itself
    (:data:`MODEL_NOTE_MARKS`), which every variant too simple or too rich gives on every trial (134 of 187
    warning lines on 13 apple clips, 2026-12-03); trials.csv, the report's Table 3 and the run's last lines (the
    trials no variant fits) say those. What may be wrong with the record or the rig values is said there too."""
    return not any(mark in warning for mark in MODEL_NOTE_MARKS)


def trial_status(trial: str, source: str, rig: str, documents: list[tuple[str, str, dict]]) -> dict:
    """One row of the status table from a trial's stage documents.

    ``documents``: (stage, log path, JSON document) in pipeline order; a stage
    may be qualified (``fit:quadratic``). The trial failed at the first failed
    document, in the stage named there (an upstream failure passed on keeps its
    origin, e.g. ``geometry`` for an angle record without a pivot). Where every document of a qualified stage
    failed with one error (every variant's fit refused for the rig's values), the stage is named so:
    ``fit (every variant)``. Where the track and the angle record were made (also when a later stage failed:
    another rig's values refuse the fit, the record stands), ``ok_frames_pct`` is the share of the frames not held
    by hand that are usable and ``period_s`` the record's period as swung (the tracks and angles JSON's); else
    None.
    """
    measured = {**_measured(documents), **_warned(documents)}
    for stage, log_path, document in documents:
        if is_failed(document):
            origin = document.get("failed_stage", stage)
            named = stage if origin == stage.split(":")[0] else origin
            base = stage.split(":")[0]
            family = [d for s, _, d in documents if s.split(":")[0] == base] if ":" in stage else []
            if (
                named == stage
                and len(family) > 1
                and all(is_failed(d) and d.get("error") == document.get("error") for d in family)
            ):
                named = f"{base} (every variant)"
            return {
                "trial": trial,
                "source": source,
                "rig": rig,
                "status": "failed",
                "stage": named,
                **measured,
                "reason": document.get("error", ""),
                "log": document.get("log") or log_path,  # a stage no trial owns (a camera's calibration) names its own
            }
    return {
        "trial": trial,
        "source": source,
        "rig": rig,
        "status": "ok",
        "stage": "",
        **measured,
        "reason": "",
        "log": "",
    }


def skipped_status(trial: str, source: str, reason: str) -> dict:
    """The status row of a trial its sidecar skips (``skip: <why>``): no stage ran, nothing failed."""
    row = dict.fromkeys(STATUS_COLUMNS, "")
    row.update(trial=trial, source=source, status="skipped", reason=reason, n_warnings=0)
    row.update(ok_frames_pct=None, period_s=None)
    return row


def usable_percent(flags: dict) -> float | None:
    """The share (%) of a track's frames that are ``ok``, of those not held by hand (the tracks JSON's ``flags``,
    as the tracks log counts them); None without such frames."""
    free = sum(flags.values()) - flags.get("held", 0)
    return 100.0 * flags.get("ok", 0) / free if free > 0 else None


def _measured(documents: list[tuple[str, str, dict]]) -> dict:
    """The usable share of a trial's frames (its tracks document) and its record's period (its angles document)."""
    found = {"ok_frames_pct": None, "period_s": None}
    for stage, _, document in documents:
        if is_failed(document):
            continue
        if stage == "tracks" and document.get("flags"):
            share = usable_percent(document["flags"])
            found["ok_frames_pct"] = None if share is None else round(share, 2)
        elif stage == "angles" and isinstance(document.get("period_s"), (int, float)):
            found["period_s"] = round(float(document["period_s"]), 6)
    return found


def trial_warnings(documents: list[tuple[str, str, dict]]) -> list[str]:
    """Every distinct warning of a trial's stage documents that succeeded, as ``stage: warning``, in pipeline order:
    the video's (frames), the body's silhouette (tracks), the angle record's and each fit's. A warning every
    variant's fit gives is said once, as ``fit (every variant)``; that every variant misses the record (each in
    its own words: said once too) comes first of all (:func:`misfit_trials`)."""
    found: dict[str, list[str]] = {}
    for stage, _, document in documents:
        if is_failed(document):
            continue
        texts = list(document.get("warnings") or [])
        if stage == "tracks" and (document.get("body") or {}).get("warning"):
            texts.append(document["body"]["warning"])
        for text in texts:
            found.setdefault(text, []).append(stage)
    fits = [s for s, _, d in documents if s.startswith("fit:") and not is_failed(d)]
    order = {stage: k for k, (stage, _, _) in enumerate(documents)}
    first_fit = min((order[s] for s in fits), default=len(documents)) - 0.5
    lines = []
    for text, stages in found.items():
        if fits and sorted(stages) == sorted(fits):
            lines.append((first_fit, f"{EVERY_VARIANT}{text}"))
        else:
            lines += [(order[stage], f"{stage}: {text}") for stage in dict.fromkeys(stages)]
    missed = [w for text, stages in found.items() if MISFIT_MARK in text for w in [text] * len(stages)]
    said = any(line.startswith(EVERY_VARIANT) and MISFIT_MARK in line for _, line in lines)
    if fits and len(missed) == len(fits) and not said:  # each variant misses, with its own figures
        ratios = sorted(float(m) for w in missed for m in re.findall(r"(\d+(?:\.\d+)?)× the record's noise", w))
        spread = f" ({ratios[0]:.0f}–{ratios[-1]:.0f}× its noise)" if ratios else ""
        lines.append(
            (
                first_fit - 0.1,
                f"{EVERY_VARIANT}each of the {len(fits)} misses the record{spread}: the model "
                f"{MISFIT_MARK}; it may bias the coefficients, and their intervals do not cover it",
            )
        )
    ordered = [line for _, line in sorted(lines, key=lambda item: item[0])]
    wrong = [line for line in ordered if line.startswith(EVERY_VARIANT) and MISFIT_MARK in line]
    return wrong + [line for line in ordered if line not in wrong]  # what matters most, first


def _warned(documents: list[tuple[str, str, dict]]) -> dict:
    warnings = trial_warnings(documents)
    return {"n_warnings": len(warnings), "warnings": " | ".join(warnings)}


def misfit_trials(table: pd.DataFrame) -> list[str]:
    """Trials that succeeded but whose every fitted variant misses its record (coefficients that may be biased)."""
    if "warnings" not in table.columns:
        return []
    return [
        str(r.trial)
        for r in table[table.status == "ok"].itertuples()
        if any(w.startswith(EVERY_VARIANT) and MISFIT_MARK in w for w in str(r.warnings).split(" | "))
    ]


def rig_mismatch_trials(table: pd.DataFrame) -> list[str]:
    """Trials that succeeded but whose fits say their period and the rig values cannot both be right (an added mass
    many times the body's, or below zero): a wrong rig value, or a record on another time base (a slow-motion clip)."""
    if "warnings" not in table.columns:
        return []
    return [str(r.trial) for r in table[table.status == "ok"].itertuples() if says_rig_mismatch(str(r.warnings))]


def mark_copies(rows: list[dict], digests: dict[str, str | None]) -> None:
    """Warn on each trial whose angle record is an earlier-named trial's, sample for sample (``record_sha256``, the
    angles documents'): the group fits count it once (:func:`pendulum.status.fitted_trials`, by the same
    :func:`pendulum.status.copies_of`); trials.csv says so too, not only the report."""
    ok = {row["trial"]: digests.get(row["trial"]) for row in rows if row.get("status") == "ok"}
    copies = copies_of(ok)
    for row in rows:
        if row["trial"] in copies:
            said = f"angles: {same_record(copies[row['trial']])} in the joint fits, body fits and discovery"
            row["warnings"] = " | ".join([w for w in [row.get("warnings") or ""] if w] + [said])
            row["n_warnings"] = int(row.get("n_warnings") or 0) + 1


def status_table(rows: list[dict]) -> pd.DataFrame:
    return pd.DataFrame(rows, columns=STATUS_COLUMNS).sort_values("trial", kind="stable").reset_index(drop=True)


VIDEO_STAGES = ("frames", "tracks")  # a trial failed here has no angle record: nothing later can mend it


def failure_summary(table: pd.DataFrame) -> str | None:
    """Every failed trial and why, one line each, for the terminal and the check's log; None when all succeeded.

    One line per trial so that the reason of each can be read where Snakemake's own error follows it (a
    paragraph of 4,000 characters was printed twice there, 2026-12-02)."""
    run = table[table.status != "skipped"]  # a trial skipped by its sidecar ran nothing and fails nothing
    bad = run[run.status == "failed"]
    if bad.empty:
        return None
    built = (
        f"the report and the other {len(run) - len(bad)} trial(s)' results were built"
        if len(bad) < len(run)
        else "the report says why, trial by trial"
    )
    skipped = len(table) - len(run)
    built += f" ({skipped} more skipped by their sidecars)" if skipped else ""
    lines = [f"{len(bad)} of {len(run)} trial(s) failed; {built}:"]
    lines += [f"  - {r.trial}, at {r.stage}{_recorded(r)}: {r.reason}" for r in bad.itertuples()]
    unreadable = bad[bad.stage.isin(VIDEO_STAGES)]  # no angle record from the video: a fit's failure is mended
    asks = unreadable.reason.astype(str).str.contains(ASKS_FOR_A_VALUE, regex=True)
    if asks.any():  # a hint mends it (two pendulums in view: start_px), not a skip
        first = unreadable[asks].iloc[0]
        lines.append(
            f"A video whose reason asks which object to follow is tracked once its sidecar gives its start_px "
            f"({_sidecar(first)} for {first.trial}); two pendulums in one video: one copy (or link) of the video per "
            "pendulum, each with its own sidecar and the start_px of its own (docs/your-data.md)."
        )
    if (~asks).any():
        first = unreadable[~asks].iloc[0]
        lines.append(
            "A video that cannot give an angle record (a clip that is no pendulum, a file that cannot be read) is left "
            f"out by `skip: <why>` in its sidecar ({_sidecar(first)} for {first.trial}, or the sidecar it already "
            "has); it then fails nothing (docs/your-data.md)."
        )
    lines.append("See results/status/trials.csv (stage, reason and log of each) and results/report/report.html.")
    return "\n".join(lines)


# a tracks refusal that asks which object to follow (a sidecar's start_px mends it), not one of a clip that cannot
# give a record (whose messages may offer hints too: "give tracking polarity, marker_radius_px and start_px")
ASKS_FOR_A_VALUE = (
    r"two moving objects of similar size|two objects swing|two marker-like spots|not sure which object is the marker"
    r"|is on no moving body in the first frame|no spot swings at start_px"
)


def _sidecar(row) -> str:
    """The sidecar of a status row's trial: its video's path with .yaml."""
    if isinstance(row.source, str) and row.source:
        return Path(row.source).with_suffix(".yaml").as_posix()
    return f"<raw_dir>/{row.trial}.yaml"


def _recorded(row) -> str:
    """For a trial that failed after its angle record was made (a fit the rig's values refuse): what stands."""
    period = pd.to_numeric(getattr(row, "period_s", None), errors="coerce")
    if pd.isna(period):
        return ""
    usable = pd.to_numeric(getattr(row, "ok_frames_pct", None), errors="coerce")
    frames = "" if pd.isna(usable) else f"{usable:.4g} % of frames usable, "
    return f" (its track and angle record stand: {frames}period {period:.4g} s as swung)"


def print_outcome(log_path, since_s: float, passed_over: list | None = None) -> None:
    """The Snakefile's ``onsuccess`` and ``onerror``: :func:`outcome_logged` printed last, under a heading, after
    the raw folder's files that are no trial (``passed_over``: :func:`pendulum.camera.raw_folder.passed_over`), so
    that a video in a container not read as one is not left out unsaid."""
    if passed_over:
        names = ", ".join(Path(p).name for p in passed_over)
        folder = Path(passed_over[0]).parent.as_posix()
        hidden = (
            ", or hidden: a name that starts with a dot" if any(Path(p).name[0] == "." for p in passed_over) else ""
        )
        print(f"\nPassed over in {folder} (no video or angle table by its extension{hidden}): {names}", file=sys.stderr)
    said = outcome_logged(log_path, since_s)
    if said:
        print(f"\nTrials ({Path(log_path).as_posix()}):\n{said}", file=sys.stderr)


def outcome_logged(log_path, since_s: float) -> str | None:
    """What ``check_trials`` logged in this run (its log written at or after ``since_s``), its entries' messages in
    order: the trials no variant fits and those whose period and rig values disagree (WARNING), then the failed
    trials one per line (ERROR) or the count of those ok and skipped (INFO); None where the log is older (the run
    ended before the check). The Snakefile's ``onsuccess`` and ``onerror`` print it after Snakemake's own lines,
    where a user reads last."""
    path = Path(log_path)
    if not path.exists() or path.stat().st_mtime < since_s:
        return None
    entries = re.split(r"^\S+ \S+ (?:DEBUG|INFO|WARNING|ERROR) ", path.read_text(), flags=re.M)
    said = [entry.rstrip() for entry in entries if entry.strip()]
    return "\n".join(said) or None
