"""The swing's geometry from marker tracks: circles fitted to the path, the pivot, the vertical, image angles.

θ = atan2(x − x_p, y − y_p) − φ, with image y pointing down, the pivot at
(x_p, y_p) and φ the image angle of the true vertical (camera roll); θ > 0
swings to +x. The arc displacement is s = L θ. The pivot, when not given, is
the centre of a circle fitted to the marker path (pooled over a rig's trials);
the vertical, when not given, is the centre of the oscillation. The angle record
itself is made in :mod:`pendulum.angles.record`.
"""

from __future__ import annotations

import math
from dataclasses import asdict, dataclass

import numpy as np
import pandas as pd

from pendulum.angles.rod import join_rod
from pendulum.angles.swings import swing_centre_rad
from pendulum.tracking.path_shape import arc_span_deg


@dataclass
class CircleFit:
    pivot_x_px: float
    pivot_y_px: float
    radius_px: float
    rms_px: float
    n_points: int
    arc_span_deg: float
    pivot_covariance_px2: list | None = None  # 2×2 covariance of (x_p, y_p), for the error budget
    effective_points: float | None = None  # n corrected for the residuals' autocorrelation


def fit_circle(x, y, weights=None) -> CircleFit:
    """Geometric least-squares circle (algebraic Kåsa fit as the start), minimising Σ w (|p − c| − R)².

    ``weights`` w per point (None: all 1). The pivot covariance is σ² (JᵀWJ)⁻¹
    with σ² = Σ w r² / (n − 3), inflated for the residuals' lag-1 correlation.
    """
    from scipy.optimize import least_squares  # here: the angles job imports this module and rarely fits a circle

    x = np.asarray(x, float)
    y = np.asarray(y, float)
    good = np.isfinite(x) & np.isfinite(y)
    x, y = x[good], y[good]
    root_w = None if weights is None else np.sqrt(np.asarray(weights, float)[good])
    if x.size < 10:
        raise ValueError(f"a circle fit needs at least 10 tracked points, got {x.size}")
    a = np.column_stack([x, y, np.ones_like(x)])
    b = x**2 + y**2
    (c0, c1, c2), *_ = np.linalg.lstsq(a, b, rcond=None)
    cx, cy = c0 / 2, c1 / 2
    r0 = math.sqrt(max(c2 + cx**2 + cy**2, 1e-9))

    def residual(p):
        return np.hypot(x - p[0], y - p[1]) - p[2]

    if root_w is None:
        sol = least_squares(residual, [cx, cy, r0], x_scale="jac")
    else:
        sol = least_squares(lambda p: root_w * residual(p), [cx, cy, r0], x_scale="jac")
    cx, cy, r = sol.x
    # Covariance σ² (JᵀJ)⁻¹, with n replaced by an effective count n (1 − ρ)/(1 + ρ):
    # neighbouring track points share their errors (texture, blur), ρ is the lag-1 correlation.
    res = sol.fun
    rho = float(np.clip(np.corrcoef(res[1:], res[:-1])[0, 1], 0.0, 0.99)) if res.size > 3 else 0.0
    n_eff = max(x.size * (1 - rho) / (1 + rho), 4.0)
    sigma2 = float(res @ res) / max(x.size - 3, 1)
    cov = np.linalg.pinv(sol.jac.T @ sol.jac) * sigma2 * x.size / n_eff
    return CircleFit(
        float(cx),
        float(cy),
        float(r),
        float(np.sqrt(np.mean(res**2))) if root_w is None else float(np.sqrt(np.mean(residual(sol.x) ** 2))),
        int(x.size),
        arc_span_deg(x, y, (cx, cy)),
        cov[:2, :2].tolist(),
        float(n_eff),
    )


def wrapped_rad(angle):
    """An angle (or array) brought to [−π, π)."""
    return np.mod(angle + math.pi, 2 * math.pi) - math.pi


def circular_mean_rad(angles) -> float:
    """The mean direction of angles (radians), 0 for none: what crosses ±π is not cut in two."""
    a = np.asarray(angles, float)
    return math.atan2(float(np.sin(a).sum()), float(np.cos(a).sum())) if a.size else 0.0


def image_angle_rad(x, y, pivot_px) -> np.ndarray:
    """atan2(x − x_p, y − y_p): the marker's angle from the image's downward vertical."""
    return np.arctan2(np.asarray(x, float) - pivot_px[0], np.asarray(y, float) - pivot_px[1])


OUTLIER_TRACK_FACTOR = 8.0  # a track this many times the others' circle RMS off their circle is left out
OUTLIER_TRACK_FLOOR_PX = 1.0  # ... and at least this far (px RMS)


def _radial_rms_px(track: pd.DataFrame, circle: CircleFit) -> float:
    ok = track.flag == "ok"
    d = np.hypot(track.x_px[ok] - circle.pivot_x_px, track.y_px[ok] - circle.pivot_y_px) - circle.radius_px
    return float(np.sqrt(np.mean(d.to_numpy(float) ** 2))) if ok.any() else math.inf


OUTLIER_CANDIDATES = 12  # tracks tried as the one to leave out of a pooled circle, farthest off it first
NOISY_TRACK_FACTOR = 2.0  # a track more than this × the median track's RMS off the circle is down-weighted
STILL_TOLERANCE_PX = 0.5  # a run of ok frames all this close to their running mean ...
STILL_MIN_FRAMES = 10  # ... and at least this long is the marker held still: one point of the path


def path_points(track: pd.DataFrame) -> tuple[np.ndarray, np.ndarray]:
    """The ok positions of a track, each run of ≥ 10 frames within 0.5 px of its running mean (the hold
    before the release, the rest after it) replaced by its median: one position measured many times.

    Its frames share one error (the same sub-pixel phase, a video codec's persistent blocks: a new
    user's 1.5 s hold was 0.11 px off in all 42 frames while the swing's frames were within 0.035 px);
    counted 42 times, that error moved the pooled pivot by 2.3 px on a 27° arc.
    """
    ok = (track.flag == "ok").to_numpy()
    x, y = track.x_px.to_numpy(float)[ok], track.y_px.to_numpy(float)[ok]
    keep_x, keep_y = [], []
    i = 0
    while i < x.size:
        j, sx, sy = i + 1, x[i], y[i]
        while j < x.size and math.hypot(x[j] - sx / (j - i), y[j] - sy / (j - i)) <= STILL_TOLERANCE_PX:
            sx, sy, j = sx + x[j], sy + y[j], j + 1
        if j - i >= STILL_MIN_FRAMES:
            keep_x.append(float(np.median(x[i:j])))
            keep_y.append(float(np.median(y[i:j])))
            i = j
        else:
            keep_x.append(float(x[i]))
            keep_y.append(float(y[i]))
            i += 1
    return np.array(keep_x), np.array(keep_y)


def _pooled_circle(tracks: dict[str, pd.DataFrame], points: dict | None = None) -> CircleFit:
    """Circle through the pooled paths (:func:`path_points`; ``points``: theirs already taken, by name), each
    track weighted min(1, (2 σ_median / σ_k)²).

    σ_k is track k's RMS distance from the unweighted pooled circle: a track
    noisier than twice the median counts by its inverse variance. When no track
    is that noisy every weight is 1 and the unweighted fit is the answer.
    """
    names = list(tracks)  # the callers' order: the pooled sums are the same numbers every time
    points = {n: points[n] if points and n in points else path_points(tracks[n]) for n in names}
    xs = np.concatenate([points[n][0] for n in names])
    ys = np.concatenate([points[n][1] for n in names])
    circle = fit_circle(xs, ys)
    if len(tracks) < 2:
        return circle
    spread = {n: _radial_rms_px(tracks[n], circle) for n in names}
    median = float(np.median([v for v in spread.values() if math.isfinite(v)] or [0.0]))
    weight = {n: min(1.0, (NOISY_TRACK_FACTOR * median / spread[n]) ** 2) if spread[n] > 0 else 1.0 for n in names}
    if all(w == 1.0 for w in weight.values()):
        return circle
    w = np.concatenate([np.full(points[n][0].size, weight[n]) for n in names])
    return fit_circle(xs, ys, weights=w)


def pooled_pivot(tracks: dict[str, pd.DataFrame]) -> tuple[CircleFit, dict[str, str]]:
    """Circle through the pooled marker paths, leaving out tracks that are not on it.

    Where the tracks share no pivot (:func:`unshared_pivot`), the largest set that lies on one circle keeps it
    and the others are left out (:func:`_largest_shared_group`; none when there is no largest set of three).
    Then, with three or more tracks, the track whose leaving out lets the others fit one circle best (the least RMS; of
    the :data:`OUTLIER_CANDIDATES` tracks farthest off the pooled circle) is compared with the circle fitted to the
    others: more than OUTLIER_TRACK_FACTOR × their RMS and more than OUTLIER_TRACK_FLOOR_PX off, it is left out
    (a moved camera, a tracked reflection, another rig's clip) and the test repeated. Not simply the track
    farthest off the pooled circle: a real clip of an apple on a string dropped among the five demo videos pulled
    that circle 57 px RMS off their paths, and three of the demo's lay farther off it than the apple (2026-12-02).
    Returns the circle and {trial: reason} of the tracks left out.
    """
    kept = dict(tracks)
    rejected: dict[str, str] = {}
    points = {name: path_points(track) for name, track in tracks.items()}
    circle = _pooled_circle(kept, points)
    if len(kept) >= 3 and unshared_pivot(kept, circle):  # several placements or pendulums: the most that share one
        found = _largest_shared_group(kept, points)
        if found is not None:
            group, circle = found
            for name in sorted(set(kept) - set(group)):
                off = _radial_rms_px(kept[name], circle)
                rejected[name] = (
                    f"its tracked path is {off:.2f} px RMS off the circle that {len(group)} of the rig's {len(kept)} "
                    f"trials share (the most that share one pivot): {ELSEWHERE}"
                )
            kept = {name: kept[name] for name in group}
    while len(kept) >= 3:
        farthest = sorted(kept, key=lambda name: (-_radial_rms_px(kept[name], circle), name))[:OUTLIER_CANDIDATES]
        without = {name: _pooled_circle({k: v for k, v in kept.items() if k != name}, points) for name in farthest}
        worst = min(farthest, key=lambda name: without[name].rms_px)  # the first of equals: the farthest
        others = {k: v for k, v in kept.items() if k != worst}
        reference = without[worst]
        off = _radial_rms_px(kept[worst], reference)
        limit = max(OUTLIER_TRACK_FACTOR * reference.rms_px, OUTLIER_TRACK_FLOOR_PX)
        if not off > limit:
            break
        rejected[worst] = (
            f"its tracked path is {off:.2f} px RMS off the circle through the other {len(others)} trials' paths "
            f"(limit {limit:.2f} px): {ELSEWHERE}"
        )
        kept, circle = others, reference
    return circle, rejected


ELSEWHERE = (
    "the camera moved between trials, they were filmed from different places, or it is another pendulum (one rig "
    "per camera placement and pendulum: `rig` in a trial's sidecar names its own)"
)


def unlike_picture(name: str, pictures: dict[str, tuple], kept) -> str | None:
    """Why a trial left out of its rig's pivot has other pixels than the trials kept, or None: its frames'
    ``(width, height, display rotation)`` in ``pictures`` are of another size than the most common of theirs (a
    cropped, scaled or turned export of a clip: its path lies elsewhere in its own pixels, not on a camera that
    moved). A display rotation alone is a camera turned (a phone held upright): its frames are used as stored."""
    theirs = [pictures[k] for k in sorted(kept) if k != name and pictures.get(k)]
    mine = pictures.get(name)
    if not mine or not theirs:
        return None
    usual = max(sorted(set(theirs)), key=theirs.count)
    if tuple(mine[:2]) == tuple(usual[:2]):
        return None

    def said(picture) -> str:
        width, height, turn = picture
        return f"{width}×{height} px" + (f", shown turned by {turn:g}°" if turn else "")

    return (
        f"its frames are {said(mine)} where the rig's other trials' are {said(usual)}: a cropped, scaled or "
        "rotated copy of a clip has other pixels (export every trial of a rig alike, or give this one its own `rig`)"
    )


SHARED_GROUP_SEEDS = 12  # tracks tried as the seed of a group that shares one pivot (the widest arcs first)
SHARED_GROUP_ROUNDS = 5  # refits of a group's circle, each taking in the tracks that lie on it


def _largest_shared_group(tracks: dict[str, pd.DataFrame], points: dict) -> tuple[list[str], CircleFit] | None:
    """The largest set of tracks that lie on one circle, and its circle; None unless it has at least three tracks
    and every other set found is smaller.

    Each seed (the widest arc not yet in a set, up to :data:`SHARED_GROUP_SEEDS`) starts from its own circle;
    a track lies on a circle when it is no farther off it than OUTLIER_TRACK_FACTOR × its own RMS off its own
    circle (at most the median track's) and OUTLIER_TRACK_FLOOR_PX; the set's pooled circle is refitted and
    the set taken again until it holds. Seven clips of other pendulums (the real apple, transformed, at three
    scales and mirrored) dropped beside the five demo videos lay 131 px RMS off the pooled circle, none farther
    than the rest: no one track's leaving out helped, and all twelve trials, the demo's too, used their own
    pivots (a ±5° trial's 6 px off; 2026-12-02). Here the demo's five are the largest set.
    """
    own = {name: _pooled_circle({name: track}, points) for name, track in tracks.items()}
    own_rms = {name: _radial_rms_px(track, own[name]) for name, track in tracks.items()}
    median = float(np.median([v for v in own_rms.values() if math.isfinite(v)] or [math.inf]))
    limit = {n: max(OUTLIER_TRACK_FACTOR * min(v, median), OUTLIER_TRACK_FLOOR_PX) for n, v in own_rms.items()}
    groups: list[tuple[list[str], CircleFit]] = []
    seen: set[str] = set()
    by_arc = sorted(tracks, key=lambda name: (-own[name].arc_span_deg, name))
    for seed in by_arc:
        if len(groups) >= SHARED_GROUP_SEEDS:
            break
        if seed in seen:
            continue
        group, circle = [seed], own[seed]
        for _ in range(SHARED_GROUP_ROUNDS):
            on = sorted(name for name, track in tracks.items() if _radial_rms_px(track, circle) <= limit[name])
            if not on or on == group:
                break
            group = on
            circle = _pooled_circle({name: tracks[name] for name in group}, points)
        seen.update(group)
        seen.add(seed)
        groups.append((group, circle))
    groups.sort(key=lambda found: -len(found[0]))
    if not groups or len(groups[0][0]) < 3 or (len(groups) > 1 and len(groups[1][0]) >= len(groups[0][0])):
        return None
    return groups[0]


SHARED_PIVOT_CHI2 = 30.0  # a track's own pivot this far (Mahalanobis², its own covariance) from the pooled one


def unshared_pivot(tracks: dict[str, pd.DataFrame], circle: CircleFit) -> str | None:
    """Why the tracks do not share one pivot, or None: their pooled circle's RMS is more than
    OUTLIER_TRACK_FACTOR × the median of each track's RMS off its own circle, or a track's own pivot lies
    farther from the pooled one than SHARED_PIVOT_CHI2 allows under its own covariance (and > 1 px), the circle
    fit's and a slow tracking bias's along its arm (:func:`track_bias_covariance`: two clips of one clock's ±3° arc,
    biased ∓0.1 px, have pivots 150 px apart along it, 30–50 σ of the fits' own; said to share none before
    2026-12-05).

    Two tracks leave no majority to tell which one moved (:func:`pooled_pivot`), and tracks from unrelated
    clips all lie far off any one circle, none farther than the rest: their pooled circle is no pivot at all
    (four copies of one real track, scaled, rotated and at 3×, as four clips of one rig: 97 px RMS; two
    pendulums side by side swinging ±4°: 0.34 px RMS, its centre 234,000 px away; before 2026-11-28 the pivot
    every one of them used). Measured Mahalanobis² (with a 0.1 px bias; 0.2 px since 2026-12-06) on rigs that
    share a pivot: the demo's five trials ≤ 2.7, the apple clip beside itself 0.0, beside the two-tone ball measured
    at its lower half 5.1; two pendulums side by side 2.5·10⁴ and more.
    """
    if len(tracks) < 2:
        return None
    pooled = np.array([circle.pivot_x_px, circle.pivot_y_px])
    own_rms, apart = [], []
    for name, track in sorted(tracks.items()):
        own = _pooled_circle({name: track})
        own_rms.append(_radial_rms_px(track, own))
        offset = pooled - [own.pivot_x_px, own.pivot_y_px]
        if own.pivot_covariance_px2 is not None and math.hypot(*offset) > OUTLIER_TRACK_FLOOR_PX:
            covariance = np.asarray(own.pivot_covariance_px2, float) + _own_bias_covariance(track, own)
            chi2 = float(offset @ np.linalg.pinv(covariance) @ offset)
            if chi2 > SHARED_PIVOT_CHI2:
                apart.append(f"{name}'s own pivot is {math.hypot(*offset):.0f} px from it ({math.sqrt(chi2):.0f} σ)")
    own_px = float(np.median([v for v in own_rms if math.isfinite(v)] or [math.inf]))
    limit = max(OUTLIER_TRACK_FACTOR * own_px, OUTLIER_TRACK_FLOOR_PX)
    if not (circle.rms_px > limit or apart):
        return None
    why = (
        f"{circle.rms_px:.2f} px RMS off their pooled circle, each {own_px:.2f} px RMS (median) off its own "
        f"(limit {limit:.2f} px)"
        if circle.rms_px > limit
        else "; ".join(apart)
    )
    return f"the paths of its {len(tracks)} trials do not share one pivot: {why}: {ELSEWHERE}"


def _own_bias_covariance(track: pd.DataFrame, own: CircleFit) -> np.ndarray:
    """:func:`track_bias_covariance` of a track's own circle, along its arm to the path's middle (the vertical is not
    known yet): two clips of one short arc, each with its own slow bias, have pivots that far apart along it."""
    x, y = path_points(track)
    vertical_deg = math.degrees(math.atan2(np.median(x) - own.pivot_x_px, np.median(y) - own.pivot_y_px))
    return track_bias_covariance(own.radius_px, own.arc_span_deg, vertical_deg)


def off_rig_circle(track: pd.DataFrame, geometry: dict, name: str | None = None) -> str | None:
    """Why a track cannot use its rig's pooled pivot (its path is off the rig's circle, or the rig's trials
    share none), or None; for trial ``name`` whose frames are another size than the rig's (``unlike_picture`` in
    the geometry document) that is said in place of a moved camera."""
    if geometry.get("shared") is False:
        return "its rig's trials do not share one pivot"
    circle = geometry.get("circle")
    if not circle:
        return None
    off = _radial_rms_px(track, CircleFit(**circle))
    limit = max(OUTLIER_TRACK_FACTOR * circle["rms_px"], OUTLIER_TRACK_FLOOR_PX)
    if off > limit:
        why = (geometry.get("unlike_picture") or {}).get(name, ELSEWHERE)
        return f"the tracked path is {off:.2f} px RMS off the rig's pivot circle (limit {limit:.2f} px): {why}"
    return None


def trial_geometry(
    track: pd.DataFrame, geometry: dict, vertical_deg=None, name=None, rod_lines=None
) -> tuple[dict, str | None]:
    """The pivot and vertical one trial's angles use: its rig's pooled ones (``geometry``), or, where its path is
    off the rig's circle (:func:`off_rig_circle`), its own (:func:`estimate_rig_geometry` of this track alone;
    ``vertical_deg`` given is kept; ``name``: the trial's, for its reason; ``rod_lines``: its own rod's). Returns
    ``{pivot_px, pivot_covariance_px2, vertical_deg, warnings}`` and why its own was used (None when the rig's)."""
    problem = off_rig_circle(track, geometry, name)
    if problem is None:
        vertical = vertical_deg if vertical_deg is not None else geometry["vertical_deg"]
        return {
            "pivot_px": geometry["pivot_px"],
            "pivot_covariance_px2": geometry.get("pivot_covariance_px2"),
            "vertical_deg": vertical,
            "warnings": [],
        }, None
    own = estimate_rig_geometry({"trial": track}, vertical_deg=vertical_deg, rod_lines={"trial": rod_lines or []})
    what = "pivot" if vertical_deg is not None else "pivot and vertical"
    return own, f"{problem}: its {what} estimated from its own track instead"


MAX_ANGLE_SCALE_STDERR_PCT = 2.0  # an estimated pivot that leaves the angles' scale more uncertain: said
# The least slow bias of a track across its arc (a glass's static reflection, a bob's shading and glint) assumed:
# 0.06–0.15 px in a helper's renders of two clock pendulums (2026-12-05), 0.12 px in a two-tone ball's outline
# centre (2026-12-05), 0.14–0.2 px in another helper's clock dots measured against their truth (2026-12-06: the
# pivot 1–3.4 % off along the arm where 0.1 px said ±1.4–2.5 %)
TRACK_BIAS_PX = 0.2
SLOW_BIAS_BINS = 16  # the arc's stretches over which a track's slow departure from its circle is measured
MAX_BIAS_ARM_SHARE = 0.5  # that bias's σ along the arm at most half the arm: the angles' scale ± 50 % or more


def arc_sagitta_px(radius_px: float, arc_span_deg: float) -> float:
    """How far an arc of span φ bends from its chord: s = R (1 − cos(φ/2))."""
    return radius_px * (1.0 - math.cos(math.radians(min(arc_span_deg, 180.0)) / 2))


def slow_bias_px(tracks: dict[str, pd.DataFrame], circle: CircleFit) -> float:
    """The largest slow departure of a track from ``circle``: the RMS over :data:`SLOW_BIAS_BINS` stretches of its arc
    (equal numbers of its points) of its mean distance from the circle, less its own mean and the noise's share
    (√(mean m_k² − mean σ_k²/n_k)). A circle fit absorbs the part of a slow bias that bends the arc as a moved pivot
    would, and leaves the rest: a body's highlight sliding over it, a print's centroid (a helper's clock bobs tracked
    by their silhouettes: 0.15–0.3 px, their pivots 2–21 % off along the arm)."""
    largest = 0.0
    for track in tracks.values():
        x, y = path_points(track)
        if x.size < 4 * SLOW_BIAS_BINS:
            continue
        angle = np.arctan2(x - circle.pivot_x_px, y - circle.pivot_y_px)
        off = np.hypot(x - circle.pivot_x_px, y - circle.pivot_y_px) - circle.radius_px
        off = off - off.mean()
        stretch = np.argsort(np.argsort(angle)) * SLOW_BIAS_BINS // angle.size  # equal numbers of points
        counts = np.bincount(stretch, minlength=SLOW_BIAS_BINS)
        means = np.bincount(stretch, weights=off, minlength=SLOW_BIAS_BINS) / counts
        spread = np.bincount(stretch, weights=off**2, minlength=SLOW_BIAS_BINS) / counts - means**2
        largest = max(largest, math.sqrt(max(float(np.mean(means**2) - np.mean(spread / counts)), 0.0)))
    return largest


def track_bias_covariance(
    radius_px: float, arc_span_deg: float, vertical_deg: float, bias_px: float = TRACK_BIAS_PX
) -> np.ndarray:
    """The pivot's covariance from a slow tracking bias b = ``bias_px`` (:data:`TRACK_BIAS_PX` where not measured
    larger: :func:`slow_bias_px`) across the arc, which no circle
    fit's scatter shows: a change δ of the arc's sagitta s = R (1 − cos(φ/2)) (φ its span), its chord held, moves
    the fitted centre by R δ / s along the arm a = (sin v, cos v): (R b / s)² a aᵀ, the angles' scale by ± b / s.
    Its σ is held to :data:`MAX_BIAS_ARM_SHARE` of R (beyond, the scale is unknown, and the fits' budget, which
    moves each angle by its linear change with the pivot, would flip their signs). On a wide swing the scale's
    part is negligible (a 75° arc at R = 560 px: s = 116 px, 0.09 %); a clock's 3° arc at R = 300 px (s = 0.1 px)
    leaves it unknown."""
    along = radius_px * bias_px / max(arc_sagitta_px(radius_px, arc_span_deg), 1e-9)
    along = min(along, MAX_BIAS_ARM_SHARE * radius_px)
    a = np.array([math.sin(math.radians(vertical_deg)), math.cos(math.radians(vertical_deg))])
    return along**2 * np.outer(a, a)


def pivot_uncertainty(pivot_covariance_px2, radius_px: float, vertical_deg: float) -> dict:
    """Standard errors of an estimated pivot and the angle offset they cause.

    A pivot error δp moves every angle by the component of δp across the arm at
    rest, divided by the arm: σ_θ = √(eᵀ C e) / R with e = (cos φ, −sin φ), φ the
    vertical's image angle (a constant offset, absorbed by the fits' rest offset); its
    component along the arm, a = (sin φ, cos φ), scales every angle by R / (R + δp·a):
    ``angle_scale_stderr_pct`` = 100 √(aᵀ C a) / R (a short arc's pivot is known across the arm far
    better than along it).
    """
    cov = np.asarray(pivot_covariance_px2, float)
    phi = math.radians(vertical_deg)
    e = np.array([math.cos(phi), -math.sin(phi)])
    a = np.array([math.sin(phi), math.cos(phi)])
    return {
        "angle_scale_stderr_pct": float(100 * math.sqrt(max(a @ cov @ a, 0.0)) / radius_px),
        "pivot_stderr_px": [float(math.sqrt(max(cov[0, 0], 0.0))), float(math.sqrt(max(cov[1, 1], 0.0)))],
        "angle_offset_stderr_deg": float(math.degrees(math.sqrt(max(e @ cov @ e, 0.0)) / radius_px)),
    }


def _swing_vertical_deg(tracks: dict[str, pd.DataFrame], pivot_px) -> tuple[float, int]:
    """The median oscillation centre (:func:`swing_centre_rad`, about each path's circular mean angle: a camera
    upside down gives about 180°) of the tracks' clean swings about ``pivot_px``, and how many had one (0°, 0:
    none)."""
    centres = []
    for track in tracks.values():
        th = image_angle_rad(track.x_px.where(track.flag == "ok"), track.y_px.where(track.flag == "ok"), pivot_px)
        # about the path's circular mean, so a swing across ±180° is not cut in two where atan2 wraps
        mean = circular_mean_rad(th[np.isfinite(th)])
        found = swing_centre_rad(wrapped_rad(th - mean))
        if found is not None:
            centres.append(found[0] + mean)
    if not centres:
        return 0.0, 0
    middle = circular_mean_rad(centres)  # the median of the centres about it, in [−180°, 180°)
    return math.degrees(float(wrapped_rad(middle + np.median(wrapped_rad(np.asarray(centres) - middle))))), len(centres)


def estimate_rig_geometry(tracks: dict[str, pd.DataFrame], pivot_px=None, vertical_deg=None, rod_lines=None) -> dict:
    """Pivot (circle through the pooled marker paths, outlying tracks left out; joined with where the rod's lines
    meet, ``rod_lines`` per trial, :func:`pendulum.angles.rod.join_rod`, where the arc bends too little) and vertical.

    The vertical is the median oscillation centre (:func:`swing_centre_rad`, any
    amplitude, about each path's circular mean angle: a camera upside down gives about 180°) of the
    tracks used; when no track has a clean swing it is the
    image vertical (0°) with a warning under ``warnings`` (the fits' rest offset
    absorbs a camera roll). Values given are kept; only the missing ones are
    estimated. An estimated pivot comes with ``pivot_stderr_px`` and
    ``angle_offset_stderr_deg``.
    """
    result: dict = {"trials": sorted(tracks), "rejected_trials": {}, "warnings": []}
    if pivot_px is None:
        if not tracks:
            raise ValueError("no trial has a usable track to estimate the pivot from; give pivot_px")
        circle, rejected = pooled_pivot(tracks)
        tracks = {k: v for k, v in tracks.items() if k not in rejected}
        pivot_px = [circle.pivot_x_px, circle.pivot_y_px]
        result["rejected_trials"] = rejected
        unshared = unshared_pivot(tracks, circle)
        result["shared"] = unshared is None
        if unshared:
            result["warnings"].append(f"{unshared}; each trial's pivot is estimated from its own track")
        result["pivot_source"] = f"estimated: circle fitted to the pooled marker paths of {len(tracks)} trial(s)" + (
            "; not used: the trials share no pivot, each has its own (its angles JSON)" if unshared else ""
        )
        result["circle"] = asdict(circle)
        result["pivot_covariance_px2"] = circle.pivot_covariance_px2
    else:
        result["pivot_source"] = "given"
    result["pivot_px"] = [float(pivot_px[0]), float(pivot_px[1])]
    if vertical_deg is None:
        vertical_deg, found = _swing_vertical_deg(tracks, pivot_px)
        if found:
            result["vertical_source"] = f"estimated: median oscillation centre of {found} trial(s)"
        else:
            why = (
                "no usable track"
                if not tracks
                else "no trial has a clean swing: three turning points above the noise, each in view"
            )
            result["vertical_source"] = "image vertical (not estimated)"
            result["warnings"].append(
                f"cannot estimate the vertical ({why}); the image vertical (0°) is used: the fits' rest offset "
                "absorbs a camera roll, give vertical_deg to state it"
            )
    else:
        result["vertical_source"] = "given"
    result["vertical_deg"] = float(vertical_deg)
    if result.get("circle") and result["pivot_covariance_px2"] is not None:
        circle = result["circle"]
        # measured against the pooled circle where the trials share it (else each trial's own: trial_geometry)
        measured = slow_bias_px(tracks, CircleFit(**circle)) if result.get("shared") is not False else 0.0
        bias_px = max(TRACK_BIAS_PX, measured)
        bias = track_bias_covariance(circle["radius_px"], circle["arc_span_deg"], vertical_deg, bias_px)
        result["pivot_covariance_px2"] = (np.asarray(result["pivot_covariance_px2"]) + bias).tolist()
        result["pivot_track_bias_px"] = round(bias_px, 4)  # in the covariance beside the circle fit's own
        result["slow_departure_px"] = round(measured, 4)  # the tracks' own, measured (slow_bias_px)
        result.update(pivot_uncertainty(result["pivot_covariance_px2"], circle["radius_px"], vertical_deg))
        lines = [line for name in sorted(tracks) for line in (rod_lines or {}).get(name, [])]  # the pooled trials'
        if lines and result.get("shared") is False:
            result["rod"] = {"used": False, "reason": "the trials share no pivot: each is measured about its own"}
        elif lines and join_rod(result, lines):
            if result["vertical_source"] != "given":  # about the joined pivot
                result["vertical_deg"] = vertical_deg = _swing_vertical_deg(tracks, result["pivot_px"])[0]
            result.update(pivot_uncertainty(result["pivot_covariance_px2"], result["rod"]["arm_px"], vertical_deg))
        scale = result["angle_scale_stderr_pct"]
        if scale > MAX_ANGLE_SCALE_STDERR_PCT and result.get("shared") is not False:  # else no trial uses it
            sagitta = arc_sagitta_px(circle["radius_px"], circle["arc_span_deg"])
            result["warnings"].append(
                f"the pivot, {circle['radius_px']:.0f} px from the swing's arc of {circle['arc_span_deg']:.1f}°, is "
                f"known along the arm only to ± {scale * circle['radius_px'] / 100:.0f} px: every angle's scale is "
                f"uncertain by ± {scale:.1f} %{' or more' if scale >= 100 * MAX_BIAS_ARM_SHARE else ''} (1σ: the "
                "circle fit's scatter and a slow tracking bias of "
                f"{bias_px:.2g} px{' (its path off the circle by that much)' if measured > TRACK_BIAS_PX else ''} "
                f"against the arc's {sagitta:.2g} px sagitta), and the amplitude-dependent "
                "coefficients with it (drag, friction): give pivot_px (the pivot's place in the picture, measured in "
                "a frame that shows it) or film a wider swing"
            )
    return result
