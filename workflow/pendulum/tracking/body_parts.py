"""The body's pixels in one frame (:mod:`pendulum.tracking.body`): the moving component to take for it, whether it
touches the frame's border, its core without a rod, its own centre where it meets something else, and the body as a
scene's first frame shows it (:func:`body_measure`).
"""

from __future__ import annotations

import math
from typing import NamedTuple

import cv2
import numpy as np

from pendulum.tracking.body_scene import (
    MIN_BODY_AREA_PX,
    STRONG_FRACTION,
    components,
    one_sided,
    silhouette_fraction,
    soft_centroid,
)

REACH_SLACK, REACH_MARGIN_PX = 1.3, 4.0  # a part joined to the body lies within this × its reach (+ this) of it
MAX_AREA_RATIO, MIN_AREA_RATIO = 1.5, 0.5  # the body with something else, or a part of it: its area's range
TYPICAL_SAMPLES, TYPICAL_AREA_RATIO = 9, 1.2  # samples spread over the clip for the body's usual size; its range


SOFT_EDGE_RATIO = 1 / 3  # a component whose edge is this much softer than a heavy one's beside it: its shadow
# ... or this much softer and fainter, and lighter: a shadow (its penumbra blurred beyond the body's edge) a few grey
# levels deep, its mass (its depth × its disk's area: the blur keeps the sum) under the body's
FAINT_EDGE_RATIO, FAINT_CONTRAST_RATIO = 2 / 3, 0.4
HEAVY_SHARE = 0.25  # ... where that one holds at least this share of the heaviest component's mass


def component_contrast(diff: np.ndarray, labels: np.ndarray, stats: np.ndarray, i: int) -> float:
    """The 90th percentile of D over component ``i`` of ``diff`` (its contrast)."""
    x0, y0, w, h = (int(v) for v in stats[i, :4])
    crop = diff[y0 : y0 + h, x0 : x0 + w].astype(np.float32)
    return float(np.percentile(crop[labels[y0 : y0 + h, x0 : x0 + w] == i], 90))


def edge_sharpness(diff: np.ndarray, labels: np.ndarray, stats: np.ndarray, i: int) -> float:
    """How sharply component ``i`` of ``diff`` ends (1/px, about 1/w for an edge w px wide): the 90th percentile of
    |∇D| (D smoothed by σ = 1 px) on its outline (from 3 px inside to 2 px outside it: a large body's inside does not
    count) over the 90th percentile of D in it. A body's limb is one or two pixels wide, defocused a few; the
    penumbra of its shadow on a wall behind it many."""
    x0, y0, w, h = (int(v) for v in stats[i, :4])
    pad = 6  # beyond the outline's 2 px, the smoothing's and the Sobel kernel's reach
    ya, yb = max(y0 - pad, 0), min(y0 + h + pad, diff.shape[0])
    xa, xb = max(x0 - pad, 0), min(x0 + w + pad, diff.shape[1])
    mask = (labels[ya:yb, xa:xb] == i).astype(np.uint8)
    crop = diff[ya:yb, xa:xb].astype(np.float32)
    smooth = cv2.GaussianBlur(crop, (0, 0), 1.0)
    gradient = np.hypot(cv2.Sobel(smooth, cv2.CV_32F, 1, 0, ksize=3), cv2.Sobel(smooth, cv2.CV_32F, 0, 1, ksize=3)) / 8
    outside = cv2.dilate(mask, cv2.getStructuringElement(cv2.MORPH_ELLIPSE, (5, 5))) > 0
    inside = cv2.erode(mask, cv2.getStructuringElement(cv2.MORPH_ELLIPSE, (7, 7)), borderType=cv2.BORDER_REPLICATE)
    outline = outside & ~(inside > 0)
    level = component_contrast(diff, labels, stats, i)
    return float(np.percentile(gradient[outline], 90)) / level if level > 0 and outline.any() else 0.0


def _boxes_within(a: np.ndarray, b: np.ndarray, gap: int) -> bool:
    """Whether two components' boxes ``(x, y, w, h)`` lie within ``gap`` px of each other."""
    return not (
        a[0] > b[0] + b[2] + gap or a[0] + a[2] < b[0] - gap or a[1] > b[1] + b[3] + gap or a[1] + a[3] < b[1] - gap
    )


def soft_components(diff: np.ndarray, labels: np.ndarray, stats: np.ndarray, masses: np.ndarray, ids, gap: int) -> set:
    """Of the components ``ids``, those lying within ``gap`` px (boxes) of a heavy one (:data:`HEAVY_SHARE` of the
    heaviest's mass or more) whose edge is over 1 / :data:`SOFT_EDGE_RATIO` times as sharp (:func:`edge_sharpness`):
    a soft shadow beside the body, which the body's parts within that gap would otherwise be joined to. Measured on
    a printed ball of 21 px radius and its two shadows, heavier than the ball (its light and dark squares ±50–60
    grey levels off the wall, the shadows −30): 0.21 and 0.03 per px. Also one whose edge is softer than
    :data:`FAINT_EDGE_RATIO` of that one's and whose contrast (90th percentile of D) is under
    :data:`FAINT_CONTRAST_RATIO` of its and whose mass is under its (a shadow that faint is lighter than its body
    unless cast over 1.5 times its size): a two-tone ball of 22 px beside its shadow 19 grey levels deep and σ 6 px
    (0.19 and 0.105 per px; contrast 72 and 19; mass 72,000 and 22,000). Not a faint body beside a sharp, darker
    but smaller thing (a reviewer's: a ball 25 levels off the wall defocused by σ 3 px, a dark object of 12 px 8 px
    from it, which was followed 40 px off). Components far apart are left as they are (the heaviest taken): a
    defocused body is not set apart from a sharp hand or its hard shadow elsewhere."""
    top = max((masses[i] for i in ids), default=0.0)
    heavy = [i for i in ids if masses[i] >= HEAVY_SHARE * top]
    if len(heavy) < 2:
        return set()
    sharpness, contrasts = {}, {}

    def sharp(i):
        if i not in sharpness:
            sharpness[i] = edge_sharpness(diff, labels, stats, i)
        return sharpness[i]

    def contrast(i):
        if i not in contrasts:
            contrasts[i] = component_contrast(diff, labels, stats, i)
        return contrasts[i]

    def beside_sharper(i, j):
        if j == i or not _boxes_within(stats[i], stats[j], gap) or sharp(j) <= 0:
            return False
        softer = sharp(i) / sharp(j)
        return softer < SOFT_EDGE_RATIO or (
            softer < FAINT_EDGE_RATIO and contrast(i) < FAINT_CONTRAST_RATIO * contrast(j) and masses[i] < masses[j]
        )

    return {i for i in ids if any(beside_sharper(i, j) for j in heavy)}


def solidity(component: np.ndarray) -> float:
    """A silhouette's area over its convex hull's (a body: over 0.3; a wavy water line, caustics' web: under)."""
    hull = cv2.convexHull(cv2.findNonZero(component.astype(np.uint8)))
    return float(component.sum() / max(cv2.contourArea(hull), 1.0))


def body_reach(component: np.ndarray) -> float:
    """The distance (px) of a silhouette's farthest pixel from its centroid."""
    ys, xs = np.nonzero(component)
    return float(np.hypot(xs - xs.mean(), ys - ys.mean()).max()) if xs.size else 0.0


def body_component(
    diff: np.ndarray,
    threshold: float,
    open_px: int,
    close_px: int,
    near=None,
    area_px=None,
    reach_px=None,
    shadows_apart: bool = False,
):
    """The moving pixels to take for the body: the component nearest ``near`` (else the heaviest) with every
    component whose box lies within 2 closing widths of it (a print's patches, a body cut by a wall-coloured
    band): ``(mask, (x, y, w, h))``, or ``(None, None)``. With the body's ``area_px``: where the nearest is over
    :data:`MAX_AREA_RATIO` of it (the body with what held it) and another is the body's size, that one (the body
    let go, the hand drawn back). With its ``reach_px`` (:func:`body_reach`) and ``near``, a component is joined only
    where all of it lies within :data:`REACH_SLACK` × that (+ :data:`REACH_MARGIN_PX`) of ``near``: a part of the body,
    not a light blinking beside it or a second pendulum's bob passing near. With ``shadows_apart``, a component whose
    edge is much softer than that of a heavy one beside it (:func:`soft_components`: the body's soft shadow on the
    wall, heavier than a print whose light and dark squares average to the wall's grey) is neither taken (unless at
    ``near``) nor joined."""
    labels, stats, masses = components(diff, threshold, open_px, close_px)
    ids = [i for i in range(1, len(masses)) if stats[i, cv2.CC_STAT_AREA] >= MIN_BODY_AREA_PX]
    if not ids:
        return None, None
    gap = 2 * close_px
    soft = soft_components(diff, labels, stats, masses, ids, gap) if shadows_apart else set()
    if near is None:
        first = max((i for i in ids if i not in soft), key=lambda i: masses[i])
    else:
        nx, ny = near

        def distance(i):
            x0, y0, w, h = stats[i, :4]
            dx = max(x0 - nx, 0, nx - (x0 + w - 1))
            dy = max(y0 - ny, 0, ny - (y0 + h - 1))
            return math.hypot(dx, dy), -masses[i]

        first = min(ids, key=distance)
        if area_px and stats[first, cv2.CC_STAT_AREA] > MAX_AREA_RATIO * area_px:
            sized = [i for i in ids if MIN_AREA_RATIO <= stats[i, cv2.CC_STAT_AREA] / area_px <= MAX_AREA_RATIO]
            first = min(sized, key=distance, default=first)
    box = [int(v) for v in stats[first, :4]]
    group = {first}
    apart = set() if first in soft else soft  # where start_px points at a soft one, nothing is set apart
    grown = True
    while grown:
        grown = False
        for i in ids:
            if i in group or i in apart or not _boxes_within(stats[i], box, gap):
                continue
            x0, y0, w, h = stats[i, :4]
            if reach_px and near is not None:
                ys, xs = np.nonzero(labels[y0 : y0 + h, x0 : x0 + w] == i)
                if np.hypot(xs + x0 - near[0], ys + y0 - near[1]).max() > REACH_SLACK * reach_px + REACH_MARGIN_PX:
                    continue
            group.add(i)
            right, bottom = max(box[0] + box[2], x0 + w), max(box[1] + box[3], y0 + h)
            box[0], box[1] = min(box[0], x0), min(box[1], y0)
            box[2], box[3] = right - box[0], bottom - box[1]
            grown = True
    mask = labels == first if len(group) == 1 else np.isin(labels, list(group))
    return mask, tuple(box)


def touches_border(component: np.ndarray, cut=None, frame_shape=None) -> bool:
    """Whether a body's pixels reach the frame's outermost rows or columns (part of it out of view); for a
    component of a cut-out ``cut = (y0, y1, x0, x1)`` of a frame of ``frame_shape``, only its sides that are the
    frame's."""
    y0, y1, x0, x1 = cut if cut is not None else (0, component.shape[0], 0, component.shape[1])
    h, w = frame_shape if frame_shape is not None else component.shape
    return bool(
        (y0 == 0 and component[0].any())
        or (y1 == h and component[-1].any())
        or (x0 == 0 and component[:, 0].any())
        or (x1 == w and component[:, -1].any())
    )


def body_core(component: np.ndarray, reach_px: float):
    """The body without what sticks out of it: the component's pixels within ``reach_px`` of its thickest
    point (the maximum of its distance transform), and their box ``(x, y, w, h)``: whether the body itself
    touches the frame's border, not a rod or thread leaving it."""
    dist = cv2.distanceTransform(component.astype(np.uint8), cv2.DIST_L2, 3)
    cy, cx = np.unravel_index(int(np.argmax(dist)), dist.shape)
    yy, xx = np.ogrid[: component.shape[0], : component.shape[1]]
    kept = component & ((xx - cx) ** 2 + (yy - cy) ** 2 <= reach_px**2)
    ys, xs = np.nonzero(kept)
    return kept, (int(xs.min()), int(ys.min()), int(xs.max() - xs.min() + 1), int(ys.max() - ys.min() + 1))


def own_centre(component: np.ndarray, inner_radius_px: float, near) -> tuple[float, float] | None:
    """The body's own centre in a component it forms with something else (a second pendulum's bob it meets, a
    hand): of the component's thickest points (local maxima of its distance transform at least 0.7 of the body's
    inner radius deep), the one nearest ``near``; None where there is none."""
    depth = cv2.distanceTransform(component.astype(np.uint8), cv2.DIST_L2, 5)
    peaks = (depth >= 0.7 * inner_radius_px) & (depth >= cv2.dilate(depth, np.ones((5, 5), np.uint8)))
    ys, xs = np.nonzero(peaks)
    if not xs.size:
        return None
    k = int(np.argmin(np.hypot(xs - near[0], ys - near[1])))
    return float(xs[k]), float(ys[k])


def body_close_size(inner_radius_px: float) -> int:
    """Closing disk (odd, px) for a body of this inner radius: ~½ of it, so a print's dark patches (a third
    of the radius apart) are one object before the opening."""
    return 2 * int(round(inner_radius_px / 4)) + 1


def open_size(inner_radius_px: float) -> int:
    """Opening disk (odd, px) that removes strings and thin rods but keeps the body: ~⅔ of its inner radius."""
    return max(3, 2 * int(round(inner_radius_px / 3)) + 1)


START_SLACK_RADII = 0.5  # the user's start_px may miss the body's first-frame silhouette by this × its radius ...
START_SLACK_PX = 5.0  # ... and by this many px at least


def start_missed(component: np.ndarray, hull: np.ndarray, near: tuple[float, float]) -> str | None:
    """Why ``near`` (the user's ``start_px``) points at no part of ``component``, the moving body nearest it in the
    first frame: farther from its convex ``hull`` (a ring's hole, a two-tone ball's half left out are the body's)
    than :data:`START_SLACK_RADII` of its radius (and :data:`START_SLACK_PX`), so that the nearest moving thing is
    not followed in its place; None where it is on it or that near."""
    ys, xs = np.nonzero(component)
    radius = math.sqrt(xs.size / math.pi)
    gap = max(-cv2.pointPolygonTest(hull, (float(near[0]), float(near[1])), True), 0.0)
    if gap <= max(START_SLACK_PX, START_SLACK_RADII * radius):
        return None
    return (
        f"start_px ({near[0]:.0f}, {near[1]:.0f}) is on no moving body in the first frame: the nearest, centred at "
        f"({xs.mean():.0f}, {ys.mean():.0f}) px and {radius:.0f} px in radius, lies {gap:.0f} px from it; give "
        "start_px at the centre of the body to follow as the first frame shows it (x from the left edge, y down from "
        "the top, in the video's pixels)"
    )


CONTRAST_FRACTION = 0.25  # a body pixel differs by more than this share of its own contrast (a soft shadow less)
NOISE_SIGMAS = 5.0  # a pixel moves when |I − B| exceeds this many σ of the frame-to-scene noise
MIN_CUT_GREY = 4.0  # ... and at least this many grey levels


def silhouette_cut(noise_grey: float, contrast_grey: float = 0.0) -> float:
    """The |I − B| a body pixel exceeds: max(5 σ of the noise, 4 grey levels, ¼ of the body's contrast); without
    ``contrast_grey``, the |I − B| a moving pixel exceeds."""
    return max(NOISE_SIGMAS * noise_grey, MIN_CUT_GREY, CONTRAST_FRACTION * contrast_grey)


class Seen(NamedTuple):
    """The body in one frame: soft centre, contrast, silhouette fraction, pixels (None: a thread or rod only)."""

    x: float
    y: float
    contrast: float
    fraction: float
    component: np.ndarray | None
    inner_radius_px: float
    sample: int = 0  # the sample it was seen in (find_body's), and the window (y0, y1, x0, x1) its pixels are in
    window: tuple | None = None


def body_measure(diff: np.ndarray, threshold: float, close_px: int, near, shadows_apart: bool = True) -> Seen | None:
    """The body in one frame's difference from the scene (:class:`Seen`); None when nothing moves.

    The heaviest moving object (or the one at ``near``) of those not much softer-edged than another heavy one (its
    soft shadow on the wall, :func:`soft_components`), again above a quarter of its own contrast (a fainter shadow
    beside it falls away), then opened to cut its thread (the part at its thickest point kept). Without
    ``shadows_apart`` (the colour view: white light casts no shadow in it, and its chroma's edges are soft) the
    heaviest, as before."""
    component, _ = body_component(diff, threshold, 3, close_px, near=near, shadows_apart=shadows_apart)
    if component is None:
        return None
    contrast = float(np.percentile(diff[component], 90))
    threshold = max(threshold, CONTRAST_FRACTION * contrast)
    strong, _ = body_component(diff, threshold, 3, close_px, near=near, shadows_apart=shadows_apart)
    component = component if strong is None else strong
    depth = cv2.distanceTransform(component.astype(np.uint8), cv2.DIST_L2, 5)
    inner, (ty, tx) = float(depth.max()), np.unravel_index(int(np.argmax(depth)), depth.shape)
    close_px = max(close_px, body_close_size(inner))
    # of its parts after the opening, the one at ``near``, else at its thickest point (its centre may be on a rod)
    opened, _ = body_component(
        diff, threshold, open_size(inner), close_px, near=near or (float(tx), float(ty)), shadows_apart=shadows_apart
    )
    if opened is None:
        return Seen(math.nan, math.nan, contrast, STRONG_FRACTION, None, inner)
    inner = float(cv2.distanceTransform(opened.astype(np.uint8), cv2.DIST_L2, 5).max())
    fraction = silhouette_fraction(diff[opened])
    x, y, _, _, _ = soft_centroid(diff, opened, fraction)
    return Seen(x, y, contrast, fraction, opened, inner)


def first_and_usual(
    images, background, excluded, polarity: str, threshold: float, close_px: int, near, shadows_apart, aside=None
) -> tuple[Seen | None, Seen | None]:
    """The body in the first of ``images`` (:func:`body_measure` of I − B on the side ``polarity`` names), and as most
    of the clip shows it: of :data:`TYPICAL_SAMPLES` samples spread over the clip (each cut out around its moving
    pixels, ``excluded``: :class:`~pendulum.tracking.scene_stack.EnlargedMasks`), the body in full view of median
    area, where the first frame's is out of view in part or not of its size (within :data:`TYPICAL_AREA_RATIO`: a
    hand holding it before the release). ``aside``: pixels left out of every difference (a moving object set aside
    as no body)."""

    def diff(k, y0=0, y1=None, x0=0, x1=None):
        d = one_sided(images[k][y0:y1, x0:x1] - background[y0:y1, x0:x1], polarity)
        return d if aside is None else np.where(aside[y0:y1, x0:x1], np.float32(0), d)

    first = body_measure(diff(0), threshold, close_px, near, shadows_apart)
    if first is None or first.component is None or near is not None:
        return first, first
    seen = []
    for k in range(1, len(images), max(1, (len(images) - 1) // TYPICAL_SAMPLES)):
        rows, cols = excluded.extent(k)
        if not rows.size:  # nothing moving in this sample
            continue
        margin = 2 * close_px + 8  # the sample's moving objects, cut out with a margin (a 1080p frame is large)
        y0, y1 = max(rows[0] - margin, 0), min(rows[-1] + margin + 1, background.shape[0])
        x0, x1 = max(cols[0] - margin, 0), min(cols[-1] + margin + 1, background.shape[1])
        body = body_measure(diff(k, y0, y1, x0, x1), threshold, close_px, None, shadows_apart)
        if body is None or body.component is None:
            continue
        if not touches_border(body.component, (y0, y1, x0, x1), background.shape):  # in full view
            seen.append(body._replace(sample=k, window=(y0, y1, x0, x1)))
    if not seen:
        return first, first
    typical = sorted(seen, key=lambda s: int(s.component.sum()))[len(seen) // 2]
    ratio = first.component.sum() / typical.component.sum()
    if touches_border(first.component) or not 1 / TYPICAL_AREA_RATIO <= ratio <= TYPICAL_AREA_RATIO:
        return first, typical
    return first, first


MIN_SOLIDITY = 0.3  # a body fills more of its convex hull (even a slender vehicle: > 0.9; a tank's caustics 0.09)
IN_PLACE_SHARE, MAX_SET_ASIDE = 0.8, 3  # a mover that is no body, moving in this share of the samples: set aside


def in_place_set_aside(first: Seen, whole: Seen, measured, excluded, close_px: int):
    """``(first, whole, aside, set_aside)``: where the first frame's heaviest moving object is no body (under
    :data:`MIN_SOLIDITY` of its hull, or across the frame's width) and moves in place (in :data:`IN_PLACE_SHARE` of
    the samples' moving pixels, ``excluded``: a tank's wavy water surface, a rippling light), it is set aside (its
    place, grown by a closing width each side, left out of every difference) and the body sought again by
    ``measured(aside)``; a swinging body leaves its place. Not where the body then found lies within an object set
    aside's convex hull (or a closing width of it: a part of that object, e.g. a thread inside a hoop-like body that
    swings little). ``set_aside``: where each was and how much of its hull it filled; ``aside`` the pixels left out
    (None: none)."""
    found, aside, set_aside, hulls = (first, whole), None, [], []
    while first is not None and first.component is not None and len(set_aside) < MAX_SET_ASIDE:
        solid, cols = solidity(first.component), np.flatnonzero(first.component.any(axis=0))
        if solid >= MIN_SOLIDITY and not (cols[0] == 0 and cols[-1] == first.component.shape[1] - 1):
            break  # a compact body, or one that does not span the frame's width as a water surface does
        if float(np.median(excluded.count_over_samples()[first.component])) < IN_PLACE_SHARE * len(excluded):
            break
        set_aside.append({"x_px": round(first.x, 1), "y_px": round(first.y, 1), "hull_fill": round(solid, 3)})
        hulls.append(cv2.convexHull(cv2.findNonZero(first.component.astype(np.uint8))).astype(np.float32))
        grown = cv2.dilate(first.component.astype(np.uint8), np.ones((2 * close_px + 1,) * 2, np.uint8)) > 0
        aside = grown if aside is None else aside | grown
        first, whole = measured(aside)
    # what is found within an object set aside (a thread inside a hoop-like body that swings little) is part of it:
    # nothing set aside, the first object refused as before
    if first is not None and any(cv2.pointPolygonTest(h, (first.x, first.y), True) > -close_px for h in hulls):
        return *found, None, []
    return first, whole, aside, set_aside
