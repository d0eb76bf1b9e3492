"""Snakemake adapter: one model variant fitted jointly to every trial of one rig that could be fitted."""

from pathlib import Path

import pandas as pd

import _setup  # noqa: F401
from pendulum.fit.output_error import fit_joint
from pendulum.fit.records import FitSettings, load_record
from pendulum.fit.summary import fit_document
from pendulum.io import read_json, script_logger, write_json
from pendulum.status import fitted_trials, run_stage

sm = snakemake  # noqa: F821
log = script_logger(sm.log[0], "fit_joint")
rig, variant = sm.wildcards.rig, sm.wildcards.variant
settings = FitSettings(**sm.params.fitting)


def work():
    angles = {Path(p).stem: p for p in sm.input.angles}
    angle_info = {Path(p).stem: read_json(p) for p in sm.input.angle_info}
    fits = {Path(p).stem: read_json(p) for p in sm.input.fits}
    names, excluded = fitted_trials(sm.params.trial_rigs, angle_info, fits, log, f"rig {rig}, variant {variant}")
    if not names:
        raise ValueError(f"rig {rig}: no trial could be fitted with variant {variant}, so there is no joint fit")
    records = [
        load_record(
            pd.read_csv(angles[n]),
            n,
            sm.params.trial_rigs[n],
            settings,
            tolerances=sm.params.tolerances[n],
            angle_info=angle_info[n],
            source=angles[n],
        )
        for n in names
    ]
    log.info("rig %s, variant %s: joint fit of %d trial(s) %s", rig, variant, len(names), names)
    joint = fit_joint(records, sm.params.terms, {n: fits[n] for n in names}, settings)
    log.info("rig %s, variant %s: consistency %s", rig, variant, joint["consistency"]["verdict"])
    document = fit_document(
        joint, variant=variant, rig={"name": rig}, sources=[angles[n] for n in names], settings=settings
    )
    write_json({"status": "ok", **document, "excluded_trials": excluded}, sm.output.joint)


def write_failed(document):
    write_json({"variant": variant, "rig": {"name": rig}, **document}, sm.output.joint)


run_stage("joint fit", log, work, write_failed)
