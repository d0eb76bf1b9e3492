"""Snakemake adapter: the workflow's last step; fails (so Snakemake exits non-zero) when any trial failed.

The failures go to its log only; the Snakefile's ``onerror`` prints them from there after Snakemake's own
error lines, where a user reads last (once, not twice above the traceback)."""

import logging

import pandas as pd

import _setup  # noqa: F401
from pendulum.io import script_logger, write_text
from pendulum.status import failure_summary

sm = snakemake  # noqa: F821
log = script_logger(sm.log[0], "check_trials")
log.handlers = [h for h in log.handlers if isinstance(h, logging.FileHandler)]  # the terminal gets them from onerror
table = pd.read_csv(sm.input.table, keep_default_na=False)
problem = failure_summary(table)
if problem:
    log.error("%s", problem)
    raise SystemExit(1)
log.info("all %d trial(s) ok", len(table))
write_text(f"all {len(table)} trial(s) ok\n", sm.output.done)
