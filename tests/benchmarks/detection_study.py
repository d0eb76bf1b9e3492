"""Study: marker detection and hands-free tracking on many random scenes with real footage's faults.

    nice -n 10 .venv/bin/python tests/benchmarks/detection_study.py [--n 40] [--seed 1000] [--only SEED ...]
        [--duration 10] [--margin 8] [--workdir DIR] [--csv PATH]

Scene ``s`` (seeds ``seed … seed + n − 1``) is drawn by :func:`random_scene` from ``s`` alone, so
``--only s`` renders and judges exactly that scene again. Every scene has all the faults at once:
polarity bright or dark, marker radius uniform 5–20 px, release ±(5–30)°, 640×360 or 960×540,
30 or 60 fps, a rig of ``tracking_accuracy`` (small, short or long), camera roll ±1°, background
stripes (random width, period, offset and grey; vertical, horizontal or slanted), a second disk
(back and forth on a line, or rising bubbles) of the marker's grey on a path inside the picture, and
letterbox or pillarbox borders; the marker's swing stays inside the picture, its edge ``MARGIN_PX`` = 8 px
from the borders (the tracker's ring around it must fit). Renders are cached in
``--workdir`` (by spec hash, as ``tracking_accuracy`` does).

Per scene, with config.yaml's tracking values (polarity auto, marker_radius_px null: no hints):

* ``det``: detection found the marker (``detect_marker`` raised nothing and its start is within
  1 px of the truth); otherwise the error is printed below the table;
* ``r_true``/``r_det``: marker radius rendered and found (px); ``start``: error of the detected
  centre in frame 0 (px);
* ``span_r``: the marker's path over the clip's second half, in marker radii (≲ 2: the marker sits in
  the median background that detection subtracts); ``near%``: frames after the release with the second
  disk within reach of the tracker's window (:func:`second_object_near`);
* ``ok%``: frames after the true release flagged ``ok``; ``ok_clear%``: the same over the frames without
  the second disk near; ``mk_px``: RMS of the tracked centre against the truth (exposure mean), ok frames;
* ``rms``/``max``: angle error (degrees) of the angle record (``angles_from_track`` with the true pivot
  and vertical: the tracking's own error) against the true θ at the frame time, over its ``ok``
  samples; ``rms_fp``: the same with the pivot fitted to this track alone (``estimate_rig_geometry``);
* ``pass``: found, ``ok%`` ≥ 95 and ``rms`` ≤ 0.05° (issue 12's acceptance figures).

The summary gives the passes of n with a one-sided 95 % Clopper–Pearson bound on the per-scene failure
rate, the worst figures, and for each failure its seed, the command that reproduces it and its spec.
"""

from __future__ import annotations

import argparse
import math
import sys
import tempfile
import textwrap
import time
from pathlib import Path

import numpy as np
import pandas as pd
import yaml
from scipy.stats import beta

ROOT = Path(__file__).resolve().parents[2]
sys.path.insert(0, str(ROOT / "workflow"))
sys.path.insert(0, str(Path(__file__).resolve().parent))

from tracking_accuracy import (  # noqa: E402
    EFFECTS,
    RIG_LONG,
    RIG_SHORT,
    RIG_SMALL,
    TRUTH_LONG,
    TRUTH_SHORT,
    TRUTH_SMALL,
    render_cached,
)

from pendulum.angles.geometry import estimate_rig_geometry  # noqa: E402
from pendulum.angles.record import InputError, angles_from_track  # noqa: E402
from pendulum.camera.video import VideoError  # noqa: E402
from pendulum.synthetic.experiment import release_time_s, truth_record  # noqa: E402
from pendulum.synthetic.specs import TrialSpec  # noqa: E402
from pendulum.tracking.detection import DetectionError, detect_marker  # noqa: E402
from pendulum.tracking.marker import track_video  # noqa: E402
from pendulum.tracking.settings import TrackerSettings  # noqa: E402

RIGS = {"small": (RIG_SMALL, TRUTH_SMALL), "short": (RIG_SHORT, TRUTH_SHORT), "long": (RIG_LONG, TRUTH_LONG)}
# The marker's edge stays this far inside the picture over the whole swing: the tracker measures a ring
# reaching r + 6.5 px from the centre and flags a frame "edge" when it crosses a border (centroids.py).
MARGIN_PX = 8.0
MIN_USABLE = 0.95  # acceptance: share of frames after the release flagged ok
MAX_ANGLE_RMS_DEG = 0.05  # acceptance: angle RMS against the truth
MAX_START_ERROR_PX = 1.0  # detection's start this close to the truth: it found the marker, not another object


def random_scene(seed: int, duration_s: float = 10.0, margin_px: float = MARGIN_PX) -> TrialSpec:
    """One random scene with every fault (see the module docstring), drawn from ``seed`` alone; the marker's
    edge stays ``margin_px`` inside the picture."""
    rng = np.random.default_rng(seed)
    polarity = str(rng.choice(["bright", "dark"]))
    width, height = ((640, 360), (960, 540))[int(rng.integers(2))]
    fps = (30.0, 60.0)[int(rng.integers(2))]
    radius = float(rng.uniform(5.0, 20.0))
    release_deg = float(rng.choice([-1.0, 1.0]) * rng.uniform(5.0, 30.0))
    rig_name = str(rng.choice(sorted(RIGS)))
    roll_deg = float(rng.uniform(-1.0, 1.0))
    # Borders: letterbox (top/bottom) or pillarbox (left/right), each side its own width.
    if rng.random() < 0.5:
        borders = {"top_px": int(rng.integers(8, height // 8)), "bottom_px": int(rng.integers(8, height // 8))}
    else:
        borders = {"left_px": int(rng.integers(10, width // 6)), "right_px": int(rng.integers(10, width // 6))}
    x0, y0 = borders.get("left_px", 0), borders.get("top_px", 0)
    x1, y1 = width - borders.get("right_px", 0), height - borders.get("bottom_px", 0)
    # Pivot at or above the picture's top, near the middle; the longest arm that keeps the marker inside.
    pivot = (float(rng.uniform(x0 + 0.4 * (x1 - x0), x0 + 0.6 * (x1 - x0))), float(rng.uniform(y0 - 0.1 * height, y0)))
    keep = radius + margin_px
    reach = math.sin(math.radians(abs(release_deg) + abs(roll_deg)))
    arm_max = min(y1 - keep - pivot[1], (pivot[0] - x0 - keep) / reach, (x1 - pivot[0] - keep) / reach)
    arm = float(rng.uniform(0.6, 1.0) * arm_max)
    # Stripes: vertical (half), horizontal or slanted; a grey between the scene's and away from the marker's.
    stripe_width = float(rng.uniform(4.0, 30.0))
    period = stripe_width + float(rng.uniform(12.0, 90.0))
    kind = rng.random()
    angle = 0.0 if kind < 0.5 else 90.0 if kind < 0.65 else float(rng.choice([-1, 1]) * rng.uniform(10.0, 60.0))
    level = float(rng.uniform(70.0, 200.0) if polarity == "dark" else rng.uniform(30.0, 175.0))
    stripes = {
        "width_px": stripe_width,
        "period_px": period,
        "offset_px": float(rng.uniform(0, period)),
        "level": level,
        "angle_deg": angle,
    }
    # Second object: the marker's grey; its size the marker's or 0.6–1.5 times; path inside the picture.
    second_radius = None if rng.random() < 0.5 else float(np.clip(radius * rng.uniform(0.6, 1.5), 4.0, 24.0))
    r2 = radius if second_radius is None else second_radius
    if rng.random() < 0.5:
        pad = r2 + margin_px
        while True:
            start = (float(rng.uniform(x0 + pad, x1 - pad)), float(rng.uniform(y0 + pad, y1 - pad)))
            end = (float(rng.uniform(x0 + pad, x1 - pad)), float(rng.uniform(y0 + pad, y1 - pad)))
            if math.dist(start, end) >= 6 * r2:
                break
        second = {"path": "linear", "start_px": start, "end_px": end, "period_s": float(rng.uniform(1.5, 4.0))}
    else:
        wobble = float(rng.uniform(0.0, 8.0))
        pad = r2 + wobble + margin_px
        start = (float(rng.uniform(x0 + pad, x1 - pad)), float(y1 - pad - rng.uniform(0, 0.2 * (y1 - y0))))
        end_x = float(np.clip(start[0] + rng.uniform(-0.2, 0.2) * (x1 - x0), x0 + pad, x1 - pad))
        end = (end_x, float(y0 + pad + rng.uniform(0, 0.2 * (y1 - y0))))
        second = {
            "path": "bubble",
            "start_px": start,
            "end_px": end,
            "period_s": float(rng.uniform(1.5, 4.0)),
            "wobble_px": wobble,
            "wobble_period_s": float(rng.uniform(0.3, 0.8)),
        }
    second["radius_px"] = second_radius
    rig, truth = RIGS[rig_name]
    return TrialSpec.from_mapping(
        {
            "name": f"scene{seed}_{rig_name}",
            "release_deg": round(release_deg, 3),
            "rig": dict(rig),
            "truth": dict(truth),
            "effects": list(EFFECTS),
            "seed": seed,
            "hold_s": 1.0,
            "duration_s": duration_s,
            "camera": {
                "width_px": width,
                "height_px": height,
                "fps": fps,
                "pivot_px": pivot,
                "marker_arm_px": arm,
                "marker_radius_px": radius,
                "polarity": polarity,
                "roll_deg": roll_deg,
            },
            "faults": {"stripes": stripes, "letterbox": borders, "second_object": second},
        }
    )


def config_tracking() -> TrackerSettings:
    """The tracking settings of config.yaml (polarity auto, marker_radius_px null: found by detection)."""
    values = yaml.safe_load((ROOT / "config.yaml").read_text())["tracking"]
    return TrackerSettings(**values)


def describe(spec: TrialSpec) -> dict:
    """The scene's drawn values, one table row's worth."""
    cam, faults = spec.camera, spec.faults
    box = faults.letterbox
    return {
        "seed": spec.seed,
        "pol": cam.polarity[0],
        "size": f"{cam.width_px}x{cam.height_px}",
        "fps": int(cam.fps),
        "rig": spec.name.rsplit("_", 1)[1],
        "rel": spec.release_deg,
        "arm": cam.marker_arm_px,
        "border": "letter" if box.top_px else "pillar",
        "stripe": f"{faults.stripes.width_px:.0f}/{faults.stripes.period_px:.0f}@{faults.stripes.angle_deg:.0f}",
        "second": faults.second_object.path,
        "r_true": cam.marker_radius_px,
    }


def second_object_near(spec: TrialSpec, truth: pd.DataFrame) -> np.ndarray:
    """Per frame: the second disk reaches into the tracker's window, |c₂ − c| < r + r₂ + 6.5 px + streak/2
    (the ring around the marker reaches r + 6.5 px, stretched along the streak); NaN (a bubble wrapping) counts."""
    r = spec.camera.marker_radius_px
    r2 = spec.faults.second_object.radius_px or r
    d = np.hypot(truth.second_x_px - truth.marker_x_px, truth.second_y_px - truth.marker_y_px).to_numpy()
    return ~(d >= r + r2 + 6.5 + 0.5 * truth.streak_px.to_numpy())


def swing_span_radii(spec: TrialSpec, truth: pd.DataFrame) -> float:
    """Extent of the marker's path over the clip's second half, in marker radii (small: the marker sits in
    most frames' median, the background that detection subtracts)."""
    late = truth[truth.time_s >= 0.5 * spec.duration_s]
    extent = math.hypot(np.ptp(late.marker_x_px), np.ptp(late.marker_y_px))
    return extent / spec.camera.marker_radius_px


def evaluate_scene(spec: TrialSpec, folder: Path, settings: TrackerSettings | None = None) -> dict:
    """Detect and track the rendered scene in ``folder`` with no hints; its errors against the truth."""
    settings = config_tracking() if settings is None else settings
    video = folder / f"{spec.name}.mp4"
    truth = pd.read_csv(folder / f"{spec.name}.csv").set_index("frame")
    row = {**describe(spec), "span_r": swing_span_radii(spec, truth), "det": False, "passed": False, "error": ""}
    released = truth.time_s >= release_time_s(spec)
    near = pd.Series(second_object_near(spec, truth), index=truth.index)
    row["near%"] = 100.0 * near[released].mean()
    started = time.perf_counter()
    try:
        found = detect_marker(video)
    except DetectionError as exc:
        row["error"] = f"detection: {exc}"
        return row
    row["det_s"] = time.perf_counter() - started
    row["r_det"] = found.marker_radius_px
    start = (truth.marker_x_px.loc[0], truth.marker_y_px.loc[0])
    row["start"] = math.nan if found.start_px is None else math.dist(found.start_px, start)
    row["det"] = bool(row["start"] <= MAX_START_ERROR_PX)
    if not row["det"]:
        what = "found no start (not seen in the first frame)" if found.start_px is None else "took another object"
        row["error"] = f"detection {what}: {found.summary()}"
    started = time.perf_counter()
    try:
        track = track_video(video, settings, detection=found)
    except VideoError as exc:
        row["error"] = "; ".join(filter(None, (row["error"], f"tracking: {exc}")))
        return row
    row["track_s"] = time.perf_counter() - started
    after = released.loc[track.frame].to_numpy()
    ok = (track.flag == "ok").to_numpy()
    row["ok%"] = 100.0 * ok[after].mean()
    clear = after & ~near.loc[track.frame].to_numpy()
    row["ok_clear%"] = 100.0 * ok[clear].mean() if clear.any() else math.nan
    row["not_ok"] = " ".join(f"{k}:{v}" for k, v in sorted(track.flag[after & ~ok].value_counts().items()))
    used = after & ok
    true_xy = truth.loc[track.frame[used], ["marker_x_px", "marker_y_px"]].to_numpy()
    dxy = track.loc[used, ["x_px", "y_px"]].to_numpy() - true_xy
    row["mk_px"] = float(np.sqrt(np.mean(np.sum(dxy**2, axis=1))))
    cam = spec.camera
    pivots = {"rms": cam.pivot_px}
    pivots["rms_fp"] = estimate_rig_geometry({spec.name: track}, vertical_deg=cam.roll_deg)["pivot_px"]
    for key, pivot in pivots.items():
        try:
            table, _ = angles_from_track(
                track, pivot_px=pivot, vertical_deg=cam.roll_deg, length_m=spec.rig["length_m"], source=spec.name
            )
        except InputError as exc:
            row["error"] = "; ".join(filter(None, (row["error"], f"angles ({key}): {exc}")))
            return row
        good = (table.flag == "ok").to_numpy()
        err = np.degrees(table.theta_rad.to_numpy()[good] - truth.theta_rad.loc[table.frame[good]].to_numpy())
        row[key] = float(np.sqrt(np.mean(err**2)))
        if key == "rms":
            row["max"] = float(np.max(np.abs(err)))
    row["passed"] = bool(row["det"] and row["ok%"] >= 100 * MIN_USABLE and row["rms"] <= MAX_ANGLE_RMS_DEG)
    if row["det"] and not row["passed"]:
        row["error"] = f"acceptance: ok {row['ok%']:.1f} % ({row['not_ok']}), angle RMS {row['rms']:.4f}°"
    return row


def run_scene(seed: int, workdir: Path, duration_s: float = 10.0, margin_px: float = MARGIN_PX) -> dict:
    """Render (cached) and judge scene ``seed``; the row has the render time too."""
    spec = random_scene(seed, duration_s, margin_px)
    started = time.perf_counter()
    folder = render_cached(spec, workdir)
    render_s = time.perf_counter() - started
    return {**evaluate_scene(spec, folder), "render_s": render_s}


FORMATS = {
    "rel": "{:+.1f}".format,
    "arm": "{:.0f}".format,
    "r_true": "{:.2f}".format,
    "r_det": "{:.2f}".format,
    "start": "{:.3f}".format,
    "span_r": "{:.1f}".format,
    "near%": "{:.1f}".format,
    "ok%": "{:.1f}".format,
    "ok_clear%": "{:.1f}".format,
    "mk_px": "{:.3f}".format,
    "rms": "{:.4f}".format,
    "max": "{:.4f}".format,
    "rms_fp": "{:.4f}".format,
    "render_s": "{:.0f}".format,
    "det_s": "{:.1f}".format,
    "track_s": "{:.1f}".format,
}


def report(table: pd.DataFrame, duration_s: float, margin_px: float = MARGIN_PX) -> None:
    columns = [c for c in (*describe(random_scene(0)).keys(), "det", *FORMATS, "passed") if c in table]
    columns = list(dict.fromkeys(columns))
    with pd.option_context("display.width", 250, "display.max_columns", 40):
        print(table[columns].to_string(index=False, na_rep="-", formatters=FORMATS))
    n, passes = len(table), int(table.passed.sum())
    failures = n - passes
    bound = float(beta.ppf(0.95, failures + 1, n - failures)) if failures < n else 1.0
    print(
        f"\n{passes} of {n} scenes pass (found, ok ≥ {100 * MIN_USABLE:.0f} % after release, angle RMS ≤ "
        f"{MAX_ANGLE_RMS_DEG}°); detection found the marker in {int(table.det.sum())} of {n}; per-scene failure "
        f"rate ≤ {100 * bound:.1f} % at 95 % confidence (one-sided Clopper–Pearson, {failures} of {n})"
    )
    found = table[table.det].dropna(subset=["rms"]) if "rms" in table else table.iloc[:0]
    if len(found):

        def worst(column, unit, largest=True):
            i = found[column].idxmax() if largest else found[column].idxmin()
            return f"{found[column][i]:.4g}{unit} (seed {int(found.seed[i])})"

        print(
            f"where detection found the marker and tracking gave a record ({len(found)} scenes): angle RMS worst "
            f"{worst('rms', '°')}, median {found.rms.median():.4f}°; with a pivot fitted to the one track worst "
            f"{worst('rms_fp', '°')}; ok share worst {worst('ok%', ' %', False)}, median {found['ok%'].median():.1f} %;"
            f" ok share away from the second object worst {worst('ok_clear%', ' %', False)}; marker RMS worst "
            f"{worst('mk_px', ' px')}; start error worst {worst('start', ' px')}; |radius found − true| worst "
            f"{(found.r_det - found.r_true).abs().max():.2f} px"
        )
    print(
        f"times per scene ({duration_s:g} s clips): render {table.render_s.mean():.0f} s (0 when cached), detection "
        f"{table.det_s.mean():.1f} s, tracking {table.get('track_s', pd.Series(dtype=float)).mean():.1f} s (means)"
    )
    for _, row in table[~table.passed].iterrows():
        spec = random_scene(int(row.seed), duration_s, margin_px)
        record = truth_record(spec)
        faults = {k: v for k, v in record["faults"].items() if k in ("stripes", "letterbox", "second_object")}
        camera = {k: v for k, v in record["camera"].items() if k not in ("crf", "preset", "noise_sigma")}
        print(f"\nFAILED seed {int(row.seed)}: {row.error}")
        options = f"--duration {duration_s:g} --margin {margin_px:g} --only {int(row.seed)}"
        print(f"  reproduce: nice -n 10 .venv/bin/python tests/benchmarks/detection_study.py {options}")
        spec_text = {"release_deg": record["release_deg"], "rig": spec.name.rsplit("_", 1)[1], "camera": camera}
        text = yaml.safe_dump({**spec_text, "faults": faults}, width=250, default_flow_style=None, sort_keys=False)
        print("  spec:\n" + textwrap.indent(text, "    "), end="")


def main(argv=None) -> pd.DataFrame:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--n", type=int, default=40, help="number of scenes")
    parser.add_argument("--seed", type=int, default=1000, help="seed of the first scene")
    parser.add_argument("--only", type=int, nargs="*", help="just these scene seeds")
    parser.add_argument("--duration", type=float, default=10.0, help="clip length, s")
    parser.add_argument("--margin", type=float, default=MARGIN_PX, help="marker edge to picture edge, px")
    parser.add_argument("--workdir", type=Path, default=Path(tempfile.gettempdir()) / "pendulum_detection_study")
    parser.add_argument("--csv", type=Path, help="also write the table here")
    args = parser.parse_args(argv)
    args.workdir.mkdir(parents=True, exist_ok=True)
    seeds = args.only or list(range(args.seed, args.seed + args.n))
    rows = []
    for seed in seeds:
        row = run_scene(seed, args.workdir, args.duration, args.margin)
        rows.append(row)
        status = "pass" if row["passed"] else f"FAIL: {row['error'][:200]}"
        print(
            f"  seed {seed}: render {row['render_s']:.0f} s, ok {row.get('ok%', math.nan):.1f} %, "
            f"angle RMS {row.get('rms', math.nan):.4f}°: {status}",
            file=sys.stderr,
            flush=True,
        )
    table = pd.DataFrame(rows)
    report(table, args.duration, args.margin)
    if args.csv:
        table.to_csv(args.csv, index=False)
    return table


if __name__ == "__main__":
    main()
