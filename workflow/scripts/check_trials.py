"""Snakemake adapter: the workflow's last step; fails (so Snakemake exits non-zero) when any trial failed.

The failures, the trials no variant fits and the count of those ok and skipped go to its log only; the
Snakefile's ``onsuccess`` and ``onerror`` print them from there after Snakemake's own lines, where a user reads
last (once, not twice above the traceback; not 60 lines up behind the final job's listing)."""

import logging

import pandas as pd

import _setup  # noqa: F401
from pendulum.io import script_logger, write_text
from pendulum.outcomes import failure_summary, misfit_trials, rig_mismatch_trials

sm = snakemake  # noqa: F821
log = script_logger(sm.log[0], "check_trials")
log.handlers = [h for h in log.handlers if isinstance(h, logging.FileHandler)]  # the terminal: onsuccess/onerror
table = pd.read_csv(sm.input.table, keep_default_na=False)
problem = failure_summary(table)
wrong = misfit_trials(table)
if wrong:  # built and ok, but no variant fits: said at the end of a run that succeeded too (Snakefile)
    note = (
        f"{len(wrong)} trial(s) ok whose every model variant misses the record far beyond its noise (what it "
        "misses may bias the coefficients, and their intervals do not cover it; the warnings in "
        "results/status/trials.csv, and where the residual lies in the discovery verdict): "
        f"{', '.join(wrong)}"
    )
    log.warning("%s", note)
mismatched = rig_mismatch_trials(table)
if mismatched:  # built and ok, but the coefficients cannot be right: said at the end of a run that succeeded too
    note = (
        f"{len(mismatched)} trial(s) ok whose period and rig values cannot both be right (an added mass many times "
        "the body's, or below zero: check the rig values, and the time base of a slow-motion clip, capture_fps; a "
        "light body swung in air, whose added mass is tiny, may need a negative one allowed, "
        "fitting.added_mass_lower_kg, which holds for every rig; the warnings in results/status/trials.csv): "
        f"{', '.join(mismatched)}"
    )
    log.warning("%s", note)
if problem:
    log.error("%s", problem)
    raise SystemExit(1)
skipped = table[table.status == "skipped"]
doubts = [f"{len(wrong)} missed by every model variant"] if wrong else []
doubts += [f"{len(mismatched)} with the rig values in doubt"] if mismatched else []
done = (
    f"all {len(table) - len(skipped)} trial(s) ok"
    + (f" ({', '.join(doubts)}, above)" if doubts else "")
    + (f", {len(skipped)} skipped by their sidecars" if len(skipped) else "")
)
log.info("%s", done)
write_text(done + "\n", sm.output.done)
