"""The clip's clock read from its frames' time stamps: the frame interval, frames the camera lost, a variable
frame rate, and stamps rounded to the container's time base.

A container stores each frame's presentation time in ticks of its time base. Where that tick does not divide
the frame period (59.94 fps in milliseconds, as Matroska/WebM and some muxers store them, or in an iPhone's
1/600 s) the stamps of a constant-rate camera step by two neighbouring tick counts (16 and 17 ms): each stamp
is the frame's time rounded, off by up to half a tick (0.5 ms: 0.03° at mid-swing of a 20° swing of 2 s), and
the median step is not the frame period. Stamps that lie within their rounding of one regular clock,
t_k = c + P n_k (n_k the frame's slot, counting lost frames; c and P fitted, so ¾ of a tick is allowed), are taken
as that clock; stamps that do not (a phone's variable frame rate) keep their own times.
"""

from __future__ import annotations

import numpy as np

IRREGULAR_INTERVAL = 0.1  # an interval more than this fraction of the median off a whole multiple of it
VARIABLE_RATE_FRACTION = 0.02  # more irregular intervals than this (and ≥ 3): a variable frame rate
ROUNDING_TOLERANCE = 0.75  # rounding steps: stamps within this of one regular clock (a least-squares line: more than
# the 0.5 of the true clock where few steps are long) are that clock, rounded


def regular_times(stamp_s: np.ndarray) -> tuple[np.ndarray, float] | None:
    """The regular clock that stamps ``stamp_s`` (seconds from the first frame, in order) round: ``(times from the
    first frame, the rounding step q in s)``, where their steps take two lengths one q apart (16 and 17 ms; q to
    the stamps' precision, a muxer may store milliseconds in finer ticks), every stamp is a whole number of q, and
    every stamp lies within :data:`ROUNDING_TOLERANCE` q of c + P n_k (n_k: the frame's slot; a lost frame leaves a
    slot empty; c and P fitted); else None (even stamps need nothing; uneven ones are a variable frame rate)."""
    stamp_s = np.asarray(stamp_s, float)
    steps = np.diff(stamp_s)
    if steps.size < 10 or not np.all(np.isfinite(stamp_s)) or np.any(steps <= 0):
        return None
    typical = float(np.median(steps))
    regular = steps[np.abs(steps - typical) <= 0.5 * typical]
    values = np.unique(np.round(regular, 9))
    if values.size != 2:
        return None
    step = float(regular.sum() / np.rint(regular / (values[1] - values[0])).sum())  # to the stamps' precision
    ticks = (stamp_s - stamp_s[0]) / step
    if np.abs(ticks - np.rint(ticks)).max() > 1e-3:
        return None
    pts = np.rint(ticks)
    slot = np.rint(pts / float(np.rint(regular / step).mean()))
    period, offset = np.polyfit(slot, pts, 1)
    times = offset + period * slot
    if np.abs(pts - times).max() > ROUNDING_TOLERANCE:
        return None
    return (times - times[0]) * step, step


def read_clock(time_s: np.ndarray, stated_rates: list[float], path) -> tuple[dict, list[str]]:
    """The clock of frames shown at ``time_s`` (from the first shown frame): ``interval`` per frame (NaN for the
    first), ``frame_interval`` (the median interval), ``irregular`` (more than 10 % off a whole number of frame
    intervals), ``variable`` (more than 2 % irregular, and at least 3), ``dropped`` (frames missing before each
    one: an interval ≥ 1.5 frame intervals; constant frame rate only) and the warnings to give."""
    warnings = []
    interval = np.diff(time_s, prepend=np.nan)
    positive = interval[np.isfinite(interval) & (interval > 0)]
    frame_interval = float(np.median(positive)) if positive.size else 1.0 / stated_rates[0]
    with np.errstate(invalid="ignore", divide="ignore"):
        multiple = interval / frame_interval
        irregular = np.isfinite(multiple) & (multiple > 0) & (np.abs(multiple - np.rint(multiple)) > IRREGULAR_INTERVAL)
        irregular |= np.isfinite(multiple) & (multiple > 0) & (np.rint(multiple) == 0)
    n_irregular = int(irregular.sum())
    variable = n_irregular >= 3 and n_irregular > VARIABLE_RATE_FRACTION * max(1, positive.size)
    if variable:
        dropped = np.zeros(time_s.size, int)
        warnings.append(
            f"{path}: variable frame rate: frame intervals {positive.min() * 1e3:.1f}–{positive.max() * 1e3:.1f} ms "
            f"(median {frame_interval * 1e3:.1f} ms, {n_irregular} irregular); every frame keeps its own timestamp "
            "and no frames are counted as dropped"
        )
    else:
        with np.errstate(invalid="ignore"):
            dropped = np.where(interval >= 1.5 * frame_interval, np.rint(interval / frame_interval) - 1, 0)
        dropped = np.nan_to_num(dropped).astype(int)
        if positive.size and all(abs(frame_interval * r - 1) > 0.01 for r in stated_rates):
            warnings.append(
                f"{path}: the container states {stated_rates[0]:.3f} fps but the frames come every "
                f"{frame_interval * 1e3:.2f} ms ({1 / frame_interval:.3f} fps); the timestamps are used"
            )
    clock = {
        "interval": interval,
        "frame_interval": frame_interval,
        "irregular": irregular,
        "variable": bool(variable),
        "dropped": dropped,
    }
    return clock, warnings
