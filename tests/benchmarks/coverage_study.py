"""Coverage of the fitted coefficients' 95 % intervals on rendered video (issue 8, item 4).

Run: .venv/bin/python tests/benchmarks/coverage_study.py [--workdir /tmp/coverage_study] [--out note.md]

24 synthetic trials are rendered (cached in --workdir; a rerun only re-tracks when
the tracker's modules changed, and always refits), in 6 groups of 4 trials. A group is one
camera set-up on one rig: the paper's Table 1 rig (as data/synthetic/demo.yaml) or a
second rig (heavier, shorter, larger body with a given inertia, seen by a camera placed
differently, smaller marker). Groups alternate rig, marker polarity (bright marker on a
dark scene / dark marker on a light body) and frame rate (30/60 fps); releases span
5–60° with both signs. The true physics has quadratic drag, linear damping and
Coulomb friction; every trial is fitted with the `friction` variant, per trial and
jointly per group, as the workflow does: the pivot is the circle fitted to the group's
pooled marker paths (estimate_rig_geometry), the vertical is given (the camera roll).

Rig values given to the fitter: per group, stated = truth + N(0, tolerance), drawn once
(the same for all the group's trials, as a lab measures its rig once), with the
tolerances passed on, so the systematic part of the interval is tested for real. A
second table uses the exact rig values with zero tolerances (statistical and pivot part
only); a third (diagnostic) adds the true pivot, leaving the tracking error alone.

Coverage = fraction of fits whose combined ci95 contains the truth. A coefficient at its
lower bound has a one-sided interval [bound, hi]: it counts as covering when the truth is
inside it. Not-identifiable estimates (stderr > 50 % of the value) are counted normally
and reported. Target: ≥ 90 % for every parameter.
"""

from __future__ import annotations

import argparse
import hashlib
import json
import math
import os
import subprocess
import sys
import time
from concurrent.futures import ProcessPoolExecutor
from dataclasses import asdict
from pathlib import Path

import numpy as np
import pandas as pd
import yaml
from scipy import stats

ROOT = Path(__file__).resolve().parents[2]
sys.path.insert(0, str(ROOT / "workflow"))
sys.path.insert(0, str(ROOT / "tests"))

from paper_rig import PAPER_RIG, TRUTH  # noqa: E402
from pendulum.synthetic.experiment import generate_trial, truth_record  # noqa: E402
from pendulum.synthetic.specs import Camera, TrialSpec  # noqa: E402

FRICTION = ("quadratic_drag", "linear_damping", "coulomb_friction")
PARAMETERS = ("added_mass_kg", "drag_area_m2", "drag_coefficient", "linear_damping_nm_s", "friction_torque_nm")
STARTED = time.perf_counter()

# The two rigs: measured values (truth), their stated 1σ tolerances, the true hydrodynamics.
RIGS = {
    "paper": {
        "values": dict(PAPER_RIG),
        # as config.yaml's paper_rig; density takes the default fraction, gravity 0
        "tolerances": {"mass_kg": 0.005, "length_m": 0.001, "frontal_area_m2": 0.0005, "displaced_volume_m3": 2e-5},
        "truth": dict(TRUTH),
        "camera": {"pivot_px": (640.3, 70.6), "marker_arm_px": 560.0, "marker_radius_px": 10.0},
        "duration_s": 18.0,
    },
    "second": {
        "values": {
            "mass_kg": 5.2,
            "length_m": 0.55,
            "frontal_area_m2": 0.045,
            "displaced_volume_m3": 0.0032,
            "fluid_density_kg_m3": 1000.0,
            "gravity_m_s2": 9.81,
            "body_inertia_kg_m2": 1.9,
        },
        "tolerances": {
            "mass_kg": 0.01,
            "length_m": 0.0015,
            "frontal_area_m2": 0.0009,
            "displaced_volume_m3": 3e-5,
            "body_inertia_kg_m2": 0.04,
        },
        "truth": {
            "added_mass_kg": 3.8,
            "drag_area_m2": 0.0405,  # C_d = 0.9
            "linear_damping_nm_s": 0.1,
            "friction_torque_nm": 0.03,
        },
        "camera": {"pivot_px": (597.8, 112.4), "marker_arm_px": 470.0, "marker_radius_px": 8.0},
        "duration_s": 16.0,
    },
}

# Six camera set-ups × four releases; rig, polarity and frame rate alternate.
GROUPS = [
    {"name": "g1", "rig": "paper", "polarity": "bright", "fps": 30.0, "roll_deg": 0.0, "shift_px": (0, 0)},
    {"name": "g2", "rig": "second", "polarity": "dark", "fps": 30.0, "roll_deg": 0.6, "shift_px": (12, -8)},
    {"name": "g3", "rig": "paper", "polarity": "dark", "fps": 60.0, "roll_deg": -0.4, "shift_px": (-25, 14)},
    {"name": "g4", "rig": "second", "polarity": "bright", "fps": 60.0, "roll_deg": 0.0, "shift_px": (30, 5)},
    {"name": "g5", "rig": "paper", "polarity": "bright", "fps": 60.0, "roll_deg": 0.3, "shift_px": (18, 9)},
    {"name": "g6", "rig": "second", "polarity": "dark", "fps": 30.0, "roll_deg": -0.7, "shift_px": (-20, -4)},
]
RELEASES_DEG = [
    (5, -18, 33, -52),
    (-7, 21, -37, 60),
    (9, -14, 28, -47),
    (-6, 24, -40, 55),
    (11, -16, 30, -58),
    (-8, 20, -35, 45),
]
RIG_DRAW_SEED = 20240608


def log(message: str) -> None:
    print(f"[{time.perf_counter() - STARTED:7.1f} s] {message}", file=sys.stderr, flush=True)


# ---------------------------------------------------------------------------
# Trials: specs, rendering (cached) and tracking (cached by tracker source)


def group_specs(group: dict, index: int) -> list[TrialSpec]:
    rig = RIGS[group["rig"]]
    cam = rig["camera"]
    pivot = (cam["pivot_px"][0] + group["shift_px"][0], cam["pivot_px"][1] + group["shift_px"][1])
    camera = Camera(
        fps=group["fps"],
        pivot_px=pivot,
        marker_arm_px=cam["marker_arm_px"],
        marker_radius_px=cam["marker_radius_px"],
        polarity=group["polarity"],
        roll_deg=group["roll_deg"],
    )
    specs = []
    for k, release in enumerate(RELEASES_DEG[index]):
        specs.append(
            TrialSpec(
                name=f"{group['name']}_{'p' if release > 0 else 'm'}{abs(release):02d}",
                release_deg=float(release),
                rig=dict(rig["values"]),
                truth=dict(rig["truth"]),
                effects=list(FRICTION),
                seed=1000 * (index + 1) + 17 * k + (500 if group["rig"] == "second" else 0),
                hold_s=1.0,
                duration_s=rig["duration_s"],
                camera=camera,
            )
        )
    return specs


def _source_hash(*names: str) -> str:
    digest = hashlib.sha256()
    for name in names:
        digest.update((ROOT / "workflow" / "pendulum" / name).read_bytes())
    return digest.hexdigest()[:16]


def build_trial(spec: TrialSpec, workdir: str, rerender: bool) -> dict:
    """Render (unless cached with the same spec) and track (unless cached with the same tracker)."""
    from pendulum.tracking.marker import track_video
    from pendulum.tracking.settings import TrackerSettings

    workdir = Path(workdir)
    videos, truth_dir, tracks = workdir / "videos", workdir / "truth", workdir / "tracks"
    tracks.mkdir(parents=True, exist_ok=True)
    video = videos / f"{spec.name}.mp4"
    truth_yaml = truth_dir / f"{spec.name}.yaml"
    wanted = json.loads(json.dumps(truth_record(spec)))
    cached = truth_yaml.is_file() and video.is_file() and yaml.safe_load(truth_yaml.read_text()) == wanted
    timing = {"name": spec.name}
    if rerender or not cached:
        start = time.perf_counter()
        generate_trial(spec, videos, truth_dir, progress=None)
        timing["render_s"] = time.perf_counter() - start
    settings = TrackerSettings(marker_radius_px=spec.camera.marker_radius_px, polarity=spec.camera.polarity)
    key = {
        "tracker": _source_hash(
            "tracking/marker.py",
            "tracking/settings.py",
            "tracking/acquisition.py",
            "tracking/marker_arc.py",
            "tracking/checks.py",
            "tracking/centroids.py",
            "camera/video.py",
        ),
        "settings": asdict(settings),
        "video": video.stat().st_size,
    }
    key = json.loads(json.dumps(key))
    meta = tracks / f"{spec.name}.json"
    track_csv = tracks / f"{spec.name}.csv"
    if "render_s" in timing or not meta.is_file() or json.loads(meta.read_text()) != key:
        start = time.perf_counter()
        track = track_video(video, settings)
        track.to_csv(track_csv, index=False, float_format="%.6f")
        meta.write_text(json.dumps(key))
        timing["track_s"] = time.perf_counter() - start
    return timing


# ---------------------------------------------------------------------------
# Fits


def draw_stated(group_index: int, rig_name: str) -> tuple[dict, dict]:
    """Stated rig values = truth + N(0, tolerance), one draw per group; and the absolute tolerances."""
    from pendulum.fit.records import rig_tolerances

    rig = RIGS[rig_name]
    tolerances = rig_tolerances(rig["values"], rig["tolerances"])
    rng = np.random.default_rng(RIG_DRAW_SEED + group_index)
    stated = dict(rig["values"])
    for name in sorted(tolerances):
        stated[name] = rig["values"][name] + tolerances[name] * float(rng.standard_normal())
    return stated, tolerances


def fit_group(task: dict) -> dict:
    """Angles, per-trial and joint fits of one group under one configuration (runs in a worker)."""
    from pendulum.angles.geometry import estimate_rig_geometry
    from pendulum.angles.record import angles_from_track
    from pendulum.fit.output_error import fit_joint, fit_trials
    from pendulum.fit.records import FitSettings, load_record

    settings = FitSettings()
    workdir = Path(task["workdir"])
    names = task["trials"]
    tracks = {n: pd.read_csv(workdir / "tracks" / f"{n}.csv") for n in names}
    vertical = None if task["estimate_vertical"] else task["roll_deg"]
    if task["true_pivot"]:
        geometry = {"pivot_px": list(task["pivot_px"]), "pivot_covariance_px2": None, "vertical_deg": task["roll_deg"]}
    else:
        geometry = estimate_rig_geometry(tracks, pivot_px=None, vertical_deg=vertical)
    records, angle_errors = [], {}
    for name in names:
        table, info = angles_from_track(
            tracks[name],
            pivot_px=geometry["pivot_px"],
            vertical_deg=geometry["vertical_deg"],
            length_m=task["rig_values"]["length_m"],
            source=name,
            pivot_covariance_px2=geometry.get("pivot_covariance_px2"),
        )
        truth = pd.read_csv(workdir / "truth" / f"{name}.csv")
        angle_errors[name] = angle_error(table, truth, settings.release_skip_s)
        records.append(
            load_record(
                table, name, task["rig_values"], settings, tolerances=task["tolerances"], angle_info=info.to_dict()
            )
        )
    per_trial = {}
    for record in records:
        per_trial[record.trial] = fit_trials([record], FRICTION, settings)
    joint = fit_joint(records, FRICTION, per_trial, settings)
    slim = {n: _slim(f) for n, f in per_trial.items()}
    return {
        "group": task["group"],
        "per_trial": slim,
        "joint": {**_slim(joint), "consistency": joint["consistency"]["verdict"]},
        "pivot_px": geometry["pivot_px"],
        "pivot_covariance_px2": geometry.get("pivot_covariance_px2"),
        "vertical_deg": geometry["vertical_deg"],
        "angle_errors": angle_errors,
    }


def _slim(fit: dict) -> dict:
    keys = ("value", "stderr", "stderr_statistical", "stderr_systematic", "ci95", "at_bound", "identifiable")
    keys += ("error_budget", "scale_factor")
    return {
        "parameters": {n: {k: e.get(k) for k in keys} for n, e in fit["parameters"].items()},
        "warnings": fit["warnings"],
        "rms_deg": fit["rms_deg"],
    }


def angle_error(table: pd.DataFrame, truth: pd.DataFrame, skip_s: float) -> dict:
    """Tracked θ against the true θ (mid-exposure) on the fitted samples: RMS, slope, offset."""
    merged = table[["frame", "time_s", "theta_rad", "flag"]].merge(
        truth[["frame", "theta_rad"]], on="frame", suffixes=("", "_true")
    )
    merged = merged[(merged.flag == "ok") & (merged.time_s >= skip_s) & np.isfinite(merged.theta_rad)]
    tracked, true = merged.theta_rad.to_numpy(), merged.theta_rad_true.to_numpy()
    slope, offset = np.polyfit(true, tracked, 1)
    err = tracked - true
    resid = tracked - (slope * true + offset)
    return {
        "n": int(err.size),
        "rms_deg": math.degrees(float(np.sqrt(np.mean(err**2)))),
        "rms_after_line_deg": math.degrees(float(np.sqrt(np.mean(resid**2)))),
        "slope_minus_1": float(slope - 1.0),
        "offset_deg": math.degrees(float(offset)),
        "lag1": float(np.corrcoef(resid[1:], resid[:-1])[0, 1]),
    }


# ---------------------------------------------------------------------------
# Scoring and report


def truth_values(rig_name: str) -> dict:
    rig = RIGS[rig_name]
    values = dict(rig["truth"])
    values["drag_coefficient"] = values["drag_area_m2"] / rig["values"]["frontal_area_m2"]
    return values


def score(entry: dict, truth: float) -> dict:
    lo, hi = entry["ci95"]
    error = entry["value"] - truth
    se, se_stat = entry["stderr"], entry.get("stderr_statistical") or entry["stderr"]
    return {
        "covered": bool(lo <= truth <= hi),
        "z": error / se if se else math.inf,
        "z_stat": error / se_stat if se_stat else math.inf,
        "at_bound": bool(entry["at_bound"]),
        "not_identifiable": not entry["identifiable"],
        "relative_error": error / truth,
    }


def clopper_pearson(k: int, n: int) -> tuple[float, float]:
    lo = stats.beta.ppf(0.025, k, n - k + 1) if k > 0 else 0.0
    hi = stats.beta.ppf(0.975, k + 1, n - k) if k < n else 1.0
    return float(lo), float(hi)


def coverage_rows(samples: list[dict]) -> list[str]:
    """One markdown row per parameter from [{'trial', 'param', score...}]."""
    rows = []
    for name in PARAMETERS:
        items = [s for s in samples if s["param"] == name]
        n = len(items)
        k = sum(s["covered"] for s in items)
        lo, hi = clopper_pearson(k, n)
        z = np.median([abs(s["z"]) for s in items])
        zs = np.median([abs(s["z_stat"]) for s in items])
        worst = max(items, key=lambda s: abs(s["z"]))
        bound = sum(s["at_bound"] for s in items)
        unid = sum(s["not_identifiable"] for s in items)
        misses = ", ".join(f"{s['trial']} ({s['z']:+.1f})" for s in items if not s["covered"]) or "–"
        rows.append(
            f"| {name} | {k}/{n} | {100 * k / n:.0f} % | {100 * lo:.0f}–{100 * hi:.0f} % | {z:.2f} | {zs:.2f} "
            f"| {bound} | {unid} | {worst['trial']} {worst['z']:+.1f} | {misses} |"
        )
    return rows


def report_configuration(title: str, results: list[dict], specs: dict) -> tuple[list[str], list[dict]]:
    per_trial, joint = [], []
    for res in results:
        rig = specs[res["group"]]["rig"]
        truth = truth_values(rig)
        for trial, fit in res["per_trial"].items():
            for name in PARAMETERS:
                per_trial.append({"trial": trial, "param": name, **score(fit["parameters"][name], truth[name])})
        for name in PARAMETERS:
            joint.append({"trial": res["group"], "param": name, **score(res["joint"]["parameters"][name], truth[name])})
    header = (
        "| parameter | covered | coverage | 95 % CI (Clopper–Pearson) | median \\|z\\| | median \\|z_stat\\| "
        "| at bound | not identifiable | worst z | misses (z) |"
    )
    rule = "|---|---|---|---|---|---|---|---|---|---|"
    lines = [f"### {title}", "", f"Per-trial fits ({len(results)} groups):", "", header, rule]
    lines += coverage_rows(per_trial)
    lines += ["", "Joint fits (one per group):", "", header, rule]
    lines += coverage_rows(joint)
    verdicts: dict[str, list[str]] = {}
    for r in results:
        verdicts.setdefault(r["group"], []).append(r["joint"]["consistency"])
    verdicts = ", ".join(
        f"{g}: {v[0]}" if len(set(v)) == 1 and len(v) == 1 else f"{g}: " + "/".join(v) for g, v in verdicts.items()
    )
    lines += ["", f"Consistency verdicts: {verdicts}", ""]
    return lines, per_trial


def draw_shift_section(results: dict, stated: dict, groups: list) -> list[str]:
    """Is the rig part of the budget right? Drawn-minus-exact estimate against Σ budget_k × draw_k (in σ_sys)."""
    lines = [
        "### Rig draw: measured shift against the error budget's prediction (joint fits)",
        "",
        "shift = estimate(stated rig) − estimate(exact rig) on the same tracks and pivot; predicted = Σ_k "
        "error_budget_k × (stated_k − truth_k)/σ_k over the rig values; both in units of the joint fit's "
        "stderr_systematic. Agreement means the propagated rig part is right and a miss is the draw's doing.",
        "",
        "| group | " + " | ".join(f"{p} shift / predicted" for p in PARAMETERS) + " |",
        "|---|" + "---|" * len(PARAMETERS),
    ]
    drawn = {r["group"]: r for r in results["drawn"]}
    exact = {r["group"]: r for r in results["exact"]}
    for _, g in groups:
        values, tolerances = stated[g["name"]]
        truth = RIGS[g["rig"]]["values"]
        draw = {k: (values[k] - truth[k]) / tol for k, tol in tolerances.items() if tol}
        cells = []
        for p in PARAMETERS:
            d, e = drawn[g["name"]]["joint"]["parameters"][p], exact[g["name"]]["joint"]["parameters"][p]
            budget = d.get("error_budget") or {}
            predicted = sum(budget.get(k, 0.0) * v for k, v in draw.items())
            sigma = d.get("stderr_systematic") or float("nan")
            cells.append(f"{(d['value'] - e['value']) / sigma:+.2f} / {predicted / sigma:+.2f}")
        lines.append(f"| {g['name']} | " + " | ".join(cells) + " |")
    return lines + [""]


def noise_diagnostics(task: dict) -> dict:
    """Per-trial fits (exact rig, true pivot) of the true θ plus parts of the tracking error, z per parameter.

    truth: no error (the fitter's own bias); locked: the part of the error that is a linear function of
    the motion (1, θ, θ̇, θ̇|θ̇|, sgn θ̇, θ², θ|θ̇|), which repeats with every swing; remainder: the rest;
    gaussian: white + AR(0.8) noise of the same variance and lag-1 correlation (two replicates).
    z: tracked and gaussian use their own stderr; truth, locked and remainder the tracked fit's stderr
    (their own residuals are not the record's noise), so they show which part of the error moves the estimate.
    """
    from pendulum.angles.record import angles_from_track
    from pendulum.fit.output_error import fit_trials
    from pendulum.fit.records import FitSettings, load_record
    from pendulum.synthetic.records import angle_noise_rad

    settings = FitSettings()
    workdir = Path(task["workdir"])
    rig = RIGS[task["rig"]]
    track = pd.read_csv(workdir / "tracks" / f"{task['trial']}.csv")
    table, _ = angles_from_track(
        track, pivot_px=task["pivot_px"], vertical_deg=task["roll_deg"], length_m=1.0, source=task["trial"]
    )
    true = pd.read_csv(workdir / "truth" / f"{task['trial']}.csv").set_index("frame").theta_rad
    true = true.reindex(table.frame).to_numpy()
    t = table.time_s.to_numpy()
    err = table.theta_rad.to_numpy() - true
    ok = (table.flag == "ok").to_numpy() & np.isfinite(err)
    w = np.gradient(true, t)
    wm = np.abs(w).max()
    basis = [np.ones_like(t), true, w / wm, w * np.abs(w) / wm**2, np.tanh(w / (0.05 * wm))]
    basis = np.column_stack(basis + [true**2, true * np.abs(w) / wm])
    fitted = ok & (t >= settings.release_skip_s)
    coef, *_ = np.linalg.lstsq(basis[fitted], err[fitted], rcond=None)
    locked = basis @ coef
    rng = np.random.default_rng(task["seed"])
    e_ok = err[fitted]
    lag1 = float(np.corrcoef(e_ok[1:], e_ok[:-1])[0, 1])
    share = min(max(lag1 / 0.8, 0.0), 1.0)
    sd = math.degrees(float(e_ok.std()))
    variants = {"tracked": true + err, "truth": true, "locked": true + locked, "remainder": true + err - locked}
    for k in range(2):
        noise = angle_noise_rad(rng, t.size, sd * math.sqrt(1 - share), sd * math.sqrt(share), 0.8)
        variants[f"gaussian_{k}"] = true + noise
    out = {"trial": task["trial"], "locked_variance_share": float(np.var(locked[fitted]) / np.var(e_ok))}
    truth = rig["truth"]
    names = [p for p in PARAMETERS if p != "drag_coefficient"]
    reference = None
    for label, theta in variants.items():  # "tracked" first: its stderr scales the parts of its error
        t2 = table.copy()
        t2["theta_rad"] = np.where(ok, theta, np.nan)
        fit = fit_trials([load_record(t2, task["trial"], rig["values"], settings)], FRICTION, settings)
        par = fit["parameters"]
        own = {p: par[p]["stderr"] for p in names}
        reference = reference or own
        scale = own if label == "tracked" or label.startswith("gaussian") else reference
        out[label] = {p: (par[p]["value"] - truth[p]) / scale[p] for p in names}
    return out


def noise_section(items: list[dict]) -> list[str]:
    names = [p for p in PARAMETERS if p != "drag_coefficient"]
    lines = [
        "### Diagnostic: what in the tracking error makes the per-trial intervals short",
        "",
        "Per-trial fits, exact rig, true pivot, of the true θ plus: the whole tracking error (tracked); nothing "
        "(truth: the fitter's own bias, z should be ≈ 0); the part of the error that is a linear function of the "
        "motion (1, θ, θ̇, θ̇|θ̇|, sgn θ̇, θ², θ|θ̇|), i.e. repeats with every swing (locked); the rest "
        "(remainder); Gaussian white + AR(0.8) noise with the error's variance and lag-1 correlation, two "
        "replicates per trial (gaussian). z = (estimate − truth)/stderr, with the fit's own stderr for tracked "
        "and gaussian, with the tracked fit's stderr for truth, locked and remainder (their parts of the same "
        "error). Cells: fraction with |z| < 1.96 / median |z| (0.67 if calibrated).",
        "",
        "| error added | fits | " + " | ".join(names) + " |",
        "|---|---|" + "---|" * len(names),
    ]
    for label in ("tracked", "truth", "locked", "remainder", "gaussian"):
        rows = [it[k] for it in items for k in it if k == label or (label == "gaussian" and k.startswith("gaussian"))]
        cells = []
        for p in names:
            z = np.abs([r[p] for r in rows])
            cells.append(f"{100 * np.mean(z < 1.96):.0f} % / {np.median(z):.2f}")
        lines.append(f"| {label} | {len(rows)} | " + " | ".join(cells) + " |")
    share = np.median([it["locked_variance_share"] for it in items])
    lines += ["", f"Median share of the tracking-error variance in the locked part: {100 * share:.0f} %.", ""]
    return lines


def git_commit() -> str:
    try:
        out = subprocess.run(["git", "-C", str(ROOT), "log", "-1", "--format=%h %s"], capture_output=True, text=True)
        dirty = subprocess.run(
            ["git", "-C", str(ROOT), "status", "--porcelain", "workflow/pendulum"], capture_output=True, text=True
        ).stdout.strip()
        return out.stdout.strip() + (" (workflow/pendulum has uncommitted changes)" if dirty else "")
    except OSError:
        return "unknown"


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--workdir", type=Path, default=Path("/tmp/coverage_study"))
    parser.add_argument("--out", type=Path, help="also write the markdown report here")
    parser.add_argument("--jobs", type=int, default=2, help="worker processes (renders, tracks, fits)")
    parser.add_argument("--groups", nargs="*", help="only these groups (e.g. g1 g2), for a quick look")
    parser.add_argument("--rerender", action="store_true", help="render again even if cached")
    parser.add_argument("--estimate-vertical", action="store_true", help="vertical estimated, not given")
    parser.add_argument("--no-diagnostics", action="store_true", help="skip the diagnostic configurations")
    parser.add_argument(
        "--draws", type=int, default=5, help="independent rig draws per group for the pooled systematic check"
    )
    args = parser.parse_args(argv)
    os.environ.setdefault("OMP_NUM_THREADS", "1")
    os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")

    groups = [(i, g) for i, g in enumerate(GROUPS) if not args.groups or g["name"] in args.groups]
    specs_by_group = {g["name"]: group_specs(g, i) for i, g in groups}
    all_specs = [s for specs in specs_by_group.values() for s in specs]
    log(f"{len(all_specs)} trials in {len(groups)} groups; work directory {args.workdir}")
    build_start = time.perf_counter()
    with ProcessPoolExecutor(max_workers=args.jobs) as pool:
        futures = [pool.submit(build_trial, s, str(args.workdir), args.rerender) for s in all_specs]
        for done, future in enumerate(futures, 1):
            t = future.result()
            what = ", ".join(f"{k[:-2]} {v:.0f} s" for k, v in t.items() if k != "name") or "cached"
            log(f"trial {done}/{len(futures)} {t['name']}: {what}")
    build_s = time.perf_counter() - build_start

    configurations = {
        "drawn": "Rig values stated = truth + N(0, tolerance) (one draw per group), tolerances passed; pivot estimated",
        "exact": "Exact rig values, zero tolerances; pivot estimated",
    }
    if not args.no_diagnostics:
        configurations["true_pivot"] = "Diagnostic: exact rig values, zero tolerances, true pivot (tracking error only)"
    for j in range(1, args.draws):
        configurations[f"drawn_{j}"] = f"rig draw {j}"
    stated = {g["name"]: draw_stated(i, g["rig"]) for i, g in groups}
    extra_draws = {(j, g["name"]): draw_stated(i + 100 * j, g["rig"]) for j in range(1, args.draws) for i, g in groups}
    results = {}
    fit_start = time.perf_counter()
    with ProcessPoolExecutor(max_workers=args.jobs) as pool:
        futures = {}
        for config in configurations:
            for _, g in groups:
                rig = RIGS[g["rig"]]
                if config == "drawn":
                    values, tolerances = stated[g["name"]]
                elif config.startswith("drawn_"):
                    values, tolerances = extra_draws[(int(config.split("_")[1]), g["name"])]
                else:
                    values = dict(rig["values"])
                    tolerances = None  # load_record: the values are exact, no rig budget
                task = {
                    "group": g["name"],
                    "workdir": str(args.workdir),
                    "trials": [s.name for s in specs_by_group[g["name"]]],
                    "rig_values": values,
                    "tolerances": tolerances,
                    "roll_deg": g["roll_deg"],
                    "estimate_vertical": args.estimate_vertical,
                    "true_pivot": config == "true_pivot",
                    "pivot_px": specs_by_group[g["name"]][0].camera.pivot_px,
                }
                futures[(config, g["name"])] = pool.submit(fit_group, task)
        if not args.no_diagnostics:
            for _, g in groups:
                for spec in specs_by_group[g["name"]]:
                    task = {"trial": spec.name, "workdir": str(args.workdir), "rig": g["rig"]}
                    task.update(pivot_px=spec.camera.pivot_px, roll_deg=g["roll_deg"], seed=spec.seed)
                    futures[("noise", spec.name)] = pool.submit(noise_diagnostics, task)
        for (config, name), future in futures.items():
            results.setdefault(config, []).append(future.result())
            log(f"fitted {config} {name}")
    fit_s = time.perf_counter() - fit_start

    group_info = {g["name"]: g for _, g in groups}
    lines = [
        "## Coverage study on rendered video (friction variant)",
        "",
        f"Code: {git_commit()}. {len(all_specs)} trials in {len(groups)} groups (4 trials per camera set-up and rig); "
        "true physics quadratic drag + linear damping + Coulomb friction; fitted with the `friction` variant.",
        f"Vertical: {'estimated' if args.estimate_vertical else 'given (camera roll)'}; pivot: circle fit per group.",
        "",
        "Independence: the per-trial samples are NOT 24 independent draws. The trials of one group share one "
        "rig draw (a common systematic error) and one pivot estimate, so their misses come in clusters; for the "
        "rig-tolerance part there are only as many independent samples as groups. The Clopper–Pearson interval "
        "below assumes independence and is therefore too narrow for the per-trial coverage; the joint coverage "
        "(one per group) is independent but has few samples.",
        "",
        "Counting: covered = truth inside the combined ci95; an at-bound estimate's one-sided interval [bound, hi] "
        "covers when the truth is inside it. z = (estimate − truth)/stderr (combined), z_stat with "
        "stderr_statistical (falls back to stderr when the fit does not report it); a calibrated normal "
        "interval gives median |z| = 0.67. Not-identifiable estimates are scored like the others.",
        "",
    ]
    samples_by_config = {}
    for config, title in configurations.items():
        if config.startswith("drawn_"):
            continue
        order = sorted(results[config], key=lambda r: r["group"])
        section, samples = report_configuration(title, order, group_info)
        lines += section
        samples_by_config[config] = samples

    if args.draws > 1:
        pooled = [r for c in configurations if c.startswith("drawn") for r in results[c]]
        title = (
            f"Rig values drawn {args.draws} times per group (independent draws, same tracks), pooled: "
            f"{len(pooled)} joint fits with independent rig draws"
        )
        section, _ = report_configuration(title, pooled, group_info)
        lines += section[:2] + [f"Per-trial fits ({len(pooled) * 4} fits, 4 per draw share it):"] + section[3:]
    lines += draw_shift_section(results, stated, groups)
    if not args.no_diagnostics:
        lines += noise_section(results["noise"])
    lines += [
        "### Groups",
        "",
        "| group | rig | polarity | fps | roll ° | pivot error px (x, y) | pivot σ px (x, y) | "
        "stated − truth (in σ) | consistency (drawn / exact) |",
        "|---|---|---|---|---|---|---|---|---|",
    ]
    drawn = {r["group"]: r for r in results["drawn"]}
    exact = {r["group"]: r for r in results["exact"]}
    results = {c: r for c, r in results.items() if c != "noise"}
    for _, g in groups:
        res = drawn[g["name"]]
        true_pivot = specs_by_group[g["name"]][0].camera.pivot_px
        err = (res["pivot_px"][0] - true_pivot[0], res["pivot_px"][1] - true_pivot[1])
        cov = res["pivot_covariance_px2"]
        sig = (math.sqrt(cov[0][0]), math.sqrt(cov[1][1])) if cov else (float("nan"),) * 2
        values, tolerances = stated[g["name"]]
        truth = RIGS[g["rig"]]["values"]
        draws = ", ".join(
            f"{k.split('_')[0]} {(values[k] - truth[k]) / tolerances[k]:+.1f}"
            for k in sorted(tolerances)
            if tolerances[k]
        )
        lines.append(
            f"| {g['name']} | {g['rig']} | {g['polarity']} | {g['fps']:.0f} | {g['roll_deg']:+.1f} "
            f"| {err[0]:+.2f}, {err[1]:+.2f} | {sig[0]:.2f}, {sig[1]:.2f} | {draws} "
            f"| {res['joint']['consistency']} / {exact[g['name']]['joint']['consistency']} |"
        )

    lines += [
        "",
        "### Tracked angle against the truth, per trial (estimated pivot)",
        "",
        "RMS of tracked − true θ over the fitted samples, slope of tracked vs true θ (a scale error biases drag "
        "by −(slope−1) and friction by +(slope−1), relatively), offset (absorbed by the fitted rest offset), RMS "
        "after removing the line, lag-1 autocorrelation of that remainder; then z (combined, drawn rig) per "
        "parameter of the per-trial fit (* = outside the ci95).",
        "",
        "| trial | release ° | fps | pol | n | RMS ° | slope−1 (ppm) | offset ° | RMS after line ° | lag-1 "
        "| z m_a | z C_dA | z c | z τ_f |",
        "|---|---|---|---|---|---|---|---|---|---|---|---|---|---|",
    ]
    scores = {(s["trial"], s["param"]): s for s in samples_by_config["drawn"]}
    for _, g in groups:
        res = drawn[g["name"]]
        for spec in specs_by_group[g["name"]]:
            e = res["angle_errors"][spec.name]
            zs = []
            for p in ("added_mass_kg", "drag_area_m2", "linear_damping_nm_s", "friction_torque_nm"):
                s = scores[(spec.name, p)]
                zs.append(f"{s['z']:+.1f}{'' if s['covered'] else '*'}")
            lines.append(
                f"| {spec.name} | {spec.release_deg:+.0f} | {spec.camera.fps:.0f} | {spec.camera.polarity} | {e['n']} "
                f"| {e['rms_deg']:.4f} | {1e6 * e['slope_minus_1']:+.0f} | {e['offset_deg']:+.4f} "
                f"| {e['rms_after_line_deg']:.4f} | {e['lag1']:.2f} | {' | '.join(zs)} |"
            )
    lines += [
        "",
        f"Timing: render+track {build_s:.0f} s (cached trials are skipped), fits {fit_s:.0f} s, "
        f"{args.jobs} worker process(es).",
    ]
    text = "\n".join(lines) + "\n"
    raw = {"commit": git_commit(), "stated": {k: v[0] for k, v in stated.items()}, "results": results}
    (args.workdir / "results.json").write_text(json.dumps(raw, indent=1))
    print(text)
    if args.out:
        args.out.parent.mkdir(parents=True, exist_ok=True)
        args.out.write_text(text)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
