"""Detection's image side: frames sampled over the clip, the static scene behind a spot, blobs of a
difference of Gaussians, a spot refined at full resolution, and whether the marker's surround is scene.

A blob is a peak of the scale-normalised DoG_σ = G_σ ∗ F − G_1.5σ ∗ F of the foreground F = I − B on a
Gaussian pyramid (a disk of radius r responds most near σ ≈ r / 1.7), placed to a fraction of its
level's sample by the parabola vertex x̂ = x + ½ (f₋ − f₊) / (f₋ − 2 f₀ + f₊).
"""

from __future__ import annotations

import math
import warnings

import cv2
import numpy as np

from pendulum.tracking.arcs import ArcTrack, Blobs
from pendulum.tracking.centroids import edge_radius, linear_centroid
from pendulum.tracking.samples import spread_frames, spread_indices

PYRAMID_SIGMAS = (1.0, 1.5, 2.25, 3.375)  # DoG σ at each pyramid level (× 2^level), ratio 1.5
RADIUS_PER_SIGMA = 1.7  # disk radius ≈ 1.7 σ of the DoG scale where it responds most
PIXELS_PER_BLOCK = 1 << 18  # pixels per block of the marker-free median (memory, not results)


def sample_frames(path, max_samples: int, max_full: int, max_frames: int):
    """Every k-th frame (k doubling as needed) of the first ``max_frames``, at reduced scale; fewer at full size
    (:func:`pendulum.tracking.samples.spread_frames`: decoded once per clip)."""
    frames, decoded = spread_frames(path, max(max_samples, max_full), max_frames)  # the larger set holds the other
    first = frames[0][1]
    scale = max(1, int(round(max(first.shape) / 640)))
    size = (first.shape[1] // scale, first.shape[0] // scale)
    wanted = set(spread_indices(decoded, max_samples))
    small = [
        (i, image if scale == 1 else cv2.resize(image, size, interpolation=cv2.INTER_AREA))
        for i, image in frames
        if i in wanted
    ]
    wanted = set(spread_indices(decoded, max_full))
    full = [(i, image) for i, image in frames if i in wanted]
    return small, full, scale, first


def _peak_place(dogs: list[np.ndarray], y: int, x: int, sign: int) -> tuple[int, float, float]:
    """The scale a peak at (x, y) of ``sign`` × DoG responds most to (the first of equals) and its sub-sample
    offsets there: per axis, the vertex of the parabola through the peak and its two neighbours,
    δ = (f₋ − f₊) / (2 (f₋ − 2 f₀ + f₊)), within ±0.5 (0 at the border or where the three do not curve down).

    On a coarse pyramid level a sample is 4–8 px of the frame: without it, the blobs of a large marker on a
    small swing lie on a grid, and a circle through them cannot show the arc's 2 px sagitta. One peak at a
    time in plain floats (a level keeps at most 8: array steps on so few points cost more than the arithmetic);
    the responses are float32, the vertex float64."""
    responses = [sign * dog[y, x] for dog in dogs]
    which = max(range(len(dogs)), key=lambda k: (responses[k], -k))
    dog = dogs[which]
    h, w = dog.shape
    if not (0 < y < h - 1 and 0 < x < w - 1):
        return which, 0.0, 0.0
    offsets = []
    for lo, mid, hi in ((dog[y, x - 1], dog[y, x], dog[y, x + 1]), (dog[y - 1, x], dog[y, x], dog[y + 1, x])):
        lo, mid, hi = sign * float(lo), sign * float(mid), sign * float(hi)
        curvature = lo - 2.0 * mid + hi
        offsets.append(min(max(0.5 * (lo - hi) / curvature, -0.5), 0.5) if curvature < 0 else 0.0)
    return which, offsets[0], offsets[1]


def dog_pyramid(image: np.ndarray) -> list[list[np.ndarray]]:
    """The DoG responses of ``image`` on each pyramid level: ``[[DoG_σ for σ in PYRAMID_SIGMAS] per level]``.

    Every step (Gaussian blurs, differences, ``pyrDown``) is linear, so the pyramid of a foreground
    F = I − B is the pyramid of I less that of B: one pyramid per frame serves every background.
    """
    levels = []
    level_img = image.astype(np.float32, copy=False)
    while min(level_img.shape) >= 24 and len(levels) < 4:
        blurred = [cv2.GaussianBlur(level_img, (0, 0), s) for s in PYRAMID_SIGMAS]
        blurred.append(cv2.GaussianBlur(level_img, (0, 0), PYRAMID_SIGMAS[-1] * 1.5))
        levels.append([cv2.subtract(blurred[i], blurred[i + 1]) for i in range(len(PYRAMID_SIGMAS))])
        level_img = cv2.pyrDown(level_img)
    return levels


def dog_blobs(fg, scale: int, threshold: float, per_sign: int, signs: tuple[int, ...] = (1, -1)):
    """Peaks of the scale-normalised DoG of ``fg`` (an image, or its :func:`dog_pyramid`) of the given
    ``signs``: list of (sign, x, y, r, s), full-res units."""
    levels = dog_pyramid(fg) if isinstance(fg, np.ndarray) else fg
    found = []
    kernel = np.ones((3, 3), np.uint8)
    for level, dogs in enumerate(levels):
        f = scale * (1 << level)
        for sign in signs:  # the strongest response over the level's scales, of this sign
            best = dogs[0]
            for dog in dogs[1:]:
                best = cv2.max(best, dog) if sign > 0 else cv2.min(best, dog)
            if sign < 0:
                best = cv2.multiply(best, -1.0)
            peaks = (best >= cv2.dilate(best, kernel)) & (best > threshold)
            points = cv2.findNonZero(peaks.view(np.uint8))  # (x, y) row by row, as np.nonzero
            if points is None:
                continue
            points = points.reshape(-1, 2).astype(np.intp)
            xs, ys = points[:, 0], points[:, 1]
            if ys.size > per_sign:
                keep = np.argsort(best[ys, xs])[-per_sign:]
                ys, xs = ys[keep], xs[keep]
            places = [_peak_place(dogs, y, x, sign) for y, x in zip(ys.tolist(), xs.tolist(), strict=True)]
            which, dx, dy = np.array(places).T  # each peak placed on the DoG level it responds most to
            which = which.astype(np.intp)
            sigma = np.asarray(PYRAMID_SIGMAS)[which] * 1.22
            found.extend(
                zip(
                    [sign] * ys.size,
                    ((xs + dx + 0.5) * f - 0.5).tolist(),
                    ((ys + dy + 0.5) * f - 0.5).tolist(),
                    (RADIUS_PER_SIGMA * sigma * f).tolist(),
                    best[ys, xs].astype(np.float64).tolist(),
                    strict=True,
                )
            )
    # One blob per place: the strongest response suppresses weaker ones within its radius (any scale).
    found.sort(key=lambda b: -b[4])
    kept: list = []
    for b in found:
        if all(b[0] != k[0] or math.hypot(b[1] - k[1], b[2] - k[2]) > max(b[3], k[3]) for k in kept):
            kept.append(b)
    out = []
    for sign in signs:
        out.extend([b for b in kept if b[0] == sign][:per_sign])
    return out


def foreground_pyramid(
    frame: list[list[np.ndarray]], reference: list[list[np.ndarray]], out: list[list[np.ndarray]] | None = None
) -> list[list[np.ndarray]]:
    """The DoG pyramid of I − B from those of I and B (:func:`dog_pyramid`), written into ``out`` when given (a
    pyramid of the same shapes, reused from frame to frame and background to background: its images are not
    allocated anew for each)."""
    if out is None:
        out = [[np.empty_like(a) for a in fa] for fa in frame]
    for fa, fb, fo in zip(frame, reference, out, strict=True):
        for a, b, o in zip(fa, fb, fo, strict=True):
            cv2.subtract(a, b, dst=o)
    return out


def scene_quantiles(stack: np.ndarray, quantile: float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Per-pixel median, ``quantile`` and 1 − ``quantile`` of the (n, h, w) samples (float32), from one partial
    sort (the median as :func:`numpy.median` gives it: the mean of the middle two of an even n)."""
    n = stack.shape[0]
    k_low = int(quantile * (n - 1))
    k_high = n - 1 - k_low
    middle = sorted({(n - 1) // 2, n // 2})
    ordered = np.partition(stack, sorted({k_low, k_high, *middle}), axis=0)
    median = (ordered[middle[0]].astype(np.float64) + ordered[middle[-1]]) / 2
    return median.astype(np.float32), ordered[k_low].astype(np.float32), ordered[k_high].astype(np.float32)


def active_box(background: np.ndarray, scale: int) -> tuple[int, int, int, int]:
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


def refine_spot(image: np.ndarray, x: float, y: float, sign: int, radius: float, tangent):
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


def local_contrast(stack: np.ndarray, blobs: Blobs, track: ArcTrack, scale: int) -> float:
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


def full_scene(frames) -> tuple[np.ndarray, np.ndarray]:
    """The (n, h, w) stack of ``frames`` [(index, image)] and its per-pixel median, float32 (computed once per clip)."""
    images = np.stack([img for _, img in frames])
    return images, np.median(images, axis=0).astype(np.float32)


def marker_free_background(
    frames, positions: dict, radius: float, reach_radii: float = 2.5, scene: tuple | None = None
) -> np.ndarray:
    """Per-pixel median over ``frames`` [(index, image)] leaving out the marker's neighbourhood in each.

    ``positions``: frame index → marker centre (full resolution). Pixels within ``reach_radii`` r + 4 px
    of the marker in a frame do not count for that frame (a body around the marker can have
    nearly the scene's grey: a tighter reach takes it for the scene, so 1.2 r + 4 px only for a
    marker with no body); a pixel covered in every frame (a marker at rest there throughout, or
    the middle of a swing narrower than that reach) is NaN: the scene behind it is unknown.
    ``scene``: :func:`full_scene` of ``frames``, when the caller has it.
    """
    stack, median = full_scene(frames) if scene is None else scene
    h, w = stack.shape[1:]
    reach = reach_radii * radius + 4.0
    near = np.zeros((h, w), np.uint8)
    disks = []
    for k, (index, _) in enumerate(frames):
        if index in positions:
            x, y = positions[index]
            disks.append((k, x, y))
            cv2.circle(near, (int(round(x)), int(round(y))), int(math.ceil(reach)) + 1, 1, -1)
    background = median.copy()
    ys_all, xs_all = np.nonzero(near)
    seen = {k for k, _, _ in disks}
    for start in range(0, ys_all.size, PIXELS_PER_BLOCK):  # a block of pixels at a time (a 4K clip's are many)
        ys, xs = ys_all[start : start + PIXELS_PER_BLOCK], xs_all[start : start + PIXELS_PER_BLOCK]
        values = stack[:, ys, xs].astype(np.float32)
        for k in range(len(frames)):
            if k not in seen:  # marker not found in this frame (e.g. at rest, in the median): not used here
                values[k] = np.nan
        for k, x, y in disks:
            values[k, np.hypot(xs - x, ys - y) <= reach] = np.nan
        with warnings.catch_warnings():
            warnings.simplefilter("ignore", RuntimeWarning)
            background[ys, xs] = np.nanmedian(values, axis=0)
    return background.astype(np.float32)


def surround_is_scene(frames, positions: dict, background: np.ndarray, radius: float, tolerance: float) -> bool:
    """True when, in most frames, the ring just outside the marker shows the static scene (no body).

    Ring: r + 3.5 to r + 6.5 px around the marker; it matches when 85 % of its pixels are
    within ``tolerance`` grey levels (the noise's) of the background; free when 60 % of at least 3
    frames match (a long clip whose swing decays has few full-size samples on the outer half).
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
    return len(votes) >= 3 and float(np.mean(votes)) >= 0.6
