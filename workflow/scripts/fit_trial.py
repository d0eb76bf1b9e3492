"""Snakemake adapter: one model variant fitted to one trial's angle record."""

import json
from pathlib import Path

import pandas as pd

import _setup  # noqa: F401
from pendulum.fitting import fit_trials
from pendulum.io import script_logger, write_json
from pendulum.records import FitSettings, load_record
from pendulum.status import require_ok, run_stage
from pendulum.summary import fit_document

sm = snakemake  # noqa: F821
log = script_logger(sm.log[0], "fit_trial")
trial, variant = sm.wildcards.trial, sm.wildcards.variant
settings = FitSettings(**sm.params.fitting)


def work():
    angle_info = require_ok(json.loads(Path(sm.input.angle_info).read_text()), "angles")
    record = load_record(
        pd.read_csv(sm.input.angles),
        trial,
        sm.params.rig["values"],
        settings,
        tolerances=sm.params.tolerances,
        angle_info=angle_info,
        source=sm.input.angles,
    )
    log.info("trial %s, variant %s (%s): %d samples", trial, variant, "+".join(sm.params.terms), record.n_samples)
    fit = fit_trials([record], sm.params.terms, settings)
    document = fit_document(fit, variant=variant, rig=sm.params.rig, sources=[sm.input.angles], settings=settings)
    for warning in fit["warnings"]:
        log.warning("trial %s, variant %s: %s", trial, variant, warning)
    log.info("trial %s, variant %s: rms %.4f deg, %s", trial, variant, fit["rms_deg"], fit["optimiser"]["message"])
    write_json({"trial": trial, "status": "ok", **document}, sm.output.fit)


def write_failed(document):
    write_json({"trial": trial, "variant": variant, "rig": sm.params.rig, **document}, sm.output.fit)


run_stage("fit", log, work, write_failed)
