# Inputs and settings of one job, by stage: the input functions and params of the rules in
# frames.smk, tracks.smk, calibration.smk, angles.smk, fits.smk and status.smk.
import json
from pathlib import Path

from pendulum.groups import group_job_mem_mb  # noqa: E402
from pendulum.tracking.settings import job_resources  # noqa: E402


def raw_video(wildcards):
    trial = TRIALS[wildcards.trial]
    if trial.kind != "video":
        raise ValueError(f"{trial.path} is not a video")
    return trial.path


def tracking_settings(wildcards):
    return SETTINGS[wildcards.trial]["tracking"]


def _tracks_job(path) -> tuple[int, int]:
    """The tracks job's memory (MB) and runtime (min) for its clip's size, from the frames
    stage's summary (pendulum.tracking.settings.job_resources). Before the summary exists
    the missing file is raised: Snakemake shows <TBD> and evaluates them again when the
    job is ready; a failed summary (no size) gives a 1080p clip's."""
    try:
        summary = json.loads(Path(path).read_text())
        size = (
            summary["width_px"],
            summary["height_px"],
            int(summary.get("n_frames") or 0),
        )
    except FileNotFoundError:
        raise
    except (OSError, ValueError, KeyError, TypeError):
        size = 1920, 1080, 0
    return job_resources(*size)


def tracks_mem_mb(wildcards, input):
    return _tracks_job(input.frames_summary)[0]


def tracks_runtime(wildcards, input):
    return _tracks_job(input.frames_summary)[1]


def geometry_trials(wildcards):
    """The trials whose tracks estimate a rig's pivot and vertical.

    Once estimated, a rig's geometry is kept: the trials it was estimated from
    stay its inputs, so adding a video does not re-estimate it (nor rebuild every
    other trial's angles and fits), nor does giving one it did not rest on its
    own rig (pendulum.trials.kept_geometry_trials). `--config reestimate_geometry=true` pools
    every current trial of the rig instead (a deliberate re-estimate).
    """
    current = pooled_trials(config, TRIALS, wildcards.rig)
    path = Path(f"results/geometry/{wildcards.rig}.json")
    if config.get("reestimate_geometry") or not path.is_file():
        return current
    try:
        document = json.loads(path.read_text())
    except (OSError, ValueError):
        return current
    return kept_geometry_trials(document, current, VIDEO_TRIALS)


def geometry_inputs(wildcards):
    names = geometry_trials(wildcards)
    inputs = {
        "tracks": [f"results/tracks/{name}.csv" for name in names],
        "summaries": [f"results/tracks/{name}.json" for name in names],
    }
    camera = config["rigs"][wildcards.rig].get("camera")
    if camera:
        inputs["calibration"] = f"results/calibration/{camera}.json"
    return inputs


def tracks_calibration(wildcards):
    """The calibration of the trial's camera setup where it has a lens clip: the track's path is measured in the
    lens-corrected picture (scripts/tracks.py; a wide lens bends the swing's circle)."""
    camera = SETTINGS[wildcards.trial]["camera"]
    setup = (config.get("cameras") or {}).get(camera) or {}
    if camera and setup.get("calibration_video"):
        return {"calibration": f"results/calibration/{camera}.json"}
    return {}


def camera_setup(wildcards):
    """A camera setup's settings (config `cameras`), with the defaults filled in."""
    setup = (config.get("cameras") or {}).get(wildcards.camera)
    if setup is None:
        raise ValueError(f"camera setup {wildcards.camera!r} is not in config cameras")
    return {
        "pattern_inner_corners": list(setup.get("pattern_inner_corners", [9, 6])),
        "square_size_m": setup["square_size_m"],
        "plane_frame": int(setup.get("plane_frame", 0)),
        "clips": {k: setup[k] for k in CAMERA_CLIPS if setup.get(k)},
    }


CAMERA_CLIPS = ("calibration_video", "plane_video")


def calibration_inputs(wildcards):
    """The checkerboard clips of a camera setup (lens and/or swing plane) that exist: a missing one fails the
    calibration, and with it the trials of its rigs alone, naming the file (params ``clips``), where an input
    would stop the whole run (a reviewer's typo in a clip's name); once it is there, the calibration reruns.
    """
    setup = (config.get("cameras") or {}).get(wildcards.camera) or {}
    return {
        k: setup[k] for k in CAMERA_CLIPS if setup.get(k) and Path(setup[k]).is_file()
    }


def angles_inputs(wildcards):
    trial = TRIALS[wildcards.trial]
    if trial.kind == "angles":
        inputs = {"table": trial.path}
    else:
        inputs = {
            "track": f"results/tracks/{trial.name}.csv",
            "track_summary": f"results/tracks/{trial.name}.json",
        }
        if needs_rig_geometry(config, trial):
            inputs["geometry"] = (
                f"results/geometry/{SETTINGS[trial.name]['rig_name']}.json"
            )
        camera = SETTINGS[trial.name]["camera"]
        if camera:
            inputs["calibration"] = f"results/calibration/{camera}.json"
    return inputs


def angles_settings(wildcards):
    """Only what the angles stage uses, so that changing a mass or a tolerance reruns the fits, not the angles."""
    s = SETTINGS[wildcards.trial]
    settings = {
        "rig_name": s["rig_name"],
        "length_m": s["rig"]["length_m"],
        "pivot_px": s["pivot_px"],
        "vertical_deg": s["vertical_deg"],
    }
    # (absent without a camera: the params of existing trials stay as they were)
    if s["camera"]:
        settings["camera"] = s["camera"]
    return settings


def variant_terms(wildcards):
    if wildcards.variant not in config["variants"]:
        raise ValueError(
            f"model variant {wildcards.variant!r} is not in config variants"
        )
    return list(config["variants"][wildcards.variant])


def fit_rig(wildcards):
    settings = SETTINGS[wildcards.trial]
    return {"name": settings["rig_name"], "values": settings["rig"]}


def fit_tolerances(wildcards):
    return SETTINGS[wildcards.trial]["tolerances"]


def body_trials(wildcards):
    """Trials of a body's rigs (the inputs of its body fit)."""
    return group_trials(RIG_TRIALS, BODIES, wildcards.body)


def joint_trials(wildcards):
    """Trials of the rig of a joint fit (only these are its inputs)."""
    names = RIG_TRIALS.get(wildcards.rig)
    if not names:
        raise ValueError(f"rig {wildcards.rig!r} has no trials in {config['raw_dir']}")
    return names


def joint_trial_rigs(wildcards):
    """Trial → its rig values (sidecars may override rig values) for one rig's joint fit."""
    return {name: SETTINGS[name]["rig"] for name in joint_trials(wildcards)}


def joint_tolerances(wildcards):
    """Trial → the rig's stated 1σ tolerances, for one rig's joint fit."""
    return {name: SETTINGS[name]["tolerances"] for name in joint_trials(wildcards)}


def status_trials():
    """Trial → source file, rig and its stage documents (the status table's params)."""
    return {
        name: {
            "source": TRIALS[name].path,
            "rig": SETTINGS[name]["rig_name"],
            "documents": trial_documents(name),
        }
        for name in sorted(TRIALS)
    }


def group_mem_mb(wildcards, input):
    """A group fit's memory from its trials' samples (pendulum.groups.group_job_mem_mb), read from
    their angle documents; before they exist the missing file is raised (<TBD>, as for tracks).
    """
    samples = []
    for path in input.angle_info:
        try:
            samples.append(
                int(json.loads(Path(path).read_text()).get("n_samples") or 0)
            )
        except FileNotFoundError:
            raise
        except (OSError, ValueError, TypeError, AttributeError):
            samples.append(0)  # a failed record: left out of the fit
    return group_job_mem_mb(samples)
