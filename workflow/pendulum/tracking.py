"""Tracking stage: the marker centre in every frame, to sub-pixel accuracy.

Per frame, in a small region of interest (ROI) around the predicted position:

1. a coarse, robust estimate: the thresholded centroid x̂ = Σ w x / Σ w with
   w = max(I − T, 0), T = b + ½ (I_marker − b), b the ROI's border median;
2. the estimate used, the linear centroid x̂ = Σ (I − b′) m x / Σ (I − b′) m in a
   soft-edged capsule mask m (marker radius + 2.5 px, stretched along the motion
   by the frame-to-frame step) with b′ the median of a thin ring just outside the
   mask. Linear in the pixel values, it has no pixel locking (a thresholded
   centroid snaps ~0.025 px towards the pixel grid) and no threshold
   nonlinearity on a blurred streak: it is the marker's mean position over the
   exposure. The ring keeps the background local: a small body or a long streak
   puts the ROI's border on the clutter behind, never the ring.

The blur-invariant marker signal Σ (I − b′) m, compared with its value at the
start, gives each frame's quality: an occluder lowers it, glare raises it; an
occluder that the signal misses makes the two centroids disagree (> 0.4 px) and
is flagged too. A leave-one-out cubic check afterwards flags isolated jumps.
Finally each position is moved from the exposure's mean to the frame time,
x(t) = x̄ − ẍ τ²/24, with the exposure τ measured from the streaks' lengths
(see :func:`exposure_centre_correction`). Flagged frames keep their flag;
nothing is interpolated.
"""

from __future__ import annotations

import logging
import math
import time
from dataclasses import dataclass

import cv2
import numpy as np
import pandas as pd

from pendulum.video import iter_luma

log = logging.getLogger(__name__)

FLAGS = ("ok", "occluded", "glare", "jump", "duplicate", "edge", "lost")


@dataclass(frozen=True)
class TrackerSettings:
    marker_radius_px: float = 10.0
    polarity: str = "bright"  # "bright" marker on a darker scene, or "dark" on a brighter one
    start_px: tuple[float, float] | None = None  # a hint where the marker is in the first frame
    min_signal_ratio: float = 0.9  # marker signal below this fraction of normal: "occluded"
    max_signal_ratio: float = 1.12  # above this: "glare"
    jump_floor_px: float = 1.0  # smallest leave-one-out residual that counts as a jump
    jump_sigmas: float = 6.0
    reacquire_after_frames: int = 10
    max_centroid_disagreement_px: float = 0.4  # linear vs thresholded centroid; more: "occluded"
    centroid: str = "linear"
    # Shutter-open time / frame interval, for the exposure-centre correction; None: measured
    # from the streaks (needs ≥ 10 frames moving more than half a marker radius, else 0.5),
    # 0: no correction.
    exposure_fraction: float | None = (
        None  # "linear": Σ (I − b) x in a soft streak mask; "threshold": Σ max(I − T, 0) x
    )

    def __post_init__(self):
        if self.polarity not in ("bright", "dark"):
            raise ValueError(f"marker polarity must be 'bright' or 'dark', got {self.polarity!r}")
        if self.centroid not in ("linear", "threshold"):
            raise ValueError(f"centroid must be 'linear' or 'threshold', got {self.centroid!r}")
        if not self.marker_radius_px > 0:
            raise ValueError("marker_radius_px must be positive")


def _disk_template(radius: float) -> np.ndarray:
    size = int(math.ceil(radius * 4)) | 1
    c = size // 2
    yy, xx = np.mgrid[0:size, 0:size]
    return (np.hypot(xx - c, yy - c) <= radius).astype(np.float32)


def acquire_marker(image: np.ndarray, settings: TrackerSettings, near=None, search_radius_px=None):
    """Coarse marker position by normalised template matching of a disk (on a 2× reduced image).

    Returns ``(x, y, score)`` in full-resolution pixels, or None if the search window is empty.
    """
    img = image if settings.polarity == "bright" else 255 - image
    x0 = y0 = 0
    if near is not None and search_radius_px is not None:
        h, w = img.shape
        x0 = max(0, int(near[0] - search_radius_px))
        y0 = max(0, int(near[1] - search_radius_px))
        x1 = min(w, int(near[0] + search_radius_px))
        y1 = min(h, int(near[1] + search_radius_px))
        img = img[y0:y1, x0:x1]
    small = cv2.resize(img, None, fx=0.5, fy=0.5, interpolation=cv2.INTER_AREA).astype(np.float32)
    template = _disk_template(settings.marker_radius_px / 2)
    if small.shape[0] <= template.shape[0] or small.shape[1] <= template.shape[1]:
        return None
    response = cv2.matchTemplate(small, template, cv2.TM_CCOEFF_NORMED)
    _, score, _, loc = cv2.minMaxLoc(response)
    half = template.shape[0] // 2
    return x0 + 2 * (loc[0] + half) + 0.5, y0 + 2 * (loc[1] + half) + 0.5, float(score)


@dataclass
class Measurement:
    x: float
    y: float
    signal: float  # Σ (I − b) over the marker mask
    level: float  # marker brightness the threshold was set from
    background: float
    at_edge: bool
    disagreement_px: float = 0.0  # |linear − thresholded centroid|: large when something intrudes
    streak2_px2: float = math.nan  # squared length of the exposure streak (linear centroid only)


def measure_marker(image, x_guess, y_guess, settings: TrackerSettings, blur_px=0.0, marker_level=None, direction=None):
    """Sub-pixel intensity-weighted centroid of the marker near (x_guess, y_guess).

    ``blur_px`` (expected streak length) widens the ROI and the mask. Returns
    None when no pixel stands out from the local background.
    """
    r = settings.marker_radius_px
    half = int(math.ceil(2.0 * r + 0.5 * blur_px + 4))
    h, w = image.shape
    xi, yi = int(round(x_guess)), int(round(y_guess))
    x0, x1 = max(0, xi - half), min(w, xi + half + 1)
    y0, y1 = max(0, yi - half), min(h, yi + half + 1)
    if x1 - x0 < 3 or y1 - y0 < 3:
        return None
    roi = image[y0:y1, x0:x1].astype(np.float32)
    if settings.polarity == "dark":
        roi = 255.0 - roi
    border = np.concatenate([roi[0], roi[-1], roi[1:-1, 0], roi[1:-1, -1]])
    background = float(np.median(border))
    level = marker_level if marker_level is not None else float(np.percentile(roi, 99.5))
    threshold = background + 0.5 * (level - background)
    weight = roi - threshold
    np.maximum(weight, 0, out=weight)
    ys = np.arange(y0, y1, dtype=np.float32)[:, None]
    xs = np.arange(x0, x1, dtype=np.float32)[None, :]
    col, row = weight.sum(axis=0), weight.sum(axis=1)
    total = float(col.sum())
    if total <= 0:
        return None
    cx, cy = float(col @ xs[0]) / total, float(row @ ys[:, 0]) / total
    mask_r2 = (r + 0.5 * blur_px + 2.5) ** 2
    for _ in range(1 if settings.centroid == "linear" else 2):  # re-centre a circular mask on the estimate
        inside = (xs - cx) ** 2 + (ys - cy) ** 2 <= mask_r2
        wm = weight * inside
        col, row = wm.sum(axis=0), wm.sum(axis=1)
        total = float(col.sum())
        if total <= 0:
            return None
        cx, cy = float(col @ xs[0]) / total, float(row @ ys[:, 0]) / total
    if settings.centroid == "linear":
        refined = _linear_centroid(roi, x0, y0, cx, cy, r, blur_px, direction)
        if refined is None:
            return None
        disagreement = math.hypot(refined[0] - cx, refined[1] - cy)
        cx, cy, streak2, signal = refined
    else:
        inside = (xs - cx) ** 2 + (ys - cy) ** 2 <= mask_r2
        signal = float(((roi - background) * inside).sum())
        disagreement, streak2 = 0.0, math.nan
    at_edge = x0 == 0 or y0 == 0 or x1 == w or y1 == h
    return Measurement(cx, cy, signal, level, background, at_edge, disagreement, streak2)


def _linear_centroid(roi, x0, y0, cx, cy, radius, blur_px, direction, margin_px=2.5, iterations=2):
    """Centroid of (I − b) in a soft-edged mask around the (blurred) marker, b from a ring just outside.

    Linear in the pixel values, so a partly covered edge pixel counts in proportion to its
    coverage: no pixel locking and no threshold nonlinearity on a blurred streak, and the
    result is the mean position over the exposure. The mask is a capsule along the motion
    (``direction``, unit vector; ``blur_px`` the streak length allowed for) with a one-pixel
    soft edge, so its own centroid moves smoothly with the estimate. ``roi`` starts at image
    pixel (x0, y0); (cx, cy) is the starting estimate in image pixels.

    Returns ``(x, y, streak², signal)`` with streak² = 12 (var_along − var_across) of the
    weights: the squared length of the exposure streak (a disk's own variance is the same in
    both directions), NaN without a direction; signal = Σ (I − b) over the mask, which blur
    does not change. None when nothing stands out.
    """
    if direction is None:
        ux, uy, half_len = 1.0, 0.0, 0.0
    else:
        ux, uy = direction
        half_len = 0.5 * max(blur_px, 0.0)
    r_mask = radius + margin_px
    ring_in, ring_out = r_mask + 1.0, r_mask + 4.0
    # Only the window that the capsule and its ring can reach.
    h, w = roi.shape
    reach_x, reach_y = ring_out + 1.5 + half_len * abs(ux), ring_out + 1.5 + half_len * abs(uy)
    i0, i1 = max(0, int(cy - y0 - reach_y)), min(h, int(cy - y0 + reach_y) + 2)
    j0, j1 = max(0, int(cx - x0 - reach_x)), min(w, int(cx - x0 + reach_x) + 2)
    if i1 - i0 < 3 or j1 - j0 < 3:
        return None
    sub = roi[i0:i1, j0:j1]
    # Coordinates relative to the starting estimate (small numbers: float32 is exact enough).
    ox, oy = cx, cy
    xr = (np.arange(x0 + j0, x0 + j1) - ox).astype(np.float32)
    yr = (np.arange(y0 + i0, y0 + i1) - oy).astype(np.float32)
    ex = ey = 0.0  # current estimate relative to (ox, oy)
    background = None
    for _ in range(iterations):
        u = (xr[None, :] - ex) * ux + (yr[:, None] - ey) * uy  # along the motion
        v = (yr[:, None] - ey) * ux - (xr[None, :] - ex) * uy  # across it
        excess = u - np.clip(u, -half_len, half_len)
        dist = np.sqrt(v * v + excess * excess)
        if background is None:
            ring = (dist > ring_in) & (dist <= ring_out)
            if np.count_nonzero(ring) < 8:
                return None
            background = float(np.median(sub[ring]))
        mask = np.clip(r_mask + 0.5 - dist, 0.0, 1.0, out=dist)
        weight = sub - background
        weight *= mask
        col, row = weight.sum(axis=0), weight.sum(axis=1)
        total = float(col.sum())
        if total <= 0:
            return None
        ex, ey = float(col @ xr) / total, float(row @ yr) / total
    if direction is None:
        return ox + ex, oy + ey, math.nan, total
    # Moments about the last mask centre, within a small fraction of a pixel of the result.
    streak2 = 12.0 * float((weight * (u * u - v * v)).sum()) / total
    return ox + ex, oy + ey, streak2, total


def estimate_exposure_fraction(x, y, streak2, usable, min_step_px: float) -> float | None:
    """Shutter-open fraction of the frame interval: streak length over the frame-to-frame step.

    Median over usable frames whose step exceeds ``min_step_px`` (a short streak is lost
    in the noise of its second moment); None when fewer than 10 such frames.
    """
    x, y, streak2 = (np.asarray(a, float) for a in (x, y, streak2))
    step2 = np.full(x.size, np.nan)
    both = usable[2:] & usable[:-2] & usable[1:-1]
    step2[1:-1] = np.where(both, ((x[2:] - x[:-2]) ** 2 + (y[2:] - y[:-2]) ** 2) / 4.0, np.nan)
    pick = np.isfinite(step2) & np.isfinite(streak2) & (step2 > min_step_px**2)
    if pick.sum() < 10:
        return None
    ratio = np.median(streak2[pick] / step2[pick])
    return float(np.sqrt(np.clip(ratio, 0.0, 1.0)))


def exposure_centre_correction(x, usable, exposure_fraction: float) -> np.ndarray:
    """Correction to add to a blurred marker's centroid to get its position at the frame time.

    The centroid of the exposure is the mean position over the shutter-open time τ
    (in frame intervals), centred on the frame time: x̄ = x(t) + ẍ τ²/24 + O(τ⁴). The
    arc's curvature (x̄ lies inside the circle) and the angular acceleration (x̄ falls
    short of the turning points) both enter through ẍ, here the track's central second
    difference (its noise, ×τ²/24 ≈ 0.01, is negligible). Frames without two usable
    neighbours get no correction.
    """
    x = np.asarray(x, float)
    corr = np.zeros(x.size)
    if x.size < 3:
        return corr
    both = usable[2:] & usable[:-2] & usable[1:-1]
    d2 = x[2:] - 2.0 * x[1:-1] + x[:-2]
    corr[1:-1] = np.where(both, -d2 * exposure_fraction**2 / 24.0, 0.0)
    return corr


def _leave_one_out_weights(half_window: int = 4, degree: int = 3) -> np.ndarray:
    """Weights c_j predicting x_i = Σ c_j x_{i+j} from a cubic through the neighbours (j ≠ 0)."""
    offsets = np.array([j for j in range(-half_window, half_window + 1) if j != 0], float)
    design = np.vander(offsets, degree + 1, increasing=True)
    weights = np.linalg.pinv(design)[0]  # value of the fitted polynomial at offset 0
    full = np.zeros(2 * half_window + 1)
    full[np.arange(2 * half_window + 1) != half_window] = weights
    return full


def flag_jumps(x: np.ndarray, y: np.ndarray, usable: np.ndarray, settings: TrackerSettings) -> np.ndarray:
    """Frames whose position departs from a cubic through their 8 neighbours (isolated jumps)."""
    weights = _leave_one_out_weights()
    half = len(weights) // 2
    jumps = np.zeros(x.size, bool)
    for _ in range(4):
        ok = usable & ~jumps
        xv = np.where(ok, x, np.nan)
        yv = np.where(ok, y, np.nan)
        rx = xv - np.convolve(xv, weights[::-1], mode="same")
        ry = yv - np.convolve(yv, weights[::-1], mode="same")
        resid = np.hypot(rx, ry)
        resid[:half] = resid[-half:] = np.nan
        finite = np.isfinite(resid)
        if finite.sum() < 10:
            break
        sigma = 1.4826 * np.median(np.abs(resid[finite]))
        limit = max(settings.jump_floor_px, settings.jump_sigmas * sigma)
        over = finite & (resid > limit)
        if not over.any():
            break
        # Flag only local maxima: a jump also disturbs its neighbours' predictions.
        padded = np.where(finite, resid, 0.0)
        local_max = over & (padded >= np.maximum(np.roll(padded, 1), np.roll(padded, -1)))
        jumps |= local_max
    return jumps


def track_video(path, settings: TrackerSettings, progress=None, progress_every: int = 200) -> pd.DataFrame:
    """Track the marker through the whole video in one decode pass.

    Columns: ``frame``, ``time_s``, ``x_px``, ``y_px`` (NaN when lost),
    ``quality`` (marker signal relative to normal, 1 = perfect, 0 = lost),
    ``signal_ratio``, ``flag`` (one of :data:`FLAGS`).
    """
    rows = []
    history: list[tuple[int, float, float]] = []  # (frame, x, y) of good frames
    previous = None
    marker_level = None
    signal_ref = None
    signals: list[float] = []
    lost_run = 0
    streak2: dict[int, float] = {}
    started = time.perf_counter()
    n_frames = 0
    for index, t, image in iter_luma(path):
        n_frames = index + 1
        # A repeated frame is identical everywhere; every 8th row tells at 1/8 of the cost.
        rows_sample = image[::8]
        duplicate = previous is not None and np.array_equal(rows_sample, previous)
        previous = rows_sample.copy()
        if not history or lost_run >= settings.reacquire_after_frames:
            near = settings.start_px if not history and settings.start_px is not None else None
            found = acquire_marker(image, settings, near=near, search_radius_px=None if near is None else 60)
            if found is None:
                rows.append((index, t, np.nan, np.nan, 0.0, 0.0, "lost"))
                lost_run += 1
                continue
            guess, speed, direction = (found[0], found[1]), 0.0, None
        else:
            (f1, x1, y1) = history[-1]
            if len(history) >= 2 and history[-2][0] == f1 - 1:
                f0, x0, y0 = history[-2]
                vx, vy = x1 - x0, y1 - y0
            else:
                vx = vy = 0.0
            gap = index - f1
            guess = (x1 + vx * gap, y1 + vy * gap)
            step = math.hypot(vx, vy)
            direction = (vx / step, vy / step) if step > 0 else None
            speed = step + 2.0 * (gap - 1) * settings.marker_radius_px
        m = measure_marker(
            image, guess[0], guess[1], settings, blur_px=speed, marker_level=marker_level, direction=direction
        )
        if m is None:
            rows.append((index, t, np.nan, np.nan, 0.0, 0.0, "lost"))
            lost_run += 1
            continue
        if marker_level is None:
            marker_level = m.level
        if signal_ref is None:
            signals.append(m.signal)
            ratio = 1.0
            if len(signals) >= 5:
                signal_ref = float(np.median(signals))
        else:
            ratio = m.signal / signal_ref
        quality = float(np.clip(min(ratio, 1.0 / ratio) if ratio > 0 else 0.0, 0.0, 1.0))
        if ratio < 0.5:
            flag, x, y, quality = "lost", np.nan, np.nan, 0.0
        elif duplicate:
            flag, x, y = "duplicate", m.x, m.y
        elif m.at_edge:
            flag, x, y = "edge", m.x, m.y
        elif ratio < settings.min_signal_ratio or m.disagreement_px > settings.max_centroid_disagreement_px:
            flag, x, y = "occluded", m.x, m.y
        elif ratio > settings.max_signal_ratio:
            flag, x, y = "glare", m.x, m.y
        else:
            flag, x, y = "ok", m.x, m.y
        if flag == "lost":
            lost_run += 1
        else:
            lost_run = 0
            if flag in ("ok", "edge"):
                history.append((index, x, y))
                del history[:-3]
        rows.append((index, t, x, y, quality, ratio, flag))
        streak2[index] = m.streak2_px2
        if progress and index % progress_every == 0 and index:
            rate = index / (time.perf_counter() - started)
            progress(f"{path}: tracked frame {index} ({rate:.0f} frames/s)")
    table = pd.DataFrame(rows, columns=["frame", "time_s", "x_px", "y_px", "quality", "signal_ratio", "flag"])
    # The first frames set the reference signal; recompute their ratios against it.
    if signal_ref is not None:
        first = table.index[: len(signals)]
        table.loc[first, "signal_ratio"] = np.array(signals) / signal_ref
    usable = (table.flag == "ok").to_numpy()
    jumps = flag_jumps(table.x_px.to_numpy(), table.y_px.to_numpy(), usable, settings)
    table.loc[jumps, "flag"] = "jump"
    exposure = settings.exposure_fraction
    if settings.centroid == "linear" and len(table):
        usable = table.flag.isin(("ok", "edge")).to_numpy()
        if exposure is None:
            s2 = table.frame.map(streak2).to_numpy(float)
            exposure = estimate_exposure_fraction(
                table.x_px, table.y_px, s2, usable, min_step_px=0.5 * settings.marker_radius_px
            )
            if exposure is None:  # too slow to measure (and so to matter much): the 180° shutter rule
                exposure = 0.5
        if exposure:
            table["x_px"] += exposure_centre_correction(table.x_px.to_numpy(), usable, exposure)
            table["y_px"] += exposure_centre_correction(table.y_px.to_numpy(), usable, exposure)
    table.attrs["exposure_fraction"] = exposure
    if progress:
        rate = n_frames / max(time.perf_counter() - started, 1e-9)
        counts = table.flag.value_counts().to_dict()
        progress(f"{path}: tracked {n_frames} frames ({rate:.0f} frames/s); flags {counts}")
    return table
