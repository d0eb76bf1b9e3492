"""Failure is data: a stage that cannot do its work still writes its outputs, marked failed.

One bad video must not stop the other trials or the aggregates, so every
per-trial stage ends with its declared outputs on disk: the real ones, or
empty tables and a JSON document ``{"status": "failed", "failed_stage": ...,
"error": <one sentence>}``. Later stages pass an upstream failure on unchanged;
aggregates (rig geometry, joint fits, summary, report) leave failed trials out
and list them; the workflow's last rule exits non-zero when any trial failed.
"""

from __future__ import annotations

import logging
import re
from collections.abc import Callable
from pathlib import Path

import numpy as np
import pandas as pd

from pendulum.io import write_failure

STAGE_ORDER = ("frames", "tracks", "geometry", "angles", "fit", "curve")
STATUS_COLUMNS = ["trial", "source", "rig", "status", "stage", "ok_frames_pct", "period_s", "reason", "log"]


class UpstreamFailed(Exception):
    """An input of this stage is a failed document; this stage fails with the same cause."""

    def __init__(self, stage: str, error: str):
        super().__init__(f"{stage} failed: {error}")
        self.stage, self.error = stage, error


def describe(exc: BaseException) -> str:
    """One line for the user.

    Bad input raises ValueError/OSError subclasses whose message names the file
    and the problem; anything else is a bug in this tool and says so.
    """
    message = " ".join(str(exc).split()) or type(exc).__name__
    if isinstance(exc, (ValueError, OSError, RuntimeError, KeyError)) and not isinstance(exc, NotImplementedError):
        return message
    return f"internal error ({type(exc).__name__}: {message}); please report it with the log"


def failed(stage: str, error: str, **fields) -> dict:
    """The document a failed stage writes in place of its JSON output."""
    return {"status": "failed", "failed_stage": stage, "error": error, **fields}


def is_failed(document: dict) -> bool:
    return document.get("status") == "failed"


def require_ok(document: dict, what: str) -> dict:
    """Raise UpstreamFailed if ``document`` (the JSON of an input called ``what``) is a failed one."""
    if is_failed(document):
        raise UpstreamFailed(document.get("failed_stage", what), document.get("error", "failed"))
    return document


def fitted_trials(
    names, angle_info: dict[str, dict], fits: dict[str, dict], log: logging.Logger, context: str
) -> tuple[list[str], dict[str, str]]:
    """The trials whose angles and per-trial fit succeeded on a reliable record, and why each other one is left out.

    A fit marked ``reliable: false`` (its record failed the garbage checks of
    :func:`pendulum.fit.checks.record_checks`) is left out too: one mis-tracked video
    must not move the coefficients of every trial it would be pooled with.
    """
    excluded = {}
    for name in sorted(names):
        bad = next((d for d in (angle_info[name], fits[name]) if is_failed(d)), None)
        if bad:
            excluded[name] = f"{bad['failed_stage']} failed: {bad['error']}"
        elif fits[name].get("reliable") is False:
            problems = [
                p for t in fits[name].get("trials", {}).values() for p in t.get("record_checks", {}).get("problems", [])
            ]
            excluded[name] = "unreliable record: " + (problems[0] if problems else "see its fit's warnings")
        if name in excluded:
            log.warning("%s: %s left out (%s)", context, name, excluded[name])
    return [n for n in sorted(names) if n not in excluded], excluded


def run_stage(stage: str, log: logging.Logger, work: Callable[[], None], write_failed: Callable[[dict], None]) -> bool:
    """Run ``work``; on any exception log it and ``write_failed(failed document)`` instead (with the error's
    ``facts``, a dict of what it measured, where it has them).

    Returns True when the work succeeded. An upstream failure keeps its own
    stage and message; an unexpected error is logged with its traceback.
    """
    try:
        work()
        return True
    except UpstreamFailed as exc:
        log.error("not run: %s", exc)
        write_failed(failed(exc.stage, exc.error))
    except Exception as exc:
        if write_failure(exc) is not None:
            raise  # no room or no rights to write: not this trial's fault; the job fails and a rerun resumes
        reason = describe(exc)
        if reason.startswith("internal error"):
            log.exception("%s", reason)
        else:
            log.error("%s", reason)
        write_failed(failed(stage, reason, **getattr(exc, "facts", {})))  # what the error measured, as data
    return False


def empty_table(columns) -> pd.DataFrame:
    """A header-only table: the CSV output of a failed stage (no rows, so nothing is mistaken for data)."""
    return pd.DataFrame({c: pd.Series(dtype=float) for c in columns})


def failure_image(
    message: str, width_px: int = 960, height_px: int = 200, header: str = "NO CONTACT SHEET:"
) -> np.ndarray:
    """A grey image that states why there is no contact sheet (or, above a refused track's, why it was refused):
    the whole message, the image as tall as it needs (at least ``height_px``)."""
    import cv2

    def fits(text: str) -> bool:  # the line's drawn width within the image's margins
        return cv2.getTextSize(text, cv2.FONT_HERSHEY_SIMPLEX, 0.6, 1)[0][0] <= width_px - 32

    words, lines, line = message.split(), [], ""
    for word in words:
        if line and not fits(f"{line} {word}"):
            lines.append(line)
            line = word
        else:
            line = f"{line} {word}".strip()
    lines.append(line)
    image = np.full((max(height_px, 30 + 26 * len(lines) + 16), width_px), 60, np.uint8)
    for i, text in enumerate([header] + lines):
        cv2.putText(image, text, (16, 30 + 26 * i), cv2.FONT_HERSHEY_SIMPLEX, 0.6, 235, 1, cv2.LINE_AA)
    return image


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
    measured = _measured(documents)
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
                "log": log_path,
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


def status_table(rows: list[dict]) -> pd.DataFrame:
    return pd.DataFrame(rows, columns=STATUS_COLUMNS).sort_values("trial", kind="stable").reset_index(drop=True)


def failure_summary(table: pd.DataFrame) -> str | None:
    """Every failed trial and why, one line each, for the terminal and the check's log; None when all succeeded.

    One line per trial so that the reason of each can be read where Snakemake's own error follows it (a
    paragraph of 4,000 characters was printed twice there, 2026-12-02)."""
    bad = table[table.status != "ok"]
    if bad.empty:
        return None
    built = (
        f"the report and the other {len(table) - len(bad)} trial(s)' results were built"
        if len(bad) < len(table)
        else "the report says why, trial by trial"
    )
    lines = [f"{len(bad)} of {len(table)} trial(s) failed; {built}:"]
    lines += [f"  - {r.trial}, at {r.stage}{_recorded(r)}: {r.reason}" for r in bad.itertuples()]
    lines.append("See results/status/trials.csv (stage, reason and log of each) and results/report/report.html.")
    return "\n".join(lines)


def _recorded(row) -> str:
    """For a trial that failed after its angle record was made (a fit the rig's values refuse): what stands."""
    period = pd.to_numeric(getattr(row, "period_s", None), errors="coerce")
    if pd.isna(period):
        return ""
    usable = pd.to_numeric(getattr(row, "ok_frames_pct", None), errors="coerce")
    frames = "" if pd.isna(usable) else f"{usable:.4g} % of frames usable, "
    return f" (its track and angle record stand: {frames}period {period:.4g} s as swung)"


def failures_logged(log_path, since_s: float) -> str | None:
    """The failed trials as ``check_trials`` logged them (its log's ERROR entry, one line per trial), where the
    log was written at or after ``since_s`` (this run); None otherwise (the run failed somewhere else). The
    Snakefile's ``onerror`` prints it after Snakemake's own error lines, where a user reads last."""
    path = Path(log_path)
    if not path.exists() or path.stat().st_mtime < since_s:
        return None
    found = re.search(r"^\S+ \S+ ERROR (.*)", path.read_text(), flags=re.M | re.S)
    return found.group(1).rstrip() if found else None
