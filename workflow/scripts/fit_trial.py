"""Snakemake adapter: one model variant fitted to one trial's angle record, with its curve and half cycles.

One job writes the fit document, then the fitted curve (every sample, residual and
flag) and the half-cycle table, simulated from the document as written (values
rounded to 10 digits), so they are the curve and cycles of that file. A failure
writes all three outputs failed/empty: ``failed_stage`` ``fit`` (or the upstream
stage) when the fit fails, ``curve`` when the fitted model's curve or half-cycle
table cannot be made (the fit is then not used downstream either).
"""

import json
import math
from pathlib import Path

import numpy as np
import pandas as pd

import _setup  # noqa: F401
from pendulum.fit.decay import HALF_CYCLE_COLUMNS
from pendulum.fit.output_error import fit_trials
from pendulum.fit.records import FitSettings, load_record
from pendulum.fit.summary import CURVE_COLUMNS, cycle_table, fit_document, fitted_curve
from pendulum.io import read_json, script_logger, write_csv, write_json
from pendulum.outcomes import for_the_terminal
from pendulum.status import empty_table, require_ok, run_stage

sm = snakemake  # noqa: F821
log = script_logger(sm.log[0], "fit_trial")
trial, variant = sm.wildcards.trial, sm.wildcards.variant
rig_values, terms = sm.params.rig["values"], sm.params.terms
settings = FitSettings(**sm.params.fitting)


def fit_stage():
    angle_info = require_ok(json.loads(Path(sm.input.angle_info).read_text()), "angles")
    angles = pd.read_csv(sm.input.angles)
    record = load_record(
        angles.copy(),
        trial,
        rig_values,
        settings,
        tolerances=sm.params.tolerances,
        angle_info=angle_info,
        source=sm.input.angles,
    )
    log.info("trial %s, variant %s (%s): %d samples", trial, variant, "+".join(terms), record.n_samples)
    fit = fit_trials([record], terms, settings)
    document = fit_document(fit, variant=variant, rig=sm.params.rig, sources=[sm.input.angles], settings=settings)
    for warning in fit["warnings"]:  # notes on the model to its log only (trials.csv and the report list them)
        said = log.warning if for_the_terminal(warning) else log.info
        said("trial %s, variant %s: %s", trial, variant, warning.removeprefix(f"trial {trial}: "))
    log.info("trial %s, variant %s: rms %.4f deg, %s", trial, variant, fit["rms_deg"], fit["optimiser"]["message"])
    write_json({"trial": trial, "status": "ok", **document}, sm.output.fit)
    run_stage("curve", log, lambda: curve_stage(angles), write_failed)


def curve_stage(angles: pd.DataFrame):
    """The fitted curve and half-cycle table of the fit document just written."""
    document = read_json(sm.output.fit)
    fitted = fitted_curve(angles.copy(), document, rig_values, terms, trial=trial)
    cycles = cycle_table(fitted, document, rig_values, terms, trial=trial)
    used = fitted.flag == "fitted"
    rms = math.sqrt(float(np.mean(fitted.residual_rad[used] ** 2)))
    log.info(
        "trial %s, variant %s: curve of %d samples (%s), rms %.6g rad (fit: %.6g rad), %d half cycle(s)",
        trial,
        variant,
        len(fitted),
        ", ".join(f"{k} {v}" for k, v in fitted.flag.value_counts().sort_index().items()),
        rms,
        document["rms_rad"],
        len(cycles),
    )
    write_csv(fitted, sm.output.curve)
    write_csv(cycles, sm.output.cycles)


def write_failed(document):
    write_json({"trial": trial, "variant": variant, "rig": sm.params.rig, **document}, sm.output.fit)
    write_csv(empty_table(CURVE_COLUMNS), sm.output.curve)
    write_csv(empty_table([*HALF_CYCLE_COLUMNS, "predicted_amplitude_loss_rad"]), sm.output.cycles)


run_stage("fit", log, fit_stage, write_failed)
