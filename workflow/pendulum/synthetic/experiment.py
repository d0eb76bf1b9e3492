"""Synthetic free-decay experiment: known truth, rendered to a realistic video.

The truth trajectory comes from :func:`pendulum.model.physics.simulate` (the same
equations the fitter uses) with any set of effects of the library
(:data:`pendulum.model.effects.TERMS`, the history force included), including ones a
fitted model lacks, and optionally with effects outside the library
(:class:`pendulum.synthetic.specs.Disturbances`: a periodic disturbance torque, a pivot drifting in the
image; for the video-free angle tables of :mod:`pendulum.synthetic.records` a drifting zero). The
renderer draws a monochrome camera view: a textured, cluttered tank background, the pivot, the rod,
the vehicle and a circular marker dot; the exposure blur is the average of sub-exposure renders;
sensor noise is added before lossy H.264 compression. Real footage's faults
(:class:`pendulum.synthetic.specs.Faults`: background stripes, letterbox borders, a second moving
object, two-tone and shiny bobs, a trimmed clip's discarded packets; a long exposure's streak) are
off by default, so existing renders stay byte-identical; :mod:`pendulum.synthetic.scene` draws them.

Image geometry: x to the right, y down. With the pivot at (x_p, y_p), the
marker at arm radius R and the camera rolled by φ, the marker is at
``x = x_p + R sin(θ + φ)``, ``y = y_p + R cos(θ + φ)`` (θ > 0 swings to +x).
"""

from __future__ import annotations

import argparse
import functools
import math
import sys
from dataclasses import asdict, dataclass, field
from pathlib import Path

import cv2
import numpy as np
import pandas as pd
import yaml

from pendulum.model.physics import PendulumModel, simulate
from pendulum.model.rig import Rig
from pendulum.synthetic.scene import (
    disk_overlap_fraction,
    draw_bob,
    draw_disk,
    letterbox_covered_fraction,
    letterbox_mask,
    occlusion_schedule,
    pendulum_shades,
    sensor_noise,
    stripe_coverage,
)
from pendulum.synthetic.specs import Bob, Camera, TrialSpec


def frame_times_s(spec: TrialSpec) -> np.ndarray:
    """Presentation time of each frame: t_i = i / fps (the exposure is centred on it)."""
    n_frames = int(round(spec.duration_s * spec.camera.fps))
    return np.arange(n_frames) / spec.camera.fps


def release_time_s(spec: TrialSpec) -> float:
    """Release instant; deliberately not on a frame boundary."""
    rng = np.random.default_rng(spec.seed + 7919)
    return spec.hold_s + float(rng.uniform(0.1, 0.9)) / spec.camera.fps


def true_angle_rad(spec: TrialSpec, times_s: np.ndarray) -> np.ndarray:
    """θ(t): held at the release angle, then the free decay of the true physics (plus any disturbance torque)."""
    model = PendulumModel(Rig.from_mapping(spec.rig), tuple(spec.effects))
    t_release = release_time_s(spec)
    theta = np.full(times_s.shape, math.radians(spec.release_deg))
    order = np.argsort(times_s)
    sorted_t = times_s[order]
    after = sorted_t > t_release
    if after.any():
        sample_t, index = np.unique(sorted_t[after], return_inverse=True)
        grid = np.concatenate([[t_release], sample_t])
        torque = spec.disturbances.torque
        if torque is None:
            th, _ = simulate(model, spec.truth, math.radians(spec.release_deg), 0.0, grid, substeps=4)
        else:
            th, _ = simulate(
                model, spec.truth, math.radians(spec.release_deg), 0.0, grid, substeps=4, external_torque_nm=torque
            )
        theta_sorted = theta[order]
        theta_sorted[after] = th[1:][index]
        theta[order] = theta_sorted
    return theta


def marker_position_px(camera: Camera, theta_rad, pivot_px=None) -> tuple[np.ndarray, np.ndarray]:
    """Marker centre for angle θ; ``pivot_px`` (x, y), arrays allowed, overrides the camera's pivot."""
    phi = np.asarray(theta_rad) + math.radians(camera.roll_deg)
    px, py = camera.pivot_px if pivot_px is None else pivot_px
    x = px + camera.marker_arm_px * np.sin(phi)
    y = py + camera.marker_arm_px * np.cos(phi)
    return x, y


def pivot_position_px(spec: TrialSpec, times_s) -> tuple[np.ndarray, np.ndarray]:
    """The rendered pivot at video times ``times_s``: drifting linearly by ``pivot_drift_px`` over the video."""
    t = np.asarray(times_s, float) / spec.duration_s
    (x0, y0), (dx, dy) = spec.camera.pivot_px, spec.disturbances.pivot_drift_px
    return x0 + dx * t, y0 + dy * t


def _smooth_noise(rng, shape, scale_px):
    small = rng.standard_normal((max(2, shape[0] // scale_px + 2), max(2, shape[1] // scale_px + 2)))
    return cv2.resize(small, (shape[1], shape[0]), interpolation=cv2.INTER_CUBIC)


def render_background(camera: Camera, seed: int) -> np.ndarray:
    """Static tank scene: lighting gradient, multi-scale texture and clutter (float32 grey)."""
    rng = np.random.default_rng(seed)
    h, w = camera.height_px, camera.width_px
    yy, xx = np.mgrid[0:h, 0:w].astype(np.float32)
    bright = camera.polarity == "dark"
    base, span = (175.0, 45.0) if bright else (75.0, 40.0)
    img = base + 0.25 * span * ((xx / w) - 0.5) + 0.15 * span * (yy / h - 0.5)
    for scale, amp in ((160, 0.35), (40, 0.25), (8, 0.12)):
        img += amp * span * _smooth_noise(rng, (h, w), scale).astype(np.float32)
    # Clutter: tank frame tubes, tiles, labels, cables.
    for _ in range(int(rng.integers(25, 40))):
        kind = rng.integers(0, 3)
        shade = float(base + span * rng.uniform(-0.9, 0.9))
        p1 = (int(rng.integers(0, w)), int(rng.integers(0, h)))
        if kind == 0:
            p2 = (p1[0] + int(rng.integers(20, 220)), p1[1] + int(rng.integers(10, 120)))
            cv2.rectangle(img, p1, p2, shade, -1, cv2.LINE_AA)
        elif kind == 1:
            p2 = (int(rng.integers(0, w)), int(rng.integers(0, h)))
            cv2.line(img, p1, p2, shade, int(rng.integers(2, 9)), cv2.LINE_AA)
        else:
            axes = (int(rng.integers(15, 90)), int(rng.integers(8, 50)))
            cv2.ellipse(img, p1, axes, float(rng.uniform(0, 180)), 0, 360, shade, -1, cv2.LINE_AA)
    lo, hi = (110.0, 245.0) if bright else (10.0, 150.0)
    return np.clip(img, lo, hi).astype(np.float32)


def _draw_pendulum(canvas, camera: Camera, theta_rad: float, shades: dict, pivot_px=None, bob: Bob | None = None):
    phi = theta_rad + math.radians(camera.roll_deg)
    s, c = math.sin(phi), math.cos(phi)
    px, py = camera.pivot_px if pivot_px is None else pivot_px
    arm = camera.marker_arm_px
    shift = 4
    scale = 1 << shift

    def fixed(x, y):
        return (int(round(x * scale)), int(round(y * scale)))

    body_half_w, body_half_h = 0.17 * arm, 0.09 * arm
    body_centre = (px + arm * s, py + arm * c)
    rod_end = (px + (arm - body_half_h) * s, py + (arm - body_half_h) * c)
    cv2.line(canvas, fixed(px, py), fixed(*rod_end), shades["rod"], 7, cv2.LINE_AA, shift)
    corners = []
    for u, v in ((-1, -1), (1, -1), (1, 1), (-1, 1)):
        lx, ly = u * body_half_w, v * body_half_h  # body frame: x across, y along the rod
        corners.append(fixed(body_centre[0] + lx * c + ly * s, body_centre[1] - lx * s + ly * c))
    cv2.fillConvexPoly(canvas, np.array(corners, np.int32), shades["body"], cv2.LINE_AA, shift)
    cv2.circle(canvas, fixed(px, py), 14 * scale, shades["hub"], -1, cv2.LINE_AA, shift)
    if bob is None or not bob.active:
        draw_disk(canvas, body_centre[0], body_centre[1], camera.marker_radius_px, shades["marker"])
    else:
        draw_bob(canvas, body_centre[0], body_centre[1], camera, bob, phi, shades)


def exposure_subsamples(spec: TrialSpec) -> int:
    """Sub-exposures per frame: ``exposure_subsamples``, raised so no object moves more than ``blur_step_px``
    between two of them (the streak's length over k sub-exposures spaced by exposure/k). A bubble that leaves at
    the path's end while one enters at its start, within one exposure, makes no streak of that length (it raised
    k to 150–230 and a 6 s render from ~1 s to 20–29 s)."""
    cam = spec.camera
    k = cam.exposure_subsamples
    streak = float(np.max(streak_length_px(spec, k), initial=0.0))
    second = spec.faults.second_object
    if second.active:
        times = frame_times_s(spec)
        e = cam.exposure_fraction / cam.fps
        x0, y0 = second.position_px(times - e / 2)
        x1, y1 = second.position_px(times + e / 2)
        moved = np.hypot(x1 - x0, y1 - y0)
        if second.path == "bubble":  # a wrap within the exposure: two bubbles, each moving as fast as ever
            wraps = np.floor((times - e / 2) / second.period_s) != np.floor((times + e / 2) / second.period_s)
            moved = np.where(wraps, 0.0, moved)
        streak = max(streak, float(np.max(moved, initial=0.0)))
    return max(k, int(math.ceil(streak / cam.blur_step_px)))


def streak_length_px(spec: TrialSpec, k: int | None = None) -> np.ndarray:
    """Marker path length during each frame's exposure (px), from ``k`` sub-exposure positions:
    the polyline through them scaled by k/(k − 1) (they span (k − 1)/k of the exposure)."""
    cam = spec.camera
    k = cam.exposure_subsamples if k is None else k
    times = frame_times_s(spec)
    e = cam.exposure_fraction / cam.fps
    sub = times[:, None] + (((np.arange(k) + 0.5) / k - 0.5) * e)[None, :]
    x, y = marker_position_px(cam, true_angle_rad(spec, sub.reshape(-1)).reshape(sub.shape))
    if k < 2:
        return np.zeros(times.size)
    return np.hypot(np.diff(x, axis=1), np.diff(y, axis=1)).sum(axis=1) * k / (k - 1)


@dataclass
class RenderedTrial:
    frames: list  # uint8 grey frames (the shown frames)
    truth: pd.DataFrame  # per-frame truth of the shown frames
    lead_frames: list = field(default_factory=list)  # frames before the first shown one (trimmed clip)


def render_trial(spec: TrialSpec, progress=None) -> RenderedTrial:
    """Render every frame of a trial and return it with its per-frame truth.

    With faults (:class:`pendulum.synthetic.specs.Faults`) the truth gains columns: ``streak_px`` (marker path length
    during the exposure), ``second_x_px``/``second_y_px`` (the second object's exposure-mean centre),
    and ``occluded_fraction`` counts the letterbox and a second object in front. A bubble wrapping
    from the end back to the start during a frame's exposure has no centre there (NaN).
    """
    cam = spec.camera
    faults = spec.faults
    shades = pendulum_shades(cam)
    n_lead = faults.trimmed_lead_frames
    times = frame_times_s(spec)
    if n_lead:
        times = np.concatenate([np.arange(-n_lead, 0) / cam.fps, times])
    n = times.size
    exposure_s = cam.exposure_fraction / cam.fps
    k = exposure_subsamples(spec)
    extras = faults.active or k > cam.exposure_subsamples
    sub_offsets = ((np.arange(k) + 0.5) / k - 0.5) * exposure_s
    sub_times = times[:, None] + sub_offsets[None, :]
    theta_sub = true_angle_rad(spec, sub_times.reshape(-1)).reshape(n, k)
    theta_mid = true_angle_rad(spec, times)
    drifting = spec.disturbances.drifting
    pivot_sub = pivot_position_px(spec, sub_times) if drifting else None
    mx, my = marker_position_px(cam, theta_sub, pivot_sub)
    truth = pd.DataFrame(
        {
            "frame": np.arange(n) - n_lead,
            "time_s": times,
            "theta_rad": theta_mid,
            "marker_x_px": mx.mean(axis=1),  # centroid of the exposure-blurred disk
            "marker_y_px": my.mean(axis=1),
            "occluded_fraction": 0.0,
        }
    )
    if drifting:
        truth["pivot_x_px"], truth["pivot_y_px"] = pivot_position_px(spec, times)
    second = faults.second_object
    second_sub = second.position_px(sub_times) if second.active else None
    if extras:
        steps = np.hypot(np.diff(mx, axis=1), np.diff(my, axis=1)).sum(axis=1)
        truth["streak_px"] = steps * k / (k - 1) if k > 1 else 0.0
    if second_sub is not None:
        truth["second_x_px"], truth["second_y_px"] = second_sub[0].mean(axis=1), second_sub[1].mean(axis=1)
        if second.path == "bubble":  # a bubble leaving at the end and one entering at the start: no one centre
            cycle = np.floor(sub_times / second.period_s)
            wraps = cycle[:, 0] != cycle[:, -1]
            truth.loc[wraps, ["second_x_px", "second_y_px"]] = np.nan
        second_radius = cam.marker_radius_px if second.radius_px is None else second.radius_px
        second_level = shades["marker"] if second.level is None else second.level
    background = render_background(cam, spec.seed)
    if faults.stripes.active:
        cover = stripe_coverage(background.shape, faults.stripes)
        background += cover * (np.float32(faults.stripes.level) - background)
    border = letterbox_mask(background.shape, faults.letterbox) if faults.letterbox.active else None
    rng = np.random.default_rng(spec.seed + 15485863)
    noise = sensor_noise(rng, background.shape, cam.noise_sigma, n)
    release_frame = int(np.searchsorted(times, release_time_s(spec)))
    schedule = occlusion_schedule(spec, n - n_lead, release_frame - n_lead)
    events = [(start + n_lead, length) for start, length in schedule]
    occluder_value = 0.5 * (shades["marker"] + shades["body"])
    bob = faults.bob if faults.bob.active else None
    frames = []
    accum = np.empty_like(background)
    canvas = np.empty_like(background)
    for i in range(n):
        moved = drifting or second_sub is not None or not np.array_equal(theta_sub[i], theta_sub[i - 1])
        if i == 0 or moved:  # held and nothing else moving: reuse the exposure
            accum.fill(0.0)
            for j in range(k):
                np.copyto(canvas, background)
                pivot = None if pivot_sub is None else (pivot_sub[0][i, j], pivot_sub[1][i, j])
                if second_sub is not None and not second.in_front:
                    draw_disk(canvas, second_sub[0][i, j], second_sub[1][i, j], second_radius, second_level)
                _draw_pendulum(canvas, cam, float(theta_sub[i, j]), shades, pivot, bob)
                if second_sub is not None and second.in_front:
                    draw_disk(canvas, second_sub[0][i, j], second_sub[1][i, j], second_radius, second_level)
                accum += canvas
            accum /= k
        frame = accum.copy()
        for start, length in events:
            if start <= i < start + length:
                # Occluder slides across the marker during the event.
                u = (i - start + 0.5) / length
                r_occ = 1.6 * cam.marker_radius_px
                ox = truth.marker_x_px[i] + (4 * u - 2) * r_occ * 0.9
                oy = truth.marker_y_px[i] + 0.3 * r_occ
                cv2.circle(
                    frame,
                    (int(round(ox * 16)), int(round(oy * 16))),
                    int(r_occ * 16),
                    occluder_value,
                    -1,
                    cv2.LINE_AA,
                    4,
                )
                d = math.hypot(ox - truth.marker_x_px[i], oy - truth.marker_y_px[i])
                truth.loc[i, "occluded_fraction"] = disk_overlap_fraction(cam.marker_radius_px, r_occ, d)
        frame += noise(i)
        image = np.clip(np.rint(frame), 0, 255).astype(np.uint8)
        if border is not None:
            image[border] = np.uint8(np.clip(round(faults.letterbox.level), 0, 255))
        frames.append(image)
        if progress and (i % 100 == 0 or i == n - 1):
            progress(f"{spec.name}: rendered frame {i + 1}/{n}")
    if border is not None or (second_sub is not None and second.in_front):
        hidden = truth.occluded_fraction.to_numpy().copy()
        for i in range(n):
            x, y = truth.marker_x_px[i], truth.marker_y_px[i]
            if border is not None:
                hidden[i] = max(hidden[i], letterbox_covered_fraction(cam, faults.letterbox, x, y))
            if second_sub is not None and second.in_front:
                d = math.hypot(truth.second_x_px[i] - x, truth.second_y_px[i] - y)
                hidden[i] = max(hidden[i], disk_overlap_fraction(cam.marker_radius_px, second_radius, d))
        truth["occluded_fraction"] = hidden
    truth = truth.iloc[n_lead:].reset_index(drop=True)
    return RenderedTrial(frames[n_lead:], truth, frames[:n_lead])


@functools.lru_cache
def x264_cpu(cpuinfo: str = "/proc/cpuinfo") -> str | None:
    """x264's CPU features for a deterministic encode: ``"AVX2"`` on an x86 CPU with AVX-512 and AVX2 (and the
    FMA3, BMI1/2 and LZCNT that x264's AVX2 level includes), else None (x264's own detection)."""
    try:
        text = Path(cpuinfo).read_text()
    except OSError:
        return None
    flags = next((line.split(":", 1)[1].split() for line in text.splitlines() if line.startswith("flags")), [])
    needed = {"avx512f", "avx2", "fma", "bmi1", "bmi2", "abm"}
    return "AVX2" if needed <= set(flags) else None


def write_video(
    frames: list,
    path: Path,
    fps: float,
    crf: int,
    preset: str,
    lead_frames: list = (),
    plain_c: bool = False,
    colour: bool = False,
) -> None:
    """Encode grey frames as H.264 (yuv420p) in MP4 (one encoder thread); with ``colour``, frames already in
    yuv420p (each Y over U over V: 1.5 × height rows, as ``av.VideoFrame.from_ndarray`` takes them).

    ``lead_frames`` (a trimmed clip): encoded before ``frames`` with negative timestamps, so the
    file holds their packets but its edit list starts at ``frames[0]`` and decoders discard them.
    ``plain_c``: x264 without its assembly (``no-asm``), about 3.5× slower. x264's AVX-512 code gave the same
    960×540 frames different bytes in about one encode in ten (2026-11-27: 15 of 148; one outcome in 90
    encodes with its AVX2 or SSE4.2 code, the bytes of most AVX-512 encodes): on a Linux machine whose CPU has
    AVX-512 it is told to use its AVX2 code (:func:`x264_cpu`), and every render is the same bytes in every run
    (elsewhere x264 chooses, and an AVX-512 CPU may vary).
    """
    from fractions import Fraction

    import av

    path = Path(path)
    tmp = path.with_name(path.name + ".part")
    with av.open(str(tmp), mode="w", format="mp4") as container:
        stream = container.add_stream("libx264", rate=Fraction(fps).limit_denominator(1001))
        stream.width = frames[0].shape[1]
        stream.height = frames[0].shape[0] * 2 // 3 if colour else frames[0].shape[0]
        stream.pix_fmt = "yuv420p"
        keyint = str(max(1, int(round(2 * fps))))  # a key frame every 2 s, as cameras do
        stream.options = {"crf": str(crf), "preset": preset, "threads": "1", "g": keyint}
        if plain_c:
            stream.options = {**stream.options, "x264-params": "no-asm=1"}
        elif cpu := x264_cpu():
            stream.options = {**stream.options, "x264-params": f"asm={cpu}"}
        rate = Fraction(fps).limit_denominator(1001)
        for i, img in enumerate([*lead_frames, *frames]):
            vf = av.VideoFrame.from_ndarray(img, format="yuv420p" if colour else "gray")
            if len(lead_frames):
                vf.pts, vf.time_base = i - len(lead_frames), 1 / rate
            for packet in stream.encode(vf):
                container.mux(packet)
        for packet in stream.encode():
            container.mux(packet)
    tmp.replace(path)


def truth_record(spec: TrialSpec) -> dict:
    """Everything known about a trial, for data/truth/<trial>.yaml."""
    cam = asdict(spec.camera)
    cam["pivot_px"] = list(spec.camera.pivot_px)
    if spec.camera.blur_step_px == Camera.blur_step_px:  # newer fields: recorded only when changed
        del cam["blur_step_px"]
    subsamples = exposure_subsamples(spec)
    if subsamples > spec.camera.exposure_subsamples:
        cam["exposure_subsamples_used"] = subsamples
    record = {
        "trial": spec.name,
        "release_deg": spec.release_deg,
        "release_time_s": round(release_time_s(spec), 9),
        "rig": spec.rig,
        "truth": spec.truth,
        "effects": list(spec.effects),
        "camera": cam,
        "occlusions": asdict(spec.occlusions),
        "seed": spec.seed,
        "hold_s": spec.hold_s,
        "duration_s": spec.duration_s,
    }
    if spec.disturbances.active:  # effects outside the library (absent: none)
        record["disturbances"] = {**asdict(spec.disturbances), "pivot_drift_px": list(spec.disturbances.pivot_drift_px)}
    if spec.faults.active:  # real-world faults (absent: none)
        faults = asdict(spec.faults)
        for key in ("start_px", "end_px"):
            faults["second_object"][key] = list(faults["second_object"][key])
        record["faults"] = faults
    return record


def generate_trial(spec: TrialSpec, video_dir: Path, truth_dir: Path, progress=print) -> Path:
    """Render ``spec`` to ``video_dir/<name>.mp4``; truth to ``truth_dir/<name>.yaml|.csv``."""
    video_dir, truth_dir = Path(video_dir), Path(truth_dir)
    video_dir.mkdir(parents=True, exist_ok=True)
    truth_dir.mkdir(parents=True, exist_ok=True)
    rendered = render_trial(spec, progress=progress)
    video = video_dir / f"{spec.name}.mp4"
    cam = spec.camera
    write_video(rendered.frames, video, cam.fps, cam.crf, cam.preset, lead_frames=rendered.lead_frames)
    rendered.truth.to_csv(truth_dir / f"{spec.name}.csv", index=False, float_format="%.9g")
    with open(truth_dir / f"{spec.name}.yaml", "w") as fh:
        yaml.safe_dump(truth_record(spec), fh, sort_keys=False)
    return video


def load_specs(path: Path) -> list[TrialSpec]:
    """Trial specs from a YAML file with ``defaults`` merged (one level deep) into each of ``trials``."""
    doc = yaml.safe_load(Path(path).read_text())
    defaults = doc.get("defaults", {})
    specs = []
    for trial in doc["trials"]:
        merged = dict(defaults)
        for key, value in trial.items():
            if isinstance(value, dict) and isinstance(merged.get(key), dict):
                merged[key] = {**merged[key], **value}
            else:
                merged[key] = value
        specs.append(TrialSpec.from_mapping(merged))
    return specs


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description="Render synthetic free-decay pendulum videos with known truth.")
    parser.add_argument("spec", type=Path, help="YAML trial specification (see data/synthetic/demo.yaml)")
    parser.add_argument("--videos", type=Path, default=Path("data/raw"))
    parser.add_argument("--truth", type=Path, default=Path("data/truth"))
    parser.add_argument("--only", nargs="*", help="render only these trial names")
    args = parser.parse_args(argv)
    for spec in load_specs(args.spec):
        if args.only and spec.name not in args.only:
            continue
        path = generate_trial(spec, args.videos, args.truth, progress=lambda m: print(m, file=sys.stderr))
        print(f"{path}  {path.stat().st_size / 1e6:.2f} MB")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
