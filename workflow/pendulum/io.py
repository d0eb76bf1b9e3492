"""Atomic, deterministic writers: nothing half-written, identical bytes on identical input."""

from __future__ import annotations

import errno
import glob
import json
import logging
import math
import os
import re
import sys
from pathlib import Path

import numpy as np
import pandas as pd

FLOAT_FORMAT = "%.10g"
# a write that fails for want of room or rights, not because of the data: (errno, in words, what to do)
WRITE_FAILURES = {
    errno.ENOSPC: ("the disk is full", "free some space"),
    errno.EDQUOT: ("the disk quota is exceeded", "free some space or ask for a larger quota"),
    errno.EROFS: ("the file system is read-only", "make the results folder writable"),
    errno.EACCES: ("permission is denied", "make the results folder writable"),
    errno.EPERM: ("the operation is not permitted", "make the results folder writable"),
    errno.EFBIG: ("the file is larger than the file system allows", "write the results to another disk"),
}
RESUME = "snakemake -c2 --rerun-incomplete"


class WriteFailure(OSError):
    """An output could not be written (disk full, read-only folder, quota): the message names the file and
    says how to resume; finished outputs are kept."""

    def __init__(self, code: int, message: str):
        super().__init__(code, message)
        self.message = message

    def __str__(self) -> str:
        return self.message


def write_failure(exc: BaseException, path=None) -> WriteFailure | None:
    """A :class:`WriteFailure` in words for an OSError of :data:`WRITE_FAILURES`, else None.

    ``path``: the output being written (else the error's own file name, a temporary sibling's
    ``.name.tmpPID`` read back as ``name``).
    """
    if isinstance(exc, WriteFailure):
        return exc
    if not isinstance(exc, OSError) or exc.errno not in WRITE_FAILURES:
        return None
    what, todo = WRITE_FAILURES[exc.errno]
    if path is None and exc.filename:
        name = Path(str(exc.filename))
        hidden = re.fullmatch(r"\.(.+)\.tmp\d+", name.name)
        path = name.with_name(hidden.group(1)) if hidden else name
    target = f"{path} could not be written" if path is not None else "an output could not be written"
    return WriteFailure(
        exc.errno,
        f"{target}: {what} ({exc.strerror or exc}); nothing was half-written: {todo}, then run the same command "
        f"again with --rerun-incomplete (e.g. {RESUME}): finished outputs are kept",
    )


def _atomic(path: Path, write) -> None:
    """Write to a hidden temporary sibling, then rename: a reader sees the old file or the whole new one.

    Temporaries left by a killed earlier writer of the same path are removed first. A write that fails for
    want of room or rights raises :class:`WriteFailure` naming ``path``.
    """
    path = Path(path)
    tmp = path.with_name(f".{path.name}.tmp{os.getpid()}")
    try:
        path.parent.mkdir(parents=True, exist_ok=True)
        for stale in path.parent.glob(f".{glob.escape(path.name)}.tmp*"):
            stale.unlink(missing_ok=True)
        write(tmp)
        tmp.replace(path)
    except OSError as exc:
        failure = write_failure(exc, path)
        if failure is None:
            raise
        raise failure from exc
    finally:
        if tmp.exists():
            tmp.unlink()


def write_csv(table: pd.DataFrame, path) -> None:
    _atomic(path, lambda p: table.to_csv(p, index=False, float_format=FLOAT_FORMAT, lineterminator="\n"))


def _clean(value):
    if isinstance(value, dict):
        return {str(k): _clean(v) for k, v in value.items()}
    if isinstance(value, (list, tuple)):
        return [_clean(v) for v in value]
    if isinstance(value, (np.integer,)):
        return int(value)
    if isinstance(value, (np.floating, float)):
        value = float(value)
        return None if not math.isfinite(value) else float(f"{value:.10g}")
    if isinstance(value, np.bool_):
        return bool(value)
    return value


def write_json(document: dict, path) -> None:
    text = json.dumps(_clean(document), indent=2, sort_keys=False) + "\n"
    _atomic(path, lambda p: Path(p).write_text(text))


def read_json(path) -> dict:
    return json.loads(Path(path).read_text())


def write_text(text: str, path) -> None:
    _atomic(path, lambda p: Path(p).write_text(text))


def write_png(image: np.ndarray, path) -> None:
    import cv2

    def write(p):
        ok, buf = cv2.imencode(".png", image)
        if not ok:
            raise OSError(f"could not encode {path}")
        Path(p).write_bytes(buf.tobytes())

    _atomic(path, write)


def script_logger(log_path, name: str) -> logging.Logger:
    """A logger writing everything (INFO up) to the rule's log file and its warnings and errors to stderr too.

    The terminal shows Snakemake's jobs, what went wrong or may be wrong, and the trials' outcome at the end
    (the Snakefile's ``onsuccess``/``onerror``); each job's progress and facts are in its log (``logs/``), where
    they are looked up (the demo's build printed 118 lines of them among Snakemake's, 20 more for each trial)."""
    logging.raiseExceptions = False  # a log on a full disk must not print a traceback of its own
    logger = logging.getLogger(name)
    logger.setLevel(logging.INFO)
    logger.handlers.clear()
    fmt = logging.Formatter("%(asctime)s %(levelname)s %(message)s")
    terminal = logging.StreamHandler(sys.stderr)
    terminal.setLevel(logging.WARNING)
    for handler in (logging.FileHandler(log_path, mode="w"), terminal):
        handler.setFormatter(fmt)
        logger.addHandler(handler)
    return logger
