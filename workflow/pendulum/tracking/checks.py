"""What a finished track's motion tells: the exposure time from the streaks, the position at the frame
time, isolated jumps, and samples that leave their running median.

The exposure's centroid is the mean position over the shutter-open time τ (in frame intervals),
x̄ = x(t) + ẍ τ²/24 + O(τ⁴); a jump is a position farther from a cubic through its eight
neighbours than max(floor, k σ), σ the robust spread of those leave-one-out residuals.
"""

from __future__ import annotations

import math
from typing import TYPE_CHECKING

import numpy as np
from scipy.ndimage import label, maximum_filter1d, median_filter

if TYPE_CHECKING:
    from pendulum.tracking.settings import TrackerSettings

JUMP_HALF_WINDOW = 4  # neighbours on either side in the jump test's leave-one-out cubic (:func:`flag_jumps`)
STILL_PX = 1.5  # median step (px per frame) of a body held still: a hand trembles (±0.6 px in the hand variants)
OFF_SIZE_ALONE = 0.02  # of a body's usable samples off its usual size with no flag beside: its size varies by itself


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


def _leave_one_out_weights(half_window: int = JUMP_HALF_WINDOW, degree: int = 3) -> np.ndarray:
    """Weights c_j predicting x_i = Σ c_j x_{i+j} from a cubic through the neighbours (j ≠ 0)."""
    offsets = np.array([j for j in range(-half_window, half_window + 1) if j != 0], float)
    design = np.vander(offsets, degree + 1, increasing=True)
    weights = np.linalg.pinv(design)[0]  # value of the fitted polynomial at offset 0
    full = np.zeros(2 * half_window + 1)
    full[np.arange(2 * half_window + 1) != half_window] = weights
    return full


def _fill_gap_residuals(
    resid: np.ndarray, x: np.ndarray, y: np.ndarray, ok: np.ndarray, half: int, where: np.ndarray
) -> None:
    """Leave-one-out residuals for usable frames next to unusable ones (where the fixed stencil has a hole).

    The same prediction, a polynomial through the usable neighbours within ±half
    frames (cubic with ≥ 6 of them, quadratic with 4–5), evaluated at the frame,
    its residual scaled to the full stencil's noise; only frames in ``where``,
    and frames with fewer usable neighbours stay unchecked.
    """
    full_noise2 = float(np.sum(_leave_one_out_weights(half) ** 2))
    for i in np.flatnonzero(ok & ~np.isfinite(resid) & where):
        offsets = np.array([j for j in range(-half, half + 1) if j and 0 <= i + j < x.size and ok[i + j]])
        if offsets.size < 4:
            continue
        degree = 3 if offsets.size >= 6 else 2
        design = np.vander(offsets.astype(float), degree + 1, increasing=True)
        weights = np.linalg.pinv(design)[0]
        # scaled to the full stencil's noise: a sparser prediction is noisier
        scale = math.sqrt((1 + full_noise2) / (1 + float(weights @ weights)))
        resid[i] = scale * math.hypot(x[i] - weights @ x[i + offsets], y[i] - weights @ y[i + offsets])


def frame_slots(time_s: np.ndarray | None) -> np.ndarray | None:
    """Each frame's slot on the clip's even frame clock, where its time stamps leave gaps of whole frames (a
    phone's dropped frames, its true times kept: a gap over 1.5 median intervals): each step's whole frames on the
    median interval, then slot k at t₀ + k Δt fitted to them. None where there is no gap, or where the times do not
    fall on one clock (a step not near whole frames, a frame off its slot by over a quarter interval, over half the
    clock's frames missing): the frame's index is its place then."""
    if time_s is None or len(time_s) < 3:
        return None
    t = np.asarray(time_s, float)
    steps = np.diff(t)
    period = float(np.median(steps))
    if not (period > 0 and np.all(np.isfinite(t)) and (steps > 1.5 * period).any()):
        return None
    # each step's whole frames, then the clock fitted to them (a median over steps that skip frames runs long, and
    # its error grows along the clip: a phone's stamps jittered by ±0.5 ms lost their slots in most clips)
    frames = np.rint(steps / period)
    if np.any(frames < 1) or np.any(np.abs(steps - frames * period) > 0.25 * period):
        return None
    slots = np.concatenate([[0.0], np.cumsum(frames)])
    if slots[-1] + 1 > 2 * t.size:  # over half the clock's frames missing: no clock (a stray stamp far out)
        return None
    start, period = np.polynomial.polynomial.polyfit(slots, t, 1)
    if np.max(np.abs(t - start - slots * period)) > 0.25 * period:
        return None
    return slots.astype(np.intp)


def flag_jumps(
    x: np.ndarray, y: np.ndarray, usable: np.ndarray, settings: TrackerSettings, time_s: np.ndarray | None = None
) -> np.ndarray:
    """Frames whose position departs from a cubic through their 8 neighbours (isolated jumps). Given ``time_s``,
    a clip whose frames were dropped (gaps of whole frames, :func:`frame_slots`) is judged on its frame clock, a
    dropped frame a hole the sparser stencil steps over: across a gap, the index's stencil flagged good frames
    beside it (a fresh-eyes user's phone clip with 24 dropped frames: 20 good frames flagged, 2026-12-07)."""
    slots = frame_slots(time_s)
    if slots is not None:
        n = int(slots[-1]) + 1
        x_slot, y_slot = np.full(n, np.nan), np.full(n, np.nan)
        usable_slot = np.zeros(n, bool)
        x_slot[slots], y_slot[slots], usable_slot[slots] = x, y, usable
        return flag_jumps(x_slot, y_slot, usable_slot, settings)[slots]
    weights = _leave_one_out_weights()
    half = len(weights) // 2
    jumps = np.zeros(x.size, bool)
    window = 2 * half + 1
    # Frames beside lost/flagged ones are checked with a sparser stencil, but not frames beside a
    # jump found here: that would cascade through a genuinely abrupt motion (the release).
    near_gap = maximum_filter1d((~usable).astype(np.uint8), window) > 0
    for _ in range(4):
        ok = usable & ~jumps
        xv = np.where(ok, x, np.nan)
        yv = np.where(ok, y, np.nan)
        rx = xv - np.convolve(xv, weights[::-1], mode="same")
        ry = yv - np.convolve(yv, weights[::-1], mode="same")
        resid = np.hypot(rx, ry)
        near_jump = maximum_filter1d(jumps.astype(np.uint8), window) > 0
        _fill_gap_residuals(resid, xv, yv, ok, half, near_gap & ~near_jump)
        resid[:half] = resid[-half:] = np.nan
        finite = np.isfinite(resid)
        if finite.sum() < 10:
            break
        sigma = 1.4826 * np.median(np.abs(resid[finite]))
        limit = max(settings.jump_floor_px, settings.jump_sigmas * sigma)
        over = finite & (resid > limit)
        if not over.any():
            break
        # Flag only the largest within ±half frames: a jump also disturbs its neighbours'
        # predictions (most beside a gap, where the stencil extrapolates); the next pass sees the rest.
        padded = np.where(finite, resid, 0.0)
        local_max = over & (padded >= maximum_filter1d(padded, window, mode="constant"))
        jumps |= local_max
    return jumps


def robust_outliers(values: np.ndarray, usable: np.ndarray, window: int, sigmas: float, floor: float) -> np.ndarray:
    """Samples that depart from their running median by more than ``sigmas`` robust σ of the series and ``floor``."""
    out = np.zeros(values.size, bool)
    if usable.sum() < 10:
        return out
    idx = np.flatnonzero(usable)
    filled = np.interp(np.arange(values.size), idx, values[idx])
    running = median_filter(filled, size=window, mode="nearest")
    dev = values - running
    spread = 1.4826 * np.median(np.abs(dev[usable]))
    return usable & (np.abs(dev) > max(sigmas * spread, floor))


def held_still_runs(area_ratio: np.ndarray, x: np.ndarray, y: np.ndarray, above: float, still_px: float) -> np.ndarray:
    """The record's leading and trailing runs of frames whose silhouette is over ``above`` times the body's own
    area (what holds it adds to it) while it stays still (median step ≤ ``still_px``): a hand before the release, or
    one that catches it, with only its fingers in view. A run ends where three frames in a row show the body at
    its own size (a frame without a body, or a dip of one or two, does not end it); one with fewer than 3 frames
    over, or one that moves, is none."""
    n = area_ratio.size
    seen = np.isfinite(area_ratio) & np.isfinite(x) & np.isfinite(y)
    over = seen & (area_ratio > above)
    at_size = (seen & ~over).astype(int)
    step = np.hypot(np.diff(x, prepend=np.nan), np.diff(y, prepend=np.nan))
    held = np.zeros(n, bool)
    for forward in (True, False):
        three = np.flatnonzero(np.convolve(at_size if forward else at_size[::-1], np.ones(3, int), "valid") == 3)
        length = int(three[0]) if three.size else n
        run = np.arange(length) if forward else np.arange(n - length, n)
        steps = step[run[1:]]
        steps = steps[np.isfinite(steps)]
        if over[run].sum() >= 3 and steps.size and float(np.median(steps)) <= still_px:
            held[run] = True
    return held


def grown_runs(
    doubted: np.ndarray, area_ratio: np.ndarray, usable: np.ndarray, typical: float, reach: int
) -> np.ndarray:
    """``doubted`` (flags for the body's size) grown to the ``usable`` samples within ``reach`` samples of one of them,
    in a run of consecutive samples whose area is off the body's own by more than ``typical`` times (either way)
    that holds one of them (hysteresis): a merge with a shadow or a hand comes and goes over a few frames, and the
    samples beside those over the limit are off by nearly as much (an apple whose shadows met a dark band at one end
    of its swing, seed 7170 of the body study: up to 4 frames from the flagged ones, 1.24–1.49 times its area,
    9–17 px off, were left usable). Not where the body is off that size by itself in over :data:`OFF_SIZE_ALONE` of
    its usable samples (runs that hold none of them: a two-tone ball turning on its string, whose visible part
    changes for seconds at a time; grown, the real clip's turning ball lost 13–16 % of its frames)."""
    with np.errstate(invalid="ignore", divide="ignore"):
        off_size = usable & ((area_ratio > typical) | (area_ratio < 1 / typical))
    runs, _ = label(doubted | off_size)
    with_doubt = np.isin(runs, np.unique(runs[doubted & (runs > 0)]))
    if (off_size & ~with_doubt).sum() > OFF_SIZE_ALONE * max(usable.sum(), 1):
        return doubted
    return doubted | (with_doubt & (maximum_filter1d(doubted.astype(np.uint8), 2 * reach + 1) > 0))
