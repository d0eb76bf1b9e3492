"""Snakemake adapter: one model variant fitted jointly to every trial of one body on its rigs (config ``bodies``)."""

import _setup  # noqa: F401
from pendulum.fit.bodies import load_group
from pendulum.fit.group import fit_body
from pendulum.fit.records import FitSettings
from pendulum.io import script_logger, write_json
from pendulum.status import run_stage

sm = snakemake  # noqa: F821
log = script_logger(sm.log[0], "fit_body")
body, variant = sm.wildcards.body, sm.wildcards.variant
settings = FitSettings(**sm.params.fitting)


def work():
    group = load_group(sm.input, sm.params.trial_rigs, settings, log, f"body {body}, variant {variant}")
    if not group.names:
        raise ValueError(f"body {body}: no trial could be fitted with variant {variant}, so there is no body fit")
    log.info("body %s, variant %s: %d trial(s) on rig(s) %s", body, variant, len(group.names), sorted(set(group.rigs)))
    document = fit_body(group.records, group.rigs, sm.params.terms, group.starts, settings)
    for warning in document["warnings"]:
        log.warning("body %s, variant %s: %s", body, variant, warning)
    write_json(
        {
            "status": "ok",
            "body": body,
            "variant": variant,
            **document,
            "sources": [group.angle_paths[n] for n in group.names],
            "excluded_trials": group.excluded,
        },
        sm.output.body,
    )


def write_failed(document):
    write_json({"body": body, "variant": variant, **document}, sm.output.body)


run_stage("body fit", log, work, write_failed)
