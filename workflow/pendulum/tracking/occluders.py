"""Something static in front of the swing (a post, a tank's strut, a clamp): where the body is never seen
although its path crosses there, and the frames whose body reaches that place.

While the body is tracked, each frame's moving pixels (its component) are counted per image pixel (``seen``)
and, aligned at the body's centroid, per pixel of the body's own frame (its ``shape``). After the pass the
body's core (the pixels inside it in at least :data:`CORE_SHARE` of its frames) is stamped at the position of
every frame counted (not one cut by the frame's border): how often each image pixel was *expected* inside the
body. A pixel expected in at least :data:`MIN_EXPECTED` frames but seen in under :data:`SEEN_SHARE` of them, on
something that stands out of the wall in the static scene by more than a moving body must differ by, is hidden
by an object in front; a frame whose body (its shape, grown by 2 px: its soft rim) reaches such a pixel shows
only part of the body, and its centroid is pulled away from the hidden part.

A print's light squares or a faint half that drop out of the silhouette either move with the body (seen in
other frames there) or drop out of its shape too; a plain wall has nothing in front of the swing: neither
leaves a hidden place.
"""

from __future__ import annotations

import math

import cv2
import numpy as np

CORE_SHARE = 0.9  # the body's core: inside its silhouette in this share of its frames
SHAPE_SHARE = 0.5  # its shape: in half of them
MIN_EXPECTED = 8  # frames whose core covers a pixel before that pixel can be called hidden
SEEN_SHARE = 0.2  # ... seen in fewer than this share of them: hidden
MIN_HIDDEN_SHARE = 0.01  # a hidden place smaller than this share of the body's area is none (a few stray pixels)


class SilhouetteCounts:
    """Per image pixel how often the body was seen there, and its silhouettes aligned at their centroids."""

    def __init__(self, shape: tuple[int, int], radius_px: float):
        self.seen = np.zeros(shape, np.float32)
        self.half = int(math.ceil(2.0 * radius_px)) + 2
        self.shape = np.zeros((2 * self.half + 1, 2 * self.half + 1), np.float32)
        self.n = 0
        self.frames: list[int] = []  # the rows counted in ``seen``: only these are expected anywhere

    def add(self, row: int, component: np.ndarray, x0: int, y0: int, cx: float, cy: float) -> None:
        """Row ``row``'s component (bool, at ``x0, y0`` in the image), its body centred at ``cx, cy``."""
        h, w = component.shape
        self.seen[y0 : y0 + h, x0 : x0 + w] += component
        self.frames.append(row)
        # the component in the body's frame, its centroid at the middle (to the nearest pixel)
        ox, oy = self.half - int(round(cx - x0)), self.half - int(round(cy - y0))
        a0, b0 = max(ox, 0), max(oy, 0)
        a1, b1 = min(ox + w, self.shape.shape[1]), min(oy + h, self.shape.shape[0])
        if a1 > a0 and b1 > b0:
            self.shape[b0:b1, a0:a1] += component[b0 - oy : b1 - oy, a0 - ox : a1 - ox]
            self.n += 1


MAX_MEDIAN_KERNEL = 255  # OpenCV's 8-bit median over a larger window counts in 16 bits (a 350 px vehicle's failed)


def _median_wall(image: np.ndarray, size: int) -> np.ndarray:
    """The median of ``image`` (uint8) over ``size`` × ``size`` windows; above :data:`MAX_MEDIAN_KERNEL`, on the
    image reduced by the least power of two that brings the window within it, and enlarged back (the wall's
    large-scale look, all that is asked of it)."""
    if size <= MAX_MEDIAN_KERNEL:
        return cv2.medianBlur(image, size)
    factor = 2 ** math.ceil(math.log2(size / MAX_MEDIAN_KERNEL))
    small = cv2.resize(
        image, (max(image.shape[1] // factor, 1), max(image.shape[0] // factor, 1)), interpolation=cv2.INTER_AREA
    )
    wall = cv2.medianBlur(small, (size // factor) | 1)
    return cv2.resize(wall, (image.shape[1], image.shape[0]), interpolation=cv2.INTER_LINEAR)


def _stamps(image_shape, stamp: np.ndarray, half: int, xs: np.ndarray, ys: np.ndarray):
    """(index, image slice, stamp slice) of ``stamp`` centred at each finite (x, y), clipped to the image."""
    height, width = image_shape
    for k in np.flatnonzero(np.isfinite(xs) & np.isfinite(ys)):
        x0, y0 = int(round(xs[k])) - half, int(round(ys[k])) - half
        a0, b0 = max(x0, 0), max(y0, 0)
        a1, b1 = min(x0 + stamp.shape[1], width), min(y0 + stamp.shape[0], height)
        if a1 > a0 and b1 > b0:
            yield k, (slice(b0, b1), slice(a0, a1)), stamp[b0 - y0 : b1 - y0, a0 - x0 : a1 - x0]


def hidden_frames(
    counts: SilhouetteCounts,
    xs: np.ndarray,
    ys: np.ndarray,
    background: np.ndarray,
    threshold_grey: float,
    found_elsewhere: list | None = None,
) -> tuple[np.ndarray, dict]:
    """The frames whose body reaches a place something in front hides (bool per frame), and what was found:
    ``hidden_px`` (its pixel count), ``box_px`` (x, y, width, height) or None. The body is expected only where a
    counted frame put it (one cut by the frame's border is not counted, nor expected); something in front stands
    out of the wall around it by more than ``threshold_grey`` (the tracker's: what a moving body must differ by).

    ``found_elsewhere``: the box of such a place another view of the clip found (the brightness view's, for the
    colour view, where a neutral bar need not stand out): the body's unseen pixels within it, if there are as
    many as a hidden place needs, are that place in this view too (``seen_in`` ``brightness``; besides any place
    this view finds itself, and ``box_px`` then holds both). Where this view sees the body there, nothing hides
    it: the other view lost it against a wall of its own grey or colour."""
    none = np.zeros(xs.size, bool), {"hidden_px": 0, "box_px": None}
    if counts.n < MIN_EXPECTED:
        return none
    mean_shape = counts.shape / counts.n
    core = (mean_shape >= CORE_SHARE).astype(np.float32)
    body = cv2.dilate((mean_shape >= SHAPE_SHARE).astype(np.uint8), np.ones((5, 5), np.uint8)) > 0
    if core.sum() < 4:
        return none
    expected = np.zeros_like(counts.seen)
    rows = np.asarray(counts.frames, int)
    for _, where, stamp in _stamps(expected.shape, core, counts.half, xs[rows], ys[rows]):
        expected[where] += stamp
    unseen = (expected >= MIN_EXPECTED) & (counts.seen < SEEN_SHARE * expected)
    least = max(4, MIN_HIDDEN_SHARE * core.sum())
    # something in front shows in the static scene: it stands out of the wall around it
    wall = _median_wall(np.clip(np.rint(background), 0, 255).astype(np.uint8), 2 * (counts.half // 2) + 1)
    stands_out = np.abs(background - wall) > threshold_grey
    hidden = unseen & (cv2.dilate(stands_out.astype(np.uint8), np.ones((5, 5), np.uint8)) > 0)
    hidden &= hidden.sum() >= least  # a few stray pixels are no place
    facts = {}
    if found_elsewhere is not None:  # beside any place of this view's own: the other view's, if unseen here too
        x0, y0, width, height = found_elsewhere
        there = np.zeros_like(unseen)
        there[y0 : y0 + height, x0 : x0 + width] = unseen[y0 : y0 + height, x0 : x0 + width]
        if there.sum() >= least:
            hidden |= there
            facts = {"seen_in": "brightness"}
    if hidden.sum() < least:
        return none
    frames = np.zeros(xs.size, bool)
    for k, where, stamp in _stamps(hidden.shape, body, counts.half, xs, ys):
        frames[k] = bool((hidden[where] & stamp).any())
    ys_h, xs_h = np.nonzero(hidden)
    box = [int(xs_h.min()), int(ys_h.min()), int(xs_h.max() - xs_h.min() + 1), int(ys_h.max() - ys_h.min() + 1)]
    return frames, {"hidden_px": int(hidden.sum()), "box_px": box, **facts}
