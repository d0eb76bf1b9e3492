DESIGN_TARGETS = [
    f"results/design/{g}{suffix}"
    for g in sorted(DISCOVERY_GROUPS)
    for suffix in (".json", ".csv")
]


rule design:
    """What to film next for one body or rig: predicted intervals after one more trial."""
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
        discovery="results/discovery/{group}.json",
        code=script_code("design.py"),
    output:
        document="results/design/{group}.json",
        table="results/design/{group}.csv",
    log:
        "logs/design/{group}.log",
    benchmark:
        "benchmarks/jobs/design/{group}.tsv"
    wildcard_constraints:
        group=r"[A-Za-z0-9_.+-]+",
    threads: 1
    resources:
        mem_mb=group_mem_mb,  # from the trials' samples (inputs.smk), as discovery's
        runtime=10,
    params:
        trial_rigs=lambda wc: group_trial_rigs(
            SETTINGS, RIG_TRIALS, DISCOVERY_GROUPS, wc.group
        ),
        design=config.get("design", {}),
        fitting=config["fitting"],
    script:
        "../scripts/design.py"
