"""Free-decay pendulum identification: raw videos → frames → tracks → angles → fits."""

import time

from snakemake.utils import min_version

min_version("9.27")
RUN_STARTED_S = time.time()  # onerror reads the check's log only if this run wrote it


configfile: "config.yaml"


# What the rules share: the trials and validated config, the code and provenance inputs, the
# target lists and the input functions (defined before the stages that use them).
include: "workflow/rules/trials.smk"
include: "workflow/rules/provenance.smk"
include: "workflow/rules/code.smk"
include: "workflow/rules/targets.smk"
include: "workflow/rules/inputs.smk"
include: "workflow/rules/report_inputs.smk"
# The stages, in pipeline order.
include: "workflow/rules/frames.smk"
include: "workflow/rules/tracks.smk"
include: "workflow/rules/calibration.smk"
include: "workflow/rules/angles.smk"
include: "workflow/rules/fits.smk"
include: "workflow/rules/discovery.smk"
include: "workflow/rules/design.smk"
include: "workflow/rules/status.smk"
include: "workflow/rules/report.smk"
include: "workflow/rules/freeze.smk"


# Small aggregates run on the head node when a cluster executor is used.
localrules:
    all,
    code_digest,
    status_table,
    check_trials,
    fit_summary,


rule all:
    default_target: True
    input:
        lambda wildcards: default_targets(),  # asked for here alone (an empty raw folder stops it)


# After Snakemake's own lines, where a user reads last: the raw folder's files that are no trial, the trials no
# variant fits, then the trials that failed (one line each) or how many were ok and skipped, as the last job
# (check_trials) logged them in this run.
from pendulum.outcomes import print_outcome  # noqa: E402


onsuccess:
    print_outcome("logs/status/check.log", RUN_STARTED_S, PASSED_OVER)


onerror:
    print_outcome("logs/status/check.log", RUN_STARTED_S, PASSED_OVER)
