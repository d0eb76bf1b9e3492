"""Snakemake adapter: discovery of the physics the baseline variant misses, for one group (a body or a rig)."""

from pathlib import Path

import _setup  # noqa: F401
from pendulum.bodies import group_records
from pendulum.discovery import Discovery, DiscoveryOptions
from pendulum.findings import EXTINCTION_COLUMNS, RESIDUAL_COLUMNS
from pendulum.io import read_json, script_logger, write_csv, write_json
from pendulum.records import FitSettings
from pendulum.status import empty_table, fitted_trials, is_failed, run_stage

sm = snakemake  # noqa: F821
log = script_logger(sm.log[0], "discovery")
group = sm.wildcards.group
settings = FitSettings(**sm.params.fitting)


def work():
    angles = {Path(p).stem: p for p in sm.input.angles}
    angle_info = {Path(p).stem: read_json(p) for p in sm.input.angle_info}
    fits = {Path(p).stem: read_json(p) for p in sm.input.fits}
    joints = [doc for doc in map(read_json, sm.input.joint) if not is_failed(doc)]
    trial_rigs = sm.params.trial_rigs
    names, excluded = fitted_trials(trial_rigs, angle_info, fits, log, f"group {group}")
    if not names:
        raise ValueError(
            f"group {group}: no trial has a {sm.params.baseline} fit, so there is nothing to discover from"
        )
    records = group_records(names, angles, angle_info, trial_rigs, settings)
    log.info("group %s: %d trial(s) on rig(s) %s, baseline %s", group, len(names), sm.params.rigs, sm.params.baseline)
    run = Discovery(
        records,
        [trial_rigs[n]["name"] for n in names],
        sm.params.terms,
        sm.params.candidates,
        settings=settings,
        options=DiscoveryOptions(alpha=sm.params.alpha),
        baseline_fits=joints + [fits[n] for n in names],  # reused: start values, nuisance, kept samples
        noise_deg=[angle_info[n].get("noise_deg") for n in names],
    )
    document = run.run()
    residuals, extinction = run.tables(document)
    log.info("group %s: %s", group, document["verdict"])
    write_csv(residuals, sm.output.residuals)
    write_csv(extinction, sm.output.extinction)
    write_json(
        {
            "group": group,
            "status": "ok",
            "rigs": sm.params.rigs,
            "baseline_variant": sm.params.baseline,
            "trials": names,
            "excluded_trials": excluded,
            "sources": [angles[n] for n in names] + list(sm.input.joint),
            **document,
        },
        sm.output.document,
    )


def write_failed(document):
    write_csv(empty_table(RESIDUAL_COLUMNS), sm.output.residuals)
    write_csv(empty_table(EXTINCTION_COLUMNS), sm.output.extinction)
    write_json({"group": group, "rigs": sm.params.rigs, **document}, sm.output.document)


run_stage("discovery", log, work, write_failed)
