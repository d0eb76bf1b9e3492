rule status_table:
    """One row per trial: ok, or the stage that failed and why (read by the report)."""
    input:
        documents=status_documents,
        code=script_code("status_table.py"),
    output:
        table="results/status/trials.csv",
    log:
        "logs/status/trials.log",
    benchmark:
        "benchmarks/jobs/status/trials.tsv"
    threads: 1
    resources:
        mem_mb=500,
        runtime=5,
    params:
        trials=status_trials(),
        skipped=SKIPPED,
    script:
        "../scripts/status_table.py"


rule check_trials:
    """Last step: fails, so that Snakemake exits non-zero, when any trial failed (everything else is built)."""
    input:
        table="results/status/trials.csv",
        summary="results/fits/summary.csv",
        report=lambda wc: report_targets(),  # so that this check runs last
        discovery=lambda wc: DISCOVERY_TARGETS,
        code=script_code("check_trials.py"),
    output:
        done="results/status/all_trials_ok.txt",
    log:
        "logs/status/check.log",
    benchmark:
        "benchmarks/jobs/status/check.tsv"
    threads: 1
    resources:
        mem_mb=200,
        runtime=5,
    script:
        "../scripts/check_trials.py"
