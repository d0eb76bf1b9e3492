rule fit_trial:
    """One model variant fitted to one trial: coefficients, 95 % intervals, diagnostics."""
    input:
        angles="results/angles/{trial}.csv",
    output:
        fit="results/fits/{variant}/{trial}.json",
    log:
        "logs/fits/{variant}/{trial}.log",
    threads: 1
    params:
        terms=variant_terms,
        rig=fit_rig,
        fitting=config["fitting"],
    script:
        "../scripts/fit_trial.py"


rule fit_joint:
    """One variant fitted jointly to all trials of each rig, with the per-trial consistency test."""
    input:
        angles=[f"results/angles/{name}.csv" for name in sorted(TRIALS)],
        fits=lambda wc: [
            f"results/fits/{wc.variant}/{name}.json" for name in sorted(TRIALS)
        ],
    output:
        joint="results/fits/{variant}/joint.json",
    log:
        "logs/fits/{variant}/joint.log",
    threads: 1
    params:
        terms=variant_terms,
        rigs=joint_rigs,
        fitting=config["fitting"],
    script:
        "../scripts/fit_joint.py"


rule fit_summary:
    """Every variant's per-trial and joint estimates in one table (the paper's Tables 2 and 3)."""
    input:
        fits=summary_inputs,
    output:
        table="results/fits/summary.csv",
    log:
        "logs/fits/summary.log",
    threads: 1
    params:
        variants=sorted(config["variants"]),
    script:
        "../scripts/fit_summary.py"
