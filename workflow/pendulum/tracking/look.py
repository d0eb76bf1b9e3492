"""The body by its look: a rigid body whose swing never uncovers the scene behind its rest place, followed by
aligning its own picture in every frame.

A vehicle wider than its swing (an ROV on its rod in a tank, damped to rest within a few swings) covers the
place it swings about in nearly every frame: its silhouette has no scene to be measured against there, and
before a patterned wall (tiles, caustics) no fill of that place can be checked (``body_scene.unseen_behind``
refuses it). Its look needs no scene: a rigid body is the same picture in every frame, shifted and turned.

1. **Reference.** From the refused silhouette track (its places biased where the scene was filled in), the frame
   at the swing's widest turning point (the body still: no blur, and farthest from the place it hides).
2. **Template.** The reference frame's pixels that differ from the silhouette tracker's scene by more than
   T = max(5σ, ¼ C) (σ, C: the scene's noise and the body's contrast), the component at the body, closed and its
   holes filled (its markings), less the pixels no sampled frame showed clear (the fill there is a guess): only the
   body, never wall; at least :data:`MIN_TEMPLATE_SHARE` of its area. Its centroid is the point followed.
3. **Alignment.** Every frame: OpenCV's ECC (``findTransformECCWithMask``, Euclidean: a shift and a turn) of the
   template into a window about the predicted place, started from its neighbour's warp and speed (from the
   silhouette's move since the reference where that fails), forward from the reference frame and back from it to
   the first (the frames before it held until it is reached). Always against the one template: no drift.

Flags from the alignment's own evidence: ``lost`` (no convergence), ``occluded`` (a misfit 1 − ρ above
:data:`MISFIT_RATIO` × the clip's median: a hand, a bubble cloud, a reflection over it), ``edge`` (the body's
outline reaches the frame's border), then ``jump`` as for every track; a body held still before its release is
measured there too (the silhouette's ``held`` is not taken: its area grew with the filled scene, not a hand). The
turn of the template is a second measure of the swing: on a body rigid on its rod it follows the arm's angle
about the path's centre with slope −1 (image axes); ``rotation`` says how closely,
and a body that turns otherwise (a ball on a string) is warned of.
"""

from __future__ import annotations

import math
from contextlib import closing

import cv2
import numpy as np
import pandas as pd

from pendulum.camera.video import VideoError, iter_luma
from pendulum.tracking.arcs import fit_circle
from pendulum.tracking.body_parts import silhouette_cut
from pendulum.tracking.checks import flag_jumps
from pendulum.tracking.settings import TrackerSettings

EDGE_RING_PX = 3  # the template's mask reaches this far past the body's outline (ECC's blur: ECC_BLUR)
HELD_BEFORE_MB = 500  # the frames before the reference, held (8-bit luma): at 1080p within its first 241 frames
MIN_TEMPLATE_SHARE = 0.4  # the template holds at least this share of the body's area (π r²)
MISFIT_RATIO = 3.0  # a frame's misfit 1 − ρ above this many times the clip's median: something over the body
SEARCH_PX = 12  # the window about the predicted place: the template's box and this much more, plus the speed
ECC_CRITERIA = (cv2.TERM_CRITERIA_EPS | cv2.TERM_CRITERIA_COUNT, 100, 1e-5)
ECC_BLUR = 3  # ECC's own Gaussian (px)
RIGID_SLOPE_TOLERANCE = 0.05  # a turn of the body within this of the arm's (slope −1): rigid on its rod


def reference_frame(track: pd.DataFrame, within: int | None = None) -> int:
    """Index (row) of the track's widest turning point: the free, measured frame farthest from the path's median
    place whose neighbours are as far or nearer (the body at rest there: no blur); among the first ``within`` rows
    where any is free there (the frames before it are held in memory for the alignment back to the first)."""
    x, y = track.x_px.to_numpy(float), track.y_px.to_numpy(float)
    free = np.isfinite(x) & (track.flag == "ok").to_numpy()  # not a jump, a hand over it, the border
    if not free.any():
        free = np.isfinite(x) & (track.flag != "held").to_numpy() & (track.flag != "lost").to_numpy()
    if within is not None and free[:within].any():
        free[within:] = False
    if not free.any():
        raise VideoError("no frame of the body was measured")
    distance = np.where(free, np.hypot(x - np.nanmedian(x[free]), y - np.nanmedian(y[free])), -np.inf)
    turning = np.r_[False, (distance[1:-1] >= distance[:-2]) & (distance[1:-1] >= distance[2:]), False]
    return int(np.argmax(np.where(turning & free, distance, -np.inf) if (turning & free).any() else distance))


def template_of(
    reference: np.ndarray, scene: np.ndarray, hidden: np.ndarray, place, radius_px: float, threshold: float
):
    """The body's picture in ``reference`` where it differs from ``scene`` and the scene is seen (not ``hidden``:
    module docstring, step 2): the template (float32), its mask (uint8, 255 on the body and its ring), its top-left
    corner in the frame, its centroid in the template and the body's area in it (px, no ring); None where nothing
    differs at ``place``."""
    height, width = reference.shape
    half = int(2.5 * radius_px + 8)
    x0, y0 = max(int(place[0]) - half, 0), max(int(place[1]) - half, 0)
    x1, y1 = min(int(place[0]) + half + 1, width), min(int(place[1]) + half + 1, height)
    window = reference[y0:y1, x0:x1].astype(np.float32)
    differs = np.abs(cv2.GaussianBlur(window, (0, 0), 1.0) - cv2.GaussianBlur(scene[y0:y1, x0:x1], (0, 0), 1.0))
    moving = (differs > threshold).astype(np.uint8)
    size = max(3, int(radius_px / 4) | 1)
    moving = cv2.morphologyEx(moving, cv2.MORPH_CLOSE, cv2.getStructuringElement(cv2.MORPH_ELLIPSE, (size, size)))
    count, labels, stats, _ = cv2.connectedComponentsWithStats(moving)
    if count < 2:
        return None
    cx, cy = int(np.clip(place[0] - x0, 0, x1 - x0 - 1)), int(np.clip(place[1] - y0, 0, y1 - y0 - 1))
    label = labels[cy, cx] or 1 + int(np.argmax(stats[1:, cv2.CC_STAT_AREA]))
    body = (labels == label).astype(np.uint8)
    outline, _ = cv2.findContours(body, cv2.RETR_EXTERNAL, cv2.CHAIN_APPROX_NONE)
    cv2.drawContours(body, outline, -1, 1, thickness=cv2.FILLED)  # its holes filled: markings, windows
    body[hidden[y0:y1, x0:x1]] = 0  # no scene to tell the body from there: left out, not guessed
    area = int(np.count_nonzero(body))
    ring = cv2.getStructuringElement(cv2.MORPH_ELLIPSE, (2 * EDGE_RING_PX + 1, 2 * EDGE_RING_PX + 1))
    body = cv2.dilate(body, ring)  # its outline in: the edges that fix its place (a ring of wall the width of a blur)
    body[hidden[y0:y1, x0:x1]] = 0  # ... not grown back into the unseen
    if not body.any():
        return None
    ys, xs = np.nonzero(body)
    bx0, by0 = max(xs.min() - 4, 0), max(ys.min() - 4, 0)
    bx1, by1 = min(xs.max() + 5, x1 - x0), min(ys.max() + 5, y1 - y0)
    template = window[by0:by1, bx0:bx1].copy()
    mask = (255 * body[by0:by1, bx0:bx1]).astype(np.uint8)
    return template, mask, (x0 + bx0, y0 + by0), (float(xs.mean() - bx0), float(ys.mean() - by0)), area


def _align(template, mask, frame, guess: np.ndarray):
    """ECC's correlation and warp (template → frame) from ``guess``, in a window about it; None where it fails."""
    height, width = frame.shape
    th, tw = template.shape
    x0, y0 = int(max(guess[0, 2] - SEARCH_PX, 0)), int(max(guess[1, 2] - SEARCH_PX, 0))
    x1, y1 = int(min(guess[0, 2] + tw + SEARCH_PX, width)), int(min(guess[1, 2] + th + SEARCH_PX, height))
    if x1 - x0 < tw // 2 or y1 - y0 < th // 2:
        return None
    window = frame[y0:y1, x0:x1].astype(np.float32)
    start = guess.astype(np.float32).copy()
    start[0, 2] -= x0
    start[1, 2] -= y0
    valid = np.full(window.shape, 255, np.uint8)
    try:
        rho, warp = cv2.findTransformECCWithMask(
            template, window, mask, valid, start, cv2.MOTION_EUCLIDEAN, ECC_CRITERIA, ECC_BLUR
        )
    except cv2.error:  # no convergence
        return None
    warp[0, 2] += x0
    warp[1, 2] += y0
    return float(rho), warp.astype(np.float64)


def _decoded(path, wanted: int) -> np.ndarray:
    """The clip's frame ``wanted`` (luma)."""
    with closing(iter_luma(path)) as frames:
        for index, _, image in frames:
            if index == wanted:
                return image
    raise VideoError(f"{path}: the body by its look: its frame {wanted} could not be decoded again")


def _cut(path, image: np.ndarray, scene, place, wanted: int):
    """The template cut from the reference frame ``image`` at ``place`` (:func:`template_of`): the template, its
    mask, the point followed in it, its warp into the frame and its mask's hull; raises where too little is cut."""
    radius = max(scene.radius_px, 2.0)
    reference = image.astype(np.float32)
    threshold = silhouette_cut(scene.noise_grey, scene.contrast_grey)
    hidden = np.zeros(reference.shape, bool) if scene.unseen is None else scene.unseen
    found = template_of(reference, scene.background, hidden, place, radius, threshold)
    if found is None or found[4] < MIN_TEMPLATE_SHARE * math.pi * radius**2:
        raise VideoError(
            f"{path}: the body by its look: at the swing's widest (frame {wanted}) too little of the body lies "
            "before scene that some frame shows clear (a swing narrower than about the body's width)"
        )
    template, mask, corner, centre, _ = found
    warp = np.array([[1.0, 0.0, corner[0]], [0.0, 1.0, corner[1]]])
    hull = cv2.convexHull(cv2.findNonZero(mask)).reshape(-1, 2).astype(float)
    return template, mask, np.array(centre), warp, hull


def track_by_look(path, settings: TrackerSettings, refused: pd.DataFrame, scene, progress=None) -> pd.DataFrame:
    """The body followed by its look (module docstring) from its silhouette track ``refused`` and that track's
    ``scene`` (:class:`pendulum.tracking.body.BodyScene`); columns as :func:`.marker.track_video`, ``quality`` and
    ``signal_ratio`` the alignment's correlation ρ relative to its median. ``attrs["body"]``: the scene's facts with
    ``by: look`` and the alignment's (``look``). Raises :class:`~pendulum.camera.video.VideoError` where no frame
    shows the scene behind the body's widest place, or too few frames are usable."""
    x, y = refused.x_px.to_numpy(float), refused.y_px.to_numpy(float)
    budget = max(1, int(HELD_BEFORE_MB * 1e6 / scene.background.size))
    row = reference_frame(refused, budget)
    wanted = int(refused.frame.iloc[row])
    held_before = row <= budget  # the frames before the reference held: its picture cut as the pass reaches it
    if not held_before:  # the frames before it aligned forward: its picture first
        template, mask, point, warp, hull = _cut(path, _decoded(path, wanted), scene, (x[row], y[row]), wanted)
    n, report = len(refused), {}
    height, width = scene.background.shape

    def measure(k: int, image, previous, speed) -> tuple[list, np.ndarray | None]:
        """Frame k aligned from the neighbour's warp and speed (the silhouette's move since the reference where that
        fails): its place, ρ, turn and flag, and its warp (None where lost)."""
        aligned = None if previous is None else _align(template, mask, image, previous + np.c_[np.zeros((2, 2)), speed])
        if aligned is None and k < n and np.isfinite(x[k]):  # moved as the silhouette moved since the reference
            aligned = _align(template, mask, image, warp + np.c_[np.zeros((2, 2)), (x[k] - x[row], y[k] - y[row])])
        if aligned is None:
            return [math.nan, math.nan, 0.0, math.nan, "lost"], None
        rho, found = aligned
        px, py = found[:, :2] @ point + found[:, 2]
        outline = found[:, :2] @ hull.T + found[:, 2:3]  # the body's outline where it is now
        inside = outline.min() >= 0 and outline[0].max() <= width - 1 and outline[1].max() <= height - 1
        return [px, py, rho, math.degrees(math.atan2(found[1, 0], found[0, 0])), "ok" if inside else "edge"], found

    # from the reference frame on, and back from it to the first (held in memory until the reference is reached):
    # every frame starts from a neighbour already aligned, the hold before the release too
    places, before, stamps = {}, [], {}
    previous, speed = None, np.zeros(2)
    for index, time_s, image in iter_luma(path, report=report):
        k = len(stamps)
        stamps[k] = (index, float(time_s))
        if k < row and held_before:
            before.append(image.copy())
            continue
        if k == row and held_before:
            template, mask, point, warp, hull = _cut(path, image, scene, (x[row], y[row]), wanted)
        places[k], found = measure(k, image, warp if k == row else previous, speed)
        if found is None:
            speed = np.zeros(2)  # after a lost frame: from where it was last found, at rest
        else:
            speed = found[:, 2] - previous[:, 2] if previous is not None and k != row else np.zeros(2)
            previous = found
        if k == row and before:
            back, back_speed = previous, np.zeros(2)
            for j in range(row - 1, -1, -1):
                places[j], found = measure(j, before[j], back, back_speed)
                if found is not None:
                    back_speed = found[:, 2] - back[:, 2] if back is not None and j < row - 1 else np.zeros(2)
                    back = found
            before.clear()
        if progress and index and index % 500 == 0:
            progress(f"{path}: body aligned by its look through frame {index}")
    if row not in places:
        raise VideoError(f"{path}: the body by its look: its frame {wanted} could not be decoded again")
    rows = [[*stamps[k], m[0], m[1], m[2], m[2], m[4]] for k, m in sorted(places.items())]
    turns = [m[3] for _, m in sorted(places.items())]
    table = pd.DataFrame(rows, columns=["frame", "time_s", "x_px", "y_px", "quality", "signal_ratio", "flag"])
    flags = table.flag.to_numpy(object)
    rho = table.quality.to_numpy(float)
    measured = flags != "lost"
    misfit = np.median(1.0 - rho[measured]) if measured.any() else 1.0
    flags[measured & (1.0 - rho > MISFIT_RATIO * max(misfit, 1e-4))] = "occluded"
    px, py = table.x_px.to_numpy(float), table.y_px.to_numpy(float)
    usable = flags == "ok"
    flags[flag_jumps(px, py, usable, settings, table.time_s.to_numpy()) & usable] = "jump"
    table["flag"] = flags
    reference_rho = float(np.median(rho[flags == "ok"])) if (flags == "ok").any() else 1.0
    table["quality"] = table["signal_ratio"] = rho / reference_rho
    look = {
        "reference_frame": wanted,
        "template_area_px": int(np.count_nonzero(mask)),
        "median_correlation": round(reference_rho, 4),
        "rotation": rotation_agreement(px, py, np.asarray(turns, float), flags == "ok"),
    }
    table.attrs["video"] = report
    table.attrs["body"] = {**scene.to_dict(), "by": "look", "look": look}
    if look["rotation"].get("warning"):
        table.attrs["body"]["warning"] = look["rotation"]["warning"]
    table.attrs["marker"] = None
    free = int((flags != "held").sum())
    n_ok = int((flags == "ok").sum())
    if n_ok < settings.min_usable_fraction * free:
        raise VideoError(
            f"{path}: the body by its look is usable in only {n_ok} of {free} frames "
            f"({100 * n_ok / max(free, 1):.0f} %)"
        )
    return table


def rotation_agreement(x, y, turn_deg, usable) -> dict:
    """How the template's turn follows the arm's angle about the path's own centre: the slope and RMS about the line
    (a body rigid on its rod: slope −1 in image axes, y down), with a warning where it does not."""
    if usable.sum() < 10:
        return {}
    cx, cy, _ = fit_circle(x[usable], y[usable])
    arm = np.degrees(np.arctan2(x[usable] - cx, y[usable] - cy))
    turn = turn_deg[usable]
    design = np.column_stack([arm - arm.mean(), np.ones_like(arm)])
    (slope, offset), *_ = np.linalg.lstsq(design, turn, rcond=None)
    rms = float(np.sqrt(np.mean((design @ (slope, offset) - turn) ** 2)))
    facts = {"slope": round(float(slope), 4), "rms_deg": round(rms, 4), "arm_span_deg": round(float(np.ptp(arm)), 2)}
    if abs(slope + 1.0) > RIGID_SLOPE_TOLERANCE:
        facts["warning"] = (
            f"the body turns in the picture {abs(slope):.2f}× as far as its arm (a body rigid on a rod: 1.00): it is "
            "not rigid on its arm (a ball on a string, a body that twists), and the point followed by its look may "
            "not move with the swing"
        )
    return facts
