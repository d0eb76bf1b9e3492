"""Snakemake adapter: pivot and vertical of one rig from its trials' pooled tracks."""

from pathlib import Path

import pandas as pd

import _setup  # noqa: F401
from pendulum.geometry import estimate_rig_geometry
from pendulum.io import script_logger, write_json

sm = snakemake  # noqa: F821
log = script_logger(sm.log[0], "rig_geometry")
tracks = {}
for path in sm.input.tracks:
    table = pd.read_csv(path)
    if len(table):
        tracks[Path(path).stem] = table
    else:
        log.warning("%s: empty track (unreadable video), left out of the pooled geometry", path)
if not tracks:
    raise ValueError(f"rig {sm.wildcards.rig}: no readable track to estimate the pivot from; give pivot_px")
geometry = estimate_rig_geometry(tracks, pivot_px=sm.params.pivot_px, vertical_deg=sm.params.vertical_deg)
log.info("rig %s: %s", sm.wildcards.rig, geometry)
write_json(geometry, sm.output.geometry)
