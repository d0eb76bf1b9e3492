"""Snakemake adapter: one trial's fitted curve and half-cycle table under one model variant."""

import json
import math
from pathlib import Path

import numpy as np
import pandas as pd

import _setup  # noqa: F401
from pendulum.decay import HALF_CYCLE_COLUMNS
from pendulum.io import script_logger, write_csv
from pendulum.status import empty_table, require_ok, run_stage
from pendulum.summary import CURVE_COLUMNS, cycle_table, fitted_curve

sm = snakemake  # noqa: F821
log = script_logger(sm.log[0], "fit_curve")
trial, variant = sm.wildcards.trial, sm.wildcards.variant
rig_values, terms = sm.params.rig["values"], sm.params.terms


def work():
    document = require_ok(json.loads(Path(sm.input.fit).read_text()), "fit")
    curve = fitted_curve(pd.read_csv(sm.input.angles), document, rig_values, terms, trial=trial)
    cycles = cycle_table(curve, document, rig_values, terms, trial=trial)
    used = curve.flag == "fitted"
    rms = math.sqrt(float(np.mean(curve.residual_rad[used] ** 2)))
    log.info(
        "trial %s, variant %s: %d samples (%s), rms %.6g rad (fit: %.6g rad), %d half cycle(s)",
        trial,
        variant,
        len(curve),
        ", ".join(f"{k} {v}" for k, v in curve.flag.value_counts().sort_index().items()),
        rms,
        document["rms_rad"],
        len(cycles),
    )
    write_csv(curve, sm.output.curve)
    write_csv(cycles, sm.output.cycles)


def write_failed(document):
    write_csv(empty_table(CURVE_COLUMNS), sm.output.curve)
    write_csv(empty_table([*HALF_CYCLE_COLUMNS, "predicted_amplitude_loss_rad"]), sm.output.cycles)


run_stage("curve", log, work, write_failed)
