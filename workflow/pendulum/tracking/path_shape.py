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
The positions are then brought to the camera of mid-clip, p − (c(t) − c₀), so the angle
about the pivot is the swing's. What the moving circle does not explain (a swing out of
the plane, a stretching string, a body that turns off its centre) is reported, in pixels
and as the angle error it allows, never absorbed silently.
"""

from __future__ import annotations

import math

import numpy as np
import pandas as pd

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


def _fit(x, y, t, degree: int, start):
    from scipy.optimize import least_squares  # here: the angles job imports arc_span_deg

    basis, _, _ = _design(t, degree)

    def residual(p):
        cx = p[0] + basis @ p[3 : 3 + degree]
        cy = p[1] + basis @ p[3 + degree : 3 + 2 * degree]
        return np.hypot(x - cx, y - cy) - p[2]

    p0 = np.r_[start, np.zeros(2 * degree)]
    sol = least_squares(residual, p0, x_scale="jac")
    res = sol.fun
    rho = float(np.clip(np.corrcoef(res[1:], res[:-1])[0, 1], 0.0, 0.99)) if res.size > 3 else 0.0
    n_eff = max(res.size * (1 - rho) / (1 + rho), 2 * degree + 4.0)
    sigma2 = float(res @ res) / max(res.size - sol.x.size, 1)
    cov = np.linalg.pinv(sol.jac.T @ sol.jac) * sigma2 * res.size / n_eff
    return sol.x, cov, float(np.sqrt(np.mean(res**2)))


def _motion(params: np.ndarray, cov: np.ndarray, degree: int, t: np.ndarray) -> tuple[np.ndarray, float, float]:
    """The centre's displacement at every t (n×2), its largest extent over the clip (px) and that extent's σ."""
    basis, _, _ = _design(t, degree)
    dx = basis @ params[3 : 3 + degree]
    dy = basis @ params[3 + degree : 3 + 2 * degree]
    shift = np.column_stack([dx, dy])
    extent = np.hypot(*(shift.max(axis=0) - shift.min(axis=0)))
    # σ of the end-to-end displacement (first vs last frame), by the delta method
    ends = basis[-1] - basis[0]
    g = np.zeros((2, params.size))
    g[0, 3 : 3 + degree] = ends
    g[1, 3 + degree : 3 + 2 * degree] = ends
    end_to_end = g @ params
    c = g @ cov @ g.T
    norm = float(np.hypot(*end_to_end))
    sigma = float(math.sqrt(max(end_to_end @ c @ end_to_end, 0.0)) / norm) if norm > 0 else math.inf
    return shift, float(extent), sigma


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
    degree, params, cov, rms_after, motion = best
    radius = float(params[2])
    creep = {"degree": degree, "corrected": degree > 0, "rms_after_px": round(rms_after, 4)}
    if motion is not None:
        shift, extent, sigma = motion
        creep.update(
            motion_px=round(extent, 3),
            motion_stderr_px=round(sigma, 3),
            start_to_end_px=[round(float(shift[-1, 0] - shift[0, 0]), 3), round(float(shift[-1, 1] - shift[0, 1]), 3)],
        )
        basis, _, _ = _design(track.time_s.to_numpy(float), degree)
        out["x_image_px"] = track.x_px
        out["y_image_px"] = track.y_px
        out["x_px"] = track.x_px.to_numpy(float) - basis @ params[3 : 3 + degree]
        out["y_px"] = track.y_px.to_numpy(float) - basis @ params[3 + degree : 3 + 2 * degree]
    unexplained = rms_after
    document.update(
        creep=creep,
        corrected=bool(creep["corrected"]),
        radius_px=round(radius, 3),
        unexplained_rms_px=round(unexplained, 4),
        unexplained_angle_deg=round(math.degrees(unexplained / radius), 4) if radius > 0 else None,
    )
    parts = [f"the path sits {rms:.2f} px RMS off one fixed circle (noise {noise_px:.3f} px)"]
    if creep["corrected"]:
        dx, dy = creep["start_to_end_px"]
        parts.append(
            f"the pivot moves by ({dx:+.1f}, {dy:+.1f}) px from the first to the last frame (camera or stand "
            f"creeping; ± {creep['motion_stderr_px']:.1f} px), corrected: {rms_after:.2f} px RMS after"
        )
    along = np.column_stack([x, y]) - np.column_stack([x, y]).mean(axis=0)
    swing_px = float(np.sqrt(np.linalg.eigvalsh(np.cov(along.T))[-1]))  # SD along the path's main direction
    document["swing_sd_px"] = round(swing_px, 3)
    below = float(np.median(y)) < float(params[1])  # the circle's centre lies below the body
    not_circle = (
        unexplained > NOT_CIRCLE_SWING_FRACTION * swing_px
        and unexplained > NOT_CIRCLE_NOISE_RATIO * noise_px
        and unexplained > 1.0
    )
    document["not_a_pendulum"] = bool(not_circle)
    if not_circle:
        document["verdict"] = (
            "not a rigid pendulum about a fixed pivot (an object that spins or twists on its thread, a swing far "
            "out of the image plane, or the wrong object followed): the tracked object does not move on a circle "
            f"about a fixed point; its path sits {unexplained:.1f} px "
            f"RMS off the best circle{' about a creeping pivot' if creep['corrected'] else ''}, "
            f"{100 * unexplained / swing_px:.1f} % of its swing ({swing_px:.0f} px SD along the path; noise "
            f"{noise_px:.2f} px; a rigid pendulum's path, a creeping camera allowed for, stays under "
            f"{100 * NOT_CIRCLE_SWING_FRACTION:.0f} %)" + (", and that circle's centre lies below it" if below else "")
        )
        return out, document
    if unexplained > max(UNEXPLAINED_NOISE_RATIO * noise_px, MIN_DEPARTURE_PX):
        parts.append(
            f"{unexplained:.2f} px RMS ({document['unexplained_angle_deg']:.3f}° on the {radius:.0f} px arm) is not a "
            "circle about a fixed or creeping pivot: a swing out of the image plane, a stretching string or a body "
            "turning off its centre; the angle record carries it"
        )
        document["departs"] = True
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
