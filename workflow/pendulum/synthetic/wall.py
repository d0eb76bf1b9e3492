"""Real footage's world, rendered: a shaded body on a faint thread before a wall, with known truth.

Learned from the real clips (``../shared/data/real-video/redapple_480p.mov`` measured: a light wall
of grey 161–199 with a lighting gradient of ~20 grey levels across the frame; an apple of radius
~20 px, grey 56–96 from its shading and skin; two soft shadows of it on the wall 30–45 px below,
blurred by σ ≈ 8 px, ~10 grey levels deep; a thread a few grey levels darker than the wall; the
pivot far above the frame; the swing under way in the first frame; the phone creeping ~13 px over
21 s), not from guesses. A render is compared with the real clip side by side
(``tests/benchmarks/body_study.py --compare``) before it is trusted.

The pendulum's angle comes from the same physics as every render and every fit
(:func:`pendulum.synthetic.experiment.true_angle_rad`). The body is a disk of radius R in the image (a sphere's
silhouette), its inside drawn from its look (:class:`WallBody`): ``apple`` (dark, shaded from above,
mottled skin), ``two_tone`` (a bright patterned top half over a dark bottom half, as the held-out
ball, its seam's plane tilted by ``seam_tilt_deg``: the body study's up to 30°), ``pattern`` (a printed
checker); ``spin_deg_per_s`` turns the look about the thread (the silhouette stays a disk). Coverage is
exact to 1/16 px² (4×4 supersampling at the sub-pixel centre; pixel k centred on k, as OpenCV and the
trackers measure), exposure blur is the mean of sub-exposures no more than 1.5 px apart, and each frame
has its own sensor noise (:func:`~pendulum.synthetic.scene.sensor_noise`).

The scene (:class:`Wall`): the wall's grey and gradient, a soft static dark band (a shadow across
the wall), soft shadows that follow the body, the thread, slow exposure drift (auto-exposure),
defocus, camera creep (the whole picture, pivot included, moving in the image), and a mid-swing
start (the first frame ``start_s`` after the release). Truth per frame: ``theta_rad`` and the body
centre's exposure-mean image position ``marker_x_px``, ``marker_y_px``.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field, replace

import cv2
import numpy as np
import pandas as pd

from pendulum.synthetic.experiment import true_angle_rad, write_video
from pendulum.synthetic.scene import sensor_noise
from pendulum.synthetic.specs import TrialSpec


@dataclass(frozen=True)
class WallBody:
    look: str = "apple"  # apple, two_tone or pattern
    radius_px: float = 20.0
    level: float = 75.0  # mean grey (the two-tone ball's dark half)
    other_level: float = 215.0  # two_tone: the top half's grey; pattern: the light squares'
    texture: float = 20.0  # grey amplitude of shading and skin
    spin_deg_per_s: float = 0.0  # the look turning about the thread
    seam_tilt_deg: float = 0.0  # two_tone: its seam's plane tilted from level (turning with the look)
    dot_radius_px: float = 0.0  # a marker dot painted at the body's centre (a clock bob's coloured dot); 0: none
    dot_level: float = 40.0  # the dot's grey
    # a shiny body (a bauble): the specular highlight of a lamp at lamp_px = (x, y, distance in front of the
    # wall plane), this much brighter at its peak (0: matte), Gaussian σ this fraction of the radius
    gloss: float = 0.0
    gloss_sigma: float = 0.1
    lamp_px: tuple = (320.0, 0.0, 700.0)

    def __post_init__(self):
        if self.look not in ("apple", "two_tone", "pattern"):
            raise ValueError(f"body look must be apple, two_tone or pattern, got {self.look!r}")


@dataclass(frozen=True)
class Wall:
    level: float = 183.0
    gradient: float = 20.0  # grey levels of lighting falloff across the frame (brighter bottom right)
    band_depth: float = 0.0  # a soft static dark band across the wall (grey levels); 0: none
    band_y_px: float = 180.0
    band_width_px: float = 40.0  # Gaussian σ of the band
    band_angle_deg: float = 10.0
    vignette: float = 8.0  # the frame's centre this much brighter than its sides
    grain: float = 0.0  # a patterned wall's fine texture (wood, tiles, a print): its grey SD, ~4 px grain
    shadows: tuple = ((27.0, 58.0), (75.0, 58.0))  # offsets (px) of soft shadows that follow the body
    shadow_depth: float = 12.0
    shadow_blur_px: float = 8.0
    thread_depth: float = 40.0  # the thread (or rod) this much darker than the wall ...
    thread_width_px: int = 1  # ... and this wide
    exposure_drift: float = 0.0  # auto-exposure gain swinging by ± this fraction ...
    exposure_drift_period_s: float = 9.0  # ... over this period
    defocus_px: float = 0.0  # Gaussian σ of the whole picture
    creep_px: tuple = (0.0, 0.0)  # the picture moves by this much over the clip (camera creeping)
    start_s: float = 0.0  # the first frame is this long after the release (mid-swing start)
    # a phone's clock under even time stamps: (frame, periods) — from that frame on every frame is taken that many
    # frame periods later (1: a frame lost; -1: the frame before shown twice; a fraction: the clock slipped)
    clock_slips: tuple = ()


@dataclass
class WallTrial:
    spec: TrialSpec
    body: WallBody = field(default_factory=WallBody)
    wall: Wall = field(default_factory=Wall)


def _wall_image(spec: TrialSpec, wall: Wall) -> np.ndarray:
    cam = spec.camera
    h, w = cam.height_px, cam.width_px
    rng = np.random.default_rng(spec.seed + 31)
    yy, xx = np.mgrid[0:h, 0:w].astype(np.float32)
    img = wall.level + wall.gradient * (yy / h - 0.5) + wall.vignette * (1 - 4 * (xx / w - 0.5) ** 2)
    small = rng.standard_normal((h // 80 + 2, w // 80 + 2)).astype(np.float32)
    img += 1.0 * cv2.resize(small, (w, h), interpolation=cv2.INTER_CUBIC)  # paint's unevenness
    if wall.grain:
        fine = cv2.resize(rng.standard_normal((h // 4 + 2, w // 4 + 2)).astype(np.float32), (w, h))
        img += wall.grain * fine / float(fine.std())
    if wall.band_depth:
        a = math.radians(wall.band_angle_deg)
        u = yy * math.cos(a) - xx * math.sin(a) - wall.band_y_px
        img -= wall.band_depth * np.exp(-0.5 * (u / wall.band_width_px) ** 2)
    return img


def _disk_coverage(gx: np.ndarray, gy: np.ndarray, cx: float, cy: float, r: float) -> np.ndarray:
    """Each pixel's share of 4 × 4 sub-pixel samples within r of (cx, cy): 1 or 0 away from the rim, counted
    near it (a sample lies within 0.53 px of its pixel's centre)."""
    d = np.hypot(gx - cx, gy - cy)
    coverage = (d < r).astype(np.float64)
    rim = np.nonzero(np.abs(d - r) <= 1.0)
    sub = (np.arange(4) + 0.5) / 4 - 0.5
    sx, sy = np.meshgrid(sub, sub)
    fx = gx[rim][:, None] + sx.ravel() - cx
    fy = gy[rim][:, None] + sy.ravel() - cy
    coverage[rim] = (fx**2 + fy**2 <= r * r).mean(axis=1)
    return coverage


def _body_patch(body: WallBody, cx: float, cy: float, spin_rad: float, swing_rad: float):
    """(x0, y0, grey, coverage) of the body disk at sub-pixel centre (cx, cy), its look turned by the swing."""
    r = body.radius_px
    x0, y0 = int(math.floor(cx - r - 2)), int(math.floor(cy - r - 2))
    size = int(math.ceil(2 * r + 5))
    gy, gx = np.mgrid[0:size, 0:size].astype(np.float32)
    coverage = _disk_coverage(gx, gy, cx - x0, cy - y0, r)
    u = (gx - (cx - x0)) / r  # body frame: across and along the thread
    v = (gy - (cy - y0)) / r
    cs, sn = math.cos(swing_rad), math.sin(swing_rad)
    across, along = u * cs - v * sn, u * sn + v * cs
    rho2 = np.clip(across**2 + along**2, 0, 1)
    spun = across * math.cos(spin_rad) + np.sqrt(1 - rho2) * math.sin(spin_rad)  # a sphere's surface turning
    t = body.texture
    if body.look == "apple":
        # lit from above left: a lighter cap, a darker underside and rim, a mottled skin turning with it
        grey = body.level - 0.6 * t * along - 0.3 * t * across + 0.3 * t * np.sin(7 * spun + 3 * along) - 0.4 * t * rho2
    elif body.look == "two_tone":
        tilt = math.radians(body.seam_tilt_deg)  # the seam's plane: cos α · along + sin α · spun = 0
        top = math.cos(tilt) * along + math.sin(tilt) * spun < 0
        grey = np.where(top, body.other_level + t * np.sin(9 * spun) * np.cos(5 * along), body.level - 0.5 * t * along)
    else:
        grey = np.where(
            (np.floor(3 * spun + 3) + np.floor(3 * along + 3)) % 2 == 0, body.other_level, body.level
        ) + 0.3 * t * (-along)
    if body.gloss > 0:  # the highlight where the sphere's normal halves the lamp's and the view's directions
        to_lamp = np.array([body.lamp_px[0] - cx, body.lamp_px[1] - cy, body.lamp_px[2]], float)
        half = to_lamp / np.linalg.norm(to_lamp) + np.array([0.0, 0.0, 1.0])
        hx, hy = half[:2] / np.linalg.norm(half)
        spot = np.exp(-0.5 * ((u - hx) ** 2 + (v - hy) ** 2) / body.gloss_sigma**2)
        grey = np.minimum(grey + body.gloss * spot, 255.0)
    if body.dot_radius_px > 0:  # the dot's exact coverage, as the body's
        dot = _disk_coverage(gx, gy, cx - x0, cy - y0, body.dot_radius_px)
        grey = grey + dot * (body.dot_level - grey)
    return x0, y0, grey.astype(np.float32), coverage.astype(np.float32)


def _shadow_patch(body: WallBody, wall: Wall, cx: float, cy: float):
    """(x0, y0, darkening) of one soft shadow centred at (cx, cy): a disk blurred by σ, depth at its centre."""
    r, s = body.radius_px, wall.shadow_blur_px
    reach = r + 3 * s
    x0, y0 = int(math.floor(cx - reach)), int(math.floor(cy - reach))
    size = int(math.ceil(2 * reach + 2))
    gy, gx = np.mgrid[0:size, 0:size].astype(np.float32)
    dist = np.hypot(gx - (cx - x0), gy - (cy - y0))
    from scipy.special import ndtr

    return x0, y0, (wall.shadow_depth * ndtr((r - dist) / max(s, 1e-3))).astype(np.float32)


def _paste(canvas: np.ndarray, x0: int, y0: int, patch: np.ndarray, op):
    h, w = canvas.shape
    ph, pw = patch.shape[:2]
    a0, b0 = max(x0, 0), max(y0, 0)
    a1, b1 = min(x0 + pw, w), min(y0 + ph, h)
    if a0 >= a1 or b0 >= b1:
        return
    op(canvas[b0:b1, a0:a1], (slice(b0 - y0, b1 - y0), slice(a0 - x0, a1 - x0)))


def _theta(spec: TrialSpec, times_s: np.ndarray) -> np.ndarray:
    """θ at ``times_s`` (any shape), integrated on a grid that is dense from the release on (a mid-swing start
    leaves no long first step to the integrator)."""
    times_s = np.asarray(times_s, float)
    lead = np.arange(0.0, float(times_s.min()), 0.25 / spec.camera.fps)
    theta = true_angle_rad(spec, np.concatenate([lead, times_s.reshape(-1)]))
    return theta[lead.size :].reshape(times_s.shape)


def render_wall_trial(trial: WallTrial, progress=None) -> tuple[list, pd.DataFrame]:
    """Every frame (uint8 grey) and the per-frame truth (module docstring)."""
    spec, body, wall = trial.spec, trial.body, trial.wall
    cam = spec.camera
    n = int(round(spec.duration_s * cam.fps))
    video_t = np.arange(n) / cam.fps  # when each frame was taken (its stamp: frame / fps)
    for first, periods in wall.clock_slips:
        video_t[int(first) :] += periods / cam.fps
    exposure = cam.exposure_fraction / cam.fps
    arm = cam.marker_arm_px
    roll = math.radians(cam.roll_deg)
    # sub-exposures no more than blur_step_px apart at the fastest swing
    even = np.arange(n) / cam.fps
    omega = np.gradient(_theta(spec, even + wall.start_s), even) if n > 1 else np.zeros(1)
    k = max(cam.exposure_subsamples, int(math.ceil(float(np.max(np.abs(omega))) * arm * exposure / cam.blur_step_px)))
    offsets = ((np.arange(k) + 0.5) / k - 0.5) * exposure
    sub_t = video_t[:, None] + offsets[None, :]
    theta = _theta(spec, sub_t + wall.start_s)
    creep = np.asarray(wall.creep_px, float)
    shift = (sub_t / max(spec.duration_s, 1e-9))[..., None] * creep  # the picture's displacement (n, k, 2)
    phi = theta + roll
    px = cam.pivot_px[0] + shift[..., 0]
    py = cam.pivot_px[1] + shift[..., 1]
    bx = px + arm * np.sin(phi)
    by = py + arm * np.cos(phi)
    truth = pd.DataFrame(
        {
            "frame": np.arange(n),
            "time_s": video_t,
            "theta_rad": _theta(spec, video_t + wall.start_s),
            "marker_x_px": bx.mean(axis=1),
            "marker_y_px": by.mean(axis=1),
        }
    )
    base = _wall_image(spec, wall)
    h, w = base.shape
    rng = np.random.default_rng(spec.seed + 15485863)
    noise = sensor_noise(rng, base.shape, cam.noise_sigma, n)

    def draw(canvas, i, j, part=(slice(None), slice(None))):
        """The body, its shadows and its thread at sub-exposure j of frame i, drawn onto ``canvas``."""
        x, y = float(bx[i, j]), float(by[i, j])
        for ox, oy in wall.shadows:
            sx0, sy0, dark = _shadow_patch(body, wall, x + ox, y + oy)

            def darken(view, idx, dark=dark):
                view -= dark[idx]

            _paste(canvas, sx0, sy0, dark, darken)
        if wall.thread_depth:
            end = _thread_end(i, j)
            cv2.line(
                layer,
                (int(round(px[i, j] * 16)), int(round(py[i, j] * 16))),
                (int(round(end[0] * 16)), int(round(end[1] * 16))),
                1.0,
                wall.thread_width_px,
                cv2.LINE_AA,
                4,
            )
            canvas[part] -= wall.thread_depth * layer[part]
            layer[part] = 0.0
        spin = math.radians(body.spin_deg_per_s) * float(sub_t[i, j] + wall.start_s)
        x0, y0, grey, cover = _body_patch(body, x, y, spin, float(phi[i, j]))

        def blend(view, idx, grey=grey, cover=cover):
            view += cover[idx] * (grey[idx] - view)

        _paste(canvas, x0, y0, grey, blend)

    def _thread_end(i, j):
        x, y = float(bx[i, j]), float(by[i, j])
        return x - body.radius_px * math.sin(phi[i, j]), y - body.radius_px * math.cos(phi[i, j])

    def _frame_box(i, w, h):
        """(x0, x1, y0, y1) in the frame holding everything drawn over frame i's sub-exposures, or None."""
        r = body.radius_px
        reach = r + 3 * wall.shadow_blur_px
        xs, ys = [], []
        for j in range(k):
            x, y = float(bx[i, j]), float(by[i, j])
            x0, y0, size = math.floor(x - r - 2), math.floor(y - r - 2), math.ceil(2 * r + 5)
            xs += [x0, x0 + size]
            ys += [y0, y0 + size]
            for ox, oy in wall.shadows:
                x0, y0, size = math.floor(x + ox - reach), math.floor(y + oy - reach), math.ceil(2 * reach + 2)
                xs += [x0, x0 + size]
                ys += [y0, y0 + size]
            if wall.thread_depth:
                end = _thread_end(i, j)
                pad = wall.thread_width_px + 2
                xs += [math.floor(min(px[i, j], end[0])) - pad, math.ceil(max(px[i, j], end[0])) + pad + 1]
                ys += [math.floor(min(py[i, j], end[1])) - pad, math.ceil(max(py[i, j], end[1])) + pad + 1]
        x0, x1, y0, y1 = max(min(xs), 0), min(max(xs), w), max(min(ys), 0), min(max(ys), h)
        return (x0, x1, y0, y1) if x0 < x1 and y0 < y1 else None

    frames = []
    accum = np.empty_like(base)
    still = np.zeros_like(base)  # k unmoved walls summed as the loop below sums them (the same bytes)
    for _ in range(k):
        still += base
    canvas = base.copy()
    layer = np.zeros_like(base)
    for i in range(n):
        if np.any(shift[i]):  # the picture moves: every pixel changes
            accum.fill(0.0)
            for j in range(k):
                dx, dy = shift[i, j]
                canvas = (
                    cv2.warpAffine(
                        base,
                        np.float32([[1, 0, dx], [0, 1, dy]]),
                        (w, h),
                        flags=cv2.INTER_LINEAR,
                        borderMode=cv2.BORDER_REFLECT,
                    )
                    if dx or dy
                    else base.copy()
                )
                draw(canvas, i, j)
                accum += canvas
            canvas = base.copy()
        else:  # only what the body, its shadows and its thread cover differs from the wall: summed there alone
            np.copyto(accum, still)
            box = _frame_box(i, w, h)
            if box is not None:
                part = (slice(box[2], box[3]), slice(box[0], box[1]))
                accum[part] = 0.0
                for j in range(k):
                    draw(canvas, i, j, part)
                    accum[part] += canvas[part]
                    canvas[part] = base[part]
        frame = accum / k
        if wall.exposure_drift:
            frame *= 1 + wall.exposure_drift * math.sin(2 * math.pi * video_t[i] / wall.exposure_drift_period_s)
        if wall.defocus_px > 0:
            frame = cv2.GaussianBlur(frame, (0, 0), wall.defocus_px)
        frame += noise(i)
        np.rint(frame, out=frame)
        frames.append(np.minimum(np.maximum(frame, 0, out=frame), 255, out=frame).astype(np.uint8))
        if progress and (i % 100 == 0 or i == n - 1):
            progress(f"{spec.name}: rendered frame {i + 1}/{n}")
    return frames, truth


def write_wall_trial(trial: WallTrial, video_dir, truth_dir=None, plain_c: bool = False) -> tuple:
    """Render and encode ``<name>.mp4`` (H.264, the camera's crf; ``plain_c``: the same bytes every run, see
    :func:`~pendulum.synthetic.experiment.write_video`); the truth to ``<name>.csv`` in ``truth_dir``."""
    from pathlib import Path

    frames, truth = render_wall_trial(trial)
    cam = trial.spec.camera
    video = Path(video_dir) / f"{trial.spec.name}.mp4"
    write_video(frames, video, cam.fps, cam.crf, cam.preset, plain_c=plain_c)
    if truth_dir is not None:
        truth.to_csv(Path(truth_dir) / f"{trial.spec.name}.csv", index=False)
    return video, truth


# A body on a string in air, as the real clips are: the apple decays from 22° to 19° in 21 s.
STRING_RIG = {
    "mass_kg": 0.18,
    "length_m": 1.0,
    "frontal_area_m2": 0.0045,
    "displaced_volume_m3": 0.0002,
    "fluid_density_kg_m3": 1.2,
    "gravity_m_s2": 9.81,
}
STRING_TRUTH = {"added_mass_kg": 0.0001, "drag_area_m2": 0.0025, "linear_damping_nm_s": 0.0004}
STRING_EFFECTS = ["quadratic_drag", "linear_damping"]


def _drawn_camera(rng, frame: tuple, pivot_px: tuple, arm_px: float, radius_px: float, upper: tuple):
    """A camera of ``frame`` = (width, height, fps) with its roll, exposure, noise and compression drawn from
    ``rng`` (in that order): roll ±1°, exposure 0.2 … ``upper[0]``, noise 1 … ``upper[1]`` grey levels, crf
    18 … ``upper[2]`` − 1."""
    from pendulum.synthetic.specs import Camera

    width, height, fps = frame
    return Camera(
        width_px=width,
        height_px=height,
        fps=fps,
        pivot_px=pivot_px,
        marker_arm_px=arm_px,
        marker_radius_px=radius_px,
        roll_deg=float(rng.uniform(-1, 1)),
        exposure_fraction=float(rng.uniform(0.2, upper[0])),
        noise_sigma=float(rng.uniform(1.0, upper[1])),
        crf=int(rng.integers(18, upper[2])),
    )


def random_wall_trial(seed: int, rig: dict = STRING_RIG, truth: dict = STRING_TRUTH, effects=STRING_EFFECTS):
    """A scene of real footage's faults drawn at random (the body study's scenes)."""

    rng = np.random.default_rng(seed)
    width, height = [(640, 360), (960, 540)][int(rng.integers(0, 2))]
    fps = float(rng.choice([30.0, 60.0]))
    look = str(rng.choice(["apple", "two_tone", "pattern"]))
    radius = float(rng.uniform(15, 40)) * width / 640
    arm = float(rng.uniform(1.0, 2.2)) * height
    pivot_y = float(rng.uniform(0.25, 0.55)) * height - arm  # the body in the upper half to the middle
    pivot_x = width / 2 + float(rng.uniform(-0.1, 0.1)) * width
    # a release of 8–30°, kept so the whole swing stays in the frame
    room = min(pivot_x, width - pivot_x) - radius - 12
    amplitude = min(float(rng.uniform(8, 30)), math.degrees(math.asin(min(room / arm, 1.0))))
    # a swing of at least four body radii each way (a pendulum test's swing; a body that hardly leaves its
    # place holds its own pixels in most frames and has no static scene behind it)
    amplitude = max(amplitude, math.degrees(math.asin(min(4 * radius / arm, 1.0))))
    level = float(rng.uniform(40, 110)) if look != "pattern" else float(rng.uniform(30, 80))
    camera = _drawn_camera(rng, (width, height, fps), (pivot_x, pivot_y), arm, radius, (0.6, 3.0, 24))
    spec = TrialSpec(
        name=f"wall_{seed}",
        release_deg=float(rng.choice([-1, 1])) * amplitude,
        rig=rig,
        truth=truth,
        effects=effects,
        seed=seed,
        hold_s=0.0,
        duration_s=8.0,
        camera=camera,
    )
    wall = Wall(
        level=float(rng.uniform(150, 215)),
        gradient=float(rng.uniform(0, 35)),
        band_depth=float(rng.choice([0.0, rng.uniform(20, 60)])),
        band_y_px=float(rng.uniform(0.3, 0.7)) * height,
        band_width_px=float(rng.uniform(0.05, 0.15)) * height,
        band_angle_deg=float(rng.uniform(-20, 20)),
        vignette=float(rng.uniform(0, 12)),
        shadows=tuple(
            (float(rng.uniform(-4, 4)) * radius, float(rng.uniform(1.5, 3.5)) * radius)
            for _ in range(int(rng.integers(0, 3)))
        ),
        shadow_depth=float(rng.uniform(5, 20)),
        shadow_blur_px=float(rng.uniform(0.2, 0.5)) * radius,
        thread_depth=float(rng.uniform(5, 40)),
        exposure_drift=float(rng.uniform(0, 0.06)),
        defocus_px=float(rng.choice([0.0, rng.uniform(0.5, 2.0)])),
        creep_px=(float(rng.uniform(-6, 6)), float(rng.uniform(-6, 6))) if rng.uniform() < 0.5 else (0.0, 0.0),
        start_s=float(rng.uniform(0, 3)),
    )
    body = WallBody(
        look=look,
        radius_px=radius,
        level=level,
        other_level=float(rng.uniform(170, 240)),
        texture=float(rng.uniform(4, 16)),
        spin_deg_per_s=float(rng.uniform(-10, 10)),  # the real apple turns ≤ 48° in 21 s: up to 4× that
        seam_tilt_deg=float(rng.uniform(0, 30)),  # drawn last: the other values as before it was
    )
    return WallTrial(spec, body, wall)


def render_wall_pair(left: WallTrial, right: WallTrial) -> tuple[list, pd.DataFrame, pd.DataFrame]:
    """Two pendulums in one view (two clock pendulums side by side): every frame and each one's truth.

    Both trials share the camera size, frame rate, wall and seed (so the same wall and noise); each pixel of
    a frame is taken from the render in which it differs more from the empty wall (drawn with the same
    noise): a pendulum's rod, bob and shadows from its own render, the wall from either.
    """
    frames_a, truth_a = render_wall_trial(left)
    frames_b, truth_b = render_wall_trial(right)
    cam = left.spec.camera
    away = replace(cam, pivot_px=(-10.0 * cam.width_px, -10.0 * cam.height_px))  # the body far outside the view
    empty = replace(
        left,
        spec=replace(left.spec, camera=away),
        body=replace(left.body, dot_radius_px=0.0),
        wall=replace(left.wall, thread_depth=0.0, shadows=()),
    )
    walls, _ = render_wall_trial(empty)
    frames = []
    for a, b, w in zip(frames_a, frames_b, walls, strict=True):
        da = np.abs(a.astype(np.int16) - w)
        db = np.abs(b.astype(np.int16) - w)
        frames.append(np.where(da >= db, a, b))
    return frames, truth_a, truth_b


def random_clock_pair(seed: int, duration_s: float = 6.0) -> tuple[WallTrial, WallTrial]:
    """Two rigid pendulums side by side (as the held-out clip of two clock pendulums): a rod from a pivot in
    the frame's top (or above it), a round bob of radius 12–30 px at 640 px width with a dot of another grey
    at its centre (radius 0.2–0.35 of the bob's), swinging ±1.2–3 bob radii (a clock's few degrees), before a
    dark case or a light wall; different lengths and phases. The two trials share camera, wall and seed."""

    rng = np.random.default_rng(seed)
    width, height = [(640, 360), (960, 540)][int(rng.integers(0, 2))]
    fps = float(rng.choice([30.0, 60.0]))
    dark_case = bool(rng.uniform() < 0.5)
    wall_level = float(rng.uniform(40, 90)) if dark_case else float(rng.uniform(160, 210))
    bob_level = float(rng.uniform(150, 210)) if dark_case else float(rng.uniform(40, 100))
    dot_level = float(np.clip(bob_level + float(rng.choice([-1, 1])) * rng.uniform(50, 90), 10, 245))
    pivot_y = float(rng.choice([rng.uniform(0.05, 0.15) * height, -rng.uniform(0.2, 0.6) * height]))
    rod_px = max(2, int(round(rng.uniform(0.006, 0.012) * width)))
    wall = Wall(
        level=wall_level,
        gradient=float(rng.uniform(0, 25)),
        vignette=float(rng.uniform(0, 10)),
        shadows=(),
        thread_depth=wall_level - float(rng.uniform(0.6, 0.9) * bob_level + 0.1 * wall_level),
        thread_width_px=rod_px,
        exposure_drift=float(rng.uniform(0, 0.03)),
        start_s=0.0,
    )
    trials = []
    for x_frac in (float(rng.uniform(0.25, 0.38)), float(rng.uniform(0.62, 0.75))):
        radius = float(rng.uniform(12, 30)) * width / 640
        bob_y = float(rng.uniform(0.55, 0.8)) * height
        arm = bob_y - pivot_y
        swing_px = float(rng.uniform(1.2, 3.0)) * radius
        camera = _drawn_camera(rng, (width, height, fps), (x_frac * width, pivot_y), arm, radius, (0.5, 2.5, 23))
        spec = TrialSpec(
            name=f"clocks_{seed}",
            release_deg=float(rng.choice([-1, 1])) * math.degrees(math.asin(min(swing_px / arm, 1.0))),
            rig=dict(STRING_RIG, length_m=float(rng.uniform(0.25, 1.0))),
            truth=STRING_TRUTH,
            effects=STRING_EFFECTS,
            seed=seed,
            hold_s=0.0,
            duration_s=duration_s,
            camera=camera,
        )
        body = WallBody(
            look="apple",
            radius_px=radius,
            level=bob_level,
            texture=float(rng.uniform(2, 8)),
            dot_radius_px=float(rng.uniform(0.2, 0.35)) * radius,
            dot_level=dot_level,
        )
        trials.append(WallTrial(spec, body, replace(wall, start_s=float(rng.uniform(0, 2)))))
    return trials[0], trials[1]
