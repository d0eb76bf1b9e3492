rule fit_trial:
    """One model variant fitted to one trial: coefficients, 95 % intervals, diagnostics; its fitted curve and half cycles."""
    input:
        angles="results/angles/{trial}.csv",
        angle_info="results/angles/{trial}.json",
        code=code_digest("fit_trial.py"),
    output:
        fit="results/fits/{variant}/{trial}.json",
        curve="results/fits/{variant}/{trial}.curve.csv",
        cycles="results/fits/{variant}/{trial}.cycles.csv",
    log:
        "logs/fits/{variant}/{trial}.log",
    benchmark:
        "benchmarks/jobs/fits/{variant}/{trial}.tsv"
    priority: 1  # before more videos' frames and tracks: the joint fits and discovery (the long tail) start sooner
    threads: 1
    resources:
        mem_mb=1000,
        runtime=10,  # 8 s at most on 25 trials (a helper's cluster run): a short request backfills sooner
    params:
        terms=variant_terms,
        rig=fit_rig,
        tolerances=fit_tolerances,
        fitting=config["fitting"],
    script:
        "../scripts/fit_trial.py"


rule fit_joint:
    """One variant fitted jointly to all trials of one rig, with the per-trial consistency test."""
    input:
        angles=lambda wc: [f"results/angles/{name}.csv" for name in joint_trials(wc)],
        angle_info=lambda wc: [
            f"results/angles/{name}.json" for name in joint_trials(wc)
        ],
        fits=lambda wc: [
            f"results/fits/{wc.variant}/{name}.json" for name in joint_trials(wc)
        ],
        code=script_code("fit_joint.py"),
    output:
        joint="results/fits/{variant}/joint/{rig}.json",
    log:
        "logs/fits/{variant}/joint/{rig}.log",
    benchmark:
        "benchmarks/jobs/fits/{variant}/joint/{rig}.tsv"
    priority: 2
    threads: 1
    resources:
        mem_mb=group_mem_mb,  # from the trials' samples (inputs.smk)
        runtime=120,
    params:
        terms=variant_terms,
        trial_rigs=joint_trial_rigs,
        tolerances=joint_tolerances,
        fitting=config["fitting"],
    script:
        "../scripts/fit_joint.py"


rule fit_summary:
    """Every variant's per-trial and per-rig joint estimates in one table (the paper's Tables 2 and 3)."""
    input:
        fits=summary_inputs,
        code=script_code("fit_summary.py"),
    output:
        table="results/fits/summary.csv",
    log:
        "logs/fits/summary.log",
    benchmark:
        "benchmarks/jobs/fits/summary.tsv"
    threads: 1
    resources:
        mem_mb=500,
        runtime=5,
    params:
        variants=sorted(config["variants"]),
    script:
        "../scripts/fit_summary.py"


rule fit_body:
    """One variant fitted jointly to every trial of one body on its rigs (config `bodies`): m_a, C_d·A, K_h shared."""
    input:
        angles=lambda wc: [f"results/angles/{n}.csv" for n in body_trials(wc)],
        angle_info=lambda wc: [f"results/angles/{n}.json" for n in body_trials(wc)],
        fits=lambda wc: [f"results/fits/{wc.variant}/{n}.json" for n in body_trials(wc)],
        joint=lambda wc: [
            f"results/fits/{wc.variant}/joint/{rig}.json" for rig in BODIES[wc.body]
        ],
        code=script_code("fit_body.py"),
    output:
        body="results/fits/{variant}/body/{body}.json",
    log:
        "logs/fits/{variant}/body/{body}.log",
    benchmark:
        "benchmarks/jobs/fits/{variant}/body/{body}.tsv"
    wildcard_constraints:
        body=r"[A-Za-z0-9_.+-]+",
    threads: 1
    resources:
        mem_mb=group_mem_mb,  # from the trials' samples (inputs.smk)
        runtime=120,
    params:
        terms=variant_terms,
        trial_rigs=lambda wc: group_trial_rigs(SETTINGS, RIG_TRIALS, BODIES, wc.body),
        fitting=config["fitting"],
    script:
        "../scripts/fit_body.py"
