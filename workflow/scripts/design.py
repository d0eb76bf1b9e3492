"""Snakemake adapter: what to film next for one group (a body or a rig), from discovery's final model."""

import _setup  # noqa: F401
from pendulum.design.next_trials import ROW_COLUMNS, DesignOptions, design_group, design_table, fit_final_model
from pendulum.design.tolerances import stated_by_rig
from pendulum.fit.bodies import load_group
from pendulum.fit.records import FitSettings
from pendulum.io import read_json, script_logger, write_csv, write_json
from pendulum.status import empty_table, is_failed, run_stage

sm = snakemake  # noqa: F821
log = script_logger(sm.log[0], "design")
name = sm.wildcards.group
settings = FitSettings(**sm.params.fitting)


def work():
    discovery = read_json(sm.input.discovery)
    if is_failed(discovery):
        raise ValueError(f"group {name}: discovery failed ({discovery.get('error', 'no reason given')}), so no design")
    group = load_group(sm.input, sm.params.trial_rigs, settings, log, f"group {name}")
    if not group.names:
        raise ValueError(f"group {name}: no trial could be fitted, so there is nothing to design from")
    fit = fit_final_model(group, discovery, settings)
    options = DesignOptions.from_config(sm.params.design)
    stated = stated_by_rig(sm.params.trial_rigs)
    document, rows = design_group(
        fit,
        discovery["parameters"],
        settings,
        options,
        discovery.get("indistinguishable"),
        stated,
        misfit=discovery["verdict"] if discovery.get("unexplained") else None,
    )
    for warning in [document["model_misfit"]] * bool(document["model_misfit"]) + document["warnings"]:
        log.warning("group %s: %s", name, warning)
    for item in document["recommendations"] + document["separating"]:
        log.info("group %s: %s", name, item["sentence"])
    write_csv(design_table(rows), sm.output.table)
    write_json({"group": name, "status": "ok", "sources": [sm.input.discovery], **document}, sm.output.document)


def write_failed(document):
    write_csv(empty_table(ROW_COLUMNS), sm.output.table)
    write_json({"group": name, **document}, sm.output.document)


run_stage("design", log, work, write_failed)
