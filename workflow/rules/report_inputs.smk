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
    rigs = sorted(RIG_TRIALS)
    # camera setups of rigs with video trials (calibration.smk); no key without cameras
    calibration = {c: f"results/calibration/{c}.json" for c in used_cameras()}
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
        # the design rule's outputs (DESIGN_TARGETS: design.smk)
        "design": {
            g: {
                "document": f"results/design/{g}.json",
                "table": f"results/design/{g}.csv",
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


def report_mem_mb(wildcards):
    """The report job's memory grows with what it draws: 512 MB measured at 25 trials, 697 at 225 and 1,290 at 425
    (3 variants each; a helper's runs, 2026-12-05), where a fixed 800 MB had a scheduler kill it. 600 MB and 1 MB per
    trial and variant (1,875 MB at 425 × 3); its runtime 30 min and 1 min per 10 trials (242 s measured at 425).
    """
    return 600 + len(TRIALS) * len(config["variants"])


def report_runtime(wildcards):
    return 30 + len(TRIALS) // 10


def report_trials():
    """Trial → rig, kind, source file, the rig values (and pivot, vertical) its sidecar overrides and the 1σ
    tolerances stated for its values."""
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
            # as its fits take them (its sidecar's, for the values it gives)
            "tolerances": SETTINGS[name]["tolerances"],
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
        for rig in sorted(RIG_TRIALS)
    }


def used_cameras():
    """The camera setups of rigs with video trials, sorted (their calibrations are the report's, and frozen)."""
    cameras = {
        config["rigs"][rig].get("camera")
        for rig, names in RIG_TRIALS.items()
        if any(TRIALS[n].kind == "video" for n in names)
    }
    return sorted(cameras - {None})


def say_missing_camera_clips():
    """Said while the DAG is built, so a dry run says it too: the run fails those trials alone
    (calibrate_camera.py)."""
    for camera in used_cameras():
        for key in CAMERA_CLIPS:
            clip = config["cameras"][camera].get(key)
            if clip and not Path(clip).is_file():
                print(
                    f"Camera setup {camera}: {clip} (cameras/{camera}/{key}) is not there: its calibration will "
                    "fail, and the trials of its rigs with it",
                    file=sys.stderr,
                )


say_missing_camera_clips()
