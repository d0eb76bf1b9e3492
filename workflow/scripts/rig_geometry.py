"""Snakemake adapter: pivot and vertical of one rig from its trials' pooled tracks (failed tracks left out)."""

import json
from pathlib import Path

import pandas as pd

import _setup  # noqa: F401
from pendulum.geometry import estimate_rig_geometry
from pendulum.io import script_logger, write_json
from pendulum.status import is_failed, run_stage

sm = snakemake  # noqa: F821
log = script_logger(sm.log[0], "rig_geometry")
rig = sm.wildcards.rig


def work():
    tracks, failed = {}, {}
    for path, summary_path in zip(sm.input.tracks, sm.input.summaries, strict=True):
        summary = json.loads(Path(summary_path).read_text())
        name = Path(path).stem
        if is_failed(summary):
            failed[name] = summary["error"]
            log.warning("%s: left out of the pooled geometry (tracking failed: %s)", name, summary["error"])
        else:
            tracks[name] = pd.read_csv(path)
    if not tracks:
        raise ValueError(f"rig {rig}: no trial has a usable track to estimate the pivot from; give pivot_px in config")
    geometry = estimate_rig_geometry(tracks, pivot_px=sm.params.pivot_px, vertical_deg=sm.params.vertical_deg)
    for name, reason in geometry["rejected_trials"].items():
        log.warning("%s: left out of the pooled geometry: %s", name, reason)
    log.info("rig %s: %s", rig, geometry)
    inputs = sorted(Path(p).stem for p in sm.input.tracks)
    write_json(
        {"rig": rig, "status": "ok", "input_trials": inputs, **geometry, "failed_trials": failed}, sm.output.geometry
    )


run_stage("geometry", log, work, lambda document: write_json({"rig": rig, **document}, sm.output.geometry))
