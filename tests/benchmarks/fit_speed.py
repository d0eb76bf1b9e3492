"""Wall time of the fits: one per-trial fit of each variant and each variant's joint fit.

Run: .venv/bin/python tests/benchmarks/fit_speed.py
Uses the demo's angle records (results/angles, after `snakemake -c2`) when present,
else model-generated records of the demo releases; plus one 20 s, 60 fps record
of the friction variant (target: under 2 s on one core).
"""

import math
import sys
import time
from pathlib import Path

import numpy as np
import pandas as pd

ROOT = Path(__file__).resolve().parents[2]
sys.path.insert(0, str(ROOT / "workflow"))

from pendulum.fit.output_error import fit_trials  # noqa: E402
from pendulum.fit.records import FitSettings, load_record  # noqa: E402
from pendulum.model.physics import PendulumModel  # noqa: E402
from pendulum.model.rig import Rig  # noqa: E402
from pendulum.synthetic.records import synthetic_angle_table  # noqa: E402

RIG = {"mass_kg": 3.53, "length_m": 0.76, "frontal_area_m2": 0.0322, "displaced_volume_m3": 0.0025}
VARIANTS = {
    "quadratic": ("quadratic_drag",),
    "linear": ("quadratic_drag", "linear_damping"),
    "friction": ("quadratic_drag", "linear_damping", "coulomb_friction"),
}
TRUTH = {"added_mass_kg": 2.5, "drag_area_m2": 0.02576, "linear_damping_nm_s": 0.15, "friction_torque_nm": 0.02}
RELEASES = {"demo_p75": 75, "demo_p20": 20, "demo_m15": -15, "demo_p05": 5, "demo_m05": -5}


def timed(fn, repeats=3):
    best = math.inf
    for _ in range(repeats):
        start = time.perf_counter()
        result = fn()
        best = min(best, time.perf_counter() - start)
    return best, result


def measure(angles_dir: Path | None = None, repeats: int = 3) -> dict:
    """Best-of-``repeats`` wall time (s) of one per-trial fit (demo_p20) and one joint fit of each variant.

    ``angles_dir``: a built project's ``results/angles`` (default the repository's, when built);
    records missing there are model-generated. Also the friction variant on a 20 s, 60 fps record.
    """
    angles_dir = ROOT / "results" / "angles" if angles_dir is None else Path(angles_dir)
    settings = FitSettings()
    model = PendulumModel(Rig(**RIG), VARIANTS["friction"])
    records, sources = [], set()
    for name, release in RELEASES.items():
        path = angles_dir / f"{name}.csv"
        if path.is_file():
            table, source = pd.read_csv(path), "demo video"
        else:
            table = synthetic_angle_table(model, TRUTH, release, rng=np.random.default_rng(1))
            source = "model-generated"
        records.append(load_record(table, name, RIG, settings))
        sources.add(source)
    out = {"source": " and ".join(sorted(sources)), "samples": [r.n_samples for r in records]}
    out["per_trial_s"], out["joint_s"] = {}, {}
    for variant, terms in VARIANTS.items():
        out["per_trial_s"][variant], _ = timed(lambda terms=terms: fit_trials([records[1]], terms, settings), repeats)
        out["joint_s"][variant], _ = timed(lambda terms=terms: fit_trials(records, terms, settings), repeats=1)
    long = synthetic_angle_table(model, TRUTH, 20, fps=60, duration_s=20, rng=np.random.default_rng(2))
    record = load_record(long, "p20_60fps", RIG, settings)
    out["long_record_s"], fit = timed(lambda: fit_trials([record], VARIANTS["friction"], settings), repeats)
    out["long_record_samples"] = record.n_samples
    out["long_record_evaluations"] = fit["optimiser"]["evaluations"]
    return out


def measure_budget(angles_dir: Path | None = None) -> dict:
    """One per-trial (demo_p20) and one joint fit of 5 trials as the workflow fits: rig tolerances stated,
    so every rig value is refitted for the systematic error budget. {variant: (per-trial s, joint s, inputs)}."""
    angles_dir = ROOT / "results" / "angles" if angles_dir is None else Path(angles_dir)
    settings = FitSettings()
    model = PendulumModel(Rig(**RIG), VARIANTS["friction"])
    tables = []
    for name, release in RELEASES.items():
        path = angles_dir / f"{name}.csv"
        tables.append(
            pd.read_csv(path)
            if path.is_file()
            else synthetic_angle_table(model, TRUTH, release, rng=np.random.default_rng(1))
        )
    stated = [load_record(t, name, RIG, settings, tolerances={}) for name, t in zip(RELEASES, tables, strict=True)]
    out = {}
    for variant in ("quadratic", "friction"):
        terms = VARIANTS[variant]
        seconds, fit = timed(lambda terms=terms: fit_trials([stated[1]], terms, settings), repeats=1)
        joint, _ = timed(lambda terms=terms: fit_trials(stated, terms, settings), repeats=1)
        out[variant] = (seconds, joint, len(fit["parameters"]["added_mass_kg"]["error_budget"]))
    return out


def main():
    figures = measure()
    print(f"demo records ({figures['source']}): {figures['samples']} samples")
    for variant in VARIANTS:
        print(
            f"{variant:>10}: per-trial fit (demo_p20) {figures['per_trial_s'][variant]:6.3f} s   "
            f"joint fit of 5 trials {figures['joint_s'][variant]:6.3f} s"
        )
    print(
        f"friction per-trial fit, 20 s at 60 fps ({figures['long_record_samples']} samples): "
        f"{figures['long_record_s']:.3f} s ({figures['long_record_evaluations']} evaluations); target < 2 s"
    )
    for variant, (seconds, joint, inputs) in measure_budget().items():
        print(
            f"{variant:>10} with the systematic budget ({inputs} inputs refitted): per-trial {seconds:6.3f} s   "
            f"joint of 5 trials {joint:6.3f} s"
        )


if __name__ == "__main__":
    main()
