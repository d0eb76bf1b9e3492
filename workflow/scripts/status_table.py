"""Snakemake adapter: one status row per trial (ok, or the stage that failed and why)."""

import json
from pathlib import Path

import _setup  # noqa: F401
from pendulum.io import script_logger, write_csv
from pendulum.status import status_table, trial_status

sm = snakemake  # noqa: F821
log = script_logger(sm.log[0], "status")
rows = []
for trial, info in sm.params.trials.items():
    documents = [(stage, log_path, json.loads(Path(path).read_text())) for stage, path, log_path in info["documents"]]
    rows.append(trial_status(trial, info["source"], info["rig"], documents))
table = status_table(rows)
for row in table.itertuples():
    (log.info if row.status == "ok" else log.error)("%s: %s %s %s", row.trial, row.status, row.stage, row.reason)
write_csv(table, sm.output.table)
