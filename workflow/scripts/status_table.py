"""Snakemake adapter: one status row per trial (ok, or the stage that failed and why)."""

import json
from pathlib import Path

import _setup  # noqa: F401
from pendulum.io import script_logger, write_csv
from pendulum.outcomes import mark_copies, skipped_status, status_table, trial_status

sm = snakemake  # noqa: F821
log = script_logger(sm.log[0], "status")
rows, digests = [], {}
for trial, info in sm.params.trials.items():
    documents = [(stage, log_path, json.loads(Path(path).read_text())) for stage, path, log_path in info["documents"]]
    rows.append(trial_status(trial, info["source"], info["rig"], documents))
    digests[trial] = next((d.get("record_sha256") for stage, _, d in documents if stage == "angles"), None)
mark_copies(rows, digests)
rows += [skipped_status(trial, info["source"], info["reason"]) for trial, info in sm.params.skipped.items()]
table = status_table(rows)
for row in table.itertuples():
    (log.error if row.status == "failed" else log.info)("%s: %s %s %s", row.trial, row.status, row.stage, row.reason)
write_csv(table, sm.output.table)
