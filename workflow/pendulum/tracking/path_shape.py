"""The tracked path against one fixed circle: how far it departs, and a creeping pivot.

A point fixed to a pendulum that swings in one plane about a fixed pivot, filmed by a still
camera, stays on one circle. A real clip's path may not: the phone creeps on its stand or
its stabilisation shifts the picture, so the whole scene, pivot included, moves slowly in
the image. That motion is told from the path itself: a circle whose centre moves as a
polynomial in time,

    |p(t) − c(t)| = R,   c(t) = c₀ + Σₖ vₖ τᵏ,   τ = (t − t̄) / T (k = 1 … d, d ≤ 2),

is fitted to the ok frames; each degree is tried in turn and kept where it cuts the best fit's RMS distance
from the circle by at least a fifth and its motion over the clip is at least 0.5 px and 5 standard errors (a
degree that fails does not stop the next: the first 17 s of the apple clip's creep, a line 4.4 standard errors
long, is a parabola of 10 standard errors; 2026-12-02).
A camera knocked once adds a step of the centre (:func:`_knock`); one whose move a creep took in is sought
where the swing's centre in the picture steps (:func:`_centre_step`: moved across the swing, or turned).
The positions are then brought to the camera of mid-clip, p − (c(t) − c₀), so the angle
about the pivot is the swing's. What the moving circle does not explain (a swing out of
the plane, a stretching string, a body that turns off its centre, a camera that moves a
little) is reported, in pixels and as the angle error it allows, never absorbed silently.
"""

from __future__ import annotations

import math

import numpy as np
import pandas as pd

from pendulum.tracking.timing import path_turning_points

MIN_ARC_SPAN_DEG = 5.0  # a path shorter than this says nothing about its circle
MAX_DEGREE = 2
MIN_RMS_GAIN = 0.2  # a higher degree must cut the RMS distance by this fraction
MIN_MOTION_PX = 0.5
MOTION_SIGMAS = 5.0
UNEXPLAINED_NOISE_RATIO = 5.0  # RMS off the (moving) circle above this × the path's noise ...
MIN_DEPARTURE_PX = 0.25  # ... and this: reported as a departure
# Not a pendulum about a fixed point: what no circle explains is more than this fraction of the swing's
# spread along the path (a clean swing: 0.1–0.3 %; a paper star spinning on its thread: 4.6 %), more than
# NOT_CIRCLE_NOISE_RATIO × the noise and more than 1 px
NOT_CIRCLE_SWING_FRACTION = 0.02
NOT_CIRCLE_NOISE_RATIO = 3.0
KNOCK_MARGIN = 30  # ok frames on either side of a step of the camera
KNOCK_PASSES = 4
KNOCK_RMS_RATIO = 3.0  # a step this many times the RMS left without it: a knock, not part of a slow departure
HANDLED_RATIO, HANDLED_MAX_S = 3.0, 5.0  # a side of a knock this many times as far off the circle, this short:
# the camera in the hand (set down after the recording started, or picked up before it stopped)
SETTLE_S = 0.5  # the frames this long after a knock are flagged whatever their distance from the circle (a shake
# along the path does not change it: the reviewer's 7 Hz ring moved θ by up to 0.27° there)
RING_S = 1.0  # a knocked picture shakes for up to this long ...
RING_NOISE, RING_RMS = 4.0, 3.0  # ... its frames off the circle by this × the noise and × the RMS left
# a camera knocked whose move a creep took in: the swing's centre in the picture (gravity's direction there, which a
# turning camera or one moved across the swing moves) steps by at least this, this many standard errors, and leaves
# a smooth curve this many times the misfit of the curve with the step
CENTRE_STEP_DEG, CENTRE_STEP_SIGMAS, CENTRE_STEP_GAIN = 0.1, 6.0, 10.0
CENTRE_STEP_SIDE = 3  # centre pairs on each side of the step
OUT_OF_PLANE_GAIN = 0.5  # the swing's speed terms must halve what the circle leaves to name an elliptical swing,
MAX_OUT_OF_PLANE_SHARE = 0.035  # ... and that be under this share of the swing (a bob circling: 4 %, a 15 % ellipse
# seen from the arm's distance 2.5 %, with a creeping camera 30–50 % ellipses 2.3–3.0 %)


def arc_span_deg(x, y, centre) -> float:
    """The angle the points (x, y) span about ``centre``: the spread of their directions about their mean
    direction, so that a path across the upward vertical (a camera upside down: atan2 wraps at ±180° there) is
    not counted as 360°."""
    direction = np.arctan2(np.asarray(x, float) - centre[0], np.asarray(y, float) - centre[1])
    if not direction.size:
        return 0.0
    mean = math.atan2(float(np.sin(direction).sum()), float(np.cos(direction).sum()))
    return float(np.degrees(np.ptp(np.mod(direction - mean + math.pi, 2 * math.pi) - math.pi)))


def _design(t: np.ndarray, degree: int) -> tuple[np.ndarray, float, float]:
    centre, span = float(np.mean(t)), float(max(np.ptp(t), 1e-9))
    tau = (t - centre) / span
    return np.column_stack([tau ** (k + 1) for k in range(degree)]) if degree else np.zeros((t.size, 0)), centre, span


def _basis(t: np.ndarray, degree: int, step_s: float | None = None) -> np.ndarray:
    """The centre's motion terms at times t: τᵏ (k = 1 … degree) and, with ``step_s``, a step there (a knock)."""
    basis, _, _ = _design(t, degree)
    return basis if step_s is None else np.column_stack([basis, (t >= step_s).astype(float)])


def _fit(x, y, t, degree: int, start, step_s: float | None = None):
    from scipy.optimize import least_squares  # here: the angles job imports arc_span_deg

    basis = _basis(t, degree, step_s)
    k = basis.shape[1]

    def residual(p):
        cx = p[0] + basis @ p[3 : 3 + k]
        cy = p[1] + basis @ p[3 + k : 3 + 2 * k]
        return np.hypot(x - cx, y - cy) - p[2]

    p0 = np.r_[start, np.zeros(2 * k)]
    sol = least_squares(residual, p0, x_scale="jac")
    res = sol.fun
    rho = float(np.clip(np.corrcoef(res[1:], res[:-1])[0, 1], 0.0, 0.99)) if res.size > 3 else 0.0
    n_eff = max(res.size * (1 - rho) / (1 + rho), 2 * k + 4.0)
    sigma2 = float(res @ res) / max(res.size - sol.x.size, 1)
    cov = np.linalg.pinv(sol.jac.T @ sol.jac) * sigma2 * res.size / n_eff
    return sol.x, cov, float(np.sqrt(np.mean(res**2)))


def _motion(params: np.ndarray, cov: np.ndarray, degree: int, t: np.ndarray, step_s=None):
    """The centre's displacement at every t (n×2), its largest extent over the clip (px) and that extent's σ."""
    basis = _basis(t, degree, step_s)
    k = basis.shape[1]
    dx = basis @ params[3 : 3 + k]
    dy = basis @ params[3 + k : 3 + 2 * k]
    shift = np.column_stack([dx, dy])
    extent = np.hypot(*(shift.max(axis=0) - shift.min(axis=0)))
    # σ of the end-to-end displacement (first vs last frame), by the delta method
    ends = basis[-1] - basis[0]
    g = np.zeros((2, params.size))
    g[0, 3 : 3 + k] = ends
    g[1, 3 + k : 3 + 2 * k] = ends
    end_to_end = g @ params
    c = g @ cov @ g.T
    norm = float(np.hypot(*end_to_end))
    sigma = float(math.sqrt(max(end_to_end @ c @ end_to_end, 0.0)) / norm) if norm > 0 else math.inf
    return shift, float(extent), sigma


def _step_gain(x, y, centre: np.ndarray, radius: float) -> np.ndarray:
    """Per frame k, the squared residual a step of the circle's centre after it would remove from the distances of
    the points from a moving ``centre`` (n×2) less ``radius``: a centre moved by Δ changes each later distance by
    −u·Δ (u: the unit vector from the centre), so Δ_k = (Σ u uᵀ)⁻¹ Σ u r over the frames from k, and it removes
    (Σ u r)ᵀ (Σ u uᵀ)⁻¹ (Σ u r) (sums from the end: one pass)."""
    dx, dy = x - centre[:, 0], y - centre[:, 1]
    d = np.hypot(dx, dy)
    ux, uy, r = dx / d, dy / d, d - radius
    terms = np.column_stack([ux * ux, ux * uy, uy * uy, ux * r, uy * r])
    a, b, c, s1, s2 = np.cumsum(terms[::-1], axis=0)[::-1].T  # sums over frames k … n − 1
    det = a * c - b * b
    with np.errstate(divide="ignore", invalid="ignore"):
        return np.where(det > 0, (c * s1 * s1 - 2 * b * s1 * s2 + a * s2 * s2) / det, 0.0)


def _step_time(x, y, t, centre: np.ndarray, radius: float, margin: int, within=None) -> float | None:
    """The time at which a step of the centre best explains the distances (:func:`_step_gain`), at least ``margin``
    frames from either end (None at that margin's edge: a step beyond it, or none), and within ``within`` (s, s)
    where given."""
    if x.size < 2 * margin + 2:
        return None
    gain = _step_gain(x, y, centre, radius)
    gain[:margin] = gain[-margin:] = 0.0
    if within is not None:
        gain[(t < within[0]) | (t > within[1])] = 0.0
    k = int(np.argmax(gain))
    if gain[k] <= 0 or k in (margin, x.size - margin - 1):
        return None
    return 0.5 * (t[k - 1] + t[k])


def _out_of_plane(x, y, t, degree: int, params: np.ndarray, step_s=None) -> float | None:
    """The RMS distance (px) from the circle left where the swing is elliptical, out of the image plane by a share
    of its in-plane swing a quarter period later: the body nears the camera on one half swing and leaves it on
    the other, so its image scales by 1 + Z/D about the camera's axis with Z ∝ θ̇; the whole path then moves and
    its radius changes with the swing's speed. The best circle (its creep and any knock kept) is fitted again with
    its centre and radius each given terms a q + b (q² − ⟨q²⟩), q = θ̇ / SD(θ̇) (q²: the swing's depth seen by a
    far camera). None where θ̇ cannot be formed. On the apple clip made a swing out of plane by 15 % (a camera at
    the arm's distance): 3.40 → 1.01 px; on the paper star spinning on its thread 3.35 → 2.56 px."""
    from scipy.optimize import least_squares

    if x.size < 30 or np.any(np.diff(t) <= 0):
        return None
    centre = _centre(params, t, degree, step_s)
    speed = np.gradient(np.unwrap(np.arctan2(x - centre[:, 0], y - centre[:, 1])), t)
    if not np.std(speed) > 0:
        return None
    q = speed / np.std(speed)
    swing = np.column_stack([q, q**2 - np.mean(q**2)])
    basis = np.column_stack([_basis(t, degree, step_s), swing])
    k, m = basis.shape[1], swing.shape[1]

    def residual(p):
        cx = p[0] + basis @ p[3 : 3 + k]
        cy = p[1] + basis @ p[3 + k : 3 + 2 * k]
        return np.hypot(x - cx, y - cy) - (p[2] + swing @ p[3 + 2 * k :])

    motion = params[3:].reshape(2, -1)
    start = np.r_[params[:3], motion[0], np.zeros(m), motion[1], np.zeros(m), np.zeros(m)]
    return float(np.sqrt(np.mean(least_squares(residual, start, x_scale="jac").fun ** 2)))


def _centre(params: np.ndarray, t: np.ndarray, degree: int, step_s=None, with_step: bool = True) -> np.ndarray:
    """The fitted centre at times t (n×2); without its step where ``with_step`` is False."""
    basis = _basis(t, degree, step_s)
    k = basis.shape[1]
    ax, ay = params[3 : 3 + k].copy(), params[3 + k : 3 + 2 * k].copy()
    if step_s is not None and not with_step:
        ax[-1] = ay[-1] = 0.0
    return np.column_stack([params[0] + basis @ ax, params[1] + basis @ ay])


def _knock(x, y, t, best: tuple, noise_px: float, within=None):
    """A camera knocked once (its stand bumped: the picture jumps and settles): the best fit (``best``, as
    :func:`path_departure` keeps it) with a step of the centre added at :func:`_step_time`, each polynomial
    degree tried again with it. Kept where it cuts the RMS by :data:`MIN_RMS_GAIN`, and the step is at least
    :data:`MIN_MOTION_PX`, :data:`MOTION_SIGMAS` σ and :data:`KNOCK_RMS_RATIO` times the RMS the fit without
    it leaves (a sharp jump, not a share of a slow departure). Returns (best, step time, facts) or None; the
    facts' ``from_s``–``to_s`` are the picture's shaking: from the frame before the step to :data:`SETTLE_S` after
    it, or to the last frame within :data:`RING_S` after it whose distance from the circle is off by more than
    :data:`RING_NOISE` × the noise, :data:`RING_RMS` × the RMS left and 0.3 px. ``within`` (s, s): a knock known to
    lie there from another measure (the swing's centre stepping: :func:`_centre_step`), sought there only and kept
    where it lowers the RMS at all and moves the centre by :data:`MIN_MOTION_PX` (the apple clip's own 0.4 px
    departure can leave a knock's fit within a fifth of the creep's)."""
    fit, step_s = (best[0], best[1], best[2], best[3]), None
    for _ in range(KNOCK_PASSES):  # the step's time, then the fit with it, until the time stays (a creep took part)
        centre = _centre(fit[1], t, fit[0], step_s, False)
        found = _step_time(x, y, t, centre, fit[1][2], KNOCK_MARGIN, within)
        if found is None or found == step_s:
            break
        step_s, fit = found, None
        for degree in range(MAX_DEGREE + 1):
            p, c, r = _fit(x, y, t, degree, best[1][:3], step_s)
            if fit is None or r <= (1 - MIN_RMS_GAIN) * fit[3]:
                fit = (degree, p, c, r)
    if step_s is None:
        return None
    degree, p, c, r = fit
    k = degree + 1
    jump = np.array([p[2 + k], p[2 + 2 * k]])
    size = float(np.hypot(*jump))
    g = jump / size if size > 0 else np.zeros(2)
    sigma = float(math.sqrt(max(g @ c[np.ix_([2 + k, 2 + 2 * k], [2 + k, 2 + 2 * k])] @ g, 0.0)))
    if within is None:  # from the path alone: a sharp jump that clearly explains more than the creep
        kept = r <= (1 - MIN_RMS_GAIN) * best[3] and size >= max(
            MIN_MOTION_PX, MOTION_SIGMAS * sigma, KNOCK_RMS_RATIO * best[3]
        )
    else:  # the swing's centre says a knock happened there: the path only places and sizes its move
        kept = r < best[3] and size >= MIN_MOTION_PX
    if not kept:
        return None
    centre = _centre(p, t, degree, step_s)
    residual = np.hypot(x - centre[:, 0], y - centre[:, 1]) - p[2]
    off = max(RING_NOISE * noise_px, RING_RMS * r, 0.3)
    after = (t >= step_s) & (t <= step_s + RING_S) & (np.abs(residual) > off)
    # when the step may have been (3σ): a step along the path shows only where the path turns away from it
    gain = _step_gain(x, y, _centre(p, t, degree, step_s, False), p[2])
    may = t[gain >= gain.max() - 9 * r * r]
    start, end = min(float(may[0]), step_s), max(float(may[-1]), step_s)
    before = t[t < start]
    facts = {
        "time_s": round(float(step_s), 4),
        "shift_px": [round(float(jump[0]), 3), round(float(jump[1]), 3)],
        "stderr_px": round(sigma, 3),
        "from_s": round(float(before[-1]) if before.size else start, 4),
        "to_s": round(max(float(t[after][-1]) if after.any() else step_s, end + SETTLE_S), 4),
    }
    # a camera in the hand before it was set down (or after it was picked up): that side alone is farther off the
    # circle than a pendulum's path can be (NOT_CIRCLE_SWING_FRACTION of the swing, over 5 frames' means), and the
    # other side keeps to it (a side merely farther off, a larger swing's departure or noise, is no hand: a
    # reviewer's decaying swings)
    smooth = np.convolve(residual, np.ones(5) / 5, mode="same")  # a hand's shake stays, frame-to-frame noise less
    sides = (t < step_s, t > facts["to_s"])
    rms = [_rms(smooth[side]) for side in sides]
    swing_px = _swing_sd(x, y)
    for near, name, edge in ((0, "before", "from_s"), (1, "after", "to_s")):
        span = step_s - t[0] if near == 0 else t[-1] - facts["to_s"]
        far = rms[1 - near]
        if span <= HANDLED_MAX_S and rms[near] > max(
            HANDLED_RATIO * max(far, noise_px), NOT_CIRCLE_SWING_FRACTION * swing_px
        ):
            facts.update({"handled": name, edge: round(float(t[0] if near == 0 else t[-1]), 4)})
            break
    return (degree, p, c, r, _motion(p, c, degree, t, step_s)), step_s, facts


def _centre_step(x, y, t, centre) -> dict | None:
    """A step of the swing's centre in the picture about a fixed ``centre``: the camera knocked, moved across the
    swing or turned (a turn about the lens's axis moves the path along its circle, which the circle cannot show),
    its move taken for part of a creep.

    The swing's centre from each three turning points p₀, q, p₁ (their angles about ``centre``; locally geometric
    decay: c = (p₀ p₁ − q²) / (p₀ + p₁ − 2q), as ``pendulum.angles.swings.swing_centres`` has it for θ, which this
    stage cannot import: the angles come after it), averaged in pairs, against time: a quadratic (a camera creeping
    turns the picture slowly too) and a step, the up to three pairs that straddle it (a pair spans about three half
    swings) left out, at the split that fits best. Kept where the step is at least :data:`CENTRE_STEP_DEG` and
    :data:`CENTRE_STEP_SIGMAS` σ and the quadratic alone leaves :data:`CENTRE_STEP_GAIN` × its misfit per degree of
    freedom. Returns ``from_s``/``to_s`` (the last pair before and the first after), ``step_deg``, ``stderr_deg``."""
    times, _, points = path_turning_points(t, x, y)
    if times.size < 2 * CENTRE_STEP_SIDE + 6:
        return None
    phi = np.unwrap(np.arctan2(points[:, 0] - centre[0], points[:, 1] - centre[1]))
    p0, q, p1 = phi[:-2], phi[1:-1], phi[2:]
    with np.errstate(divide="ignore", invalid="ignore"):
        centres = (p0 * p1 - q * q) / (p0 + p1 - 2 * q)
    at = 0.5 * (times[1:-2] + times[2:-1])
    values = 0.5 * (centres[1:] + centres[:-1])
    usable = np.isfinite(values)
    at, values = at[usable], values[usable]
    n = values.size
    if n < 2 * CENTRE_STEP_SIDE + 4:
        return None
    tau = (at - at.mean()) / max(float(np.ptp(at)), 1e-9)
    smooth = np.column_stack([np.ones(n), tau, tau**2])

    def misfit(design, keep):
        coef, *_ = np.linalg.lstsq(design[keep], values[keep], rcond=None)
        resid = values[keep] - design[keep] @ coef
        return coef, float(resid @ resid) / max(int(keep.sum()) - design.shape[1], 1)

    _, plain = misfit(smooth, np.ones(n, bool))
    best = None
    for j in range(CENTRE_STEP_SIDE, n - CENTRE_STEP_SIDE):
        for gap in range(4):
            if n - j - gap < CENTRE_STEP_SIDE:
                break
            keep = np.ones(n, bool)
            keep[j : j + gap] = False
            design = np.column_stack([smooth, (np.arange(n) >= j + gap).astype(float)])
            coef, per = misfit(design, keep)
            if best is None or per < best[0]:
                best = (per, coef, design, keep, j, gap)
    per, coef, design, keep, j, gap = best
    stderr = math.sqrt(max(per * float(np.linalg.pinv(design[keep].T @ design[keep])[3, 3]), 0.0))
    step = float(coef[3])
    if not (
        abs(step) >= max(math.radians(CENTRE_STEP_DEG), CENTRE_STEP_SIGMAS * stderr)
        and plain >= CENTRE_STEP_GAIN * max(per, 1e-18)
    ):
        return None
    return {
        "from_s": round(float(at[j - 1]), 4),
        "to_s": round(float(at[j + gap]), 4),
        "step_deg": round(math.degrees(step), 4),
        "stderr_deg": round(math.degrees(stderr), 4),
    }


def _swing_sd(x: np.ndarray, y: np.ndarray) -> float:
    """The path's SD along its main direction (px)."""
    along = np.column_stack([x, y]) - np.column_stack([x, y]).mean(axis=0)
    return float(np.sqrt(np.linalg.eigvalsh(np.cov(along.T))[-1]))


def _rms(values: np.ndarray) -> float:
    return float(np.sqrt(np.mean(values**2))) if values.size else 0.0


def path_departure(track: pd.DataFrame, noise_px: float | None = None) -> tuple[pd.DataFrame, dict]:
    """Measure the path's departure from one circle and correct a creeping pivot (module docstring).

    Returns the track (``x_px``, ``y_px`` corrected when a creep is found; the image positions kept
    in ``x_image_px``, ``y_image_px``) and a document: ``circle_rms_px`` (fixed circle),
    ``creep`` (``degree``, ``motion_px`` over the clip, ``motion_stderr_px``, ``start_to_end_px``,
    ``rms_after_px``, ``corrected``), ``unexplained_rms_px`` and ``unexplained_angle_deg``
    (what no circle explains, as an angle on the arm), ``noise_px`` and a ``verdict`` sentence.
    """
    ok = (track.flag == "ok").to_numpy() & track.x_px.notna().to_numpy() & track.y_px.notna().to_numpy()
    x = track.x_px.to_numpy(float)[ok]
    y = track.y_px.to_numpy(float)[ok]
    t = track.time_s.to_numpy(float)[ok]
    out = track.copy()
    if x.size < 30:
        return out, {"verdict": "too few ok frames to judge the path's shape", "corrected": False}
    if noise_px is None:  # frame-to-frame noise from third differences of the positions
        d3 = np.diff(np.column_stack([x, y]), 3, axis=0)
        noise_px = float(1.4826 * np.median(np.abs(d3)) / math.sqrt(20)) if d3.size else 0.0
    a = np.column_stack([x, y, np.ones_like(x)])
    (c0, c1, c2), *_ = np.linalg.lstsq(a, x**2 + y**2, rcond=None)
    start = [c0 / 2, c1 / 2, math.sqrt(max(c2 + (c0 / 2) ** 2 + (c1 / 2) ** 2, 1e-9))]
    params, cov, rms = _fit(x, y, t, 0, start)
    span = arc_span_deg(x, y, params[:2])
    document = {"circle_rms_px": round(rms, 4), "noise_px": round(noise_px, 4), "arc_span_deg": round(span, 2)}
    best = (0, params, cov, rms, None)
    # a creeping pivot is told from a path that spans enough of its circle
    for degree in range(1, MAX_DEGREE + 1 if span >= MIN_ARC_SPAN_DEG else 1):
        p, c, r = _fit(x, y, t, degree, best[1][:3])
        shift, extent, sigma = _motion(p, c, degree, t)
        if r > (1 - MIN_RMS_GAIN) * best[3] or extent < MIN_MOTION_PX or extent < MOTION_SIGMAS * sigma:
            continue  # the next degree is tried against the best so far (a creep that turns back is no line)
        best = (degree, p, c, r, (shift, extent, sigma))
    knock = _knock(x, y, t, best, noise_px) if span >= MIN_ARC_SPAN_DEG else None
    turned = None
    if knock is None and best[0] > 0 and span >= MIN_ARC_SPAN_DEG:
        turned = _centre_step(x, y, t, params[:2])  # a knock a creep took in, told by the swing's centre
        if turned is not None:
            knock = _knock(x, y, t, best, noise_px, (turned["from_s"], turned["to_s"]))
    if knock is not None:
        best, step_s, step = knock
    else:
        step_s, step = None, None
    degree, params, cov, rms_after, motion = best
    radius = float(params[2])
    creep = {"degree": degree, "corrected": degree > 0 or step is not None, "rms_after_px": round(rms_after, 4)}
    if motion is not None:
        shift, extent, sigma = motion
        creep.update(
            motion_px=round(extent, 3),
            motion_stderr_px=round(sigma, 3),
            start_to_end_px=[round(float(shift[-1, 0] - shift[0, 0]), 3), round(float(shift[-1, 1] - shift[0, 1]), 3)],
        )
        basis = _basis(track.time_s.to_numpy(float), degree, step_s)
        k = basis.shape[1]
        out["x_image_px"] = track.x_px
        out["y_image_px"] = track.y_px
        out["x_px"] = track.x_px.to_numpy(float) - basis @ params[3 : 3 + k]
        out["y_px"] = track.y_px.to_numpy(float) - basis @ params[3 + k : 3 + 2 * k]
    if step is not None:
        if turned is not None:  # found where the swing's centre stepped
            step["centre_step"] = turned
        creep["knock"] = step
        ringing = (track.time_s >= step["from_s"]) & (track.time_s <= step["to_s"]) & (track.flag == "ok")
        out.loc[ringing, "flag"] = "jump"  # the picture still shaking: off the swing's path, not the swing
        timing = track.attrs.get("timing") or {}
        frames = track.frame.to_numpy() if "frame" in track else np.arange(len(track))
        at = dict(zip(frames.tolist(), track.time_s.to_numpy(float).tolist(), strict=True))
        knocked = [f for f in timing.get("unexplained") or [] if step["from_s"] <= at.get(f, -1.0) <= step["to_s"]]
        if knocked:  # a break in the track's timing the knock explains (timing.find_slips saw the jump)
            rest = [f for f in timing["unexplained"] if f not in knocked]
            out.attrs["timing"] = {**timing, "unexplained": rest, "knocked": knocked}
        if step.get("handled"):  # the frames of a camera in the hand flagged: the path again without them
            out = out.drop(columns=["x_image_px", "y_image_px"], errors="ignore")
            out["x_px"], out["y_px"] = track.x_px, track.y_px
            again, document = path_departure(out, noise_px)
            document["handled"] = step
            flagged = int((again.flag != track.flag).sum())
            (sx, sy), when = step["shift_px"], step["time_s"]
            span = f"to {step['to_s']:.2f} s" if step["handled"] == "before" else f"from {step['from_s']:.2f} s"
            held = "until it was set down" if step["handled"] == "before" else "from when it was picked up"
            document["verdict"] = (
                f"the camera was in the hand {held} at {when:.2f} s (the picture jumped by ({sx:+.1f}, {sy:+.1f}) px "
                f"and shook off the swing's circle): its {flagged} frames {span} are flagged jump; "
                + document["verdict"]
            )
            return again, document
    unexplained = rms_after
    document.update(
        creep=creep,
        corrected=bool(creep["corrected"]),
        radius_px=round(radius, 3),
        unexplained_rms_px=round(unexplained, 4),
        unexplained_angle_deg=round(math.degrees(unexplained / radius), 4) if radius > 0 else None,
    )
    parts = [f"the path sits {rms:.2f} px RMS off one fixed circle (noise {noise_px:.3f} px)"]
    if step is not None:
        (sx, sy), flagged = step["shift_px"], int((out.flag != track.flag).sum())
        parts.append(
            f"the pivot jumped by ({sx:+.1f}, {sy:+.1f}) px in the picture at {step['time_s']:.2f} s (± "
            f"{step['stderr_px']:.1f} px: the camera knocked or slid, or the thread slipping at the pivot), "
            f"corrected, and the {flagged} frames of its shaking to "
            f"{step['to_s']:.2f} s are flagged jump"
            + ("" if degree else f": {rms_after:.2f} px RMS after")
            + (
                f" (found where the swing's centre in the picture stepped by {turned['step_deg']:+.2f}° between "
                f"{turned['from_s']:.1f} and {turned['to_s']:.1f} s: a creep had taken it in)"
                if turned is not None
                else ""
            )
        )
    if degree:
        dx, dy = creep["start_to_end_px"]
        if step is not None:  # the creep alone
            dx, dy = dx - step["shift_px"][0], dy - step["shift_px"][1]
        parts.append(
            f"the pivot moves by ({dx:+.1f}, {dy:+.1f}) px from the first to the last frame (camera or stand "
            f"creeping; ± {creep['motion_stderr_px']:.1f} px), corrected: {rms_after:.2f} px RMS after"
        )
    swing_px = _swing_sd(x, y)
    document["swing_sd_px"] = round(swing_px, 3)
    below = float(np.median(y)) < float(params[1])  # the circle's centre lies below the body
    not_circle = (
        unexplained > NOT_CIRCLE_SWING_FRACTION * swing_px
        and unexplained > NOT_CIRCLE_NOISE_RATIO * noise_px
        and unexplained > 1.0
    )
    if not_circle:  # an elliptical swing: what the swing's speed explains is a pendulum's, seen out of plane
        left = _out_of_plane(x, y, t, degree, params, step_s)
        if (
            left is not None
            and left <= OUT_OF_PLANE_GAIN * unexplained
            and unexplained <= MAX_OUT_OF_PLANE_SHARE * swing_px
        ):
            document["out_of_plane"] = {"rms_left_px": round(left, 4)}
            not_circle = left > NOT_CIRCLE_SWING_FRACTION * swing_px
    document["not_a_pendulum"] = bool(not_circle)
    if not_circle:
        document["verdict"] = (
            "not a rigid pendulum about a fixed pivot (an object that spins or twists on its thread, a swing far out "
            "of the image plane, a camera held in the hand or shaken, or the wrong object followed): the tracked "
            f"object does not move on a circle about a fixed point; its path sits {unexplained:.1f} px "
            f"RMS off the best circle{' about a moving pivot' if creep['corrected'] else ''}, "
            f"{100 * unexplained / swing_px:.1f} % of its swing ({swing_px:.0f} px SD along the path; noise "
            f"{noise_px:.2f} px; a rigid pendulum's path, a creeping camera allowed for, stays under "
            f"{100 * NOT_CIRCLE_SWING_FRACTION:.0f} %)" + (", and that circle's centre lies below it" if below else "")
        )
        return out, document
    if unexplained > max(UNEXPLAINED_NOISE_RATIO * noise_px, MIN_DEPARTURE_PX):
        parts.append(
            f"{unexplained:.2f} px RMS ({document['unexplained_angle_deg']:.3f}° on the {radius:.0f} px arm) is not a "
            "circle about a fixed or creeping pivot: a swing out of the image plane, a stretching string, a body "
            "turning off its centre, or a camera that moves a little (held in the hand: its stabilisation leaves some "
            "of it; a plain wall does not show it); the angle record carries it"
        )
        document["departs"] = True
        if "out_of_plane" in document:
            left = document["out_of_plane"]["rms_left_px"]
            parts[-1] = (
                f"{unexplained:.2f} px RMS ({document['unexplained_angle_deg']:.3f}° on the {radius:.0f} px arm) is "
                "not a circle about a fixed or creeping pivot, and most of it follows the swing's speed "
                f"({left:.2f} px RMS left where the circle moves and scales with it): "
                "an elliptical swing, out of the image plane, the body nearing the camera on one half swing and "
                "leaving it on the other (or a string that stretches with the swing); its angles are the swing's "
                "projection on the picture: the period holds, but its amplitudes, and the coefficients that depend on "
                "them, may be biased beyond this, as its pivot is (release the body without a sideways push; film "
                "square-on, from farther away)"
            )
    else:
        document["departs"] = False
    document["verdict"] = "; ".join(parts)
    return out, document


def rest_place_area_ratio(track: pd.DataFrame) -> float | None:
    """The body's median covered area (``quality``) in the ``ok`` frames of the middle quarter of its path over
    that in the outer quarters (positions projected on the path's main direction), None with < 20 frames.

    A scene that holds the body at its rest place (a narrow swing: it is there in most samples) leaves only
    the part of the body outside that ghost in the silhouette mid-swing: the ratio falls well below 1 (0.6–0.85
    on renders of clock bobs swinging ±1.2–1.3 of their diameter), and the positions are pulled outwards.
    Motion blur, fastest mid-swing, lowers it a little (0.96 on the apple clip, 0.96–1.02 on the body study's renders).
    """
    ok = (track.flag == "ok").to_numpy()
    if ok.sum() < 20:
        return None
    xy = track.loc[ok, ["x_px", "y_px"]].to_numpy(float)
    centred = xy - np.median(xy, axis=0)
    _, _, axes = np.linalg.svd(centred - centred.mean(axis=0), full_matrices=False)
    along = np.abs(centred @ axes[0])
    reach = float(np.percentile(along, 95))
    area = track.quality.to_numpy(float)[ok]
    middle, ends = along <= 0.25 * reach, along >= 0.75 * reach
    if middle.sum() < 5 or ends.sum() < 5 or reach <= 0:
        return None
    return float(np.median(area[middle]) / np.median(area[ends]))
