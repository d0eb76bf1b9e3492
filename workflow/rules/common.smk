import ast
import functools
import json
import os
import platform
import sys
from pathlib import Path

sys.path.insert(0, str(Path(workflow.basedir) / "workflow"))

from pendulum.bodies import body_groups, group_trial_rigs, group_trials  # noqa: E402
from pendulum.provenance import config_digest, git_state, package_versions  # noqa: E402
from pendulum.trials import (  # noqa: E402
    GEOMETRY_KEYS,
    RIG_KEYS,
    add_sidecar_rigs,
    discover_trials,
    needs_rig_geometry,
    pooled_trials,
    rig_name,
    rig_trials,
    trial_settings,
    validate_config,
)

# `--config key=true` arrives as the string "true": make it the boolean it means.
for key, value in list(config.items()):
    if isinstance(value, str) and value.lower() in ("true", "false"):
        config[key] = value.lower() == "true"

validate_config(
    config, source="the configuration (config.yaml and any --configfile/--config)"
)

TRIALS = discover_trials(config["raw_dir"])
# rigs defined in sidecars join config["rigs"]
SIDECAR_RIGS = add_sidecar_rigs(config, TRIALS)
VIDEO_TRIALS = sorted(n for n, t in TRIALS.items() if t.kind == "video")
BODIES = body_groups(config, TRIALS)  # body → its rigs with trials (config `bodies`)
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
    if TRIALS:
        targets += ["results/status/trials.csv", "results/status/all_trials_ok.txt"]
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
    return targets


def raw_video(wildcards):
    trial = TRIALS[wildcards.trial]
    if trial.kind != "video":
        raise ValueError(f"{trial.path} is not a video")
    return trial.path


def tracking_settings(wildcards):
    return trial_settings(config, TRIALS[wildcards.trial])["tracking"]


def geometry_trials(wildcards):
    """The trials whose tracks estimate a rig's pivot and vertical.

    Once estimated, a rig's geometry is kept: the trials it was estimated from
    stay its inputs, so adding a video does not re-estimate it (nor rebuild every
    other trial's angles and fits). `--config reestimate_geometry=true` pools
    every current trial of the rig instead (a deliberate re-estimate).
    """
    current = pooled_trials(config, TRIALS, wildcards.rig)
    path = Path(f"results/geometry/{wildcards.rig}.json")
    if config.get("reestimate_geometry") or not path.is_file():
        return current
    try:
        kept = json.loads(path.read_text()).get("input_trials")
    except (OSError, ValueError):
        return current
    if not kept or not set(kept) <= set(current):
        return current
    return sorted(kept)


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


def camera_setup(wildcards):
    """A camera setup's settings (config `cameras`), with the defaults filled in."""
    setup = (config.get("cameras") or {}).get(wildcards.camera)
    if setup is None:
        raise ValueError(f"camera setup {wildcards.camera!r} is not in config cameras")
    return {
        "pattern_inner_corners": list(setup.get("pattern_inner_corners", [9, 6])),
        "square_size_m": setup["square_size_m"],
        "plane_frame": int(setup.get("plane_frame", 0)),
    }


def calibration_inputs(wildcards):
    """The checkerboard clips of a camera setup (lens and/or swing plane)."""
    setup = (config.get("cameras") or {}).get(wildcards.camera) or {}
    return {
        key: setup[key]
        for key in ("calibration_video", "plane_video")
        if setup.get(key)
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
            inputs["geometry"] = f"results/geometry/{rig_name(config, trial)}.json"
        camera = trial_settings(config, trial)["camera"]
        if camera:
            inputs["calibration"] = f"results/calibration/{camera}.json"
    return inputs


def angles_settings(wildcards):
    """Only what the angles stage uses, so that changing a mass or a tolerance reruns the fits, not the angles."""
    s = trial_settings(config, TRIALS[wildcards.trial])
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


def body_fits(variant):
    """The joint body fits of one variant: one file per body of config `bodies` with trials."""
    return [f"results/fits/{variant}/body/{body}.json" for body in sorted(BODIES)]


def body_trials(wildcards):
    """Trials of a body's rigs (the inputs of its body fit)."""
    return group_trials(config, TRIALS, BODIES, wildcards.body)


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


def status_trials():
    """Trial → source file, rig and its stage documents (the status table's params)."""
    return {
        name: {
            "source": TRIALS[name].path,
            "rig": rig_name(config, TRIALS[name]),
            "documents": trial_documents(name),
        }
        for name in sorted(TRIALS)
    }


def status_documents(wildcards):
    return [path for name in sorted(TRIALS) for _, path, _ in trial_documents(name)]


LIBRARY_DIR = Path(workflow.basedir) / "workflow" / "pendulum"
SCRIPTS_DIR = Path(workflow.basedir) / "workflow" / "scripts"


@functools.lru_cache(maxsize=None)  # each file parsed once per Snakemake run
def _library_imports(path):
    """Names of the `pendulum` modules a Python file imports (absolute or relative)."""
    names = set()
    for node in ast.walk(ast.parse(Path(path).read_text())):
        if isinstance(node, ast.ImportFrom):
            source = node.module or ""
            if node.level and path.parent == LIBRARY_DIR:
                names |= {source} if source else {a.name for a in node.names}
            elif source == "pendulum":
                names |= {a.name for a in node.names}
            elif source.startswith("pendulum."):
                names.add(source.split(".")[1])
        elif isinstance(node, ast.Import):
            names |= {
                a.name.split(".")[1]
                for a in node.names
                if a.name.startswith("pendulum.")
            }
    return frozenset(n for n in names if (LIBRARY_DIR / f"{n}.py").is_file())


def script_code(script):
    """The library modules a stage's script imports, directly or through each other.

    Declared as the rule's `code` input, so that editing the science of a stage
    reruns that stage (and what depends on it), not the others.
    """
    seen, todo = set(), set(_library_imports(SCRIPTS_DIR / script))
    while todo:
        name = todo.pop()
        if name not in seen:
            seen.add(name)
            todo |= _library_imports(LIBRARY_DIR / f"{name}.py")
    files = [LIBRARY_DIR / "__init__.py", SCRIPTS_DIR / "_setup.py"]
    files += [LIBRARY_DIR / f"{n}.py" for n in sorted(seen)]
    return [os.path.relpath(f) for f in files]


# The report's inputs and parameters (rule report in report.smk).


def report_files():
    """Every file the report notebook reads, by role: the rule's inputs and the notebook's `files`."""
    truth_dir = config.get("truth_dir", "data/truth")
    trials = {}
    for name in sorted(TRIALS):
        entry = {"angles": f"results/angles/{name}.json"}
        if TRIALS[name].kind == "video":
            entry["frames"] = f"results/frames/{name}/summary.json"
            entry["tracks"] = f"results/tracks/{name}.json"
            entry["contact_sheet"] = f"results/frames/{name}/contact_sheet.png"
            entry["track_sheet"] = f"results/tracks/{name}.sheet.png"
        if truth_dir and (Path(truth_dir) / f"{name}.yaml").is_file():
            entry["truth"] = str(Path(truth_dir) / f"{name}.yaml")
        trials[name] = entry
    variants = sorted(config["variants"])
    rigs = sorted(rig_trials(config, TRIALS))
    # camera setups of rigs with video trials (calibration.smk); no key without cameras
    cameras = {
        config["rigs"][rig].get("camera")
        for rig, names in rig_trials(config, TRIALS).items()
        if any(TRIALS[n].kind == "video" for n in names)
    } - {None}
    calibration = {c: f"results/calibration/{c}.json" for c in sorted(cameras)}
    return {
        **({"calibration": calibration} if calibration else {}),
        "summary": "results/fits/summary.csv",
        "status": "results/status/trials.csv",
        "trials": trials,
        "fits": {
            v: {
                name: {
                    "fit": f"results/fits/{v}/{name}.json",
                    "curve": f"results/fits/{v}/{name}.curve.csv",
                    "cycles": f"results/fits/{v}/{name}.cycles.csv",
                }
                for name in sorted(TRIALS)
            }
            for v in variants
        },
        "joint": {
            v: {rig: f"results/fits/{v}/joint/{rig}.json" for rig in rigs}
            for v in variants
        },
        # the discovery rule's outputs (DISCOVERY_GROUPS, DISCOVERY_TARGETS: discovery.smk)
        "discovery": {
            g: {
                "document": f"results/discovery/{g}.json",
                "residuals": f"results/discovery/{g}.residuals.csv",
                "extinction": f"results/discovery/{g}.extinction.csv",
            }
            for g in sorted(DISCOVERY_GROUPS)
        },
    }


def _paths(node):
    if isinstance(node, dict):
        return [p for key in sorted(node) for p in _paths(node[key])]
    return [node]


def report_inputs(wildcards):
    return {"results": _paths(report_files())}


def report_trials():
    """Trial → rig, kind, source file and the rig values (and pivot, vertical) its sidecar overrides."""
    out = {}
    for name in sorted(TRIALS):
        trial = TRIALS[name]
        rig = rig_name(config, trial)
        overrides = {
            k: v
            for k, v in sorted(trial.sidecar.items())
            if k in RIG_KEYS + GEOMETRY_KEYS and v != config["rigs"][rig].get(k)
        }
        out[name] = {
            "rig": rig,
            "kind": trial.kind,
            "source": trial.path,
            "overrides": overrides,
        }
    return out


def report_rigs():
    """Rig → stated values and 1σ tolerances (Table 1), for the rigs that have trials."""
    return {
        rig: {
            "values": {
                k: v for k, v in config["rigs"][rig].items() if k not in ("tolerances",)
            },
            "tolerances": dict(config["rigs"][rig].get("tolerances") or {}),
        }
        for rig in sorted(rig_trials(config, TRIALS))
    }


def report_provenance():
    """Commit (time, dirty flag), configuration digest and package versions; nothing time-dependent."""
    git = git_state(workflow.basedir)
    return {
        "commit": git["commit"],
        "commit_time_utc": git["commit_time_utc"],
        "dirty": git["dirty"],
        "dirty_files": git["dirty_files"],
        "config_sha256": config_digest(config),
        "python": platform.python_version(),
        "packages": package_versions(),
    }


def report_targets():
    return ["results/report/report.html"] if TRIALS else []
