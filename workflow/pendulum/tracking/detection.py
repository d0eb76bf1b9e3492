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
   response one object can have visited in turn (a circle through two pendulums' paths does not):
   |‖p − c‖ − R| ≤ tol, blob sizes alike; its least-squares refit gives the pivot
   c and arm R. An object qualifies when it moves (spans more than two radii of the arc)
   back and forth (its angle about c reverses at least twice, with about as many moves one
   way as the other: a bubble that rises and starts again does not) on a path that is a
   circle of bounded radius; a second object (a bubble, a float moving on a line, a border)
   or another part of the same pendulum (a track about the same pivot, or blobs that keep
   their place in the frame turning with the marker) is told apart by that; of the chosen
   track, blobs reached by a jump there and back (another object on the same circle, a spot
   held before the release) are dropped (:func:`pendulum.tracking.arcs.continuous_members`) and the
   circle is refitted by least squares to the rest; a spot that moves against the larger body it
   sits on (a lamp's highlight on a shiny ball: :func:`_carrying_body`) gives way to that body;
   with the user's ``start_px``, only the spot swinging there counts (:func:`_at_start`);
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
from dataclasses import dataclass, field, replace

import numpy as np

from pendulum.camera.video import VideoError
from pendulum.tracking.arcs import (
    ArcTrack,
    Blobs,
    arc_tangent,
    arc_track,
    attached,
    attached_members,
    continuous_members,
    find_arc_tracks,
    fit_circle,
)
from pendulum.tracking.spots import (
    active_box,
    dog_blobs,
    dog_pyramid,
    foreground_pyramid,
    full_scene,
    local_contrast,
    marker_free_background,
    refine_spot,
    sample_frames,
    scene_quantiles,
    surround_is_scene,
)

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


def detect_marker(
    path, max_samples: int = 60, max_full: int = 12, max_frames: int = 1800, seed: int = 0, near_px=None
) -> Detection:
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
    small, full, scale, first = sample_frames(path, max_samples, max_full, max_frames)
    n = len(small)
    if n < 12:
        raise DetectionError(
            f"{path}: only {n} frames: too short to find the swinging marker; give tracking polarity, "
            "marker_radius_px and start_px in the trial's sidecar"
        )
    stack = np.stack([img for _, img in small])
    background, _, rows = _blob_rows(stack, scale)
    scene = full_scene(full)
    outcomes = []
    for quantile in (0.5, BACKGROUND_QUANTILE):
        try:
            outcomes.append(
                _detect(path, small, full, scale, first, seed, stack, background, rows[quantile], scene, near_px)
            )
        except DetectionError as error:
            outcomes.append(error)
    started = [d for d in outcomes if isinstance(d, Detection) and d.start_px is not None]
    if len(started) == 2 and near_px is not None:  # both at the spot the user pointed at: the nearer, or the dot
        nearest = min(math.dist(d.start_px, near_px) for d in started)
        tie = 0.5 * min(d.marker_radius_px for d in started) + 2.0
        return min(started, key=lambda d: (math.dist(d.start_px, near_px) > nearest + tie, d.marker_radius_px))
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


def _blob_rows(stack: np.ndarray, scale: int) -> tuple[np.ndarray, float, dict[float, list]]:
    """The samples' median scene, the blob threshold, and per search (0.5: against the median, both signs;
    :data:`BACKGROUND_QUANTILE`: bright spots against the low quantile, dark ones against the high) the
    blobs ``(sample, sign, x, y, r, s)``. Each sample's DoG pyramid is built once and serves every
    background (:func:`pendulum.tracking.spots.dog_pyramid`)."""
    n = len(stack)
    background, low, high = scene_quantiles(stack, BACKGROUND_QUANTILE)
    some = stack[:: max(1, n // 10), ::4, ::4].astype(np.float32) - background[None, ::4, ::4]
    noise = 1.4826 * float(np.median(np.abs(some)))
    threshold = max(2.0, 1.5 * noise)
    # A bright spot is sought against the scene without it: per pixel a low quantile over the samples
    # (a dark spot: a high one). A marker that swings little, or comes to rest, covers its pixels in
    # most samples: the median would hold it and hide it; the quantiles do while it is elsewhere in at
    # least that share of them.
    searches = {
        0.5: [(dog_pyramid(background), (1, -1))],
        BACKGROUND_QUANTILE: [(dog_pyramid(low), (1,)), (dog_pyramid(high), (-1,))],
    }
    rows: dict[float, list] = {q: [] for q in searches}
    foreground = None  # one frame's foreground pyramid, its images reused by the next
    for k in range(n):
        frame = dog_pyramid(stack[k].astype(np.float32))
        for quantile, references in searches.items():
            for reference, signs in references:
                foreground = foreground_pyramid(frame, reference, foreground)
                for sign, x, y, r, s in dog_blobs(foreground, scale, threshold, 8, signs):
                    rows[quantile].append((k, sign, x, y, r, s))
    return background, threshold, rows


def _detect(
    path, small, full, scale: int, first, seed: int, stack, background, rows: list, scene, near_px=None
) -> Detection:
    """The swinging marker in the samples, from the blobs ``rows`` of one search (:func:`_blob_rows`);
    ``scene``: :func:`pendulum.tracking.spots.full_scene` of the full-size samples ``full``; ``near_px``:
    the user's ``start_px`` (:func:`_at_start`)."""
    n = len(small)
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
        t.strength = local_contrast(stack, blobs, t, scale)
    min_members = max(6, int(0.25 * n))

    def swings(t: ArcTrack) -> bool:
        return (
            t.reversals >= 2
            and t.balance >= MIN_SWING_BALANCE
            and t.span_px >= 2 * t.radius
            and len(t.members) >= min_members
        )

    swinging = [t for t in tracks if swings(t)]
    if near_px is not None:
        swinging = _at_start(blobs, swinging, near_px, scale)
        if not swinging:
            raise DetectionError(
                f"{where}no spot swings at start_px ({near_px[0]:.0f}, {near_px[1]:.0f}) in the first frame; "
                "check start_px (the marker's centre in the first frame)"
            )
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
        return math.hypot(t.cx - best.cx, t.cy - best.cy) <= max(3 * best.radius, 0.08 * best.arm) or attached(
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

    body = _carrying_body(blobs, best, swinging)
    if body is not None:  # the spot moves against the body it sits on (a highlight): the body's own spot
        best = body
        swinging.remove(best)
        swinging.insert(0, best)

    rivals = []
    for t in swinging[1:]:
        if same_pendulum(t):
            continue
        # Blobs of the pendulum's own body can share an arc with another object's: judged without them.
        own = attached_members(blobs, t, best, scale)
        if own.any():
            rest = t.members[~own]
            if rest.size < 5:
                continue
            t = arc_track(blobs, rest, t.sign, fit_circle(blobs.x[rest], blobs.y[rest]), scale)
            t.strength = local_contrast(stack, blobs, t, scale)
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
            f"{where}two objects swing: {best.describe(n)}, and {rival.describe(n)}; give the start_px of the one to "
            "follow (its centre in the first frame) in the trial's sidecar (with its polarity and marker_radius_px "
            "given too, no detection runs)"
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
    bg_full = marker_free_background(full, positions, best.radius, scene=scene)
    # Judged where the scene is best known: in the outer half of the swing (a body moving with the
    # marker covers the middle of the swing in most frames, and so is part of the median there).
    angles = {f: math.atan2(x - best.cx, y - best.cy) for f, (x, y) in positions.items()}
    middle = float(np.median(list(angles.values())))
    reach = max(abs(a - middle) for a in angles.values())
    outer = {f: xy for f, xy in positions.items() if abs(angles[f] - middle) >= 0.5 * reach}
    diff = full[len(full) // 2][1][::2, ::2] - bg_full[::2, ::2]
    noise_full = 1.4826 * float(np.nanmedian(np.abs(diff - np.nanmedian(diff))))
    free = surround_is_scene(full, outer, bg_full, best.radius, max(5.0, 2.5 * noise_full))
    if free and np.isnan(bg_full).any():  # no body: the scene is seen closer to the marker (a narrow swing's middle)
        closer = marker_free_background(full, positions, best.radius, reach_radii=1.2, scene=scene)
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
        tangent = arc_tangent(blobs.x[i], blobs.y[i], best)
        res = refine_spot(scene_removed(image), blobs.x[i], blobs.y[i], best.sign, best.radius, tangent)
        if res is not None:
            radii.append(res[2])
    radius = float(np.median(radii)) if radii else best.radius
    start = unchecked_start = None
    held = _held_from_the_start(blobs, on_arc, max(1.5 * scale, 0.1 * radius))
    # the first sample's spot: checked while it is on the kept track, or where the marker is held still
    i = on_arc[0] if 0 in on_arc else held if held is not None else first_member
    if i is not None:
        tangent = arc_tangent(blobs.x[i], blobs.y[i], best)
        res = refine_spot(scene_removed(first), blobs.x[i], blobs.y[i], best.sign, radius, tangent)
        if res is not None and (
            math.dist(res[:2], (blobs.x[i], blobs.y[i])) > max(0.5 * radius, 2.0 * scale)
            or (radii and not 0.6 <= res[2] / radius <= 1.5)
        ):  # the refinement ran off its spot (to a stripe, a rod, a body's edge): no marker-sized spot there
            # (demo_p05's median search: a 17 px spot for the arc's 10 px marker, 4–6 px off its blob)
            res = None
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
        active_box_px=active_box(background, scale),
        rival=None if rival is None else rival.describe(n),
        background=bg_full,
        free_marker=free,
        unchecked_start_px=unchecked_start,
        n_continuous=int(kept.size),
        rest_deg=math.degrees(middle),
    )


def _at_start(blobs: Blobs, tracks: list, near_px, scale: int) -> list:
    """The swinging tracks whose spot in the first sampled frame lies at ``near_px`` (the user pointed at
    it: within its radius and two sample pixels), nearest first; of a dot on a body (two spots there, about
    the same centre) the smaller. Other objects (a second pendulum) are then no rivals."""
    at = []
    for t in tracks:
        first = [int(i) for i in t.members if blobs.sample[i] == 0]
        if not first:
            continue
        i = first[0]
        distance = math.hypot(blobs.x[i] - near_px[0], blobs.y[i] - near_px[1])
        if distance <= blobs.r[i] + 2.0 * scale:
            at.append((distance, float(blobs.r[i]), t))
    if not at:
        return []
    closest = min(d for d, _, _ in at)
    # spots about as near (within half the smallest one's radius) are one place: the smaller spot is the marker
    tie = 0.5 * min(r for _, r, _ in at) + 2.0 * scale
    return [t for d, r, t in sorted(at, key=lambda a: (a[0] > closest + tie, a[1], a[0]))]


def _carrying_body(blobs: Blobs, spot: ArcTrack, tracks: list) -> ArcTrack | None:
    """The body ``spot`` sits on, when the spot moves against it (a highlight, a reflection), else None.

    The body: a swinging track of spots at least 1.5× larger, in ≥ 20 of the same samples, the spot within
    its radius in the median and its positions along the swing following the spot's to 0.25 of its radius.
    A point fixed to the pendulum moves along the swing as the body's centre scaled by its distance from the
    pivot, s = 1 + Δy / arm (Δy: how far below the body's centre it sits); a lamp's highlight on a shiny body
    moves less, by the share the lamp's direction changes over the swing. Moving against the body: the fitted
    slope departs from s by more than 0.012 + 0.15 |Δy| / arm (a 10–30° arc's arm is known to ~15 %) and 5
    standard errors. (A bauble lit from 250 px in front: −0.024 at 10 se; a dot on a bob: −0.002.)
    """
    here = {int(blobs.sample[i]): i for i in spot.members}
    for body in sorted(tracks, key=lambda t: -t.support):
        if body is spot or body.radius < 1.5 * spot.radius:
            continue
        there = {int(blobs.sample[i]): i for i in body.members}
        common = sorted(set(here) & set(there))
        if len(common) < 20:
            continue
        a = np.array([(blobs.x[here[k]], blobs.y[here[k]]) for k in common])
        c = np.array([(blobs.x[there[k]], blobs.y[there[k]]) for k in common])
        if np.median(np.hypot(*(a - c).T)) > body.radius:
            continue
        centred = c - c.mean(axis=0)
        direction = np.linalg.svd(centred, full_matrices=False)[2][0]
        along_body, along_spot = centred @ direction, (a - a.mean(axis=0)) @ direction
        if along_body.var() <= 0:
            continue
        slope = float(along_body @ along_spot / (along_body @ along_body))
        residual = along_spot - slope * along_body
        if residual.std() > 0.25 * body.radius:
            continue  # not one body's spot following the other's
        stderr = float(np.sqrt(residual.var() / (along_body.var() * len(common))))
        below = float(np.mean(a[:, 1] - c[:, 1]))
        rigid = 1.0 + below / body.arm
        if abs(slope - rigid) > max(0.012 + 0.15 * abs(below) / body.arm, 5 * stderr):
            return body
        return None
    return None


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
