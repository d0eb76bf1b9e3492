"""The static scene behind a swinging body, from frames sampled over the clip (:mod:`pendulum.tracking.body`).

Samples brought to one exposure, their moving objects found against a scene estimate and left out of the
next (the per-pixel median of the rest, :mod:`pendulum.tracking.scene_stack`; a compact one by its convex
hull, so that a ghost of it in the scene leaves with it), the pixels that almost no sample shows clear filled
from their surroundings and that fill checked (:func:`unseen_regions`), and, for a body that covers its own
rest place in most samples, the scene there from the two ends of its swing (:func:`rest_place_scene`).
"""

from __future__ import annotations

import math

import cv2
import numpy as np

from pendulum.tracking.samples import spread_frames
from pendulum.tracking.scene_stack import fill, min_clear_samples

# closing disk that joins a body's patches across gaps of wall-coloured surface: 5 px at 360 lines, 15 at 1080
CLOSE_FRACTION = 1 / 72
MIN_BODY_AREA_PX = 12  # a moving component smaller than this is noise
HULL_AREA_RATIO = 4.0  # a moving object's convex hull is left out where at most this many times its area
TWO_OBJECTS_MASS_RATIO = 0.4  # a second moving object at least this heavy (Σ D) in most samples: ambiguous


def sample_clip(path, n_samples: int, view=None) -> list[tuple[int, np.ndarray]]:
    """Every k-th decoded frame (k doubling as needed): between n and 2n frames over the whole clip, frame 0 first
    (read-only; :func:`pendulum.tracking.samples.spread_frames`: decoded once per clip; ``view``: as there)."""
    return spread_frames(path, n_samples, view=view)[0]


def close_size(shape) -> int:
    return max(5, 2 * int(round(min(shape[:2]) * CLOSE_FRACTION / 2)) + 1)


def components(diff: np.ndarray, threshold: float, open_px: int, close_px: int = 5):
    """Connected components of ``diff > threshold`` after a closing (the image continued by background), its holes
    filled where they are a body's markings (:func:`fill_markings`), and an opening (the image continued by the body
    where it is cut): (labels, stats, masses)."""
    whole = (diff > threshold).astype(np.uint8)
    # The morphology on the pixels that can change: the box of the pixels above the threshold grown by both
    # kernels' reach (beyond it the result is 0 whatever the border; where the box meets the image's edge, the
    # edge's own rule below applies). The same labels as over the whole image; a large body's window (4K) is
    # mostly wall, and an opening with a 70 px disk costs per pixel.
    points = cv2.findNonZero(whole)
    h, w = whole.shape
    if points is None:
        return np.zeros((h, w), np.int32), np.array([[0, 0, w, h, h * w]], np.int32), np.zeros(1)
    bx, by, bw, bh = cv2.boundingRect(points)
    reach = close_px // 2 + open_px // 2 + 2
    # even corners: the labelling scans 2 × 2 blocks, whose order names the components
    x0, y0 = max(bx - reach, 0) & ~1, max(by - reach, 0) & ~1
    x1, y1 = min(bx + bw + reach, w), min(by + bh + reach, h)
    mask = whole[y0:y1, x0:x1]
    # closed first: the dark squares of a print, or a body's dark patches, are one object; with the image
    # continued by background (OpenCV's default border counts beyond the image as foreground for the erosion,
    # so a closing would stretch a body near the border out to it, and call it cut by the border)
    pad = close_px // 2 + 1
    padded = cv2.copyMakeBorder(mask, pad, pad, pad, pad, cv2.BORDER_CONSTANT, value=0)
    closed = cv2.morphologyEx(padded, cv2.MORPH_CLOSE, cv2.getStructuringElement(cv2.MORPH_ELLIPSE, (close_px,) * 2))
    fill_markings(closed)
    mask = closed[pad:-pad, pad:-pad]
    if open_px > 1:  # OpenCV's default border on purpose: a body the border cuts is not opened away there
        # (at an edge of the box inside the image the border's foreground reaches no pixel the closing set: those
        # lie within the closing's reach of a pixel above the threshold, over the opening's reach from that edge)
        kernel = cv2.getStructuringElement(cv2.MORPH_ELLIPSE, (open_px, open_px))
        mask = cv2.morphologyEx(mask, cv2.MORPH_OPEN, kernel)
    n, part, stats, _ = cv2.connectedComponentsWithStats(mask, connectivity=8)
    labels = np.zeros((h, w), np.int32)
    labels[y0:y1, x0:x1] = part
    stats[1:, 0] += x0
    stats[1:, 1] += y0
    stats[0] = (0, 0, w, h, h * w - int(stats[1:, 4].sum()))  # the background: the rest of the image
    masses = np.zeros(n)
    if n > 1:
        # over the box only: every labelled pixel is in it, each summed in the same order as over the image
        masses = np.bincount(part.ravel(), weights=diff[y0:y1, x0:x1].ravel(), minlength=n)
        masses[0] = 0.0
    return labels, stats, masses


MARKING_SHARE = 0.1  # a component's holes together up to this share of it, filled: its markings (a dot: (a / R)²)
THIN_EDGE_SHARE = 0.25  # ... unless more of a hole's rim than this is thread (gone in a 3 px opening): a loop of it


def fill_markings(closed: np.ndarray) -> None:
    """Fill, in place, each component's holes in ``closed`` (uint8 0/1, its border background) where together they
    are at most :data:`MARKING_SHARE` of the component filled, and each one's rim is not mostly thread: a white dot
    or a label on a dark body is the body's own. Until 2026-12-03 such a dot stayed a hole: the body's inner radius
    came out halved, and with it the opening that cuts its thread, so an apple's stem was followed in some frames and
    not others (2 px at the swing's ends). Holes that are more of it (a print's light squares: the pattern, not its
    outline) are left as they are, and so is the wall seen through a loop of thread or a handle above the body (over
    :data:`THIN_EDGE_SHARE` of its rim gone in a 3 px opening; filled, it moved a bob 5 px along its thread)."""
    outside = closed.copy()
    cv2.floodFill(outside, None, (0, 0), 1)
    if outside.all():  # no holes at all (the usual frame)
        return
    n, labels, stats, _ = cv2.connectedComponentsWithStats(closed, connectivity=8)
    thick = cv2.morphologyEx(closed, cv2.MORPH_OPEN, np.ones((3, 3), np.uint8))
    for i in range(1, n):
        x, y, w, h, area = (int(v) for v in stats[i])
        own = np.zeros((h + 2, w + 2), np.uint8)
        own[1:-1, 1:-1] = labels[y : y + h, x : x + w] == i
        reached = own.copy()
        cv2.floodFill(reached, None, (0, 0), 1)
        holes = (reached[1:-1, 1:-1] == 0) & (closed[y : y + h, x : x + w] == 0)  # its own (islands in them aside)
        n_holes = int(np.count_nonzero(holes))
        if not n_holes or n_holes > MARKING_SHARE * (n_holes + area):
            continue
        count, parts = cv2.connectedComponents(holes.astype(np.uint8), connectivity=4)
        for k in range(1, count):
            hole = (parts == k).astype(np.uint8)
            rim = (cv2.dilate(hole, np.ones((3, 3), np.uint8)) > 0) & (own[1:-1, 1:-1] > 0)
            thin = rim & (thick[y : y + h, x : x + w] == 0)
            if np.count_nonzero(thin) <= THIN_EDGE_SHARE * np.count_nonzero(rim):
                closed[y : y + h, x : x + w][hole > 0] = 1


def reduced(image: np.ndarray, scale: int) -> np.ndarray:
    return cv2.resize(image, (image.shape[1] // scale, image.shape[0] // scale), interpolation=cv2.INTER_AREA)


def _heavy(stats: np.ndarray, masses: np.ndarray, share: float = 0.1) -> list[int]:
    """Moving components of ≥ :data:`MIN_BODY_AREA_PX`, heaviest first, down to ``share`` of the heaviest's Σ D."""
    order = [i for i in np.argsort(masses)[::-1] if i > 0 and stats[i, cv2.CC_STAT_AREA] >= MIN_BODY_AREA_PX]
    return [i for i in order if masses[i] >= share * masses[order[0]]]


def _far_pair(stats: np.ndarray, masses: np.ndarray, order: list[int]):
    """The box centres (x, y) of the two heaviest moving objects (``order``: :func:`_heavy`'s) where the second is at
    least :data:`TWO_OBJECTS_MASS_RATIO` as heavy and they lie apart by more than twice their radii; else None."""
    if len(order) < 2 or masses[order[1]] < TWO_OBJECTS_MASS_RATIO * masses[order[0]]:
        return None
    a, b = order[:2]
    (ax, ay), (bx, by) = (stats[a, :2] + stats[a, 2:4] / 2), (stats[b, :2] + stats[b, 2:4] / 2)
    ra, rb = (math.sqrt(stats[i, cv2.CC_STAT_AREA] / math.pi) for i in (a, b))
    return ((float(ax), float(ay)), (float(bx), float(by))) if math.hypot(ax - bx, ay - by) > 2 * (ra + rb) else None


def two_objects_where(image: np.ndarray, background: np.ndarray, threshold: float, sampled) -> str:
    """Where two swinging objects are, for a refusal that asks for ``start_px``: their centres in ``image`` (the
    first frame, as start_px is given) where it shows both, else ``sampled`` (their centres in a later sample)."""
    diff = np.abs(image.astype(np.float32) - background)
    labels, stats, masses = components(diff, threshold, 3, close_size(diff.shape))
    order = _heavy(stats, masses, 0.0)
    pair = _far_pair(stats, masses, order)
    if pair:  # each by its centroid weighted by D, within its box (its box's centre, or a hull's, is pulled along
        # its thread: soft_centroid's filled hull put the real apple 48 px above itself)
        pair = []
        for i in order[:2]:
            x0, y0, w, h = (int(v) for v in stats[i, :4])
            m = cv2.moments(np.where(labels[y0 : y0 + h, x0 : x0 + w] == i, diff[y0 : y0 + h, x0 : x0 + w], 0.0))
            pair.append((x0 + m["m10"] / m["m00"], y0 + m["m01"] / m["m00"]))
    (ax, ay), (bx, by) = pair or sampled
    where = "in the first frame" if pair else "in a sampled frame"
    return f"{where} near ({ax:.0f}, {ay:.0f}) and ({bx:.0f}, {by:.0f}) px"


def moving_objects(images: list, background: np.ndarray, threshold: float):
    """Per sample, the pixels of its heavier moving objects (each by its convex hull where that is compact:
    :func:`_hulls`; grown by 4 px); how many samples show one; how many show two far-apart objects of similar
    weight, and where."""
    excluded = np.zeros((len(images),) + background.shape, bool)
    moving, areas, pairs = 0, [], []
    grow = cv2.getStructuringElement(cv2.MORPH_ELLIPSE, (9, 9))
    for k, image in enumerate(images):
        diff = np.abs(image.astype(np.float32) - background)
        labels, stats, masses = components(diff, threshold, 3, close_size(diff.shape))
        order = _heavy(stats, masses, 0.0)
        if not order:
            continue
        moving += 1
        heavy = [i for i in order if masses[i] >= 0.1 * masses[order[0]]]
        excluded[k] = cv2.dilate(_hulls(labels, heavy), grow) > 0
        areas.append(stats[order[0], cv2.CC_STAT_AREA])
        if (pair := _far_pair(stats, masses, order)) is not None:
            pairs.append((stats[order[1], cv2.CC_STAT_AREA], *pair))
    # two objects: the second as heavy as 0.4× the first and at least a third the body's usual size, far apart
    typical = float(np.median(areas)) if areas else 0.0
    seen = [(p, q) for area, p, q in pairs if area >= typical / 3]
    return excluded, moving, len(seen), seen


OUTLINE_RATIO = 1.5  # a moving object outlined in the sample (its edge this much stronger there than in the scene)
ONE_SIDED_MEAN = 0.5  # mean(I − B) / mean|I − B| of an object lighter (or darker) than the scene in most of it


def scene_states(images: list, stack: np.ndarray, background: np.ndarray, threshold: float) -> np.ndarray | None:
    """Per sample, the pixels to leave out of the scene (as :func:`pendulum.tracking.scene_stack.masked_median`
    takes them) where ``background`` holds a ghost that :func:`min_clear_samples` samples show clear; or None.

    A body at rest over half the clip is the median scene at its rest place, and while it still swings wide every
    sample shows the wall there: a second "moving" object, often heavier than the body (before a print, whose
    grid the body covers), and taken for it in the first frame (a calendar on the wall: the track 20–127 px off in
    190 of its 1,275 ok frames). Such a ghost recurs: its pixels are the same (median |I − I_k| ≤ ``threshold``)
    in :func:`min_clear_samples` samples, where the body is elsewhere; it is the body's negative: lighter than
    the scene where a moving object beside it is darker (or the reverse), each in most of its pixels
    (:data:`ONE_SIDED_MEAN`); and its outline is the scene's (:func:`_outline`: a body overlapping itself near its
    turning points recurs too, outlined in the sample). There the sample shows the scene clear, and the samples
    without it are left out. A body held still before its release recurs too, but no lighter object moves beside
    a dark one; a body of both sides (a two-tone ball) is left as the median has it. ``stack``: the ``images`` as
    one (n, h, w) array."""
    n = len(images)
    clear = np.zeros(stack.shape, bool)
    for k, image in enumerate(images):
        diff = np.abs(image.astype(np.float32) - background)
        labels, stats, masses = components(diff, threshold, 3, close_size(diff.shape))
        heavy = _heavy(stats, masses)[:4]
        if len(heavy) < 2:
            continue
        recurring, sides, outlined = [], [], []
        for i in heavy:
            x, y, w, h, _ = (int(v) for v in stats[i])
            own = labels[y : y + h, x : x + w] == i
            values = stack[:, y : y + h, x : x + w][:, own].astype(np.float32)
            same = np.median(np.abs(values - values[k]), axis=1) <= threshold
            recurring.append(int(same.sum()) >= min_clear_samples(n))
            signed = values[k] - background[y : y + h, x : x + w][own]
            sides.append(float(signed.mean() / np.abs(signed).mean()))
            outlined.append(_outline(image, background, labels, i, (x, y, w, h)))
        # a ghost is the body's negative: the wall where the scene has the body, against the body where it has wall;
        # its outline is the scene's, not the sample's (a body at a turning point recurs too, outlined in the sample)
        moving = [s for r, s in zip(recurring, sides, strict=True) if not r and abs(s) >= ONE_SIDED_MEAN]
        ghosts = [
            i
            for i, r, s, o in zip(heavy, recurring, sides, outlined, strict=True)
            if r and o == "scene" and abs(s) >= ONE_SIDED_MEAN and any(s * m < 0 for m in moving)
        ]
        if ghosts:
            clear[k] = np.isin(labels, ghosts)
    ghost = clear.sum(axis=0) >= min_clear_samples(n)
    return ghost[None] & ~clear if ghost.any() else None


def _outline(image: np.ndarray, scene: np.ndarray, labels: np.ndarray, i: int, box: tuple[int, int, int, int]) -> str:
    """Whose edge runs along component ``i``'s border (``labels``, within ``box``), by the mean gradient magnitude
    there: ``"image"``
    where the image's is over :data:`OUTLINE_RATIO` times the scene's (a body in the sample: 199 against 1 grey
    level per px on a reviewer's swing before a plain wall), else ``"scene"`` (a ghost: the body is in the scene
    and the sample shows the wall; before a calendar both carry its print, 350 against 357)."""
    x, y, w, h = box
    y0, y1, x0, x1 = max(y - 2, 0), min(y + h + 2, labels.shape[0]), max(x - 2, 0), min(x + w + 2, labels.shape[1])
    own = (labels[y0:y1, x0:x1] == i).astype(np.uint8)
    border = (own - cv2.erode(own, np.ones((3, 3), np.uint8))).astype(bool)

    def edge(picture):
        crop = picture[y0:y1, x0:x1].astype(np.float32)
        return float(np.hypot(cv2.Sobel(crop, cv2.CV_32F, 1, 0), cv2.Sobel(crop, cv2.CV_32F, 0, 1))[border].mean())

    return "image" if edge(image) > OUTLINE_RATIO * edge(scene) else "scene"


def _hulls(labels: np.ndarray, chosen: list) -> np.ndarray:
    """The ``chosen`` components (uint8 mask), each filled to its convex hull where the hull is at most
    :data:`HULL_AREA_RATIO` times its area (a body, bitten, with its rod: 2–3.5×; not an L-shaped edge). Where
    the scene still holds part of the body (where it dwells over half the samples), its pixels there do not
    differ: a bite or a hole in its component, which the hull covers, so that the next scene leaves that
    sample out there too."""
    mask = np.zeros(labels.shape, np.uint8)
    for i in chosen:
        own = (labels == i).astype(np.uint8)
        hull = cv2.convexHull(cv2.findNonZero(own))
        if cv2.contourArea(hull) <= HULL_AREA_RATIO * int(own.sum()):
            cv2.fillConvexPoly(mask, hull, 1)
        mask |= own
    return mask


def unseen_regions(scene: np.ndarray, hidden: np.ndarray, avoid: np.ndarray) -> list[tuple[float, float, int, float]]:
    """Per connected region of ``hidden``: its centre x, y, area (px) and how far off its fill (:func:`fill`) is
    likely to be (grey levels): the region moved aside by its own size (left, right, up, down, in the frame),
    filled the same way (with the scene's other filled pixels, ``avoid``) and compared with the scene it covers
    where that is known (at least half of it): the 90th percentile of |filled − scene|, the median over the
    directions (one may land on a rod or a second pendulum; NaN where none fits). A plain wall or a smooth
    gradient fills to within the noise; a patterned one does not."""
    n, labels, stats, centres = cv2.connectedComponentsWithStats(hidden.astype(np.uint8), connectivity=8)
    h, w = scene.shape
    regions = []
    for i in range(1, n):
        x0, y0, bw, bh, area = (int(v) for v in stats[i])
        errors = []
        for dx, dy in ((-bw - 4, 0), (bw + 4, 0), (0, -bh - 4), (0, bh + 4)):
            if not (0 <= x0 + dx and x0 + bw + dx <= w and 0 <= y0 + dy and y0 + bh + dy <= h):
                continue
            # a crop around the region and its moved copy (the fill reaches 3 px beyond them)
            cx0, cy0 = max(min(x0, x0 + dx) - 8, 0), max(min(y0, y0 + dy) - 8, 0)
            cx1, cy1 = min(max(x0, x0 + dx) + bw + 8, w), min(max(y0, y0 + dy) + bh + 8, h)
            moved = np.zeros((cy1 - cy0, cx1 - cx0), bool)
            own = labels[y0 : y0 + bh, x0 : x0 + bw] == i
            moved[y0 + dy - cy0 : y0 + dy - cy0 + bh, x0 + dx - cx0 : x0 + dx - cx0 + bw] = own
            filled_already = avoid[cy0:cy1, cx0:cx1]
            compared = moved & ~filled_already  # where the scene there is known (a rod's, another's place is not)
            if compared.sum() < 0.5 * area:
                continue
            crop = scene[cy0:cy1, cx0:cx1]
            errors.append(np.abs(fill(crop, moved | filled_already)[compared] - crop[compared]))
        error = float(np.median([np.percentile(e, 90) for e in errors])) if errors else math.nan
        regions.append((float(centres[i][0]), float(centres[i][1]), area, error))
    return regions


def unseen_behind(scene: np.ndarray, hidden: np.ndarray, xy: np.ndarray, radius_px: float, threshold_grey: float):
    """The scene's filled pixels (``hidden``, :func:`unseen`) that the body covers on its path (within
    ``radius_px`` of a position in ``xy``: a rod's place or another pendulum's does not count), where they are at
    least 2 % of its area, per region (:func:`unseen_regions`) as facts; and a reason to refuse when one's fill
    is likely off by more than ``threshold_grey`` (or cannot be checked), else None."""
    if not hidden.any():
        return [], None
    covered = np.zeros(hidden.shape, np.uint8)
    for x, y in np.unique(np.round(xy[np.all(np.isfinite(xy), axis=1)]).astype(int), axis=0):
        cv2.circle(covered, (int(x), int(y)), int(math.ceil(radius_px)), 1, -1)
    behind = hidden & (covered > 0)
    if behind.sum() < 0.02 * math.pi * radius_px**2:
        return [], None
    facts, reason = [], None
    for x, y, area, error in unseen_regions(scene, behind, hidden):
        facts.append({"at_px": [round(x, 1), round(y, 1)], "area_px": area, "fill_error_grey": round(error, 2)})
        if reason is None and area >= 0.02 * math.pi * radius_px**2 and not error <= threshold_grey:
            why = (
                f"the wall around it is not plain enough to fill it in (a fill there is likely {error:.0f} grey levels "
                f"off, above {threshold_grey:.0f})"
                if math.isfinite(error)
                else "a fill of it cannot be checked (no place nearby where the scene is known)"
            )
            reason = (
                f"the scene behind the body near ({x:.0f}, {y:.0f}) px ({area} px) is seen clear in almost no sampled "
                f"frame (something moving covers it in nearly all: a swing narrower than about the body's width), and "
                f"{why}: its positions would be biased; film a wider swing, or give start_px at a marker dot on it"
            )
    return facts, reason


def rest_place_scene(
    frames, images, background, track, radius_px: float, threshold: float, keep=None
) -> tuple[np.ndarray, bool]:
    """The scene with the body's rest place filled from the two ends of its swing.

    A body that covers its rest place in most samples is part of the median scene there. At the ends of a
    swing wider than the body it is elsewhere: the samples (``frames``, ``images``) at each end (the tenth
    with the lowest and the highest position along the path's main direction, from ``track``'s ok frames)
    have one median each, B₋ and B₊; where they differ by more than ``threshold`` one of them holds the
    body, the end's own (the pixels on its side of the bisector between the two ends' mean positions), and
    the scene there is taken from the other; where they agree but the median scene differs from them (the
    body between its two ends), from them. Only within 2 ``radius_px`` + 10 px of the segment between the
    two ends (another moving object elsewhere is left as the median has it). Second: whether the ends saw
    the rest place clear (each more than 1.2 ``radius_px`` from the middle between them). The ``keep`` pixels
    (:func:`unseen`: filled in, the ends show the body there too) stay as ``background`` has them.
    """
    ok = track[track.flag == "ok"].set_index("frame")
    at = [(k, float(ok.x_px[f]), float(ok.y_px[f])) for k, f in enumerate(frames) if f in ok.index]
    if len(at) < 10:
        return background, False
    xy = np.array([(x, y) for _, x, y in at])
    centred = xy - xy.mean(axis=0)
    _, _, axes = np.linalg.svd(centred, full_matrices=False)
    order = np.argsort(centred @ axes[0])
    m = max(3, len(at) // 10)
    ends = []
    for picks in (order[:m], order[-m:]):
        scene = np.median(np.stack([images[at[i][0]] for i in picks]), axis=0).astype(np.float32)
        ends.append((scene, xy[picks].mean(axis=0)))
    (low, c_low), (high, c_high) = ends
    span = c_high - c_low
    length = float(np.hypot(*span))
    if length <= 0:
        return background, False
    yy, xx = np.indices(background.shape, dtype=np.float32)
    along = ((xx - c_low[0]) * span[0] + (yy - c_low[1]) * span[1]) / length
    across = np.abs((xx - c_low[0]) * span[1] - (yy - c_low[1]) * span[0]) / length
    beyond = np.maximum(np.maximum(-along, along - length), 0.0)
    near = np.hypot(across, beyond) <= 2 * radius_px + 10
    if keep is not None:
        near &= ~keep
    differs = near & (np.abs(low - high) > threshold)
    composite = np.where(along < 0.5 * length, high, low)  # the low end's body is on its side: the high end's scene
    both = 0.5 * (low + high)  # where the two ends agree, neither holds the body: the wall, if the median had it
    held = near & ~differs & (np.abs(background - both) > threshold)
    scene = np.where(differs, composite, np.where(held, both, background)).astype(np.float32)
    return scene, length / 2 > 1.2 * radius_px


ONE_SIDED_SHARE = 0.8  # the body is darker (or lighter) than the scene: this share of its moving pixels' |I − B|


def body_polarity(images: list, background: np.ndarray, moving: np.ndarray, threshold: float) -> str:
    """``"dark"``, ``"bright"`` or ``"both"``: on which side of the scene the body's grey lies, over all samples.

    Σ|I − B| of the samples' moving pixels (above ``threshold``) that are darker than the scene, against those
    lighter: one side holding :data:`ONE_SIDED_SHARE` of it makes the body one-sided. A one-sided body is
    measured by that side's difference only (:func:`one_sided`), so a part of nearly the wall's grey (a
    two-tone ball's light half) stays out of its silhouette also where it passes before a darker patch of wall
    (a shadow band), instead of joining it there and moving its centre."""
    dark = bright = 0.0
    for image, mask in zip(images, moving, strict=True):
        if mask.any():
            signed = image[mask].astype(np.float32) - background[mask]
            signed = signed[np.abs(signed) > threshold]
            dark -= float(signed[signed < 0].sum())
            bright += float(signed[signed > 0].sum())
    total = dark + bright
    if total <= 0:
        return "both"
    return "dark" if dark >= ONE_SIDED_SHARE * total else "bright" if bright >= ONE_SIDED_SHARE * total else "both"


def one_sided(signed: np.ndarray, polarity: str) -> np.ndarray:
    """The difference D a body of this polarity is measured by: −(I − B) or (I − B) clipped at 0, or |I − B|."""
    if polarity == "dark":
        return np.maximum(-signed, 0.0)
    if polarity == "bright":
        return np.maximum(signed, 0.0)
    return np.abs(signed)


STRONG_FRACTION = 0.25  # the silhouette: pixels differing by more than this fraction of the body's contrast, filled


def silhouette_fraction(values: np.ndarray) -> float:
    """The share of the body's contrast C above which a pixel counts for its silhouette, fixed for the clip.

    :data:`STRONG_FRACTION` unless the body's differences from the wall fall in two well-separated groups
    (a dark half and a half of nearly the wall's grey: Otsu's split explains ≥ 75 % of their variance and
    the lower group's mean is under 45 % of the upper's); then the split itself, so the faint part is left
    out in every frame instead of flickering in and out with its texture.
    """
    values = np.asarray(values, float)
    top = float(np.percentile(values, 90)) if values.size else 0.0
    if values.size < 30 or top <= 0:
        return STRONG_FRACTION
    scaled = np.clip(values / top * 200, 0, 255).astype(np.uint8).reshape(-1, 1)
    split, _ = cv2.threshold(scaled, 0, 255, cv2.THRESH_BINARY + cv2.THRESH_OTSU)
    cut = split / 200 * top
    low, high = values[values <= cut], values[values > cut]
    if low.size < 0.1 * values.size or high.size < 0.3 * values.size:
        return STRONG_FRACTION
    between = low.size * high.size / values.size**2 * (high.mean() - low.mean()) ** 2
    if between < 0.75 * values.var() or low.mean() > 0.45 * high.mean():
        return STRONG_FRACTION
    return max(STRONG_FRACTION, cut / top)


def silhouette_hull(diff: np.ndarray, component: np.ndarray, fraction: float) -> tuple[np.ndarray | None, float]:
    """The body's silhouette as a convex polygon, and C_f: the hull of the component's strong pixels (D > ``fraction``
    C_f, C_f the component's 90th percentile of D; None under 3 of them). A part that hardly differs from the wall
    (a bright half before a bright wall, the light squares of a print) is left out or filled in the same way in
    every frame. Taken from the strong pixels' outer boundaries within the component's box (every extreme pixel
    lies on one: the same hull as from all of them, a large body's tens of thousands of pixels not handed over)."""
    contrast = float(np.percentile(diff[component], 90))
    bx, by, bw, bh = cv2.boundingRect(component.view(np.uint8))
    box = np.s_[by : by + bh, bx : bx + bw]
    strong = (component[box] & (diff[box] > fraction * contrast)).astype(np.uint8)
    if cv2.countNonZero(strong) < 3:
        return None, contrast
    outlines, _ = cv2.findContours(strong, cv2.RETR_EXTERNAL, cv2.CHAIN_APPROX_NONE, offset=(bx, by))
    return cv2.convexHull(np.concatenate(outlines)), contrast


SOFT_EDGE_REACH_PX = 5  # soft_centroid looks this far past the silhouette: its 2 px edge and the core's 3 px reach


def soft_centroid(diff: np.ndarray, component: np.ndarray, fraction: float = STRONG_FRACTION):
    """Soft-silhouette centroid: (x, y, Σw, the filled silhouette's plain centroid x, y).

    w = 1 in the silhouette's core (:func:`silhouette_hull` filled, less its outer 2 px); in the 2 px on either side
    of its outline, the pixel's coverage D / C_local, C_local the largest D of the core within 3 px (an
    edge pixel of a body of contrast C covering a fraction f of it differs by f·C): no pixel locking.
    Computed within the silhouette's box and :data:`SOFT_EDGE_REACH_PX` more (the same numbers as over the
    window: no pixel farther away takes part).
    """
    hull, _ = silhouette_hull(diff, component, fraction)
    if hull is None:
        return math.nan, math.nan, 0.0, math.nan, math.nan
    h, w = diff.shape
    hx, hy, hw, hh = cv2.boundingRect(hull)
    x0, y0 = max(hx - SOFT_EDGE_REACH_PX, 0), max(hy - SOFT_EDGE_REACH_PX, 0)
    x1, y1 = min(hx + hw + SOFT_EDGE_REACH_PX, w), min(hy + hh + SOFT_EDGE_REACH_PX, h)
    hull_mask = np.zeros((y1 - y0, x1 - x0), np.uint8)
    cv2.fillConvexPoly(hull_mask, hull - np.int32((x0, y0)), 1)
    diff = diff[y0:y1, x0:x1]
    disk = cv2.getStructuringElement(cv2.MORPH_ELLIPSE, (5, 5))
    core = cv2.erode(hull_mask, disk)
    grown = cv2.dilate(hull_mask, disk) > 0
    if core.sum() < 5:  # a body a few pixels across: the whole silhouette is its edge
        core = hull_mask
    local = cv2.dilate(np.where(core > 0, diff, 0).astype(np.float32), np.ones((7, 7), np.uint8))
    yy, xx = np.nonzero(grown)
    edge = np.minimum(diff[yy, xx] / np.maximum(local[yy, xx], 1e-6), 1.0)
    ww = np.where(core[yy, xx] > 0, 1.0, np.where(local[yy, xx] > 0, edge, 0.0))
    total = float(ww.sum())
    ys, xs = np.nonzero(hull_mask)
    xx, yy, xs, ys = xx + x0, yy + y0, xs + x0, ys + y0  # in the window, as the callers measure
    return float(ww @ xx / total), float(ww @ yy / total), total, float(xs.mean()), float(ys.mean())


def filled_warning(ratio: float) -> str:
    """The warning for a body whose path crosses a filled-in scene (:func:`unseen_behind`) and whose silhouette is
    ``ratio`` as large mid-swing as at the ends of its swing, beyond a clean scene's."""
    return (
        f"the scene behind the body's path was filled in from around it, and its silhouette is "
        f"{abs(100 * (1 - ratio)):.0f} % {'smaller' if ratio < 1 else 'larger'} mid-swing than at the ends of its "
        "swing: what is followed may not be the body alone (a rod, a ghost of it), and its positions may be biased"
    )


WALL_GAIN_KNEE = 0.8  # a wall where the body keeps this share of its contrast or more is left as it is
MIN_WALL_GAIN = 0.2  # a wall nearer the body's grey than this: its differences amplified at most 1 / this


def wall_gain(background: np.ndarray, polarity: str, body_grey: float, *walls: float) -> np.ndarray | None:
    """Per pixel, g = clip(E / (k E₀), g_min, 1): E = ±(B − b) the contrast the body's grey b (its median as the
    clip usually shows it: ``body.BodyScene.first_grey``) has before the wall B, E₀ its contrast before the lightest
    (for a bright body, darkest) of ``walls`` (the wall behind that silhouette and the median wall behind its
    swing: its first place may lie in the band), k = :data:`WALL_GAIN_KNEE`. g is 1 wherever the body keeps at
    least k of E₀ (an even wall, a mild vignette), under it before a darker band behind a dark body, never under
    g_min. I − B divided by g is then about the difference the body would make before the light wall: its
    silhouette keeps its part before the band (its centroid no longer moving away from it). None where g is 1
    everywhere, or for a body both lighter and darker than the wall (polarity ``both``)."""
    sign = {"dark": 1.0, "bright": -1.0}.get(polarity)
    contrasts = [sign * (wall - body_grey) for wall in walls if sign is not None and math.isfinite(wall)]
    if not contrasts or not max(contrasts) > 0:
        return None
    gain = np.clip(sign * (background - body_grey) / (WALL_GAIN_KNEE * max(contrasts)), MIN_WALL_GAIN, 1.0)
    return gain.astype(np.float32) if gain.min() < 1.0 else None
