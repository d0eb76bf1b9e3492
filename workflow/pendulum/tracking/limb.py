"""A round body's limb in one frame: the edge points :mod:`pendulum.tracking.outline` fits its circle to.

Along :data:`LIMB_RAYS` rays from the silhouette's enclosing circle's centre (:func:`edge_points`), the outermost
point where D (the body's difference from the scene, masked to its component grown by 2 px: not its thread) falls
through half the body's contrast, interpolated between samples :data:`RAY_STEP_PX` apart; where the body differs
from the scene on both sides (a print's dark squares and its light ones, whether its silhouette takes both sides or
one), each side's edge at half that side's own contrast (:func:`_sides`), the outer kept; in the colour view (no
shadow there), a ray that reaches no such edge at half its own level (:func:`_own_level_edges`)."""

from __future__ import annotations

import cv2
import numpy as np

LIMB_RAYS = 96
RAY_STEP_PX = 0.25
FULL_CONTRAST = 0.8  # of the body's contrast, reached along a ray whose edge is measured
MIN_SIDE_SHARE = 0.05  # of the pixels looked at, standing out on a side of the scene, for its edge to be sought apart
MIN_SIDE_CONTRAST = 0.25  # of the body's contrast: a fainter side is the part the silhouette leaves out too
OTHER_SIDE_REACH = 1.3  # × the silhouette's enclosing radius (+ 2 px): where a dark body's light side is sought
OWN_LEVEL_PX = 6.0  # a ray's own level: its highest within this far inside its faint edge (px)
OWN_LEVEL_DEPTH_PX = 3.0  # … and above half of it this far inside its edge: not a sliver's tip
_RAYS = (
    np.cos(np.arange(LIMB_RAYS) * 2 * np.pi / LIMB_RAYS)[:, None],
    np.sin(np.arange(LIMB_RAYS) * 2 * np.pi / LIMB_RAYS)[:, None],
)
_GROW = np.ones((5, 5), np.uint8)  # the component grown by 2 px: its edge's blur, not its thread
_PATCHES = (cv2.MORPH_OPEN, np.ones((3, 3), np.uint8))  # a side's strong pixels in patches, not the wall's noise


def _percentile_90(values: np.ndarray) -> float:
    """The 90th percentile of ``values`` (linear, as numpy's), by a partial sort."""
    at = 0.9 * (values.size - 1)
    low, high = int(at), min(int(at) + 1, values.size - 1)
    part = np.partition(values, (low, high))
    return float(part[low] + (at - low) * (part[high] - part[low]))


def _sides(
    diff: np.ndarray, component: np.ndarray, signed: np.ndarray | None, polarity: str, centre, reach: float
) -> list[tuple[np.ndarray, float, np.ndarray, bool]]:
    """The differences an edge is sought in, each with its contrast C (90th percentile) and where it is sought (a
    mask): D within the body's component grown by 2 px, or, with ``signed`` (I − B) given, each side of the scene
    where that side holds part of the body: :data:`MIN_SIDE_SHARE` of the pixels looked at differing on it by half
    :data:`MIN_SIDE_CONTRAST` of D's contrast or more, in patches of 3 × 3 px at least (not the wall's noise), and
    its C, over the pixels on that side, :data:`MIN_SIDE_CONTRAST` of D's or more:

    * a body both darker and brighter than the scene (``polarity`` both): its dark and its bright side apart, each
      in the grown component, in place of D (a print's light squares, 65 levels against its dark ones' 150: their
      limb crossed at half their own contrast, never at half the dark squares');
    * a body measured by its dark side (a dark print whose light squares were left out of its silhouette): D, and
      its light side within :data:`OTHER_SIDE_REACH` × the silhouette's enclosing radius + 2 px, where it falls
      in the image, not at that disk's rim (a light patch reaching past it); never a shadow, which is dark. A
      bright body measured by its bright side keeps D alone: its dark side would take in its shadow."""
    mask = component.astype(np.uint8)
    grown = cv2.dilate(mask, _GROW)
    contrast = _percentile_90(diff[component])
    alone = [(diff, contrast, grown, False)]
    if signed is None or polarity == "bright":  # a bright body's dark side: its own shadow beside it, too
        return alone
    if polarity == "dark":
        looked, near = np.zeros_like(mask), np.zeros_like(mask)
        at = (round(centre[0]), round(centre[1]))
        cv2.circle(looked, at, round(reach), 1, -1)
        cv2.circle(near, at, round(OTHER_SIDE_REACH * reach + 2), 1, -1)
        signs, where = [1.0], near  # the light side the silhouette left out
    else:
        looked, signs, where = mask, [-1.0, 1.0], grown
    in_disk = polarity != "both"  # the disk's rim is no edge: the side must fall within 1 px beyond (edge_points)
    sides = []
    for sign in signs:
        side = np.maximum(sign * signed, 0.0)
        seen = cv2.morphologyEx(
            ((looked > 0) & (side >= 0.5 * MIN_SIDE_CONTRAST * contrast)).astype(np.uint8), *_PATCHES
        )
        if not seen.any() or np.count_nonzero(seen) < MIN_SIDE_SHARE * np.count_nonzero(looked):
            return alone
        level = _percentile_90(side[(looked > 0) & (side > 0)])
        if level < MIN_SIDE_CONTRAST * contrast:
            return alone
        sides.append((side, level, where, in_disk))
    return alone + sides if polarity != "both" else sides


def edge_points(
    diff: np.ndarray,
    component: np.ndarray,
    signed: np.ndarray | None = None,
    polarity: str = "both",
    own_levels: bool = False,
) -> np.ndarray:
    """The body's outermost edge along :data:`LIMB_RAYS` rays, (x, y) in ``diff``'s pixels, NaN where a ray finds
    none (module docstring); ``signed``: I − B, D being its size (``polarity`` both) or one side of it, each side's
    edge then found at half its own contrast (:func:`_sides`), the outer of the two kept. ``own_levels``: a ray
    that finds no edge at half the body's contrast is measured at half its own level (:func:`_own_level_edges`):
    for a view in which nothing but the body stands out, no shadow (the colour view: a two-tone ball's navy half
    there fainter than its bright prints, its limb otherwise not found: 19 rays of 96 in the median frame of a
    helper's render, 50 with it)."""
    out = np.full((LIMB_RAYS, 2), np.nan, np.float32)
    points = cv2.findNonZero(component.astype(np.uint8))
    if points is None or len(points) < 5:
        return out
    (cx, cy), reach = cv2.minEnclosingCircle(points)
    radii = np.arange(0.3 * reach, 1.4 * reach + 2.0, RAY_STEP_PX)
    cos, sin = _RAYS
    map_x, map_y = (cx + cos * radii).astype(np.float32), (cy + sin * radii).astype(np.float32)
    outermost, distance = np.full(LIMB_RAYS, -1), np.full(LIMB_RAYS, np.nan)
    for side, contrast, where, in_disk in _sides(diff, component, signed, polarity, (cx, cy), reach):
        level = 0.5 * contrast
        masked = side.astype(np.float32) * where
        profile = cv2.remap(masked, map_x, map_y, cv2.INTER_LINEAR, borderMode=cv2.BORDER_CONSTANT, borderValue=0)
        above = profile >= level
        last = radii.size - 1 - np.argmax(above[:, ::-1], axis=1)  # the outermost sample above the level
        # a ray through a sliver of the body (a crescent's tip) does not reach its full contrast: its edge is blurred in
        found = above.any(axis=1) & (last + 1 < radii.size) & (profile.max(axis=1) >= FULL_CONTRAST * contrast)
        if in_disk:  # a shadow or a thread reaching past the disk it is sought in: no edge of the body
            rays, beyond = np.arange(LIMB_RAYS), np.minimum(last + round(1 / RAY_STEP_PX), radii.size - 1)
            at_x, at_y = map_x[rays, beyond][:, None], map_y[rays, beyond][:, None]  # 1 px past each edge only
            free = cv2.remap(side.astype(np.float32), at_x, at_y, cv2.INTER_LINEAR, borderMode=cv2.BORDER_REPLICATE)
            found &= free[:, 0] < level
        rows = np.nonzero(found & (last > outermost))[0]
        distance[rows] = _crossing(profile, rows, last[rows], level, radii)
        outermost[rows] = last[rows]
        if own_levels and not in_disk:  # a part fainter than the body (a navy half beside bright prints): its level
            rows, j, own = _own_level_edges(profile, contrast, radii, outermost)
            distance[rows] = _crossing(profile, rows, j, own, radii)
            outermost[rows] = j
    rows = np.nonzero(outermost >= 0)[0]
    out[rows, 0] = cx + cos[rows, 0] * distance[rows]
    out[rows, 1] = cy + sin[rows, 0] * distance[rows]
    return out


def _crossing(profile: np.ndarray, rows: np.ndarray, j: np.ndarray, level, radii: np.ndarray) -> np.ndarray:
    """Where each ray's profile falls through ``level`` between its samples j (above) and j + 1 (below), in px
    from the rays' centre (linear interpolation)."""
    inside, outside = profile[rows, j], profile[rows, j + 1]
    return radii[j] + (inside - level) / np.maximum(inside - outside, 1e-6) * RAY_STEP_PX


def _own_level_edges(
    profile: np.ndarray, contrast: float, radii: np.ndarray, outermost: np.ndarray
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The edge of each ray that found none at half the body's contrast (``outermost`` −1) at half its own level:
    its profile's highest value within :data:`OWN_LEVEL_PX` inside the outermost sample at half
    :data:`MIN_SIDE_CONTRAST` of the contrast, where that level is :data:`MIN_SIDE_CONTRAST` of the contrast or
    more and the profile stays above its half for :data:`OWN_LEVEL_DEPTH_PX` inside the edge (a part of the body,
    not a sliver's blurred tip). Returns the rays, their samples j above the level, and the levels."""
    floor = MIN_SIDE_CONTRAST * contrast
    above = profile >= 0.5 * floor
    low = radii.size - 1 - np.argmax(above[:, ::-1], axis=1)
    window = round(OWN_LEVEL_PX / RAY_STEP_PX)
    samples = np.arange(radii.size)
    near = (samples >= low[:, None] - window) & (samples <= low[:, None])
    plateau = np.where(near, profile, 0.0).max(axis=1)
    level = 0.5 * plateau
    last = radii.size - 1 - np.argmax((profile >= level[:, None])[:, ::-1], axis=1)
    depth = round(OWN_LEVEL_DEPTH_PX / RAY_STEP_PX)
    body = (samples >= last[:, None] - depth) & (samples <= last[:, None])
    thick = np.where(body, profile >= level[:, None], True).all(axis=1) & (last >= depth)
    rows = np.nonzero((outermost < 0) & above.any(axis=1) & (plateau >= floor) & thick & (last + 1 < radii.size))[0]
    return rows, last[rows], level[rows]
