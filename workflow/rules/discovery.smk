DISCOVERY = discovery_settings(config)  # None: the default baseline is not a variant
DISCOVERY_GROUPS = discovery_groups(config, RIG_TRIALS) if DISCOVERY else {}
DISCOVERY_TARGETS = [  # the CSVs too, so that a freeze keeps what the report plots
    f"results/discovery/{g}{suffix}"
    for g in sorted(DISCOVERY_GROUPS)
    for suffix in (".json", ".residuals.csv", ".extinction.csv")
]


rule discovery:
    """The physics the baseline variant misses, named with evidence, for one body or rig."""
    input:
        angles=lambda wc: [
            f"results/angles/{n}.csv"
            for n in group_trials(RIG_TRIALS, DISCOVERY_GROUPS, wc.group)
        ],
        angle_info=lambda wc: [
            f"results/angles/{n}.json"
            for n in group_trials(RIG_TRIALS, DISCOVERY_GROUPS, wc.group)
        ],
        fits=lambda wc: [
            f"results/fits/{DISCOVERY['baseline']}/{n}.json"
            for n in group_trials(RIG_TRIALS, DISCOVERY_GROUPS, wc.group)
        ],
        joint=lambda wc: [
            f"results/fits/{DISCOVERY['baseline']}/joint/{rig}.json"
            for rig in DISCOVERY_GROUPS[wc.group]
        ],
        code=script_code("discovery.py"),
    output:
        document="results/discovery/{group}.json",
        residuals="results/discovery/{group}.residuals.csv",
        extinction="results/discovery/{group}.extinction.csv",
    log:
        "logs/discovery/{group}.log",
    benchmark:
        "benchmarks/jobs/discovery/{group}.tsv"
    wildcard_constraints:
        group=r"[A-Za-z0-9_.+-]+",
    priority: 3  # the longest job: started as soon as the baseline's fits are in
    threads: 1
    resources:
        mem_mb=group_mem_mb,  # from the trials' samples (inputs.smk)
        runtime=60,
    params:
        rigs=lambda wc: DISCOVERY_GROUPS[wc.group],
        trial_rigs=lambda wc: group_trial_rigs(
            SETTINGS, RIG_TRIALS, DISCOVERY_GROUPS, wc.group
        ),
        baseline=DISCOVERY and DISCOVERY["baseline"],
        terms=lambda wc: list(config["variants"][DISCOVERY["baseline"]]),
        candidates=DISCOVERY and DISCOVERY["candidates"],
        alpha=DISCOVERY and DISCOVERY["alpha"],
        fitting=config["fitting"],
    script:
        "../scripts/discovery.py"
