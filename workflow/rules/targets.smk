# Targets: what the workflow builds for the trials found (by default, and every file for a freeze), the
# aggregates' per-trial inputs, the documents the status table and a freeze read.


def all_targets():
    """Every result the workflow builds for the trials found in the raw folder."""
    targets = []
    for name in VIDEO_TRIALS:
        targets += [
            f"results/frames/{name}/timeline.csv",
            f"results/frames/{name}/contact_sheet.png",
            f"results/tracks/{name}.csv",
        ]
        if config["frames"]["keep_images"]:
            targets.append(f"results/frames/{name}/images")
    targets += [f"results/angles/{name}.csv" for name in sorted(TRIALS)]
    if TRIALS or SKIPPED:  # every trial skipped: the status table says so
        targets.append("results/status/trials.csv")
    if TRIALS:
        targets.append("results/status/all_trials_ok.txt")
    for variant in sorted(config["variants"]):
        for name in sorted(TRIALS):
            targets += [
                f"results/fits/{variant}/{name}.curve.csv",
                f"results/fits/{variant}/{name}.cycles.csv",
            ]
        targets += joint_fits(variant)
        targets += body_fits(variant)
    if TRIALS:
        targets.append("results/fits/summary.csv")
    targets += DISCOVERY_TARGETS  # workflow/rules/discovery.smk
    targets += DESIGN_TARGETS  # workflow/rules/design.smk
    return targets


def default_targets():
    """What a plain `snakemake` builds: the products no other job reads. Every other result comes with
    them (the status table, the summary and the report read each trial's frames, tracks, angles and fits;
    a job writes all its outputs): the same jobs as asking for every file (all_targets: ten more inputs
    per trial), whose planning of 1,000 trials took 4 % longer (13.5 against 13.0 s, alternated dry runs).
    A raw folder that is missing or holds no trial stops it, saying so (pendulum.camera.raw_folder).
    """
    problem = raw_folder_problem(config["raw_dir"], FOUND)
    if problem:
        raise ConfigError(problem)
    targets = []
    if config["frames"]["keep_images"]:
        targets += [f"results/frames/{name}/images" for name in VIDEO_TRIALS]
    if TRIALS or SKIPPED:  # every trial skipped: the status table says so
        targets.append("results/status/trials.csv")
    if TRIALS:
        targets += ["results/status/all_trials_ok.txt", "results/fits/summary.csv"]
    for variant in sorted(config["variants"]):
        targets += joint_fits(variant) + body_fits(variant)
    return targets + DISCOVERY_TARGETS + DESIGN_TARGETS + report_targets()


def joint_fits(variant):
    """The per-rig joint fits of one variant: one file per rig that has trials."""
    return [f"results/fits/{variant}/joint/{rig}.json" for rig in sorted(RIG_TRIALS)]


def body_fits(variant):
    """The joint body fits of one variant: one file per body of config `bodies` with trials."""
    return [f"results/fits/{variant}/body/{body}.json" for body in sorted(BODIES)]


def summary_inputs(wildcards):
    return [
        path
        for variant in sorted(config["variants"])
        for path in [f"results/fits/{variant}/{name}.json" for name in sorted(TRIALS)]
        + joint_fits(variant)
    ]


def trial_documents(name):
    """(stage, JSON document, log) of one trial's per-trial outputs, in pipeline order."""
    docs = []
    if TRIALS[name].kind == "video":
        docs += [
            (
                "frames",
                f"results/frames/{name}/summary.json",
                f"logs/frames/{name}.log",
            ),
            ("tracks", f"results/tracks/{name}.json", f"logs/tracks/{name}.log"),
        ]
    docs.append(("angles", f"results/angles/{name}.json", f"logs/angles/{name}.log"))
    for variant in sorted(config["variants"]):
        docs.append(
            (
                f"fit:{variant}",
                f"results/fits/{variant}/{name}.json",
                f"logs/fits/{variant}/{name}.log",
            )
        )
    return docs


def status_documents(wildcards):
    return [path for name in sorted(TRIALS) for _, path, _ in trial_documents(name)]


def report_targets():
    return ["results/report/report.html"] if TRIALS else []
