import sys
from pathlib import Path

sys.path.insert(0, str(Path(workflow.basedir) / "workflow"))

from pendulum.trials import (  # noqa: E402
    discover_trials,
    needs_rig_geometry,
    pooled_trials,
    rig_name,
    rig_trials,
    trial_settings,
    validate_config,
)

validate_config(
    config, source="the configuration (config.yaml and any --configfile/--config)"
)

TRIALS = discover_trials(config["raw_dir"])
VIDEO_TRIALS = sorted(n for n, t in TRIALS.items() if t.kind == "video")
RIGS_NEEDING_GEOMETRY = sorted(
    {
        rig_name(config, TRIALS[n])
        for n in VIDEO_TRIALS
        if needs_rig_geometry(config, TRIALS[n])
    }
)


wildcard_constraints:
    trial=r"(?!(?:joint|summary)$)[A-Za-z0-9][A-Za-z0-9_.+-]*",
    rig=r"[A-Za-z0-9_.+-]+",
    variant=r"[A-Za-z0-9_.+-]+",


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
    for variant in sorted(config["variants"]):
        for name in sorted(TRIALS):
            targets += [
                f"results/fits/{variant}/{name}.curve.csv",
                f"results/fits/{variant}/{name}.cycles.csv",
            ]
        targets += joint_fits(variant)
    if TRIALS:
        targets.append("results/fits/summary.csv")
    return targets


def raw_video(wildcards):
    trial = TRIALS[wildcards.trial]
    if trial.kind != "video":
        raise ValueError(f"{trial.path} is not a video")
    return trial.path


def sidecar_files(wildcards):
    path = TRIALS[wildcards.trial].sidecar_path
    return [path] if path else []


def tracking_settings(wildcards):
    return trial_settings(config, TRIALS[wildcards.trial])["tracking"]


def rig_tracks(wildcards):
    return [
        f"results/tracks/{name}.csv"
        for name in pooled_trials(config, TRIALS, wildcards.rig)
    ]


def angles_inputs(wildcards):
    trial = TRIALS[wildcards.trial]
    if trial.kind == "angles":
        inputs = {"table": trial.path}
    else:
        inputs = {"track": f"results/tracks/{trial.name}.csv"}
        if needs_rig_geometry(config, trial):
            inputs["geometry"] = f"results/geometry/{rig_name(config, trial)}.json"
    inputs["sidecar"] = sidecar_files(wildcards)
    return inputs


def angles_settings(wildcards):
    """Only what the angles stage uses, so that changing a mass or a tolerance reruns the fits, not the angles."""
    s = trial_settings(config, TRIALS[wildcards.trial])
    return {
        "rig_name": s["rig_name"],
        "length_m": s["rig"]["length_m"],
        "pivot_px": s["pivot_px"],
        "vertical_deg": s["vertical_deg"],
    }


def variant_terms(wildcards):
    if wildcards.variant not in config["variants"]:
        raise ValueError(
            f"model variant {wildcards.variant!r} is not in config variants"
        )
    return list(config["variants"][wildcards.variant])


def fit_rig(wildcards):
    settings = trial_settings(config, TRIALS[wildcards.trial])
    return {"name": settings["rig_name"], "values": settings["rig"]}


def fit_tolerances(wildcards):
    return trial_settings(config, TRIALS[wildcards.trial])["tolerances"]


def joint_fits(variant):
    """The per-rig joint fits of one variant: one file per rig that has trials."""
    return [
        f"results/fits/{variant}/joint/{rig}.json"
        for rig in sorted(rig_trials(config, TRIALS))
    ]


def joint_trials(wildcards):
    """Trials of the rig of a joint fit (only these are its inputs)."""
    names = rig_trials(config, TRIALS).get(wildcards.rig)
    if not names:
        raise ValueError(f"rig {wildcards.rig!r} has no trials in {config['raw_dir']}")
    return names


def joint_trial_rigs(wildcards):
    """Trial → its rig values (sidecars may override rig values) for one rig's joint fit."""
    return {
        name: trial_settings(config, TRIALS[name])["rig"]
        for name in joint_trials(wildcards)
    }


def joint_tolerances(wildcards):
    """Trial → the rig's stated 1σ tolerances, for one rig's joint fit."""
    return {
        name: trial_settings(config, TRIALS[name])["tolerances"]
        for name in joint_trials(wildcards)
    }


def summary_inputs(wildcards):
    return [
        path
        for variant in sorted(config["variants"])
        for path in [f"results/fits/{variant}/{name}.json" for name in sorted(TRIALS)]
        + joint_fits(variant)
    ]
