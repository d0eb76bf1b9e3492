"""Snakemake adapter: angle record of one trial, from its track or from an angle table."""

import json
from pathlib import Path

import pandas as pd

import _setup  # noqa: F401
from pendulum.geometry import angles_from_track, angles_from_tracker_csv
from pendulum.io import script_logger, write_csv, write_json

sm = snakemake  # noqa: F821
log = script_logger(sm.log[0], "angles")
settings = sm.params.settings
length_m = settings["length_m"]
try:
    if "table" in sm.input.keys():
        source = sm.input.table
        vertical = settings["vertical_deg"] if settings["vertical_deg"] is not None else 0.0
        table, info = angles_from_tracker_csv(
            pd.read_csv(source), vertical_deg=vertical, length_m=length_m, source=source
        )
    else:
        track_path = sm.input.track
        track = pd.read_csv(track_path)
        if track.empty:
            summary = json.loads(Path(track_path).with_suffix(".json").read_text())
            raise ValueError(f"{summary['video']}: no marker track: {summary['error']}")
        pivot, vertical = settings["pivot_px"], settings["vertical_deg"]
        pivot_cov = None
        if "geometry" in sm.input.keys():
            geometry = json.loads(Path(sm.input.geometry).read_text())
            if pivot is None:
                pivot, pivot_cov = geometry["pivot_px"], geometry.get("pivot_covariance_px2")
            vertical = vertical if vertical is not None else geometry["vertical_deg"]
        source = track_path
        table, info = angles_from_track(
            track,
            pivot_px=pivot,
            vertical_deg=vertical,
            length_m=length_m,
            source=source,
            pivot_covariance_px2=pivot_cov,
        )
except Exception as exc:
    log.error("trial %s: %s", sm.wildcards.trial, exc)
    raise
log.info("trial %s: %s", sm.wildcards.trial, info)
write_csv(table, sm.output.angles)
write_json({"trial": sm.wildcards.trial, "rig": settings["rig_name"], **info.to_dict()}, sm.output.summary)
