"""Snakemake adapter: one model variant fitted jointly to every trial of one body on its rigs (config ``bodies``)."""

from pathlib import Path

import _setup  # noqa: F401
from pendulum.bodies import group_records
from pendulum.groupfit import fit_body
from pendulum.io import read_json, script_logger, write_json
from pendulum.records import FitSettings
from pendulum.status import fitted_trials, is_failed, run_stage

sm = snakemake  # noqa: F821
log = script_logger(sm.log[0], "fit_body")
body, variant = sm.wildcards.body, sm.wildcards.variant
settings = FitSettings(**sm.params.fitting)


def work():
    angles = {Path(p).stem: p for p in sm.input.angles}
    angle_info = {Path(p).stem: read_json(p) for p in sm.input.angle_info}
    fits = {Path(p).stem: read_json(p) for p in sm.input.fits}
    joints = [doc for doc in map(read_json, sm.input.joint) if not is_failed(doc)]
    trial_rigs = sm.params.trial_rigs
    names, excluded = fitted_trials(trial_rigs, angle_info, fits, log, f"body {body}, variant {variant}")
    if not names:
        raise ValueError(f"body {body}: no trial could be fitted with variant {variant}, so there is no body fit")
    records = group_records(names, angles, angle_info, trial_rigs, settings)
    rigs = [trial_rigs[n]["name"] for n in names]
    log.info("body %s, variant %s: %d trial(s) on rig(s) %s", body, variant, len(names), sorted(set(rigs)))
    document = fit_body(records, rigs, sm.params.terms, joints + [fits[n] for n in names], settings)
    for warning in document["warnings"]:
        log.warning("body %s, variant %s: %s", body, variant, warning)
    write_json(
        {
            "status": "ok",
            "body": body,
            "variant": variant,
            **document,
            "sources": [angles[n] for n in names],
            "excluded_trials": excluded,
        },
        sm.output.body,
    )


def write_failed(document):
    write_json({"body": body, "variant": variant, **document}, sm.output.body)


run_stage("body fit", log, work, write_failed)
