"""Snakemake adapter: one model variant fitted jointly to every trial of one rig."""

import json
from pathlib import Path

import pandas as pd

import _setup  # noqa: F401
from pendulum.fitting import fit_joint
from pendulum.io import script_logger, write_json
from pendulum.records import FitSettings, load_record
from pendulum.summary import fit_document

sm = snakemake  # noqa: F821
log = script_logger(sm.log[0], "fit_joint")
rig, variant = sm.wildcards.rig, sm.wildcards.variant
settings = FitSettings(**sm.params.fitting)
angles = {Path(p).stem: p for p in sm.input.angles}
angle_info = {Path(p).stem: json.loads(Path(p).read_text()) for p in sm.input.angle_info}
fits = {Path(p).stem: json.loads(Path(p).read_text()) for p in sm.input.fits}
names = sorted(sm.params.trial_rigs)
try:
    records = [
        load_record(
            pd.read_csv(angles[n]),
            n,
            sm.params.trial_rigs[n],
            settings,
            tolerances=sm.params.tolerances[n],
            angle_info=angle_info[n],
        )
        for n in names
    ]
    log.info("rig %s, variant %s: joint fit of %d trial(s) %s", rig, variant, len(names), names)
    joint = fit_joint(records, sm.params.terms, {n: fits[n] for n in names}, settings)
except Exception as exc:
    log.error("rig %s, variant %s: %s", rig, variant, exc)
    raise
log.info("rig %s, variant %s: consistency %s", rig, variant, joint["consistency"]["verdict"])
document = fit_document(
    joint, variant=variant, rig={"name": rig}, sources=[angles[n] for n in names], settings=settings
)
write_json(document, sm.output.joint)
