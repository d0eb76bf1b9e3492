"""Snakemake adapter: the workflow's last step; fails (so Snakemake exits non-zero) when any trial failed."""

import pandas as pd

import _setup  # noqa: F401
from pendulum.io import script_logger, write_text
from pendulum.status import failure_summary

sm = snakemake  # noqa: F821
log = script_logger(sm.log[0], "check_trials")
table = pd.read_csv(sm.input.table, keep_default_na=False)
problem = failure_summary(table)
if problem:
    log.error("%s", problem)
    raise SystemExit(problem)
log.info("all %d trial(s) ok", len(table))
write_text(f"all {len(table)} trial(s) ok\n", sm.output.done)
