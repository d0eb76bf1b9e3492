"""Snakemake adapter: discovery of the physics the baseline variant misses, for one group (a body or a rig)."""

import _setup  # noqa: F401
from pendulum.discovery.findings import EXTINCTION_COLUMNS, RESIDUAL_COLUMNS
from pendulum.discovery.selection import Discovery, DiscoveryOptions
from pendulum.fit.bodies import load_group
from pendulum.fit.records import FitSettings
from pendulum.io import script_logger, write_csv, write_json
from pendulum.status import empty_table, run_stage

sm = snakemake  # noqa: F821
log = script_logger(sm.log[0], "discovery")
name = sm.wildcards.group
settings = FitSettings(**sm.params.fitting)


def work():
    group = load_group(sm.input, sm.params.trial_rigs, settings, log, f"group {name}")
    if not group.names:
        raise ValueError(f"group {name}: no trial has a {sm.params.baseline} fit, so there is nothing to discover from")
    names = group.names
    log.info("group %s: %d trial(s) on rig(s) %s, baseline %s", name, len(names), sm.params.rigs, sm.params.baseline)
    run = Discovery(
        group.records,
        group.rigs,
        sm.params.terms,
        sm.params.candidates,
        settings=settings,
        options=DiscoveryOptions(alpha=sm.params.alpha),
        baseline_fits=group.starts,  # reused: start values, nuisance, kept samples; the records carry their noise
    )
    document = run.run()
    residuals, extinction = run.tables(document)
    log.info("group %s: %s", name, document["verdict"])
    write_csv(residuals, sm.output.residuals)
    write_csv(extinction, sm.output.extinction)
    write_json(
        {
            "group": name,
            "status": "ok",
            "rigs": sm.params.rigs,
            "baseline_variant": sm.params.baseline,
            "trials": names,
            "excluded_trials": group.excluded,
            "sources": [group.angle_paths[n] for n in names] + list(sm.input.joint),
            **document,
        },
        sm.output.document,
    )


def write_failed(document):
    write_csv(empty_table(RESIDUAL_COLUMNS), sm.output.residuals)
    write_csv(empty_table(EXTINCTION_COLUMNS), sm.output.extinction)
    write_json({"group": name, "rigs": sm.params.rigs, **document}, sm.output.document)


run_stage("discovery", log, work, write_failed)
