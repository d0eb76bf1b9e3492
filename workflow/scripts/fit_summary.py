"""Snakemake adapter: every variant's per-trial and joint fits in one table."""

import json
from pathlib import Path

import _setup  # noqa: F401
from pendulum.fit.summary import summary_table
from pendulum.io import script_logger, write_csv

sm = snakemake  # noqa: F821
log = script_logger(sm.log[0], "fit_summary")
documents = [json.loads(Path(p).read_text()) for p in sm.input.fits]
table = summary_table(documents)
log.info("%d fits of %d variant(s) %s", len(table), len(sm.params.variants), sm.params.variants)
write_csv(table, sm.output.table)
