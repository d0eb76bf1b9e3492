"""Failure is data: a stage that cannot do its work still writes its outputs, marked failed.

One bad video must not stop the other trials or the aggregates, so every
per-trial stage ends with its declared outputs on disk: the real ones, or
empty tables and a JSON document ``{"status": "failed", "failed_stage": ...,
"error": <one sentence>}``. Later stages pass an upstream failure on unchanged;
aggregates (rig geometry, joint fits, summary, report) leave failed trials out
and list them; the workflow's last rule exits non-zero when any trial failed
(:mod:`pendulum.outcomes`: the status table).
"""

from __future__ import annotations

import logging
from collections.abc import Callable

import numpy as np
import pandas as pd

from pendulum.io import write_failure


class UpstreamFailed(Exception):
    """An input of this stage is a failed document; this stage fails with the same cause."""

    def __init__(self, stage: str, error: str, log: str | None = None):
        super().__init__(f"{stage} failed: {error}")
        self.stage, self.error, self.log = stage, error, log


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
        raise UpstreamFailed(document.get("failed_stage", what), document.get("error", "failed"), document.get("log"))
    return document


# the per-trial fits' warnings that the measured period and the rig values cannot both be right
# (pendulum.fit.checks.rig_checks): an added mass many times the body's, or at its bound of 0
RIG_MISMATCH_MARKS = ("× the body mass (period", "shorter than the rig values allow")


def says_rig_mismatch(warnings) -> bool:
    """Whether warnings (a fit document's list, or the status table's text of them) say that the trial's period and
    the rig values cannot both be right."""
    text = warnings if isinstance(warnings, str) else " ".join(map(str, warnings or []))
    return any(mark in text for mark in RIG_MISMATCH_MARKS)


def rig_mismatch(fit: dict) -> bool:
    """Whether a per-trial fit document warns that its period and the rig values cannot both be right."""
    return says_rig_mismatch(fit.get("warnings"))


def fitted_trials(
    names, angle_info: dict[str, dict], fits: dict[str, dict], log: logging.Logger, context: str
) -> tuple[list[str], dict[str, str]]:
    """The trials whose angles and per-trial fit succeeded on a reliable record, and why each other one is left out.

    A fit marked ``reliable: false`` (its record failed the garbage checks of
    :func:`pendulum.fit.checks.record_checks`) is left out too: one mis-tracked video
    must not move the coefficients of every trial it would be pooled with. So is a trial whose fit says its period and
    the rig values cannot both be right where other trials' fits do not (:func:`rig_mismatch`), and one whose
    angle record is another's, sample for sample (``record_sha256``): counted twice, one recording
    would narrow the intervals and pass its own held-out check.
    """
    excluded = {}
    for name in sorted(names):
        bad = next((d for d in (angle_info[name], fits[name]) if is_failed(d)), None)
        if bad:
            excluded[name] = f"{bad['failed_stage']} failed: {bad['error']}"
            # its reason said once, where it failed and in the status table; not again by every group it was in
            log.warning(
                "%s: %s left out (%s failed: see results/status/trials.csv)", context, name, bad["failed_stage"]
            )
            continue
        if fits[name].get("reliable") is False:
            problems = [
                p for t in fits[name].get("trials", {}).values() for p in t.get("record_checks", {}).get("problems", [])
            ]
            excluded[name] = "unreliable record: " + (problems[0] if problems else "see its fit's warnings")
        if name in excluded:
            log.warning("%s: %s left out (%s)", context, name, excluded[name])
    # a trial whose period the rig values cannot give, where others' they can: another rig's, or a slow-motion clip
    # timed by its file; pooled, it would move every coefficient (the others' alone are a measurement)
    kept = [n for n in sorted(names) if n not in excluded]
    off = [n for n in kept if rig_mismatch(fits[n])]
    if off and len(off) < len(kept):
        for name in off:
            excluded[name] = (
                "its period and the rig values cannot both be right, unlike the other trials' (its fit's warnings: "
                "another rig's values, or a slow-motion clip's time base, capture_fps)"
            )
            log.warning("%s: %s left out (%s)", context, name, excluded[name])
    # one recording under two names (a video copied or exported twice, tracked alike) is one measurement
    kept = [n for n in names if n not in excluded]
    for name, first in copies_of({n: angle_info[n].get("record_sha256") for n in kept}).items():
        excluded[name] = same_record(first)
        log.warning("%s: %s left out (%s)", context, name, excluded[name])
    return [n for n in sorted(names) if n not in excluded], excluded


def copies_of(digests: dict[str, str | None]) -> dict[str, str]:
    """Trial → the first-named trial whose angle record it is, sample for sample (the same ``record_sha256``)."""
    first_of: dict[str, str] = {}
    copies = {}
    for name in sorted(digests):
        digest = digests[name]
        if digest in first_of:
            copies[name] = first_of[digest]
        elif digest:
            first_of[digest] = name
    return copies


def same_record(first: str) -> str:
    """Why a trial is fitted once, not twice (:func:`copies_of`)."""
    return (
        f"the same angle record as {first}, sample for sample (the same video under another name, tracked alike): "
        "counted once"
    )


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
        log.error("not run: its %s stage failed (why: results/status/trials.csv, or that stage's log)", exc.stage)
        write_failed(failed(exc.stage, exc.error, **({"log": exc.log} if exc.log else {})))  # the origin's log
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
