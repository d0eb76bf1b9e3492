"""Sub-pixel marker centre in one frame: the estimators behind :func:`measure_marker`.

In a region of interest (ROI) around the predicted position:

1. a coarse, robust estimate: the thresholded centroid x̂ = Σ w x / Σ w with
   w = max(I − T, 0), T = b + ½ (I_marker − b), b the ROI's border median (a long
   streak: within the capsule it can occupy, thresholded at half its own peak);
2. the linear centroid x̂ = Σ (I − b′) m x / Σ (I − b′) m with a ring background:
   m the capsule window, radius r_m = r + 2.5 px about a segment of the streak's
   length along the motion, with a one-pixel soft edge; b′ the median of the ring
   r_m + 1 < d ≤ r_m + 4 just outside it. Linear in the pixel values, it has no
   pixel locking and no threshold nonlinearity on a blurred streak: it is the
   marker's mean position over the exposure;
3. for a marker with no body around it (its surround is the static scene B that
   detection gives), its coverage of the scene m = (I − B) / (M − B), M the
   marker's own grey, in the same capsule: a striped or uneven scene behind does
   not move it. Where B ≈ M the mirror pixel about the estimate fills in; what
   neither shows is returned as ``unresolved`` (a biased measurement).

The checks of :func:`capsule_check` (is the linear centroid the marker's alone?) stay inside the
capsule too: a thresholded centroid there, and the linear one in a tighter mask.

From the weights' second moments: streak² = 12 (var_along − var_across), the
squared length of the exposure streak, and width² = 4 var_across = r² for a disk
(blur along the motion does not change it; an occluder in the mask widens it).
:func:`pendulum.tracking.marker.track_video` turns these into positions and flags.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import TYPE_CHECKING

import cv2
import numpy as np

if TYPE_CHECKING:
    from pendulum.tracking.settings import TrackerSettings


@dataclass
class Measurement:
    x: float
    y: float
    signal: float  # Σ (I − b) over the marker mask
    level: float  # marker brightness the threshold was set from
    background: float
    at_edge: bool
    # |linear − thresholded centroid| in the linear one's capsule (or its last re-centring step): large when
    # something intrudes on the marker (see capsule_check)
    disagreement_px: float = 0.0
    streak2_px2: float = math.nan  # squared length of the exposure streak (linear centroid only)
    width2_px2: float = math.nan  # 4 × the signal's variance across the motion: ≈ r² for a disk (linear only)
    unresolved: float = 0.0  # share of the marker over scene of its own grey, not measured (coverage only)
    mode_coverage: bool = False  # measured as coverage of the scene (else against the ring's median)
    margin_shift_px: float = 0.0  # |linear centroid − the same in a mask 1.5 px tighter|: something in the margin


def measure_marker(
    image,
    x_guess,
    y_guess,
    settings: TrackerSettings,
    blur_px=0.0,
    marker_level=None,
    direction=None,
    background=None,
    bounds=None,
):
    """Sub-pixel intensity-weighted centroid of the marker near (x_guess, y_guess).

    ``blur_px`` (expected streak length) widens the ROI and the mask. ``bounds``
    (x0, y0, x1, y1): the picture inside letterbox borders; the ROI never leaves it
    and touching it counts as the edge. ``background``: the static scene (grey, as
    :func:`pendulum.tracking.detection.detect_marker` gives it); where the marker's
    surround is that scene (no body around the marker), the marker is measured as
    its coverage of the scene (:func:`_coverage_centroid`), so a striped or
    uneven scene behind it does not move the centroid. Otherwise the linear
    centroid (ring background) starts from the coarse thresholded one and is
    iterated until re-centring its mask moves it less than 0.02 px (at most 3 more
    rounds: a coarse start pulled off the marker by something else in the ROI),
    then checked by :func:`capsule_check`. Returns None when no pixel stands out
    from the local background.
    """
    r = settings.marker_radius_px
    half = int(math.ceil(2.0 * r + 0.5 * blur_px + 4))
    h, w = image.shape
    bx0, by0, bx1, by1 = (0, 0, w, h) if bounds is None else bounds
    xi, yi = int(round(x_guess)), int(round(y_guess))
    x0, x1 = max(bx0, xi - half), min(bx1, xi + half + 1)
    y0, y1 = max(by0, yi - half), min(by1, yi + half + 1)
    if x1 - x0 < 3 or y1 - y0 < 3:
        return None
    roi = image[y0:y1, x0:x1].astype(np.float32)
    if settings.polarity == "dark":
        roi = 255.0 - roi
    border = np.concatenate([roi[0], roi[-1], roi[1:-1, 0], roi[1:-1, -1]])
    background_level = float(np.median(border))
    ys = np.arange(y0, y1, dtype=np.float32)[:, None]
    xs = np.arange(x0, x1, dtype=np.float32)[None, :]
    if marker_level is None:  # the marker's own level: from its disk about the guess, not the whole ROI
        # (whose corners may reach past a bob round a dot to a wall of the marker's polarity)
        near = (xs - x_guess) ** 2 + (ys - y_guess) ** 2 <= (r + 0.5 * blur_px + 4.0) ** 2
        level = float(np.percentile(roi[near], 99.5)) if near.any() else float(np.percentile(roi, 99.5))
    else:
        level = marker_level
    streak_zone = None
    if direction is not None and blur_px > r:
        # A long streak is dimmer than the marker (its peak coverage ≈ 2r / length) and the ROI holds
        # more of the scene: threshold halfway to the streak's own peak, within the capsule it can occupy.
        u = (xs - x_guess) * direction[0] + (ys - y_guess) * direction[1]
        v = (ys - y_guess) * direction[0] - (xs - x_guess) * direction[1]
        excess = np.abs(u) - np.minimum(np.abs(u), 0.5 * blur_px + 2.0)
        streak_zone = v * v + excess * excess <= (r + 4.0) ** 2
        level = min(level, float(roi[streak_zone].max())) if streak_zone.any() else level
    threshold = background_level + 0.5 * (level - background_level)
    weight = roi - threshold
    np.maximum(weight, 0, out=weight)
    if streak_zone is not None:
        weight *= streak_zone
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
    unresolved = 0.0
    margin_shift = 0.0
    refined = None
    if settings.centroid == "linear" and background is not None and marker_level is not None:
        bg = background[y0:y1, x0:x1]
        bg = 255.0 - bg if settings.polarity == "dark" else bg
        refined = _coverage_centroid(roi, bg, x0, y0, cx, cy, r, blur_px, direction, marker_level)
    coverage = refined is not None
    if coverage:
        cx, cy, streak2, signal, width2, unresolved = refined
        disagreement = 0.0  # the thresholded centroid sees the scene's stripes; the coverage needs no check
    elif settings.centroid == "linear":
        refined = linear_centroid(roi, x0, y0, cx, cy, r, blur_px, direction)
        if refined is None:
            return None
        check = capsule_check(roi, x0, y0, refined[0], refined[1], r, blur_px, direction, level)
        for _ in range(3):  # a coarse start pulled off the marker (by something in the ROI): iterate on
            if check is None or check[0] <= 0.02:
                break
            again = linear_centroid(roi, x0, y0, refined[0], refined[1], r, blur_px, direction)
            if again is None:
                break
            refined = again
            check = capsule_check(roi, x0, y0, refined[0], refined[1], r, blur_px, direction, level)
        if check is None:
            return None
        disagreement, margin_shift = check[1], check[2]
        cx, cy, streak2, signal, width2 = refined
    else:
        inside = (xs - cx) ** 2 + (ys - cy) ** 2 <= mask_r2
        signal = float(((roi - background_level) * inside).sum())
        disagreement, streak2, width2 = 0.0, math.nan, math.nan
    if bounds is None:
        at_edge = x0 == 0 or y0 == 0 or x1 == w or y1 == h
    else:  # the picture is known: the marker's mask and ring must stay inside it (not on a border)
        ux, uy = (0.0, 0.0) if direction is None else direction
        reach_x = r + 6.5 + 0.5 * blur_px * abs(ux)  # the ring's reach, longer along the streak
        reach_y = r + 6.5 + 0.5 * blur_px * abs(uy)
        at_edge = cx - reach_x < bx0 or cy - reach_y < by0 or cx + reach_x > bx1 - 1 or cy + reach_y > by1 - 1
    measured = (cx, cy, signal, level, background_level, at_edge, disagreement, streak2, width2, unresolved)
    return Measurement(*measured, mode_coverage=coverage, margin_shift_px=margin_shift)


def _capsule_window(shape, x0, y0, cx, cy, radius, blur_px, direction, margin_px):
    """The capsule mask about (cx, cy) and the part of an ROI (``shape``, starting at image pixel (x0, y0)) it reaches.

    The capsule: radius r_m = ``radius`` + ``margin_px`` about a segment of half-length
    ``blur_px``/2 along the unit ``direction`` (none: a disk); its ring r_m + 1 < d ≤ r_m + 4.
    Returns ``(ux, uy, half_len, r_mask, ring_in, ring_out, i0, i1, j0, j1)``, rows i0:i1 and
    columns j0:j1 of the ROI, or None when fewer than 3 rows or columns are left.
    """
    if direction is None:
        ux, uy, half_len = 1.0, 0.0, 0.0
    else:
        ux, uy = direction
        half_len = 0.5 * max(blur_px, 0.0)
    r_mask = radius + margin_px
    ring_in, ring_out = r_mask + 1.0, r_mask + 4.0
    h, w = shape
    reach_x, reach_y = ring_out + 1.5 + half_len * abs(ux), ring_out + 1.5 + half_len * abs(uy)
    i0, i1 = max(0, int(cy - y0 - reach_y)), min(h, int(cy - y0 + reach_y) + 2)
    j0, j1 = max(0, int(cx - x0 - reach_x)), min(w, int(cx - x0 + reach_x) + 2)
    if i1 - i0 < 3 or j1 - j0 < 3:
        return None
    return ux, uy, half_len, r_mask, ring_in, ring_out, i0, i1, j0, j1


def _capsule_coordinates(xr, yr, ex, ey, ux, uy, half_len):
    """About the estimate (ex, ey): u along the motion (ux, uy), v across it, and the distance
    d = √(v² + (u − clip(u, ±half_len))²) from the capsule's centre segment."""
    u = (xr[None, :] - ex) * ux + (yr[:, None] - ey) * uy
    v = (yr[:, None] - ey) * ux - (xr[None, :] - ex) * uy
    excess = u - np.clip(u, -half_len, half_len)
    return u, v, np.sqrt(v * v + excess * excess)


def _weighted_centre(weight, xr, yr):
    """(x̄, ȳ, Σw) = (Σ w x / Σ w, Σ w y / Σ w, Σ w) on the grid xr × yr; None when Σ w ≤ 0."""
    col, row = weight.sum(axis=0), weight.sum(axis=1)
    total = float(col.sum())
    if total <= 0:
        return None
    return float(col @ xr) / total, float(row @ yr) / total, total


def _spread(weight, u, v, total, directed: bool):
    """(streak², width²) of the weights: 12 (var_u − var_v) (NaN without a direction) and 4 var_v."""
    across2 = float((weight * v * v).sum()) / total
    streak2 = 12.0 * float((weight * (u * u)).sum()) / total - 12.0 * across2 if directed else math.nan
    return streak2, 4.0 * across2


def linear_centroid(roi, x0, y0, cx, cy, radius, blur_px, direction, margin_px=2.5, iterations=2):
    """Centroid of (I − b) in a soft-edged mask around the (blurred) marker, b from a ring just outside.

    Linear in the pixel values, so a partly covered edge pixel counts in proportion to its
    coverage: no pixel locking and no threshold nonlinearity on a blurred streak, and the
    result is the mean position over the exposure. The mask is a capsule along the motion
    (``direction``, unit vector; ``blur_px`` the streak length allowed for) with a one-pixel
    soft edge, so its own centroid moves smoothly with the estimate. ``roi`` starts at image
    pixel (x0, y0); (cx, cy) is the starting estimate in image pixels.

    Returns ``(x, y, streak², signal, width²)`` with streak² = 12 (var_along − var_across) of
    the weights: the squared length of the exposure streak (a disk's own variance is the same
    in both directions), NaN without a direction; signal = Σ (I − b) over the mask, which blur
    does not change; width² = 4 var_across (r² for a disk, unchanged by blur along the motion:
    a larger spot in the mask, e.g. an occluder, widens it). None when nothing stands out.
    """
    window = _capsule_window(roi.shape, x0, y0, cx, cy, radius, blur_px, direction, margin_px)
    if window is None:
        return None
    ux, uy, half_len, r_mask, ring_in, ring_out, i0, i1, j0, j1 = window
    sub = roi[i0:i1, j0:j1]
    # Coordinates relative to the starting estimate (small numbers: float32 is exact enough).
    ox, oy = cx, cy
    xr = (np.arange(x0 + j0, x0 + j1) - ox).astype(np.float32)
    yr = (np.arange(y0 + i0, y0 + i1) - oy).astype(np.float32)
    ex = ey = 0.0  # current estimate relative to (ox, oy)
    background = None
    for _ in range(iterations):
        u, v, dist = _capsule_coordinates(xr, yr, ex, ey, ux, uy, half_len)
        if background is None:
            ring = (dist > ring_in) & (dist <= ring_out)
            if np.count_nonzero(ring) < 8:
                return None
            background = float(np.median(sub[ring]))
        mask = np.clip(r_mask + 0.5 - dist, 0.0, 1.0, out=dist)
        weight = sub - background
        weight *= mask
        centre = _weighted_centre(weight, xr, yr)
        if centre is None:
            return None
        ex, ey, total = centre
    # Moments about the last mask centre, within a small fraction of a pixel of the result.
    streak2, width2 = _spread(weight, u, v, total, direction is not None)
    return ox + ex, oy + ey, streak2, total, width2


def edge_radius(image, x, y, radius, n_rays=64, step_px=0.2):
    """Marker radius from its edge: the median over ``n_rays`` rays from (x, y) of the steepest fall.

    Along each ray the profile I(ρ) (bilinear, ``image`` with the marker brighter than its
    surround) is differentiated; its edge is the ρ of the largest −dI/dρ within 0.6–1.5
    ``radius`` (the starting estimate), to a parabola's sub-sample. A rod, a body edge or a
    stripe that touches the marker spoils only the rays that cross it, where the width² of the
    moments takes it in whole. Unbiased to ±0.07 px on rendered disks of 5–20 px; a streak
    lengthens the rays along the motion (use it on unblurred spots). None when no ray has an edge.
    """
    phi = np.arange(n_rays) * (2.0 * math.pi / n_rays)
    rho = np.arange(0.4 * radius, 1.7 * radius + 2.0, step_px)
    xs = (x + np.outer(np.cos(phi), rho)).astype(np.float32)
    ys = (y + np.outer(np.sin(phi), rho)).astype(np.float32)
    profile = cv2.remap(
        image.astype(np.float32), xs, ys, cv2.INTER_LINEAR, borderMode=cv2.BORDER_CONSTANT, borderValue=float("nan")
    )
    fall = -np.gradient(profile, step_px, axis=1)
    lo, hi = np.searchsorted(rho, 0.6 * radius), np.searchsorted(rho, 1.5 * radius)
    window = fall[:, lo:hi]
    usable = np.isfinite(window).all(axis=1)
    if not usable.any():
        return None
    j = lo + np.argmax(window[usable], axis=1)
    rows = fall[usable]
    a, b, c = (rows[np.arange(j.size), j + d] for d in (-1, 0, 1))
    curvature = a - 2.0 * b + c
    offset = np.where(curvature < 0, 0.5 * (a - c) / np.where(curvature < 0, curvature, -1.0), 0.0)
    return float(np.median(rho[j] + np.clip(offset, -0.5, 0.5) * step_px))


def capsule_check(roi, x0, y0, x, y, radius, blur_px, direction, level, margin_px=2.5, tight_margin_px=1.0):
    """Is the linear centroid (x, y) the marker's alone? ``(residual_px, disagreement_px, margin_shift_px)``.

    All in the linear centroid's own window (:func:`_capsule_window` about (x, y), ring median b′), so
    that nothing beyond it (a second object, a stripe past the body) counts. ``residual_px``: distance
    of the centroid x̂ = Σ w x / Σ w, w = (I − b′) m, recomputed about (x, y) from (x, y) (not 0: the
    iteration had not converged); ``disagreement_px``: the larger of it and the distance of the
    thresholded centroid, w = max(I − T, 0) m with T = b′ + ½ (``level`` − b′) (an occluder of a grey
    between the marker's and the surround's weighs differently in the two); ``margin_shift_px``: the
    shift of the linear centroid when its mask shrinks to r + ``tight_margin_px``: something in the
    margin r … r + ``margin_px`` beyond the marker's edge (there the thresholded centroid, for an
    object of the marker's grey, agrees with the linear one). None: no window (too few ring pixels,
    nothing stands out).
    """
    window = _capsule_window(roi.shape, x0, y0, x, y, radius, blur_px, direction, margin_px)
    if window is None:
        return None
    ux, uy, half_len, r_mask, ring_in, ring_out, i0, i1, j0, j1 = window
    sub = roi[i0:i1, j0:j1]
    xr = (np.arange(x0 + j0, x0 + j1) - x).astype(np.float32)
    yr = (np.arange(y0 + i0, y0 + i1) - y).astype(np.float32)
    _, _, dist = _capsule_coordinates(xr, yr, 0.0, 0.0, ux, uy, half_len)
    ring = (dist > ring_in) & (dist <= ring_out)
    if np.count_nonzero(ring) < 8:
        return None
    background = float(np.median(sub[ring]))
    excess = sub - background
    mask = np.clip(r_mask + 0.5 - dist, 0.0, 1.0)
    linear = _weighted_centre(excess * mask, xr, yr)
    if linear is None:
        return None
    thresholded = _weighted_centre(np.maximum(excess - 0.5 * (level - background), 0.0) * mask, xr, yr)
    tight = _weighted_centre(excess * np.clip(radius + tight_margin_px + 0.5 - dist, 0.0, 1.0), xr, yr)
    lx, ly, _ = linear
    residual = math.hypot(lx, ly)  # the recentred mask moves the centroid: not converged
    disagreement = max(residual, math.inf if thresholded is None else math.hypot(thresholded[0], thresholded[1]))
    margin_shift = math.inf if tight is None else math.hypot(tight[0] - lx, tight[1] - ly)
    return residual, disagreement, margin_shift


def _coverage_centroid(roi, bg, x0, y0, cx, cy, radius, blur_px, direction, marker_level, margin_px=2.5, iterations=3):
    """Centroid of the marker's coverage of the static scene, when the marker's surround is that scene.

    Each pixel is a blend I = m M + (1 − m) B of the marker grey M and the scene B
    behind it, so its coverage m = (I − B) / (M − B) does not depend on the scene
    (a dark ball over a dark stripe covers the stripe as much as the wall). Where the
    scene has nearly the marker's own grey (|M − B| below a third of the typical
    contrast) m is not measurable; there the marker's point symmetry (a disk, or a
    streak along the motion) fills it from the mirror pixel about the current
    estimate, and what neither pixel of such a pair shows is returned as
    ``unresolved`` (share of the marker's footprint): a biased measurement. The mask
    is the capsule of :func:`linear_centroid`. Returns ``(x, y, streak², Σ m, width²,
    unresolved)`` like it (signal in pixels of coverage), or None when the surround
    is not the scene (a body moves with the marker: use the ring background).
    """
    window = _capsule_window(roi.shape, x0, y0, cx, cy, radius, blur_px, direction, margin_px)
    if window is None:
        return None
    ux, uy, half_len, r_mask, ring_in, ring_out, i0, i1, j0, j1 = window
    sub, back = roi[i0:i1, j0:j1], bg[i0:i1, j0:j1]
    if not np.isfinite(back).all():  # the scene behind is unknown here (the marker rested on it)
        return None
    xr = (np.arange(x0 + j0, x0 + j1) - cx).astype(np.float32)
    yr = (np.arange(y0 + i0, y0 + i1) - cy).astype(np.float32)

    u, v, dist = _capsule_coordinates(xr, yr, 0.0, 0.0, ux, uy, half_len)
    ring = (dist > ring_in) & (dist <= ring_out)
    if np.count_nonzero(ring) < 8:
        return None
    diff = sub - back
    contrast = marker_level - back
    typical = float(np.median(contrast[ring]))
    if typical <= 0:
        return None
    # The surround must be the scene all round: the ring matches the background pixel by pixel
    # (no body around the marker, whose grey could match the scene's here and there).
    if float(np.percentile(np.abs(diff[ring]), 85)) > max(8.0, 0.1 * typical):
        return None
    measurable = np.abs(contrast) >= typical / 3.0
    cover = np.where(measurable, diff / np.where(measurable, contrast, 1.0), 0.0).astype(np.float32)
    ex = ey = 0.0
    unresolved = 0.0
    any_missing = not measurable.all()
    for _ in range(iterations):
        u, v, dist = _capsule_coordinates(xr, yr, ex, ey, ux, uy, half_len)
        mask = np.clip(r_mask + 0.5 - dist, 0.0, 1.0)
        filled = cover
        if any_missing:
            # mirror about the estimate: pixel (x, y) ↔ (2 ex − x, 2 ey − y), bilinear
            map_x = (2 * ex - xr[None, :] + cx - (x0 + j0)).astype(np.float32) * np.ones_like(cover)
            map_y = (2 * ey - yr[:, None] + cy - (y0 + i0)).astype(np.float32) * np.ones_like(cover)
            mirror = cv2.remap(cover, map_x, map_y, cv2.INTER_LINEAR, borderMode=cv2.BORDER_CONSTANT, borderValue=0)
            mirror_ok = cv2.remap(
                measurable.astype(np.float32), map_x, map_y, cv2.INTER_LINEAR, borderMode=cv2.BORDER_CONSTANT
            )
            gap = ~measurable
            filled = np.where(gap & (mirror_ok > 0.99), mirror, cover)
            expected = np.clip(radius + 0.5 - dist, 0.0, 1.0)  # the marker's own footprint
            lost = gap & (mirror_ok <= 0.99)
            unresolved = float((expected * lost).sum() / max(expected.sum(), 1e-9))
        weight = filled * mask
        centre = _weighted_centre(weight, xr, yr)
        if centre is None:
            return None
        ex, ey, total = centre
    streak2, width2 = _spread(weight, u, v, total, direction is not None)
    return cx + ex, cy + ey, streak2, total, width2, unresolved
