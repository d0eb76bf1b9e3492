"""Atomic, deterministic writers: nothing half-written, identical bytes on identical input."""

from __future__ import annotations

import glob
import json
import logging
import math
import os
import sys
from pathlib import Path

import numpy as np
import pandas as pd

FLOAT_FORMAT = "%.10g"


def _atomic(path: Path, write) -> None:
    """Write to a hidden temporary sibling, then rename: a reader sees the old file or the whole new one.

    Temporaries left by a killed earlier writer of the same path are removed first.
    """
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    for stale in path.parent.glob(f".{glob.escape(path.name)}.tmp*"):
        stale.unlink(missing_ok=True)
    tmp = path.with_name(f".{path.name}.tmp{os.getpid()}")
    try:
        write(tmp)
        tmp.replace(path)
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
    """A logger writing to the rule's log file and to stderr (Snakemake shows both)."""
    logger = logging.getLogger(name)
    logger.setLevel(logging.INFO)
    logger.handlers.clear()
    fmt = logging.Formatter("%(asctime)s %(levelname)s %(message)s")
    for handler in (logging.FileHandler(log_path, mode="w"), logging.StreamHandler(sys.stderr)):
        handler.setFormatter(fmt)
        logger.addHandler(handler)
    return logger
