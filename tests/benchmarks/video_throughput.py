"""Benchmark: decode-only vs frames+tracks+angles throughput on one 1920×1080, 60 fps H.264 video.

    .venv/bin/python tests/benchmarks/video_throughput.py [--seconds 10] [--repeats 3]

Renders the video once (synthetic, known truth), then alternates the two
measurements on the same file and prints frames/s for each and their ratio,
plus the tracking error against the truth.
"""

import argparse
import inspect
import sys
import tempfile
import time
from dataclasses import replace
from pathlib import Path

import numpy as np
import pandas as pd

ROOT = Path(__file__).resolve().parents[2]
sys.path.insert(0, str(ROOT / "workflow"))

from pendulum.angles.geometry import estimate_rig_geometry  # noqa: E402
from pendulum.angles.record import angles_from_track  # noqa: E402
from pendulum.camera.video import contact_sheet, frame_timeline, iter_luma  # noqa: E402
from pendulum.synthetic.experiment import generate_trial, load_specs  # noqa: E402
from pendulum.tracking.marker import track_video  # noqa: E402
from pendulum.tracking.settings import TrackerSettings  # noqa: E402

try:  # what the tracks job calls (older code: the marker tracker alone)
    from pendulum.tracking.method import track_trial as _track  # noqa: E402
except ImportError:
    _track = track_video
try:  # frames spread over a clip, held between searches of one clip
    from pendulum.tracking import samples as _samples  # noqa: E402
except ImportError:
    _samples = None


def decode_only(path):
    n = 0
    for _ in iter_luma(path):
        n += 1
    return n


def pipeline(path, settings):
    """What the frames, tracks and angles jobs do with one video, one after the other, each in a new process:
    nothing held from an earlier run (the spread frames that detection and the body's scene share are let go
    first; until 2026-11-29 a repeated run found them held from the run before and skipped their decode)."""
    if _samples is not None:
        _samples.release()
    _, timeline = frame_timeline(path)
    if "timeline" in inspect.signature(contact_sheet).parameters:  # as the frames job calls it
        contact_sheet(path, timeline=timeline)
    else:
        contact_sheet(path)
    track = _track(path, settings)
    geometry = estimate_rig_geometry({"bench": track}, vertical_deg=0.0)
    angles_from_track(track, pivot_px=geometry["pivot_px"], vertical_deg=0.0, length_m=0.76, source="bench")
    return len(track), track


def bench_spec(seconds: float = 10.0, crf: int = 17):
    """The benchmark clip: the demo's 20° trial filmed at 1920×1080, 60 fps (x264 ``crf``)."""
    base = {s.name: s for s in load_specs(ROOT / "data/synthetic/demo.yaml")}["demo_p20"]
    camera = replace(
        base.camera,
        width_px=1920,
        height_px=1080,
        fps=60.0,
        pivot_px=(960.4, 100.3),
        marker_arm_px=840.0,
        marker_radius_px=12.0,
        exposure_subsamples=4,
        crf=crf,
    )
    return replace(base, name="bench_1080p60", duration_s=seconds, camera=camera)


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--seconds", type=float, default=10.0)
    parser.add_argument("--repeats", type=int, default=3)
    parser.add_argument(
        "--crf", type=int, default=17, help="x264 quality; 17 gives ~21 Mb/s on this noisy scene, as a phone records"
    )
    args = parser.parse_args()
    spec = bench_spec(args.seconds, args.crf)
    with tempfile.TemporaryDirectory() as tmp:
        t0 = time.perf_counter()
        video = generate_trial(spec, Path(tmp), Path(tmp), progress=None)
        size = video.stat().st_size
        print(
            f"rendered {video.name}: {size / 1e6:.1f} MB ({size * 8 / args.seconds / 1e6:.1f} Mb/s)"
            f" in {time.perf_counter() - t0:.0f} s"
        )
        settings = TrackerSettings(marker_radius_px=12.0)
        decode_rates, pipe_rates = [], []
        for _ in range(args.repeats):
            t0 = time.perf_counter()
            n = decode_only(video)
            decode_rates.append(n / (time.perf_counter() - t0))
            t0 = time.perf_counter()
            n, track = pipeline(video, settings)
            pipe_rates.append(n / (time.perf_counter() - t0))
        truth = pd.read_csv(Path(tmp) / "bench_1080p60.csv")
        ok = track.flag == "ok"
        err = np.hypot(track.x_px - truth.marker_x_px, track.y_px - truth.marker_y_px)[ok]
    dec, pipe = np.median(decode_rates), np.median(pipe_rates)
    print(f"frames: {n} at 1920x1080, 60 fps, H.264")
    print(f"decode only:              {dec:7.1f} frames/s  (runs: {', '.join(f'{r:.0f}' for r in decode_rates)})")
    print(f"frames+tracks+angles:     {pipe:7.1f} frames/s  (runs: {', '.join(f'{r:.0f}' for r in pipe_rates)})")
    print(f"ratio pipeline/decode:    {pipe / dec:7.2f}")
    print(f"tracking RMS error:       {np.sqrt(np.mean(err**2)):7.3f} px over {ok.sum()} ok frames")


if __name__ == "__main__":
    main()
