"""Finding the marker in a frame: disk-like spots by normalised template matching, and the checks that
tell the marker from the scene (its contrast against its surround, a spot the static scene holds).

A candidate's score is the normalised cross-correlation of the (2× reduced) image with a disk of
the marker's radius, ρ = Σ (I − Ī)(D − D̄) / √(Σ (I − Ī)² Σ (D − D̄)²), 1 for a perfect disk; its
contrast is the mean grey inside the disk minus that of its surround, in the marker's polarity.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import TYPE_CHECKING

import cv2
import numpy as np

if TYPE_CHECKING:
    from pendulum.tracking.settings import TrackerSettings


def _disk_template(radius: float) -> np.ndarray:
    size = int(math.ceil(radius * 4)) | 1
    c = size // 2
    yy, xx = np.mgrid[0:size, 0:size]
    return (np.hypot(xx - c, yy - c) <= radius).astype(np.float32)


MIN_MARKER_CONTRAST = 6.0  # grey levels between a marker candidate's disk and its surround


@dataclass(frozen=True)
class Candidate:
    x: float
    y: float
    score: float  # normalised correlation with a disk of the marker's radius (1 = perfect)
    contrast: float  # mean grey level inside the disk minus its surround, in the marker's polarity


def marker_candidates(image: np.ndarray, settings: TrackerSettings, near=None, search_radius_px=None, n: int = 2):
    """The ``n`` best disk-like spots by normalised template matching (on a 2× reduced image).

    Spots closer than four marker radii to a better one are not counted (one
    blurred marker is one spot). Positions in full-resolution pixels.
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
    size = template.shape[0]
    if small.shape[0] <= size or small.shape[1] <= size or (template > 0).all():
        return []  # no room for the disk, or a disk under a pixel with no surround to tell it by
    response = cv2.matchTemplate(small, template, cv2.TM_CCOEFF_NORMED)
    response = np.nan_to_num(response, nan=0.0)
    inside = template > 0
    half = size // 2
    keep_out = int(math.ceil(settings.marker_radius_px * 2))  # 4 radii at full resolution
    found = []
    for _ in range(n):
        _, score, _, loc = cv2.minMaxLoc(response)
        if score <= 0:
            break
        patch = small[loc[1] : loc[1] + size, loc[0] : loc[0] + size]
        contrast = float(patch[inside].mean() - patch[~inside].mean())
        found.append(Candidate(x0 + 2 * (loc[0] + half) + 0.5, y0 + 2 * (loc[1] + half) + 0.5, float(score), contrast))
        response[
            max(0, loc[1] - keep_out) : loc[1] + keep_out + 1, max(0, loc[0] - keep_out) : loc[0] + keep_out + 1
        ] = -1
    return found


def near_any(x: float, y: float, points, distance_px: float) -> bool:
    return any(math.hypot(x - px, y - py) <= distance_px for px, py in points)


def marker_like(c: Candidate, settings: TrackerSettings, reference_contrast: float | None) -> bool:
    floor = MIN_MARKER_CONTRAST if reference_contrast is None else max(MIN_MARKER_CONTRAST, 0.5 * reference_contrast)
    return c.score >= settings.min_acquire_score and c.contrast >= floor


def inner_grey(image, x: float, y: float, radius: float, polarity: str) -> float:
    """Median grey inside the marker's inner half (in the marker's polarity): its own grey M."""
    half = max(1, int(0.5 * radius))
    xi, yi = int(round(x)), int(round(y))
    patch = image[max(0, yi - half) : yi + half + 1, max(0, xi - half) : xi + half + 1].astype(np.float32)
    grey = float(np.median(patch))
    return 255.0 - grey if polarity == "dark" else grey


def static_spot(image, background, c: Candidate, radius: float, reference_contrast: float | None) -> bool:
    """True when the scene itself holds this spot (it is in the background image): not the marker."""
    if background is None:
        return False
    half = max(1, int(radius * 0.7))
    xi, yi = int(round(c.x)), int(round(c.y))
    h, w = image.shape
    box = np.s_[max(0, yi - half) : min(h, yi + half + 1), max(0, xi - half) : min(w, xi + half + 1)]
    if image[box].size == 0:
        return True
    change = float(np.abs(image[box].astype(np.float32) - background[box]).mean())
    floor = MIN_MARKER_CONTRAST if reference_contrast is None else 0.3 * reference_contrast
    return change < floor


def spot_at(image: np.ndarray, near_px, min_score: float = 0.75) -> tuple[str, float, tuple[float, float]] | None:
    """The marker the user pointed at with ``start_px`` in the first frame, seen in that frame alone:
    ``(polarity, radius_px, centre)`` or None.

    Blobs of either sign in the DoG of the frame (:func:`pendulum.tracking.spots.dog_blobs`, per level) whose
    centre lies within their radius (and 2 px) of ``near_px``; of those that are disk-like (normalised
    disk-template correlation ≥ ``min_score``, :func:`pendulum.tracking.acquisition.marker_candidates`)
    the smallest: a dot on a body rather than the body. Radius and centre refined at full resolution
    (:func:`pendulum.tracking.spots.refine_spot`). No background is needed: what moves is not asked.
    """
    from pendulum.tracking.settings import TrackerSettings
    from pendulum.tracking.spots import dog_blobs, dog_pyramid, refine_spot

    h, w = image.shape
    reach = int(min(max(h, w) // 4, 320))
    nx, ny = float(near_px[0]), float(near_px[1])
    x0, y0 = max(0, int(nx) - reach), max(0, int(ny) - reach)
    crop = image[y0 : min(h, int(ny) + reach + 1), x0 : min(w, int(nx) + reach + 1)].astype(np.float32)
    if min(crop.shape) < 24:
        return None
    noise = 1.4826 * float(np.median(np.abs(crop[1:, 1:] - crop[:-1, :-1]))) / math.sqrt(2)
    found = []
    # per pyramid level (a dot on a bob is a weaker blob of the same sign inside the bob's: one search over
    # all scales would keep only the bob)
    threshold = max(2.0, 3.0 * noise)
    blobs = [b for k, level in enumerate(dog_pyramid(crop)) for b in dog_blobs([level], 1 << k, threshold, 64)]
    for sign, bx, by, r, _ in blobs:
        x, y = bx + x0, by + y0
        if math.hypot(x - nx, y - ny) > r + 2.0:
            continue
        refined = refine_spot(image, x, y, sign, r, None)
        if refined is None or math.hypot(refined[0] - nx, refined[1] - ny) > refined[2] + 2.0:
            continue
        polarity = "bright" if sign > 0 else "dark"
        probe = TrackerSettings(polarity=polarity, marker_radius_px=refined[2], start_px=(refined[0], refined[1]))
        best = marker_candidates(image, probe, near=refined[:2], search_radius_px=2 * refined[2] + 4, n=1)
        if (
            best
            and best[0].score >= min_score
            and math.hypot(best[0].x - refined[0], best[0].y - refined[1]) <= max(0.5 * refined[2], 2.0)
        ):
            found.append((refined[2], polarity, (refined[0], refined[1])))
    if not found:
        return None
    radius, polarity, centre = min(found, key=lambda f: f[0])
    return polarity, radius, centre
