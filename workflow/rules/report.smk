rule report:
    """The results report: the parameterised notebook executed with papermill, as one self-contained HTML file."""
    input:
        unpack(report_inputs),
        notebook="notebooks/report.ipynb",
        code=script_code("report.py"),
    output:
        html="results/report/report.html",
        notebook="results/report/report.ipynb",
    log:
        "logs/report/report.log",
    benchmark:
        "benchmarks/jobs/report/report.tsv"
    threads: 1
    resources:
        mem_mb=report_mem_mb,
        runtime=report_runtime,
    params:
        files=report_files(),
        trials=report_trials(),
        rigs=report_rigs(),
        variants={v: list(t) for v, t in sorted(config["variants"].items())},
        fitting=config["fitting"],
        provenance=report_provenance(),
    script:
        "../scripts/report.py"
