"""Arcs in sparse blob detections: RANSAC circle tracks, their swing statistics and continuity.

The blobs come from :mod:`pendulum.tracking.spots` (one list over all samples, full-resolution pixels).
A track is the set of blobs, at most one per sample, on a circle |‖p − c‖ − R| ≤ tol with sizes
alike; it is judged by its span, its reversals (the angle about c changes direction), the balance of
its moves both ways, whether a circle fits it clearly better than a line, and (for the chosen
track) which of its blobs one object can have visited in turn. Another track's blobs are parts of the
same pendulum when they keep their place in the frame turning with it (rotated about its pivot by
minus its angle in the same sample).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np


@dataclass
class Blobs:
    """Every blob found in the samples, one entry per blob (parallel arrays)."""

    sample: np.ndarray  # index of the sample (0 = first)
    sign: np.ndarray  # +1 brighter than the background, −1 darker
    x: np.ndarray  # full-resolution pixels
    y: np.ndarray
    r: np.ndarray  # radius estimate, full-resolution pixels
    s: np.ndarray  # DoG response (grey levels)


def circles_through(ax, ay, bx, by, cx, cy):
    """Centres and radii of the circles through three points each (arrays): ``(ux, uy, r, on_line)``, where
    ``on_line`` marks points on a line (no circle; their centre and radius are not meaningful)."""
    d = 2 * (ax * (by - cy) + bx * (cy - ay) + cx * (ay - by))
    on_line = np.abs(d) < 1e-9
    d = np.where(on_line, 1.0, d)
    a2, b2, c2 = ax * ax + ay * ay, bx * bx + by * by, cx * cx + cy * cy
    ux = (a2 * (by - cy) + b2 * (cy - ay) + c2 * (ay - by)) / d
    uy = (a2 * (cx - bx) + b2 * (ax - cx) + c2 * (bx - ax)) / d
    r = np.array([math.hypot(px - qx, py - qy) for px, py, qx, qy in zip(ax, ay, ux, uy, strict=True)])
    return ux, uy, r, on_line


def fit_circle(x, y):
    """Algebraic (Kåsa) least-squares circle: centre and radius."""
    a = np.column_stack([x, y, np.ones_like(x)])
    b = x * x + y * y
    (p, q, c), *_ = np.linalg.lstsq(a, b, rcond=None)
    cx, cy = p / 2, q / 2
    return cx, cy, math.sqrt(max(c + cx * cx + cy * cy, 0.0))


@dataclass
class ArcTrack:
    """Blobs on one circle (at most one per sample) and how they move along it."""

    sign: int
    cx: float
    cy: float
    arm: float
    members: np.ndarray  # blob indices, one per sample
    radius: float  # median blob radius
    strength: float  # median response
    reversals: int
    span_px: float  # arc length covered
    curved: bool  # a circle fits clearly better than a straight line
    balance: float  # moves one way over moves the other (≤ 1): ~1 for a swing, small for creep-and-jump-back

    @property
    def support(self) -> float:
        return len(self.members) * self.strength

    def describe(self, n_samples: int) -> str:
        kind = "bright" if self.sign > 0 else "dark"
        return (
            f"a {kind} spot (radius ≈ {self.radius:.0f} px) on an arc about ({self.cx:.0f}, {self.cy:.0f}) px "
            f"(arm {self.arm:.0f} px) in {len(self.members)} of {n_samples} sampled frames"
        )


def arc_inliers(blobs: Blobs, cand: np.ndarray, cx, cy, arm, radius, tol):
    d = np.abs(np.hypot(blobs.x[cand] - cx, blobs.y[cand] - cy) - arm)
    ok = (d <= tol) & (blobs.r[cand] <= 2.2 * radius) & (blobs.r[cand] >= radius / 2.2)
    idx = cand[ok]
    # one blob per sample: the one nearest the circle
    order = np.lexsort((d[ok], blobs.sample[idx]))
    idx = idx[order]
    first = np.ones(idx.size, bool)
    first[1:] = blobs.sample[idx][1:] != blobs.sample[idx][:-1]
    return idx[first]


def moves(angles: np.ndarray, noise: float) -> tuple[int, float]:
    """Direction changes of a sequence (steps below ``noise`` ignored), and how evenly it moves both ways.

    Each move is a change of at least ``noise`` from the last anchor; the balance is
    min(n_up, n_down) / max(n_up, n_down) over the moves: about 1 for a swing (out and back alike),
    small for a path that creeps one way and jumps back (a rising bubble that starts again).
    """
    count, direction, anchor = 0, 0, angles[0] if angles.size else 0.0
    ups = downs = 0
    for a in angles[1:]:
        step = a - anchor
        if abs(step) <= noise:
            continue
        d = 1 if step > 0 else -1
        ups, downs = ups + (d > 0), downs + (d < 0)
        if direction and d != direction:
            count += 1
        direction, anchor = d, a
    return count, (min(ups, downs) / max(ups, downs) if max(ups, downs) else 0.0)


def _weighted_triples(rng, cand: np.ndarray, weights: np.ndarray, n: int) -> np.ndarray:
    """``n`` rows of ``rng.choice(cand, size=3, replace=False, p=weights)``, drawn at once: the same rows and the
    same ``rng`` state after as ``n`` such calls (NumPy's rule: three uniforms through the weights' cumulative
    sum; a repeated pick is drawn again from the weights with the picks so far set to 0)."""
    p = np.asarray(weights, dtype=np.float64)
    if np.count_nonzero(p > 0) < 3 or not np.all(p >= 0):
        raise ValueError("Fewer non-zero entries in p than size")  # as NumPy's choice
    cdf = np.cumsum(p)
    cdf /= cdf[-1]
    state = rng.bit_generator.state
    uniforms, first = np.empty(0), []  # the stream's uniforms, and each one's pick through the whole cdf

    def drawn(upto: int) -> None:  # at least ``upto`` uniforms of the same stream
        nonlocal uniforms
        if upto > uniforms.size:
            more = rng.random(3 * n + 16)
            uniforms = np.concatenate([uniforms, more])
            first.extend(cdf.searchsorted(more, side="right").tolist())

    rows = np.empty((n, 3), np.int64)
    pos = 0
    for k in range(n):
        drawn(pos + 3)
        a, b, c = first[pos : pos + 3]
        pos += 3
        if a != b and a != c and b != c:
            rows[k] = a, b, c
            continue
        found = list(dict.fromkeys((a, b, c)))
        left = p.copy()
        while len(found) < 3:
            need = 3 - len(found)
            drawn(pos + need)
            left[found] = 0.0
            again = np.cumsum(left)
            again /= again[-1]
            found += list(dict.fromkeys(again.searchsorted(uniforms[pos : pos + need], side="right").tolist()))
            pos += need
        rows[k] = found
    rng.bit_generator.state = state
    rng.random(pos)  # the state as after exactly the uniforms used
    return cand[rows]


def _ransac_circles(blobs: Blobs, cand: np.ndarray, picks: np.ndarray, scale: int, max_arm: float):
    """The circle through each triple of ``picks`` that RANSAC tries (three samples, radii alike, points apart,
    arm 3 r … ``max_arm``), in order: ``(cx, cy, arm, radius, tol)`` arrays."""
    sample = blobs.sample[picks]
    distinct = (sample[:, 0] != sample[:, 1]) & (sample[:, 0] != sample[:, 2]) & (sample[:, 1] != sample[:, 2])
    rs = np.sort(blobs.r[picks], axis=1)
    radius = rs[:, 1]
    x, y = blobs.x[picks], blobs.y[picks]
    points = [list(zip(px, py, strict=True)) for px, py in zip(x.tolist(), y.tolist(), strict=True)]
    apart = np.array([min(math.dist(a, b), math.dist(a, c), math.dist(b, c)) for a, b, c in points]) >= 1.5 * radius
    keep = distinct & ~(rs[:, 2] > 2.2 * rs[:, 0]) & apart
    (ax, bx, cx), (ay, by, cy) = x[keep].T, y[keep].T
    ux, uy, arm, line = circles_through(ax, ay, bx, by, cx, cy)
    radius = radius[keep]
    good = ~line & (3 * radius <= arm) & (arm <= max_arm)
    radius = radius[good]
    return ux[good], uy[good], arm[good], radius, np.maximum(1.5 * scale, 0.35 * radius)


def _arc_scores(blobs: Blobs, cand: np.ndarray, cx, cy, arm, radius, tol, block: int = 256) -> np.ndarray:
    """Per circle, ``blobs.s[idx].sum()`` of its inliers ``idx`` (:func:`arc_inliers`: on the circle within ``tol``,
    radius alike, one blob per sample, the one nearest the circle), the inliers of many circles found at once."""
    bx, by, br, bs, bsample = blobs.x[cand], blobs.y[cand], blobs.r[cand], blobs.s[cand], blobs.sample[cand]
    scores = np.zeros(cx.size)
    for start in range(0, cx.size, block):
        part = slice(start, start + block)
        d = np.abs(np.hypot(bx[None, :] - cx[part, None], by[None, :] - cy[part, None]) - arm[part, None])
        size = radius[part, None]
        ok = (d <= tol[part, None]) & (br[None, :] <= 2.2 * size) & (br[None, :] >= size / 2.2)
        row, col = np.nonzero(ok)
        order = np.lexsort((d[row, col], bsample[col], row))
        row, col = row[order], col[order]
        first = np.ones(row.size, bool)
        first[1:] = (row[1:] != row[:-1]) | (bsample[col[1:]] != bsample[col[:-1]])
        row, values = row[first], bs[col[first]]  # per circle its inliers, in arc_inliers' order
        ends = np.searchsorted(row, np.arange(min(block, cx.size - start) + 1))
        # NumPy's sum of each circle's inliers (as blobs.s[idx].sum(): the same order of additions)
        scores[part] = [values[a:b].sum() for a, b in zip(ends[:-1], ends[1:], strict=True)]
    return scores


def find_arc_tracks(blobs: Blobs, n_samples: int, shape, scale: int, rng, exclude=None, iterations: int = 1500):
    """Best arc track per sign (RANSAC; of its circles the one one object can have followed:
    :func:`_most_continuous`), then refit; tracks that move back and forth only. The ``iterations`` triples
    are drawn and their circles scored at once (:func:`_weighted_triples`, :func:`_arc_scores`)."""
    h, w = shape
    max_arm = 2.0 * math.hypot(h, w)
    tracks = []
    for sign in (1, -1):
        cand = np.flatnonzero((blobs.sign == sign) & (np.ones(blobs.sign.size, bool) if exclude is None else ~exclude))
        if cand.size < 6 or np.unique(blobs.sample[cand]).size < 6:
            continue
        weights = blobs.s[cand] / blobs.s[cand].sum()
        picks = _weighted_triples(rng, cand, weights, iterations)
        cx, cy, arm, radius, tol = _ransac_circles(blobs, cand, picks, scale, max_arm)
        if not cx.size:
            continue
        scores = _arc_scores(blobs, cand, cx, cy, arm, radius, tol)
        tried = [
            (float(scores[k]), (float(cx[k]), float(cy[k]), float(arm[k])), float(radius[k]), float(tol[k]))
            for k in range(cx.size)
        ]
        best = _most_continuous(blobs, cand, tried, scale)
        if best is None:
            continue
        score, (cx, cy, arm), radius, tol = best
        idx = arc_inliers(blobs, cand, cx, cy, arm, radius, tol)
        for _ in range(2):  # refit on the inliers, kept while it holds as much response (inliers of other objects pull)
            if idx.size < 5:
                break
            circle = fit_circle(blobs.x[idx], blobs.y[idx])
            r_refit = float(np.median(blobs.r[idx]))
            refit = arc_inliers(blobs, cand, *circle, r_refit, tol)
            if blobs.s[refit].sum() < score:
                break
            (cx, cy, arm), radius, idx, score = circle, r_refit, refit, blobs.s[refit].sum()
        if idx.size < 5 or not arm <= max_arm:
            continue
        tracks.append(arc_track(blobs, idx, sign, (cx, cy, arm), scale, radius))
    return tracks


def _most_continuous(blobs: Blobs, cand: np.ndarray, tried: list, scale: int, n_best: int = 12):
    """Of RANSAC's circles, the one whose inliers one object can have visited in turn hold the most
    response (:func:`continuous_members`), among the ``n_best`` circles of most response with distinct
    inliers.

    A circle that crosses two objects' paths (two pendulums side by side, each sample's blob taken from
    whichever is on it there) can gather more inliers than either path's own circle; its members jump
    from one object to the other, and only one object's piece counts.
    """
    tried.sort(key=lambda c: -c[0])
    seen: list[set] = []
    best = None
    for _, circle, radius, tol in tried:
        idx = arc_inliers(blobs, cand, *circle, radius, tol)
        score = blobs.s[idx].sum()
        members = set(idx.tolist())
        if idx.size < 5 or any(len(members & s) >= 0.8 * len(members | s) for s in seen):
            continue  # another of the same blobs (an arc is found by many triples)
        seen.append(members)
        if len(seen) > n_best:
            break
        kept, _ = continuous_members(
            blobs, arc_track(blobs, idx, int(blobs.sign[idx[0]]), circle, scale, radius), scale
        )
        held = float(blobs.s[kept].sum())
        if best is None or (held, held / score) > best[0]:  # on a tie, the one that jumps less
            best = ((held, held / score), score, circle, radius, tol)
    return None if best is None else best[1:]


def arc_track(blobs: Blobs, idx: np.ndarray, sign: int, circle, scale: int, radius: float | None = None) -> ArcTrack:
    """The track of blobs ``idx`` on ``circle`` (cx, cy, arm): its span, reversals and whether it is curved.

    ``radius``: the spot's radius (default: the median blob radius).
    """
    cx, cy, arm = circle
    idx = idx[np.argsort(blobs.sample[idx])]
    radius = float(np.median(blobs.r[idx])) if radius is None else radius
    x, y = blobs.x[idx], blobs.y[idx]
    angles = np.unwrap(np.arctan2(x - cx, y - cy))
    span = float(angles.max() - angles.min()) * arm
    # a straight line through the same points: residual RMS against the circle's
    centred = np.column_stack([x - x.mean(), y - y.mean()])
    line_rms = float(np.linalg.svd(centred, compute_uv=False)[-1] / math.sqrt(len(x)))
    circle_rms = float(np.sqrt(np.mean((np.hypot(x - cx, y - cy) - arm) ** 2)))
    curved = line_rms > 2.0 * circle_rms + 0.5 * scale
    noise = max(0.5 * radius, 1.0 * scale) / arm
    reversals, balance = moves(angles, noise)
    return ArcTrack(sign, cx, cy, arm, idx, radius, float(np.median(blobs.s[idx])), reversals, span, curved, balance)


def _local_medians(values: np.ndarray, used: np.ndarray, half: int, fallback: float) -> np.ndarray:
    """Per i, the median of the ``used`` values among ``values[i - half : i + half + 1]`` (``fallback`` where
    fewer than 3): NumPy's median (the middle one, or the mean of the two middle ones) for every window at once."""
    n = values.size
    window = 2 * half + 1
    rows = np.lib.stride_tricks.sliding_window_view(np.pad(values, half), window)
    taken = np.lib.stride_tricks.sliding_window_view(np.pad(used, half), window)
    ordered = np.sort(np.where(taken, rows, np.inf), axis=1)
    count = taken.sum(axis=1)
    at = np.arange(n)
    middle = (ordered[at, np.maximum((count - 1) // 2, 0)] + ordered[at, count // 2]) / 2
    return np.where(count >= 3, middle, fallback)


def continuous_members(blobs: Blobs, track: ArcTrack, scale: int) -> tuple[np.ndarray, float]:
    """The track's members that one object can have visited in turn, and the step allowed per sample there.

    A swing's steps between samples reach about 1.4 × their median (a sinusoid: peak over median of
    |sin|); a blob of another object on the same circle (a static spot held in the first samples, a
    second object crossing the arc) is reached by a jump there and back. The members split at steps
    longer than the local limit max(3.5 × the median moving step within ±6 steps, 1.5 r) (moving:
    longer than 1.5 pyramid pixels; local, as a swing decays); the largest piece is kept, and another
    piece joins when the kept members next to it, at most eight samples away, are within the limit
    (twice the limit over a gap) of its ends on every side where there are such members. Returns the
    kept members and the limit at the first of them.
    """
    m = track.members
    if m.size < 5:
        return m, math.inf
    sample, x, y = blobs.sample[m], blobs.x[m], blobs.y[m]
    gaps = np.diff(sample)
    steps = np.hypot(np.diff(x), np.diff(y))
    moving = (gaps == 1) & (steps > 1.5 * scale)
    if moving.sum() < 5:
        return m, math.inf
    overall = float(np.median(steps[moving]))
    limits = np.maximum(3.5 * _local_medians(steps, moving, 6, overall), 1.5 * track.radius)
    piece = np.concatenate([[0], np.cumsum(steps > limits * np.maximum(gaps, 1))])
    keep = piece == int(np.argmax(np.bincount(piece)))

    def verdict(a: int | None, b: int) -> bool | None:
        """Is member ``b`` reached from kept member ``a``? None: no kept member within eight samples."""
        gap = None if a is None else abs(int(sample[b]) - int(sample[a]))
        if gap is None or gap > 8:
            return None
        return bool(math.hypot(x[a] - x[b], y[a] - y[b]) <= limits[min(a, b, steps.size - 1)] * min(2, gap))

    changed = True
    while changed:  # grow outwards from the largest piece: a piece joins when reached on every side it has
        changed = False
        for p in range(int(piece.max()) + 1):
            members = np.flatnonzero(piece == p)
            if keep[members[0]]:
                continue
            before = np.flatnonzero(keep[: members[0]])
            after = members[-1] + 1 + np.flatnonzero(keep[members[-1] + 1 :])
            sides = [
                verdict(before[-1] if before.size else None, members[0]),
                verdict(after[0] if after.size else None, members[-1]),
            ]
            if True in sides and False not in sides:
                keep[members] = changed = True
    first = int(np.flatnonzero(keep)[0])
    return m[keep], float(limits[min(first, steps.size - 1)])


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


def attached(blobs: Blobs, other: ArcTrack, track: ArcTrack) -> bool:
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


def attached_members(blobs: Blobs, other: ArcTrack, track: ArcTrack, scale: int) -> np.ndarray:
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


def arc_tangent(x, y, track: ArcTrack):
    rx, ry = x - track.cx, y - track.cy
    norm = math.hypot(rx, ry) or 1.0
    return (-ry / norm, rx / norm)
