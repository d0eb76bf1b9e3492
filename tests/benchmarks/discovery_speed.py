"""Wall time of discovery on the demo set (issue 10, item 7: within 60 s on 2 cores).

Run: .venv/bin/python tests/benchmarks/discovery_speed.py [--project DIR] [--rule]

Reads a built project (default the repository root, after `snakemake -c2`): the demo's angle
records and its `quadratic` fits (per trial and joint), and times what the `discovery` rule does
in its one process with one BLAS thread: the discovery of paper_rig (baseline fit, three forward
rounds of refits, held-out checks, backward step, final intervals with the systematic budget)
and its residual and extinction tables. ``--rule`` also times the rule itself
(`snakemake -c2 --forcerun discovery`), Snakemake's start-up included.
"""

import os

os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")  # as Snakemake sets it for a one-thread rule
os.environ.setdefault("OMP_NUM_THREADS", "1")

import argparse  # noqa: E402
import json  # noqa: E402
import subprocess  # noqa: E402
import sys  # noqa: E402
import time  # noqa: E402
from pathlib import Path  # noqa: E402

import pandas as pd  # noqa: E402
import yaml  # noqa: E402

ROOT = Path(__file__).resolve().parents[2]
sys.path.insert(0, str(ROOT / "workflow"))

from pendulum.discovery.selection import Discovery, DiscoveryOptions  # noqa: E402
from pendulum.fit.records import FitSettings, load_record  # noqa: E402
from pendulum.trials import RIG_KEYS  # noqa: E402


def measure(project: Path, n_trials: int | None = None) -> dict:
    """Wall time (s) of what the `discovery` rule computes for paper_rig in a built ``project``; with ``n_trials``,
    on that many trials: the project's records over again under new names (a lab's many trials of one body)."""
    project = Path(project).resolve()
    config = yaml.safe_load((project / "config.yaml").read_text())
    rig = config["rigs"]["paper_rig"]
    discovery = {"baseline": "quadratic", "candidates": None, "alpha": 0.01, **(config.get("discovery") or {})}
    variant = discovery["baseline"]
    settings = FitSettings(**config["fitting"])
    names = sorted(p.stem for p in (project / "results/angles").glob("*.csv"))
    if not names or not (project / f"results/fits/{variant}/joint/paper_rig.json").is_file():
        raise SystemExit(f"{project}: no built demo results (run `snakemake -c2` there first)")
    started = time.perf_counter()
    records, fits, noise = [], [], []
    for i in range(n_trials or len(names)):
        name = names[i % len(names)]
        trial = name if i < len(names) else f"{name}_copy{i // len(names)}"
        info = json.loads((project / f"results/angles/{name}.json").read_text())
        table = pd.read_csv(project / f"results/angles/{name}.csv")
        values = {k: rig[k] for k in RIG_KEYS if k in rig}
        records.append(load_record(table, trial, values, settings, tolerances=rig.get("tolerances"), angle_info=info))
        fit = json.loads((project / f"results/fits/{variant}/{name}.json").read_text())
        fits.append({**fit, "trials": {trial: fit["trials"][name]}})
        noise.append(info["noise_deg"])
    if n_trials:
        started = time.perf_counter()  # the records read; discovery's own time, from each trial's own fit
        joint = None
    else:
        joint = json.loads((project / f"results/fits/{variant}/joint/paper_rig.json").read_text())
    run = Discovery(
        records,
        ["paper_rig"] * len(records),
        config["variants"][variant],
        discovery["candidates"] or ["linear_damping", "coulomb_friction", "history_force", "restoring_correction"],
        settings=settings,
        options=DiscoveryOptions(alpha=discovery["alpha"]),
        baseline_fits=[joint, *fits] if joint else fits,
        noise_deg=noise,
    )
    document = run.run()
    run.tables(document)
    return {
        "seconds": time.perf_counter() - started,
        "n_trials": len(names),
        "models_fitted": len(run.fitted_models),
        "verdict": document["verdict"],
    }


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--project", type=Path, default=ROOT)
    parser.add_argument("--rule", action="store_true", help="also time the Snakemake rule")
    args = parser.parse_args(argv)
    project = args.project.resolve()
    figures = measure(project)
    print(
        f"discovery on the demo set ({figures['n_trials']} trials, {figures['models_fitted']} models fitted): "
        f"{figures['seconds']:.1f} s (target 60 s)"
    )
    print(f"  {figures['verdict']}")
    if args.rule:
        started = time.perf_counter()
        subprocess.run(
            [sys.executable, "-m", "snakemake", "-c2", "--forcerun", "discovery", "results/discovery/paper_rig.json"],
            cwd=project,
            check=True,
            capture_output=True,
        )
        print(f"snakemake -c2 --forcerun discovery (start-up included): {time.perf_counter() - started:.1f} s")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
