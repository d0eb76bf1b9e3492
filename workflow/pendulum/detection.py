"""Marker detection: the object that swings about one fixed point, found from the video alone.

One sparse pass over the clip (every k-th decoded frame, ≤ ``max_samples`` spread over
the whole clip, reduced to ≤ ~640 px wide):

1. the static scene (clutter, stripes, letterbox borders, reflections of fixed lamps) per
   pixel: B_bright = the 10 % quantile of the samples, behind a spot brighter than it, and
   B_dark = the 90 % quantile, behind a darker one (a marker that swings little or comes to
   rest covers its pixels in most samples: a median would hold it; the quantiles do only if
   it is there in more than 90 % of them);
2. in every sample, the foreground F = I − B is searched for blobs (bright ones in I − B_bright,
   dark ones in I − B_dark) with a scale-normalised difference of Gaussians,
   DoG_σ = G_σ ∗ F − G_1.5σ ∗ F (a disk of radius r responds most near σ ≈ r / 1.7), on a
   Gaussian pyramid, each peak placed to a fraction of its level's sample (parabola vertex);
3. per sign, RANSAC finds the circle through blobs of different samples that holds most
   samples: |‖p − c‖ − R| ≤ tol, blob sizes alike; its least-squares refit gives the pivot
   c and arm R. An object qualifies when it moves (spans more than two radii of the arc)
   back and forth (its angle about c reverses at least twice, with about as many moves one
   way as the other: a bubble that rises and starts again does not) on a path that is a
   circle of bounded radius; a second object (a bubble, a float moving on a line, a border)
   or another part of the same pendulum (a track about the same pivot, or blobs that keep
   their place in the frame turning with the marker) is told apart by that; of the chosen
   track, blobs reached by a jump there and back (another object on the same circle, a spot
   held before the release) are dropped (:func:`pendulum.arcs.continuous_members`) and the
   circle is refitted by least squares to the rest;
4. the marker's radius is refined at full resolution from its width across the arc,
   width² = 4 var_across = r² for a disk (blur along the arc does not change it; where a rod
   or a body edge in the mask widens it, the edge radius stands), and its centre in the first
   frame from the linear centroid.

When no object qualifies, or two swing about different pivots with similar support,
:class:`DetectionError` says what was found and which tracking value (``polarity``,
``marker_radius_px``, ``start_px`` in the trial's sidecar) settles it.
"""

from __future__ import annotations

import math
import warnings
from dataclasses import dataclass, field, replace

import cv2
import numpy as np

from pendulum.arcs import (
    ArcTrack,
    Blobs,
    arc_track,
    continuous_members,
    find_arc_tracks,
    fit_circle,
)
from pendulum.centroids import edge_radius, linear_centroid
from pendulum.video import VideoError, iter_luma

PYRAMID_SIGMAS = (1.0, 1.5, 2.25, 3.375)  # DoG σ at each pyramid level (× 2^level), ratio 1.5
RADIUS_PER_SIGMA = 1.7  # disk radius ≈ 1.7 σ of the DoG scale where it responds most
MIN_SWING_BALANCE = 0.35  # moves one way over the other: a swing ~1 (0.53–1 seen), creep-and-jump-back ≤ 0.25
HANGS_DEG = 6.0  # a pendulum swings about the vertical below its pivot: its median angle within the camera roll
BACKGROUND_QUANTILE = 0.1  # scene behind a bright spot: the 10 % quantile of the samples (a dark one: 90 %)


class DetectionError(VideoError):
    """No single object swings about one fixed point clearly enough; the message says what was seen."""


@dataclass(frozen=True)
class Detection:
    """What the sparse pass found: the swinging marker, its arc and the static background."""

    polarity: str  # "bright" or "dark" against its surround
    marker_radius_px: float
    start_px: tuple[float, float] | None  # marker centre in frame 0 (None: not seen there)
    pivot_px: tuple[float, float]  # centre of the marker's arc (rough)
    arm_px: float  # radius of the arc
    confidence: float  # 0–1: samples on the arc, motion, no rival
    n_samples: int
    n_on_arc: int
    reversals: int
    active_box_px: tuple[int, int, int, int]  # x0, y0, x1, y1 of the picture inside letterbox borders
    rival: str | None = None  # the best other moving object, described, or None
    free_marker: bool = False  # the scene itself surrounds the marker (a ball on a string), no body around it
    # the first sample's spot on the arc when the continuity test dropped it (start_px then None): used only
    # when no search has a start that passed the test
    unchecked_start_px: tuple[float, float] | None = None
    n_continuous: int = 0  # samples on the arc that one object could have visited in turn (continuity test)
    rest_deg: float = 0.0  # median angle of the arc's samples about the pivot from the image's downward vertical
    background: np.ndarray | None = field(default=None, repr=False, compare=False)  # full-resolution median

    def describe(self) -> str:
        """One phrase: what was found, where it starts and its arc."""
        start = "" if self.start_px is None else f" starting at ({self.start_px[0]:.0f}, {self.start_px[1]:.0f}) px"
        return (
            f"a {self.polarity} spot (radius ≈ {self.marker_radius_px:.0f} px){start} on an arc about "
            f"({self.pivot_px[0]:.0f}, {self.pivot_px[1]:.0f}) px (arm {self.arm_px:.0f} px)"
        )

    def summary(self) -> dict:
        """JSON-ready record of the detection (no image)."""
        return {
            "polarity": self.polarity,
            "marker_radius_px": round(self.marker_radius_px, 2),
            "start_px": None if self.start_px is None else [round(v, 2) for v in self.start_px],
            "pivot_px": [round(v, 1) for v in self.pivot_px],
            "arm_px": round(self.arm_px, 1),
            "confidence": round(self.confidence, 3),
            "n_samples": self.n_samples,
            "n_on_arc": self.n_on_arc,
            "reversals": self.reversals,
            "active_box_px": list(self.active_box_px),
            "rival": self.rival,
            "free_marker": self.free_marker,
        }


def _sample_frames(path, max_samples: int, max_full: int, max_frames: int):
    """Every k-th frame (k doubling as needed) of the first ``max_frames``, at reduced scale; fewer at full size."""
    small, full = [], []  # (frame index, image)
    stride, stride_full, scale = 1, 1, None
    first = None
    for index, _t, image in iter_luma(path):
        if index >= max_frames:
            break
        if scale is None:
            scale = max(1, int(round(max(image.shape) / 640)))
            first = image.copy()
        if index % stride == 0:
            reduced = (
                image
                if scale == 1
                else cv2.resize(image, (image.shape[1] // scale, image.shape[0] // scale), interpolation=cv2.INTER_AREA)
            )
            small.append((index, reduced.copy()))
            if len(small) >= 2 * max_samples:
                small, stride = small[::2], stride * 2
        if index % stride_full == 0:
            full.append((index, image.copy()))
            if len(full) >= 2 * max_full:
                full, stride_full = full[::2], stride_full * 2
    if first is None:
        raise VideoError(f"{path}: no frame could be decoded")
    return small, full, scale, first


def _peak_offset(response: np.ndarray, y: int, x: int, sign: int) -> tuple[float, float]:
    """Sub-sample offset of a peak of ``sign`` × ``response`` at (x, y): the vertex of the parabola through it
    and its two neighbours, per axis, δ = (f₋ − f₊) / (2 (f₋ − 2 f₀ + f₊)), within ±0.5 (0 at the border).

    On a coarse pyramid level a sample is 4–8 px of the frame: without it, the blobs of a large marker on a
    small swing lie on a grid, and a circle through them cannot show the arc's 2 px sagitta."""
    h, w = response.shape
    offsets = []
    for dy, dx in ((0, 1), (1, 0)):
        if not (0 < y < h - 1 and 0 < x < w - 1):
            offsets.append(0.0)
            continue
        lo, mid, hi = (sign * float(response[y + k * dy, x + k * dx]) for k in (-1, 0, 1))
        curvature = lo - 2.0 * mid + hi
        offsets.append(float(np.clip(0.5 * (lo - hi) / curvature, -0.5, 0.5)) if curvature < 0 else 0.0)
    return offsets[0], offsets[1]


def _dog_blobs(fg: np.ndarray, scale: int, threshold: float, per_sign: int):
    """Peaks of the scale-normalised DoG of ``fg`` (both signs): list of (sign, x, y, r, s), full-res units."""
    found = []
    level_img = fg
    level = 0
    while min(level_img.shape) >= 24 and level < 4:
        blurred = [cv2.GaussianBlur(level_img, (0, 0), s) for s in PYRAMID_SIGMAS]
        blurred.append(cv2.GaussianBlur(level_img, (0, 0), PYRAMID_SIGMAS[-1] * 1.5))
        dogs = [cv2.subtract(blurred[i], blurred[i + 1]) for i in range(len(PYRAMID_SIGMAS))]
        top, low = dogs[0], dogs[0]
        for dog in dogs[1:]:
            top, low = cv2.max(top, dog), cv2.min(low, dog)
        kernel = np.ones((3, 3), np.uint8)
        f = scale * (1 << level)
        for sign in (1, -1):
            best = top if sign > 0 else cv2.multiply(low, -1.0)
            peaks = (best >= cv2.dilate(best, kernel)) & (best > threshold)
            ys, xs = np.nonzero(peaks)
            if ys.size > per_sign:
                keep = np.argsort(best[ys, xs])[-per_sign:]
                ys, xs = ys[keep], xs[keep]
            for yy, xx in zip(ys, xs, strict=True):
                which = int(np.argmax([sign * d[yy, xx] for d in dogs]))
                sigma = PYRAMID_SIGMAS[which] * 1.22
                dx, dy = _peak_offset(dogs[which], yy, xx, sign)
                found.append(
                    (
                        sign,
                        (xx + dx + 0.5) * f - 0.5,
                        (yy + dy + 0.5) * f - 0.5,
                        RADIUS_PER_SIGMA * sigma * f,
                        float(best[yy, xx]),
                    )
                )
        level_img = cv2.pyrDown(level_img)
        level += 1
    # One blob per place: the strongest response suppresses weaker ones within its radius (any scale).
    found.sort(key=lambda b: -b[4])
    kept: list = []
    for b in found:
        if all(b[0] != k[0] or math.hypot(b[1] - k[1], b[2] - k[2]) > max(b[3], k[3]) for k in kept):
            kept.append(b)
    out = []
    for sign in (1, -1):
        out.extend([b for b in kept if b[0] == sign][:per_sign])
    return out


def _quantile_backgrounds(stack: np.ndarray, quantile: float) -> tuple[np.ndarray, np.ndarray]:
    """Per-pixel ``quantile`` and 1 − ``quantile`` of the (n, h, w) samples (float32)."""
    n = stack.shape[0]
    k_low = int(quantile * (n - 1))
    k_high = n - 1 - k_low
    ordered = np.partition(stack, sorted({k_low, k_high}), axis=0)
    return ordered[k_low].astype(np.float32), ordered[k_high].astype(np.float32)


def _active_box(background: np.ndarray, scale: int) -> tuple[int, int, int, int]:
    """The picture inside uniform borders (letterbox/pillarbox): edge rows/columns of one flat grey."""
    b = background.astype(np.float32)

    def border(lines: np.ndarray) -> int:
        """How many lines from the start are flat (std < 2) and of the first line's grey (± 3)."""
        n = 0
        level = float(lines[0].mean())
        while n < lines.shape[0] // 3 and lines[n].std() < 2.0 and abs(float(lines[n].mean()) - level) < 3.0:
            n += 1
        return n

    h, w = b.shape
    top, bottom = border(b), border(b[::-1])
    left, right = border(b.T), border(b.T[::-1])
    return left * scale, top * scale, (w - right) * scale, (h - bottom) * scale


def _refine(image: np.ndarray, x: float, y: float, sign: int, radius: float, tangent):
    """Radius from width² across the motion and centre from the linear centroid (full resolution).

    The width² of the moments takes in whatever touches the marker inside its mask (a rod, a body
    barely larger than the marker: +1.4 px on a 14.8 px marker); on an unblurred spot whose edge
    radius (:func:`edge_radius`) disagrees by more than max(0.25 px, 2.5 %), the edge radius stands
    (on clean rendered disks of 5–20 px the two agree within 0.1 px).
    """
    h, w = image.shape

    def window(x, y, r):
        half = int(math.ceil(2.5 * r + 10))
        xi, yi = int(round(x)), int(round(y))
        x0, x1, y0, y1 = max(0, xi - half), min(w, xi + half + 1), max(0, yi - half), min(h, yi + half + 1)
        roi = image[y0:y1, x0:x1].astype(np.float32)
        return (255.0 - roi if sign < 0 else roi), x0, y0

    r = radius
    for _ in range(4):
        roi, x0, y0 = window(x, y, r)
        res = linear_centroid(roi, x0, y0, x, y, r, 0.0, tangent)
        if res is None or not math.isfinite(res[4]) or res[4] <= 0:
            return None
        x, y = res[0], res[1]
        r_new = float(np.clip(math.sqrt(res[4]), 0.7 * r, 1.4 * r))
        if abs(r_new - r) < 0.02 * r:
            r = r_new
            break
        r = r_new
    streak2 = res[2]
    if math.isfinite(streak2) and streak2 < (0.5 * r) ** 2:
        r_edge = edge_radius(roi, x - x0, y - y0, r)
        if r_edge is not None and abs(r_edge - r) > max(0.25, 0.025 * r_edge):
            r = r_edge
            roi, x0, y0 = window(x, y, r)
            res = linear_centroid(roi, x0, y0, x, y, r, 0.0, tangent)
            if res is None:
                return None
            x, y = res[0], res[1]
    return x, y, r


def detect_marker(path, max_samples: int = 60, max_full: int = 12, max_frames: int = 1800, seed: int = 0) -> Detection:
    """Find the swinging marker in the video at ``path`` (see the module docstring).

    Only the first ``max_frames`` frames are read (30 s at 60 fps: a long clip's swing is there).
    The search runs against two estimates of the static scene: the per-pixel median (a spot that
    is elsewhere most of the time) and the quantiles (a marker that swings little or rests is
    seen there too, but a scene patch the moving body often covers can look like a spot). When
    both find a marker starting at the same place, the one whose arc holds more of the marker's
    samples stands (its pivot is the better founded); when one finds none, the other's stands; when
    they disagree and only one path is a pendulum's swing (:func:`_one_swing`), that one stands;
    otherwise the video does not say which is the marker and the error names both.

    Raises :class:`DetectionError` when nothing, or more than one thing, swings about a
    fixed point; the message names what was found and the sidecar value that settles it.
    """
    small, full, scale, first = _sample_frames(path, max_samples, max_full, max_frames)
    n = len(small)
    if n < 12:
        raise DetectionError(
            f"{path}: only {n} frames: too short to find the swinging marker; give tracking polarity, "
            "marker_radius_px and start_px in the trial's sidecar"
        )
    outcomes = []
    for quantile in (0.5, BACKGROUND_QUANTILE):
        try:
            outcomes.append(_detect(path, small, full, scale, first, seed, quantile))
        except DetectionError as error:
            outcomes.append(error)
    started = [d for d in outcomes if isinstance(d, Detection) and d.start_px is not None]
    if len(started) == 2:
        median_based, quantile_based = started
        if math.dist(median_based.start_px, quantile_based.start_px) <= max(
            median_based.marker_radius_px, quantile_based.marker_radius_px
        ):  # the same marker: the arc one object visits in more samples (the median's on a tie)
            return max(started, key=lambda d: d.n_continuous)
        settled = _one_swing(median_based, quantile_based)
        if settled is not None:
            return settled
        raise DetectionError(
            f"{path}: not sure which object is the marker: against the scene's median it is "
            f"{median_based.describe()}, against the scene with every moving spot taken out "
            f"{quantile_based.describe()}; give the marker's start_px (its centre in the first frame), polarity "
            "and marker_radius_px in the trial's sidecar (with all three given, no detection runs)"
        )
    if started:
        return started[0]
    found = [d for d in outcomes if isinstance(d, Detection)]
    unchecked = [d for d in found if d.unchecked_start_px is not None]
    if unchecked:  # no search has a start that passed the continuity test: the first sample's spot on the arc
        return replace(unchecked[0], start_px=unchecked[0].unchecked_start_px)
    if found:
        return found[0]
    raise outcomes[0]


def _one_swing(a: Detection, b: Detection) -> Detection | None:
    """Of two answers that disagree, the one whose path is a pendulum's swing, if only one is.

    An arc that one object visits in turn in at least twice as many samples beats the other (whose
    blobs, jumping there and back, are of several objects: body features, a second object); then
    an arc that swings about the vertical below its pivot (median angle within ``HANGS_DEG``: the
    camera's roll; or about the vertical above it, for a nearly flat arc fitted about a centre on
    the wrong side) beats one whose samples lie more than twice that to one side (a circle fitted
    to an object moving on a line has its centre anywhere). None when neither rule separates them.
    """
    for one, other in ((a, b), (b, a)):
        if one.n_continuous >= 2 * other.n_continuous:
            return one
    for one, other in ((a, b), (b, a)):
        if _off_vertical_deg(one.rest_deg) <= HANGS_DEG and _off_vertical_deg(other.rest_deg) > 2 * HANGS_DEG:
            return one
    return None


def _off_vertical_deg(rest_deg: float) -> float:
    """How far an arc's median angle lies from the vertical through its centre, below or above: a nearly
    flat arc's centre may be fitted on the wrong side (median angle near ±180°)."""
    return min(abs(rest_deg), 180.0 - abs(rest_deg))


def _detect(path, small, full, scale: int, first, seed: int, quantile: float) -> Detection:
    """The swinging marker in the samples, spots sought against the ``quantile`` background (0.5: the median)."""
    n = len(small)
    stack = np.stack([img for _, img in small])
    background = np.median(stack, axis=0).astype(np.float32)
    some = stack[:: max(1, n // 10), ::4, ::4].astype(np.float32) - background[None, ::4, ::4]
    noise = 1.4826 * float(np.median(np.abs(some)))
    threshold = max(2.0, 1.5 * noise)
    # A bright spot is sought against the scene without it: per pixel a low quantile over the samples
    # (a dark spot: a high one). A marker that swings little, or comes to rest, covers its pixels in
    # most samples: the median would hold it and hide it; the quantiles do while it is elsewhere in at
    # least that share of them.
    if quantile == 0.5:
        references = [(background, 0)]  # both signs against the median
    else:
        low, high = _quantile_backgrounds(stack, quantile)
        references = [(low, 1), (high, -1)]
    rows = []
    for k in range(n):
        frame = stack[k].astype(np.float32)
        for reference, wanted in references:
            for sign, x, y, r, s in _dog_blobs(frame - reference, scale, threshold, per_sign=8):
                if wanted in (0, sign):
                    rows.append((k, sign, x, y, r, s))
    where = f"{path}: "
    hint = (
        "give tracking polarity, marker_radius_px and start_px (the marker's centre in the first frame) "
        "in the trial's sidecar"
    )
    if not rows:
        raise DetectionError(f"{where}nothing moves in {n} sampled frames; {hint}")
    a = np.array(rows, float)
    blobs = Blobs(a[:, 0].astype(int), a[:, 1].astype(int), a[:, 2], a[:, 3], a[:, 4], a[:, 5])
    rng = np.random.default_rng(seed)
    h, w = first.shape
    tracks = find_arc_tracks(blobs, n, (h, w), scale, rng)
    # a second round without the first tracks' blobs: other objects
    used = np.zeros(blobs.sign.size, bool)
    for t in tracks:
        used[t.members] = True
    tracks += find_arc_tracks(blobs, n, (h, w), scale, rng, exclude=used)
    for t in tracks:  # rank by the spot's own contrast in the frame (a disk on its surround), not the DoG's
        t.strength = _local_contrast(stack, blobs, t, scale)
    min_members = max(6, int(0.25 * n))

    def swings(t: ArcTrack) -> bool:
        return (
            t.reversals >= 2
            and t.balance >= MIN_SWING_BALANCE
            and t.span_px >= 2 * t.radius
            and len(t.members) >= min_members
        )

    swinging = [t for t in tracks if swings(t)]
    if not swinging:
        seen = max(tracks, key=lambda t: t.support, default=None)
        what = (
            "no moving spot follows a circle"
            if seen is None
            else (
                f"the best is {seen.describe(n)}, which "
                + (
                    "does not move back and forth"
                    if seen.reversals < 2 or seen.balance < MIN_SWING_BALANCE
                    else "hardly moves"
                )
            )
        )
        raise DetectionError(f"{where}no object swings back and forth about a fixed point ({what}); {hint}")

    # A pendulum hangs below its pivot: arcs whose samples lie about the vertical through their fitted
    # centre (median angle within 2 HANGS_DEG of straight below it or, since a nearly flat arc's centre
    # may be fitted on the wrong side, straight above) come first. An object moving on a sloped line (its
    # fitted centre off to one side) is taken only when no arc hangs.
    def hangs(t: ArcTrack) -> bool:
        return _off_vertical_deg(_rest_deg(blobs, t)) <= 2 * HANGS_DEG

    swinging.sort(key=lambda t: (not hangs(t), -t.support))
    best = swinging[0]

    def same_pendulum(t: ArcTrack) -> bool:
        """About the same pivot, or rigidly attached to the best track: a part of the same pendulum."""
        return math.hypot(t.cx - best.cx, t.cy - best.cy) <= max(3 * best.radius, 0.08 * best.arm) or _attached(
            blobs, t, best
        )

    if not best.curved:
        # A path that a straight line fits as well as a circle shows no pivot of its own (its circle is an
        # extrapolation; an object moving on a line gives one too): a clearly curved arc that hangs below
        # its pivot, with at least half the support, is the better evidence of a pendulum.
        hanging = [t for t in swinging[1:] if t.curved and abs(_rest_deg(blobs, t)) <= HANGS_DEG]
        if hanging and hanging[0].support >= 0.5 * best.support:
            best = hanging[0]
            swinging.remove(best)
            swinging.insert(0, best)

    rivals = []
    for t in swinging[1:]:
        if same_pendulum(t):
            continue
        # Blobs of the pendulum's own body can share an arc with another object's: judged without them.
        own = _attached_members(blobs, t, best, scale)
        if own.any():
            rest = t.members[~own]
            if rest.size < 5:
                continue
            t = arc_track(blobs, rest, t.sign, fit_circle(blobs.x[rest], blobs.y[rest]), scale)
            t.strength = _local_contrast(stack, blobs, t, scale)
            if not swings(t) or same_pendulum(t):
                continue
        rivals.append(t)
    rivals.sort(key=lambda t: -t.support)
    # A clearly curved arc beats a path that a straight line fits as well (an object moving on a line),
    # and an arc that hangs below its pivot one that does not (a second pendulum hangs too).
    if rivals and best.curved:
        rivals = [t for t in rivals if t.curved]
    if rivals and hangs(best):
        rivals = [t for t in rivals if hangs(t)]
    rival = rivals[0] if rivals else None
    if rival is not None and rival.support >= 0.5 * best.support:
        raise DetectionError(
            f"{where}two objects swing: {best.describe(n)}, and {rival.describe(n)}; give the marker's start_px "
            "(its centre in the first frame), polarity and marker_radius_px in the trial's sidecar (with all three "
            "given, no detection runs)"
        )
    # Blobs of other objects on the same circle (reached by a jump there and back) are not the marker's.
    # The first sample's member, if dropped, is kept aside: a start for when no search has a checked one.
    first_member = next((int(i) for i in best.members if blobs.sample[i] == 0), None)
    kept, _ = continuous_members(blobs, best, scale)
    refit = fit_circle(blobs.x[kept], blobs.y[kept])  # least squares on the one object's sub-pixel blobs
    cleaned = arc_track(blobs, kept, best.sign, refit, scale, best.radius)
    if swings(cleaned):
        best = cleaned
    # Full-resolution refinement: radius from samples on the arc, start in frame 0.
    positions = {small[int(blobs.sample[i])][0]: (blobs.x[i], blobs.y[i]) for i in best.members}
    bg_full = _marker_free_background(full, positions, best.radius)
    # Judged where the scene is best known: in the outer half of the swing (a body moving with the
    # marker covers the middle of the swing in most frames, and so is part of the median there).
    angles = {f: math.atan2(x - best.cx, y - best.cy) for f, (x, y) in positions.items()}
    middle = float(np.median(list(angles.values())))
    reach = max(abs(a - middle) for a in angles.values())
    outer = {f: xy for f, xy in positions.items() if abs(angles[f] - middle) >= 0.5 * reach}
    diff = full[len(full) // 2][1][::2, ::2] - bg_full[::2, ::2]
    noise_full = 1.4826 * float(np.nanmedian(np.abs(diff - np.nanmedian(diff))))
    free = _surround_is_scene(full, outer, bg_full, best.radius, max(5.0, 2.5 * noise_full))
    if free and np.isnan(bg_full).any():  # no body: the scene is seen closer to the marker (a narrow swing's middle)
        closer = _marker_free_background(full, positions, best.radius, reach_radii=1.2)
        bg_full = np.where(np.isnan(bg_full), closer, bg_full)

    def scene_removed(image):
        """For a free marker: the image less the scene (a striped wall does not bend the moments)."""
        if not free:
            return image
        out = image.astype(np.float32) - bg_full + 128.0
        return np.where(np.isfinite(out), out, image).astype(np.float32)

    on_arc = {int(blobs.sample[i]): i for i in best.members}
    small_index = {k: frame for k, (frame, _) in enumerate(small)}
    radii = []
    for frame, image in full:
        k = next((k for k, f in small_index.items() if f == frame), None)
        if k is None or k not in on_arc:
            continue
        i = on_arc[k]
        tangent = _tangent(blobs.x[i], blobs.y[i], best)
        res = _refine(scene_removed(image), blobs.x[i], blobs.y[i], best.sign, best.radius, tangent)
        if res is not None:
            radii.append(res[2])
    radius = float(np.median(radii)) if radii else best.radius
    start = unchecked_start = None
    held = _held_from_the_start(blobs, on_arc, max(1.5 * scale, 0.1 * radius))
    # the first sample's spot: checked while it is on the kept track, or where the marker is held still
    i = on_arc[0] if 0 in on_arc else held if held is not None else first_member
    if i is not None:
        tangent = _tangent(blobs.x[i], blobs.y[i], best)
        res = _refine(scene_removed(first), blobs.x[i], blobs.y[i], best.sign, radius, tangent)
        if res is not None and math.dist(res[:2], (blobs.x[i], blobs.y[i])) > max(0.5 * radius, 2.0 * scale):
            res = None  # the refinement ran off its spot (to a stripe, a rod): no marker-sized spot there
        if res is not None:
            if 0 in on_arc or held is not None:
                start = (float(res[0]), float(res[1]))
            elif (
                abs(math.dist(res[:2], (best.cx, best.cy)) - best.arm) <= max(radius, 2.0 * scale)
                and abs(res[2] / radius - 1.0) <= 0.2
            ):  # a spot dropped from the track: a start only where it is on the circle and marker-sized
                unchecked_start = (float(res[0]), float(res[1]))
            if not radii:
                radius = res[2]
    coverage = len(best.members) / n
    rival_share = 0.0 if rival is None else min(1.0, rival.support / best.support)
    confidence = float(min(1.0, coverage / 0.6) * min(1.0, best.reversals / 4) * (1.0 - rival_share))
    return Detection(
        polarity="bright" if best.sign > 0 else "dark",
        marker_radius_px=radius,
        start_px=start,
        pivot_px=(float(best.cx), float(best.cy)),
        arm_px=float(best.arm),
        confidence=confidence,
        n_samples=n,
        n_on_arc=len(best.members),
        reversals=best.reversals,
        active_box_px=_active_box(background, scale),
        rival=None if rival is None else rival.describe(n),
        background=bg_full,
        free_marker=free,
        unchecked_start_px=unchecked_start,
        n_continuous=int(kept.size),
        rest_deg=math.degrees(middle),
    )


def _rest_deg(blobs: Blobs, track: ArcTrack) -> float:
    """Median angle of a track's blobs about its pivot from the image's downward vertical, atan2(x − cx, y − cy)."""
    idx = track.members
    return math.degrees(float(np.median(np.arctan2(blobs.x[idx] - track.cx, blobs.y[idx] - track.cy))))


def _held_from_the_start(blobs: Blobs, on_arc: dict, still_px: float) -> int | None:
    """The first kept member when the marker is held still from the track's start, else None.

    When the first sample's spot is not on the kept track (another object's spot on the circle there) but
    the first three kept members lie in samples 1–4 within ``still_px`` of each other, the marker was
    held there before the release: in the first frame it is at that place too.
    """
    if 0 in on_arc or len(on_arc) < 3:
        return None
    firsts = sorted(on_arc)[:3]
    if firsts[-1] > 4:
        return None
    points = [(blobs.x[on_arc[k]], blobs.y[on_arc[k]]) for k in firsts]
    if max(math.dist(p, q) for p in points for q in points) > still_px:
        return None
    return int(on_arc[firsts[0]])


def _local_contrast(stack: np.ndarray, blobs: Blobs, track: ArcTrack, scale: int) -> float:
    """Median contrast of a track's spots against their own surround in the frame, in its polarity.

    Mean grey within 0.7 r of the centre minus the mean over the ring 1.3–2 r (reduced frames):
    a marker dot scores its full contrast; a corner or edge of a body scores a fraction.
    """
    values = []
    _, h, w = stack.shape
    for i in track.members:
        img = stack[int(blobs.sample[i])]
        x, y, r = blobs.x[i] / scale, blobs.y[i] / scale, max(1.0, blobs.r[i] / scale)
        half = int(math.ceil(2 * r)) + 1
        xi, yi = int(round(x)), int(round(y))
        if xi - half < 0 or yi - half < 0 or xi + half >= w or yi + half >= h:
            continue
        patch = img[yi - half : yi + half + 1, xi - half : xi + half + 1].astype(np.float32)
        yy, xx = np.mgrid[-half : half + 1, -half : half + 1]
        d = np.hypot(xx + xi - x, yy + yi - y)
        inner, ring = d <= 0.7 * r, (d >= 1.3 * r) & (d <= 2 * r)
        if inner.any() and ring.any():
            values.append(track.sign * (float(patch[inner].mean()) - float(patch[ring].mean())))
    return max(float(np.median(values)), 0.0) if values else 0.0


def _body_frame(blobs: Blobs, other: ArcTrack, track: ArcTrack) -> tuple[np.ndarray, np.ndarray]:
    """Where ``other``'s blobs sit in the frame turning with ``track``: (member positions, points).

    Each blob is rotated about the track's pivot by minus the track's angle in the same sample
    (members in samples without a track blob are left out).
    """
    angle = {int(blobs.sample[i]): math.atan2(blobs.x[i] - track.cx, blobs.y[i] - track.cy) for i in track.members}
    rows, pts = [], []
    for k, i in enumerate(other.members):
        a = angle.get(int(blobs.sample[i]))
        if a is None:
            continue
        dx, dy = blobs.x[i] - track.cx, blobs.y[i] - track.cy
        c, s = math.cos(a), math.sin(a)
        rows.append(k)
        pts.append((dx * c - dy * s, dx * s + dy * c))  # rotate by −a (angle measured from +y towards +x)
    return np.array(rows, int), np.array(pts, float).reshape(-1, 2)


def _attached(blobs: Blobs, other: ArcTrack, track: ArcTrack) -> bool:
    """True when ``other`` keeps its place in the frame that turns with ``track`` (a part of the same body):
    its blobs' places there (:func:`_body_frame`) lie within a few marker radii of one point."""
    _, pts = _body_frame(blobs, other, track)
    if len(pts) < 5:
        return False
    spread = np.median(np.hypot(*(pts - np.median(pts, axis=0)).T))
    return bool(spread <= max(3 * track.radius, 0.05 * track.arm))


def _distances(points: np.ndarray) -> np.ndarray:
    """All pairwise Euclidean distances of (n, 2) points: an (n, n) array."""
    return np.hypot(*(points[:, None, :] - points[None, :, :]).transpose(2, 0, 1))


def _attached_members(blobs: Blobs, other: ArcTrack, track: ArcTrack, scale: int) -> np.ndarray:
    """Which blobs of ``other`` are rigid parts of ``track``'s pendulum (bool per member).

    Blobs that keep one place in the frame turning with the pendulum (:func:`_body_frame`;
    at least five within tol = max(0.6 r, 0.02 arm, 1.5 px × sample scale)) while their image
    positions move apart by more than 4 tol are parts of it, and so are blobs on the pendulum's
    axis (|x| ≤ tol from the pivot to 3 r beyond the marker: the rod's or body's outline against
    the scene). A second object that only passes one place now and then (at rest, or at one phase
    of the swing) does not.
    """
    attached = np.zeros(len(other.members), bool)
    rows_left, body_left = _body_frame(blobs, other, track)
    tol = max(0.6 * other.radius, 0.02 * track.arm, 1.5 * scale)
    if rows_left.size:
        # on the line from the pivot through the marker (the rod, the body's axis): features of the
        # pendulum's own outline, e.g. where the rod crosses a background stripe
        x, y = body_left[:, 0], body_left[:, 1]
        on_axis = (np.abs(x) <= tol) & (y >= -tol) & (y <= track.arm + 3 * track.radius)
        attached[rows_left[on_axis]] = True
        rows_left, body_left = rows_left[~on_axis], body_left[~on_axis]
    while rows_left.size >= 5:
        near = _distances(body_left) <= tol
        centre = int(np.argmax(near.sum(axis=1)))
        cluster = near[centre]
        if cluster.sum() < 5:
            break
        members = other.members[rows_left[cluster]]
        image = np.column_stack([blobs.x[members], blobs.y[members]])
        moved = _distances(image).max()
        if moved > 4 * tol:
            attached[rows_left[cluster]] = True
        rows_left, body_left = rows_left[~cluster], body_left[~cluster]
    return attached


def _tangent(x, y, track: ArcTrack):
    rx, ry = x - track.cx, y - track.cy
    norm = math.hypot(rx, ry) or 1.0
    return (-ry / norm, rx / norm)


def _marker_free_background(frames, positions: dict, radius: float, reach_radii: float = 2.5) -> np.ndarray:
    """Per-pixel median over ``frames`` [(index, image)] leaving out the marker's neighbourhood in each.

    ``positions``: frame index → marker centre (full resolution). Pixels within ``reach_radii`` r + 4 px
    of the marker in a frame do not count for that frame (a body around the marker can have
    nearly the scene's grey: a tighter reach takes it for the scene, so 1.2 r + 4 px only for a
    marker with no body); a pixel covered in every frame (a marker at rest there throughout, or
    the middle of a swing narrower than that reach) is NaN: the scene behind it is unknown.
    """
    stack = np.stack([img for _, img in frames]).astype(np.float32)
    h, w = stack.shape[1:]
    reach = reach_radii * radius + 4.0
    near = np.zeros((h, w), np.uint8)
    disks = []
    for k, (index, _) in enumerate(frames):
        if index in positions:
            x, y = positions[index]
            disks.append((k, x, y))
            cv2.circle(near, (int(round(x)), int(round(y))), int(math.ceil(reach)) + 1, 1, -1)
    background = np.median(stack, axis=0)
    ys, xs = np.nonzero(near)
    if ys.size:
        values = stack[:, ys, xs]
        seen = {k for k, _, _ in disks}
        for k in range(len(frames)):
            if k not in seen:  # marker not found in this frame (e.g. at rest, in the median): not used here
                values[k] = np.nan
        for k, x, y in disks:
            values[k, np.hypot(xs - x, ys - y) <= reach] = np.nan
        with warnings.catch_warnings():
            warnings.simplefilter("ignore", RuntimeWarning)
            background[ys, xs] = np.nanmedian(values, axis=0)
    return background.astype(np.float32)


def _surround_is_scene(frames, positions: dict, background: np.ndarray, radius: float, tolerance: float) -> bool:
    """True when, in most frames, the ring just outside the marker shows the static scene (no body).

    Ring: r + 3.5 to r + 6.5 px around the marker; it matches when 85 % of its pixels are
    within ``tolerance`` grey levels (the noise's) of the background.
    """
    votes = []
    for index, image in frames:
        if index not in positions:
            continue
        x, y = positions[index]
        half = int(math.ceil(radius + 8))
        xi, yi = int(round(x)), int(round(y))
        h, w = image.shape
        if xi - half < 0 or yi - half < 0 or xi + half >= w or yi + half >= h:
            continue
        box = np.s_[yi - half : yi + half + 1, xi - half : xi + half + 1]
        yy, xx = np.mgrid[box]
        d = np.hypot(xx - x, yy - y)
        ring = (d > radius + 3.5) & (d <= radius + 6.5)
        img, bg = image[box].astype(np.float32), background[box]
        if not np.isfinite(bg[ring]).all():
            continue
        votes.append(float(np.percentile(np.abs(img[ring] - bg[ring]), 85)) <= tolerance)
    return len(votes) >= 5 and float(np.mean(votes)) >= 0.6
