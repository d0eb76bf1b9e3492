"""A round body's centre from its outline: a sphere seen in part, such as a two-tone ball turning on its string.

The body tracker measures a body by its silhouette's centroid. Where only part of a sphere stands out (a two-tone
ball's coloured half, its light half lost against a light wall), that centroid is the visible part's, and it wanders
by up to half the radius as the ball turns on its string (a seam tilted from level shows a third to two thirds
of the ball). The sphere's outline does not: a half of it bounded by a great circle always shows a semicircle of
the sphere's limb, its ends diametrically opposite, so the circle through the outermost edge is the sphere's own.

Per frame (:func:`edge_points`): along :data:`LIMB_RAYS` rays from the silhouette's enclosing circle's centre, the
outermost point where D (the body's difference from the scene, masked to its component grown by 2 px: not its
thread) falls through half the body's contrast, interpolated between samples :data:`RAY_STEP_PX` apart. Per clip
(:func:`outline_centres`): a circle through each frame's edge points, started from their enclosing circle and
refitted (algebraic least squares) to the points within :data:`ON_CIRCLE_PX` of it, and then the centre alone
refitted (Gauss–Newton) at the clip's median radius: points inside the circle (a seam, the part that does not
stand out) are left out, the limb kept. A frame whose circle holds fewer than :data:`MIN_LIMB_SHARE` of the rays
did not show its limb.

:func:`centre_by_outline` keeps the outline's centres where the measurement itself says so
(:func:`pendulum.tracking.path_shape.path_departure` on each track): the centroid's path wanders off one circle about
a fixed or creeping pivot by more than its own noise (the RMS beyond the noise, √(RMS² − noise²)), and the outline's
by at most :data:`OUTLINE_GAIN` of that, with a smaller RMS; or the two paths need different creeps of the camera
(by more than path_shape's own least creep, and five of their standard errors: a wander slow enough to pass for
a creep), the outline's path no farther off its circle than the centroid's plus its noise. The camera moves both
centres alike; only a centre that moves on the body makes them differ, and a sphere's outline cannot. An apple (its
outline no circle, its centre 2–4 times noisier) and a uniform ball (both centres on one path) keep the centroid.
"""

from __future__ import annotations

import math

import cv2
import numpy as np
import pandas as pd

from pendulum.tracking.path_shape import MIN_MOTION_PX, MOTION_SIGMAS, path_departure

LIMB_RAYS = 96
RAY_STEP_PX = 0.25
ON_CIRCLE_PX = (1.5, 1.0, 0.75)  # the successive fits' tolerances: |distance from the centre − radius|
MIN_LIMB_SHARE = 1 / 3  # a sphere shows at least half its limb whatever its markings
MIN_SEEN_SHARE = 0.9  # of the usable frames, with their limb seen, for the outline to be tried
FULL_CONTRAST = 0.8  # of the body's contrast, reached along a ray whose edge is measured
MIN_POINTS = 8  # edge points a circle is fitted to
PAIR_POINTS = 24  # of a frame's edge points, those whose pairs place the circle of the clip's radius
OUTLINE_GAIN = 0.5
OUTLINE_COLUMNS = ["outline_x_px", "outline_y_px", "outline_r_px", "outline_rays"]


def edge_points(diff: np.ndarray, component: np.ndarray) -> np.ndarray:
    """The body's outermost edge along :data:`LIMB_RAYS` rays, (x, y) in ``diff``'s pixels, NaN where a ray finds
    none (module docstring)."""
    out = np.full((LIMB_RAYS, 2), np.nan, np.float32)
    points = cv2.findNonZero(component.astype(np.uint8))
    if points is None or len(points) < 5:
        return out
    (cx, cy), reach = cv2.minEnclosingCircle(points)
    level = 0.5 * float(np.percentile(diff[component], 90))
    grown = cv2.dilate(component.astype(np.uint8), np.ones((5, 5), np.uint8))
    masked = np.where(grown > 0, diff, 0.0).astype(np.float32)
    angles = np.linspace(0.0, 2 * np.pi, LIMB_RAYS, endpoint=False)
    radii = np.arange(0.3 * reach, 1.4 * reach + 2.0, RAY_STEP_PX)
    cos, sin = np.cos(angles)[:, None], np.sin(angles)[:, None]
    map_x, map_y = (cx + cos * radii).astype(np.float32), (cy + sin * radii).astype(np.float32)
    profile = cv2.remap(masked, map_x, map_y, cv2.INTER_LINEAR, borderMode=cv2.BORDER_CONSTANT, borderValue=0)
    above = profile >= level
    last = radii.size - 1 - np.argmax(above[:, ::-1], axis=1)  # the outermost sample above the level
    # a ray through a sliver of the body (a crescent's tip) does not reach its full contrast: its edge is blurred in
    found = above.any(axis=1) & (last + 1 < radii.size) & (profile.max(axis=1) >= FULL_CONTRAST * 2 * level)
    rows = np.nonzero(found)[0]
    j = last[rows]
    inside, outside = profile[rows, j], profile[rows, j + 1]
    distance = radii[j] + (inside - level) / np.maximum(inside - outside, 1e-6) * RAY_STEP_PX
    out[rows, 0] = cx + cos[rows, 0] * distance
    out[rows, 1] = cy + sin[rows, 0] * distance
    return out


def _circle(x: np.ndarray, y: np.ndarray) -> tuple[float, float, float, int]:
    """The limb circle through one frame's edge points, its radius free (module docstring): (x, y, radius,
    points on it); from their enclosing circle, which is the limb's where it shows a semicircle or more."""
    if x.size < MIN_POINTS:
        return math.nan, math.nan, math.nan, 0
    (cx, cy), r = cv2.minEnclosingCircle(np.column_stack([x, y]).astype(np.float32))
    keep = np.zeros(x.size, bool)
    for tolerance in ON_CIRCLE_PX:
        keep = np.abs(np.hypot(x - cx, y - cy) - r) < tolerance
        if keep.sum() < MIN_POINTS:
            return math.nan, math.nan, math.nan, 0
        design = np.column_stack([x[keep], y[keep], np.ones(int(keep.sum()))])
        (p, q, s), *_ = np.linalg.lstsq(design, x[keep] ** 2 + y[keep] ** 2, rcond=None)
        cx, cy = p / 2, q / 2
        r = math.sqrt(max(s + cx**2 + cy**2, 0.0))
    return float(cx), float(cy), float(r), int(keep.sum())


def _centre_at(x: np.ndarray, y: np.ndarray, radius_px: float) -> tuple[float, float, float, int]:
    """The limb circle of ``radius_px`` through one frame's edge points: of the two circles through each pair of
    (up to :data:`PAIR_POINTS` of) them, the one with the most points within :data:`ON_CIRCLE_PX` [−1] of it less
    those beyond it (the limb is the outermost edge), then its centre refitted to those (Gauss–Newton)."""
    if x.size < MIN_POINTS:
        return math.nan, math.nan, math.nan, 0
    tolerance = ON_CIRCLE_PX[-1]
    pick = np.linspace(0, x.size - 1, min(x.size, PAIR_POINTS)).round().astype(int)
    i, j = np.triu_indices(pick.size, 1)
    x1, y1, x2, y2 = x[pick[i]], y[pick[i]], x[pick[j]], y[pick[j]]
    half = np.hypot(x2 - x1, y2 - y1) / 2
    good = (half > 0) & (half < radius_px)
    mx, my = (x1 + x2)[good] / 2, (y1 + y2)[good] / 2
    reach = np.sqrt(radius_px**2 - half[good] ** 2) / half[good]
    nx, ny = -(y2 - y1)[good] / 2 * reach, (x2 - x1)[good] / 2 * reach  # to the centre, either side
    cx, cy = np.concatenate([mx + nx, mx - nx]), np.concatenate([my + ny, my - ny])
    if cx.size == 0:
        return math.nan, math.nan, math.nan, 0
    off = np.hypot(x[None, :] - cx[:, None], y[None, :] - cy[:, None]) - radius_px
    score = (np.abs(off) < tolerance).sum(axis=1) - (off > 2 * tolerance).sum(axis=1)
    best = int(np.argmax(score))
    cx, cy = float(cx[best]), float(cy[best])
    keep = np.zeros(x.size, bool)
    for _ in range(3):
        dx, dy = x - cx, y - cy
        distance = np.maximum(np.hypot(dx, dy), 1e-9)
        keep = np.abs(distance - radius_px) < tolerance
        if keep.sum() < MIN_POINTS:
            return math.nan, math.nan, math.nan, 0
        jacobian = -np.column_stack([dx[keep], dy[keep]]) / distance[keep, None]
        (sx, sy), *_ = np.linalg.lstsq(jacobian, radius_px - distance[keep], rcond=None)
        cx, cy = cx + float(sx), cy + float(sy)
    return cx, cy, radius_px, int(keep.sum())


def outline_centres(points: np.ndarray) -> np.ndarray:
    """Per frame, from its edge points (frames × :data:`LIMB_RAYS` × 2): the limb circle's centre x, y, radius and
    the rays on it, at the clip's median radius (module docstring); NaN where it was not seen."""
    free = [_circle(*_finite(p)) for p in points]
    radii = np.array([r for _, _, r, n in free if n >= MIN_LIMB_SHARE * LIMB_RAYS])
    if radii.size == 0:
        return np.full((len(points), 4), np.nan)
    radius = float(np.median(radii))
    return np.array([_centre_at(*_finite(p), radius) for p in points], float).reshape(-1, 4)


def _finite(p: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    good = np.isfinite(p[:, 0])
    return p[good, 0].astype(float), p[good, 1].astype(float)


def _creep(document: dict) -> tuple[np.ndarray, float]:
    """The camera's creep a path's fit found, first to last frame (px), and its standard error; none: 0, 0."""
    creep = document.get("creep") or {}
    if creep.get("start_to_end_px") is None:
        return np.zeros(2), 0.0
    return np.asarray(creep["start_to_end_px"], float), float(creep["motion_stderr_px"])


def centre_by_outline(track: pd.DataFrame) -> pd.DataFrame:
    """The track with its outline's centres where they make the better pendulum (module docstring), without the
    outline columns; ``attrs["body"]["centre"]``: what each gave and which was kept."""
    if OUTLINE_COLUMNS[0] not in track.columns:
        return track
    centroid = track.drop(columns=OUTLINE_COLUMNS)
    centroid.attrs = {**track.attrs, "body": dict(track.attrs.get("body") or {})}
    ok = (track.flag == "ok").to_numpy()
    seen = ok & (track.outline_rays.to_numpy(float) >= MIN_LIMB_SHARE * LIMB_RAYS)
    facts = {"by": "silhouette", "outline_seen_frames": int(seen.sum())}
    centroid.attrs["body"]["centre"] = facts
    if seen.sum() < MIN_SEEN_SHARE * ok.sum():
        return centroid
    radius = float(np.nanmedian(track.outline_r_px.to_numpy(float)[seen]))
    outline = centroid.copy()
    outline["x_px"] = np.where(seen, track.outline_x_px, track.x_px)
    outline["y_px"] = np.where(seen, track.outline_y_px, track.y_px)
    outline.loc[ok & ~seen, "flag"] = "occluded"
    _, by_centroid = path_departure(centroid)
    _, by_outline = path_departure(outline)
    left_centroid = by_centroid.get("unexplained_rms_px", math.inf)
    left_outline = by_outline.get("unexplained_rms_px", math.inf)
    noise_centroid, noise_outline = by_centroid.get("noise_px", math.inf), by_outline.get("noise_px", math.inf)
    wander_centroid = math.sqrt(max(left_centroid**2 - noise_centroid**2, 0.0))  # beyond each path's own noise
    wander_outline = math.sqrt(max(left_outline**2 - noise_outline**2, 0.0))
    facts.update(
        outline_radius_px=round(radius, 3),
        unexplained_rms_px={"silhouette": round(left_centroid, 4), "outline": round(left_outline, 4)},
        noise_px={"silhouette": round(noise_centroid, 4), "outline": round(noise_outline, 4)},
    )
    (creep_centroid, sigma_centroid), (creep_outline, sigma_outline) = _creep(by_centroid), _creep(by_outline)
    creeps_differ = float(np.hypot(*(creep_centroid - creep_outline))) > max(
        MIN_MOTION_PX, MOTION_SIGMAS * math.hypot(sigma_centroid, sigma_outline)
    )
    facts["creep_px"] = {"silhouette": creep_centroid.round(3).tolist(), "outline": creep_outline.round(3).tolist()}
    wanders = (
        wander_centroid > noise_centroid
        and wander_outline <= OUTLINE_GAIN * wander_centroid
        and left_outline < left_centroid
    )
    # a wander slow enough to pass for the camera creeping: the centroid's creep not the outline's
    if not (wanders or (creeps_differ and left_outline <= left_centroid + noise_centroid)):
        return centroid
    unseen = int((ok & ~seen).sum())
    facts["by"] = "outline"
    if wanders:
        evidence = (
            f"the silhouette's centroid leaves its path {left_centroid:.2f} px RMS off a circle about the pivot, the "
            f"centre of its round outline ({radius:.1f} px in radius) {left_outline:.2f} px"
        )
    else:
        (sx, sy), (ox, oy) = creep_centroid, creep_outline
        evidence = (
            f"the silhouette's centroid needs the camera to creep by ({sx:+.1f}, {sy:+.1f}) px over the clip, the "
            f"centre of its round outline ({radius:.1f} px in radius) by ({ox:+.1f}, {oy:+.1f}) px"
        )
    facts["why"] = (
        f"{evidence}: a ball seen in part (one half of a two-tone ball, a print's dark patches) that turns on its "
        "string, measured by its outline's centre"
        + (f"; {unseen} frames whose outline was not seen are flagged occluded" if unseen else "")
    )
    outline.attrs = {**centroid.attrs, "body": {**centroid.attrs["body"], "centre": facts}}
    if "method" in outline.attrs:  # said where the method is
        method = outline.attrs["method"]
        outline.attrs["method"] = {**method, "reason": f"{method['reason']}; {facts['why']}"}
    return outline
