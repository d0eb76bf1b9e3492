import platform

from pendulum.provenance import config_digest, git_state, package_versions  # noqa: E402
from pendulum.trials import GEOMETRY_KEYS, RIG_KEYS  # noqa: E402


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
        if truth_dir and (Path(truth_dir) / f"{name}.yaml").is_file():
            entry["truth"] = str(Path(truth_dir) / f"{name}.yaml")
        trials[name] = entry
    variants = sorted(config["variants"])
    rigs = sorted(rig_trials(config, TRIALS))
    return {
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
        "config_sha256": config_digest(config),
        "python": platform.python_version(),
        "packages": package_versions(),
    }


def report_targets():
    return ["results/report/report.html"] if TRIALS else []


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
    threads: 1
    resources:
        mem_mb=800,
    params:
        files=report_files(),
        trials=report_trials(),
        rigs=report_rigs(),
        variants={v: list(t) for v, t in sorted(config["variants"].items())},
        fitting=config["fitting"],
        provenance=report_provenance(),
    script:
        "../scripts/report.py"
