"""Tracking stage: the marker centre in every frame, to sub-pixel accuracy.

Per frame, in a small region of interest (ROI) around the predicted position:

1. a coarse, robust estimate: the thresholded centroid x̂ = Σ w x / Σ w with
   w = max(I − T, 0), T = b + ½ (I_marker − b), b the ROI's border median;
2. the estimate used, the linear centroid x̂ = Σ (I − b′) m x / Σ (I − b′) m in a
   soft-edged capsule mask m (marker radius + 2.5 px, stretched along the motion
   by the frame-to-frame step) with b′ the median of a thin ring just outside the
   mask. Linear in the pixel values, it has no pixel locking (a thresholded
   centroid snaps ~0.025 px towards the pixel grid) and no threshold
   nonlinearity on a blurred streak: it is the marker's mean position over the
   exposure. The ring keeps the background local: a small body or a long streak
   puts the ROI's border on the clutter behind, never the ring.

The blur-invariant marker signal Σ (I − b′) m, compared with its normal value
at the marker's place on its arc, gives each frame's quality: an occluder lowers
it, glare raises it. The normal value (and the width² of the check below) is the
first frames' value times a smooth curve in the arc angle fitted to the ok frames
(:class:`pendulum.tracking.marker_arc.ArcReference`): a lens's magnification or vignetting changes it slowly
and repeatably along the swing, an occluder or a stripe within a marker diameter. Frames flagged for these
alone are judged again at the end, against the curve refitted along the whole path where it is smooth. An
occluder that the signal misses makes the linear and a thresholded centroid in
the same capsule disagree (> 0.4 px), and something of the marker's grey in the
capsule's margin moves the linear centroid when the mask shrinks to r + 1 px
(> 0.25 px): both are flagged too (what lies beyond the capsule, a second object
or a stripe past the body, does not count: it does not move the estimate). A
leave-one-out cubic check afterwards flags isolated jumps.
Finally each position is moved from the exposure's mean to the frame time,
x(t) = x̄ − ẍ τ²/24, with the exposure τ measured from the streaks' lengths
(see :func:`exposure_centre_correction`). Flagged frames keep their flag;
nothing is interpolated.

Without hints (``polarity: auto``, ``marker_radius_px: None``) the marker is first
found by :func:`pendulum.tracking.detection.detect_marker`, which also gives the static
scene and the picture inside letterbox borders: a marker with no body around it
is then measured as its coverage of the scene (:mod:`pendulum.tracking.centroids`), so
the flags mean "this measurement is biased" (part of the marker over scene of
its own grey, something else in its surround) rather than "the brightness
changed". After lost frames the window follows the arc and stays bounded (a
flagged measurement off the arc, another object's, does not move it); a long
streak's coarse centroid is taken within the capsule it can occupy, thresholded
at half its own peak.
"""

from __future__ import annotations

import logging
import math
import time
from dataclasses import replace

import numpy as np
import pandas as pd

from pendulum.camera.video import VideoError, iter_luma
from pendulum.tracking.acquisition import Candidate, inner_grey, marker_candidates, marker_like, near_any, static_spot
from pendulum.tracking.centroids import measure_marker
from pendulum.tracking.checks import estimate_exposure_fraction, exposure_centre_correction, flag_jumps
from pendulum.tracking.marker_arc import MarkerArc, MarkerSignal
from pendulum.tracking.samples import frame_count
from pendulum.tracking.settings import TrackerSettings

log = logging.getLogger(__name__)


def resolve_settings(path, settings: TrackerSettings, progress=None):
    """Settings with the marker found by detection where not given: ``(settings, detection or None)``.

    Given values (polarity, marker_radius_px, start_px) win; a detected start is used only
    when the polarity agrees with the detected one (else it may be another object's). With
    ``start_px`` given, detection looks for the spot swinging there (:func:`detect_marker`'s
    ``near_px``); where it finds none, or a larger spot about it (the bob, not its dot), the spot
    seen there in the first frame stands (:func:`pendulum.tracking.detection.spot_at`), tracked
    without detection's arc and scene.
    """
    if not settings.needs_detection:
        return settings, None
    from pendulum.tracking.acquisition import spot_at
    from pendulum.tracking.detection import DetectionError, detect_marker

    started = time.perf_counter()
    local = None
    if settings.start_px is not None:
        first = next((image for _, _, image in iter_luma(path, damaged=True) if image is not None), None)
        local = None if first is None else spot_at(first, settings.start_px)
        if local is not None and not _agrees(settings, local[0], local[1]):
            local = None  # the user's polarity or radius says it is another spot
    try:
        found = detect_marker(path, near_px=settings.start_px)
    except DetectionError:
        if local is None:
            raise
        found = None
    if local is not None:
        polarity, radius, centre = local
        same = (
            found is not None
            and found.start_px is not None
            and found.polarity == polarity
            and math.dist(found.start_px, centre) <= max(0.5 * radius, 2.0)
            and 0.67 <= found.marker_radius_px / radius <= 1.5
        )
        if not same:
            if progress:
                progress(f"{path}: the {polarity} spot at start_px, radius {radius:.1f} px, seen in the first frame")
            return replace(settings, polarity=polarity, marker_radius_px=settings.marker_radius_px or radius), None
    polarity = found.polarity if settings.polarity == "auto" else settings.polarity
    radius = found.marker_radius_px if settings.marker_radius_px is None else settings.marker_radius_px
    start = settings.start_px
    if start is None and polarity == found.polarity:
        start = found.start_px
    if progress:
        seen = found.start_px
        progress(
            f"{path}: detected a {found.polarity} marker, radius {found.marker_radius_px:.1f} px, "
            + (f"start ({seen[0]:.1f}, {seen[1]:.1f}) px, " if seen is not None else "not seen in the first frame, ")
            + f"swinging about ({found.pivot_px[0]:.0f}, {found.pivot_px[1]:.0f}) px, confidence "
            f"{found.confidence:.2f} ({time.perf_counter() - started:.1f} s)"
        )
    return replace(settings, polarity=polarity, marker_radius_px=float(radius), start_px=start), found


def _agrees(settings: TrackerSettings, polarity: str, radius: float) -> bool:
    """Whether a spot of this polarity and radius is the one the given settings describe."""
    return settings.polarity in ("auto", polarity) and (
        settings.marker_radius_px is None or 0.67 <= settings.marker_radius_px / radius <= 1.5
    )


class MarkerAbandoned(VideoError):
    """The marker pass stopped where too many frames were already not ``ok`` for the share asked of it."""

    def __init__(self, message: str, most_usable: float, settings: TrackerSettings, detection=None, at_frame=0):
        super().__init__(message)
        self.most_usable = most_usable  # the most of the clip's frames the whole pass could have had ok
        self.at_frame = at_frame  # where it stopped
        self.settings, self.detection = settings, detection  # as resolved: the whole pass without detecting again


# The next step of a parabola fitted to six consecutive positions (least squares), as weights on them: about a
# turning point, where the marker moves 0.1 px a frame, the positions' noise alone (0.2 px in a dot's colour view)
# made the three-point step exceed 0.5 px and a still frame was taken for a repeat.
STEP_WEIGHTS = np.linalg.pinv(np.vander(np.arange(-5.0, 1.0), 3, increasing=True))[1:].sum(axis=0)  # b + c


def track_video(
    path,
    settings: TrackerSettings,
    progress=None,
    progress_every: int = 200,
    detection=None,
    abandon_below: float | None = None,
    view=None,
    asked: TrackerSettings | None = None,
) -> pd.DataFrame:
    """Track the marker through the whole video in one decode pass.

    Columns: ``frame``, ``time_s``, ``x_px``, ``y_px`` (NaN when lost),
    ``quality`` (marker signal relative to normal, 1 = perfect, 0 = lost),
    ``signal_ratio``, ``flag`` (one of :data:`pendulum.tracking.settings.FLAGS`). Frames the file holds
    damaged are ``lost``. ``attrs["video"]``: the decoder's report (failed
    packets, damaged frames, an early end); ``attrs["detection"]``: what
    :func:`pendulum.tracking.detection.detect_marker` found when the settings left the
    marker's polarity or radius to it (``"auto"``/None), else None;
    ``attrs["marker"]``: the polarity, radius and start used.

    With detection, the static scene (its background image) and the letterbox
    borders are known: the marker is measured as its coverage of the scene where
    no body surrounds it, the window never reaches into the borders (touching
    them is ``edge``), and a spot that the scene itself holds (in the background
    image) is never taken for the marker. After lost frames the search window is
    predicted along the marker's arc (from detection, refitted on the track) at the last angular
    velocity, kept inside the swing seen so far and grows by at most
    ``max_lost_step_radii`` radii per frame; re-acquisition takes only spots on
    the arc. A flagged frame measured more than 1.5 r + 2 px off the arc (a second
    object the window slid onto) keeps its flag but counts as lost for the window.

    The marker is (re)acquired only where a spot scores at least
    ``min_acquire_score`` against a disk and stands out of its surround (on
    re-acquisition by at least half the first spot's contrast). Raises
    :class:`~pendulum.camera.video.VideoError` when the video cannot give a record: no
    marker anywhere, two equally marker-like spots at the first acquisition (a
    reflection; ``start_px`` resolves it), or fewer than ``min_usable_fraction``
    of the frames usable (marker out of the frame or hidden most of the time).

    ``abandon_below``: a share of ``ok`` frames the caller needs; where the clip's frame count is known
    (:func:`pendulum.tracking.samples.frame_count`) and more frames than the rest of that share allows are already
    not ``ok`` (a flag set in the pass is final, and only an ``ok`` frame becomes a ``jump`` after it), the pass
    stops with :class:`MarkerAbandoned`, which holds the most the whole pass could have had ``ok``.

    ``view``: the image the marker is measured in (its luma when None; a colour view of a coloured dot:
    :class:`pendulum.tracking.colour.MarkerColourView`), with the marker given (no detection).

    ``asked``: the settings as the user gave them where ``settings`` already holds detection's values (a stopped
    pass run whole): its advice names only the values given as given.
    """
    found_by = "detection" if detection is not None or settings.needs_detection else "given in the settings"
    asked = asked or settings  # as the user gave them (detection fills the rest)
    if detection is None:
        settings, detection = resolve_settings(path, settings, progress)
        if detection is None and found_by == "detection":
            found_by = "the spot at start_px in the first frame"
    elif settings.needs_detection:
        settings = replace(
            settings,
            polarity=detection.polarity if settings.polarity == "auto" else settings.polarity,
            marker_radius_px=settings.marker_radius_px or detection.marker_radius_px,
            start_px=settings.start_px or detection.start_px,
        )
    background = None if detection is None else detection.background
    # The marker is measured as coverage of the scene only when no body surrounds it (see detection).
    scene_behind = background if detection is not None and detection.free_marker else None
    bounds = None if detection is None else tuple(detection.active_box_px)
    arc = MarkerArc(detection, settings.marker_radius_px)
    # the normal signal (per measurement kind) and width² along the arc, from the ok frames
    signal = MarkerSignal(
        arc,
        settings.marker_radius_px,
        settings.reference_along_arc,
        settings.min_signal_ratio,
        settings.max_signal_ratio,
        settings.max_width_ratio,
    )
    rows = []
    history: list[tuple[int, float, float]] = []  # (frame, x, y) of good frames
    previous = None
    marker_level = None
    marker_grey = None  # median grey inside the marker (polarity space), for the coverage measurement
    width_ref = math.nan  # the marker's width² in the first frames: a wider spot is not the marker alone
    widths: list[float] = []
    # The two centroids' disagreement in the first frames: what is rigidly joined to the marker (a bob's rod,
    # a ball's thread) shifts them apart by the same amount in every frame; more than that is something else.
    disagreement_ref = math.nan
    disagreements: list[float] = []
    lost_run = 0
    window = None  # (frame, slice, pixels) around the marker in the last good frame: repeated frames
    streak2: dict[int, float] = {}
    started = time.perf_counter()
    n_frames = 0
    video_report: dict = {}
    reference_contrast = None  # of the spot first taken for the marker
    distractors: list[tuple[float, float]] = []  # static marker-like spots seen at the first acquisition
    r = settings.marker_radius_px
    keep_off = 1.5 * r
    intrudes = 2 * r + 7.5  # the ring around the mask reaches r + 6.5 px
    # A flagged measurement this far off the marker's circle is something else's (the circle from
    # detection is within a few px; a partly hidden marker's centroid stays inside its disk).
    off_arc_px = 1.5 * r + 2.0
    max_step = 0.0  # largest frame-to-frame step of the marker seen
    best_seen: Candidate | None = None  # best spot of any failed acquisition, for the error message
    total = frame_count(path) if abandon_below is not None else None
    allowed = math.inf if total is None else (1.0 - abandon_below) * total  # frames that may be not ok
    not_ok = counted = 0
    for index, t, image in iter_luma(path, damaged=True, report=video_report, view=view):
        not_ok += sum(row[6] != "ok" and not signal.again(k) for k, row in enumerate(rows[counted:], counted))
        counted = len(rows)
        if not_ok > allowed:
            most = (total - not_ok) / total
            raise MarkerAbandoned(
                f"{path}: the marker pass stopped at frame {index}, {not_ok} frames not ok: at most "
                f"{math.floor(1000 * most) / 10:.1f} % of the {total} frames usable",
                most,
                settings,
                detection,
                index,
            )
        n_frames = index + 1
        if image is None:  # damaged in the file
            rows.append((index, t, np.nan, np.nan, 0.0, 0.0, "lost"))
            lost_run += 1
            previous = None
            continue
        # A repeated frame is identical everywhere; every 8th row tells at 1/8 of the cost.
        rows_sample = image[::8]
        duplicate = previous is not None and np.array_equal(rows_sample, previous)
        previous = rows_sample.copy()
        if not history or lost_run >= settings.reacquire_after_frames:
            candidates = marker_candidates(image, settings, n=4)
            hinted = reference_contrast is None and settings.start_px is not None
            if hinted:  # the spot near the hint first, then the others (possible distractors)
                # within 60 px of the hint; a large marker's disk template (4 radii wide) must fit the window
                reach = max(60.0, 2 * settings.marker_radius_px + 24)
                local = marker_candidates(image, settings, near=settings.start_px, search_radius_px=reach, n=1)
                others = [c for c in candidates if not local or not near_any(c.x, c.y, [(local[0].x, local[0].y)], 4)]
                candidates = local + others if local and marker_like(local[0], settings, None) else []
            likely = [
                c
                for c in candidates
                if marker_like(c, settings, reference_contrast) and not near_any(c.x, c.y, distractors, keep_off)
            ]
            if reference_contrast is not None or not hinted:  # a moving marker on its arc, not the scene's spot
                moving = [c for c in likely if arc.near(c.x, c.y) and not static_spot(image, background, c, r, None)]
                if reference_contrast is None and background is not None:
                    # static marker-like spots of the scene: never the marker (a moving object off the
                    # arc is not one: it will be elsewhere when the marker passes here)
                    distractors += [(c.x, c.y) for c in likely if static_spot(image, background, c, r, None)]
                likely = moving
            if not likely:
                if candidates and (best_seen is None or candidates[0].score > best_seen.score):
                    best_seen = candidates[0]
                rows.append((index, t, np.nan, np.nan, 0.0, 0.0, "lost"))
                lost_run += 1
                continue
            if reference_contrast is None:
                if not hinted:
                    likely.sort(key=lambda c: -c.contrast)
                    if len(likely) > 1 and likely[1].contrast >= 0.7 * likely[0].contrast:
                        a, b = likely[0], likely[1]
                        raise VideoError(
                            f"{path}: two marker-like spots at ({a.x:.0f}, {a.y:.0f}) and ({b.x:.0f}, {b.y:.0f}) px "
                            f"in frame {index} (a reflection?); give the marker's start_px in the trial's sidecar"
                        )
                found = likely[0]
                reference_contrast = found.contrast
                # Other spots that the marker's threshold would also pick up: never taken for the marker.
                distractors += [
                    (c.x, c.y)
                    for c in likely[1:]
                    if c.contrast >= 0.5 * found.contrast
                    and (background is None or static_spot(image, background, c, r, None))
                ]
            elif history:  # several candidates: the one nearest the last good position
                found = min(likely, key=lambda c: math.hypot(c.x - history[-1][1], c.y - history[-1][2]))
            else:
                found = likely[0]
            guess, speed, direction = (found.x, found.y), 0.0, None
        else:
            (f1, x1, y1) = history[-1]
            if len(history) >= 2 and history[-2][0] == f1 - 1:
                f0, x0, y0 = history[-2]
                vx, vy = x1 - x0, y1 - y0
            else:
                vx = vy = 0.0
            gap = index - f1
            step = math.hypot(vx, vy)
            moved = step >= 0.05 or (step > 0 and max_step >= 1.0)  # held: noise, its width² read on one axis
            direction = (vx / step, vy / step) if moved else None
            if gap == 1:
                guess = (x1 + vx, y1 + vy)
                speed = step
                if len(history) >= 3 and history[-3][0] == f1 - 2 and step > 0:
                    ux0, uy0 = x0 - history[-3][1], y0 - history[-3][2]
                    # accelerating: the next step is longer
                    speed += max(0.0, step - math.hypot(ux0, uy0))
                    # on a curved path the streak at frame t lies along the tangent at t, turned by 1.5
                    # frames' turn from the last step's chord (centred at t − 1.5)
                    turn = (math.atan2(vy, vx) - math.atan2(uy0, ux0) + math.pi) % (2 * math.pi) - math.pi
                    turn *= 1.5
                    if abs(turn) < 0.5 and direction is not None:
                        c, s_ = math.cos(turn), math.sin(turn)
                        direction = (direction[0] * c - direction[1] * s_, direction[0] * s_ + direction[1] * c)
            elif all(row[6] == "duplicate" for row in rows[len(rows) - (gap - 1) :]):
                # only repeated frames since (the marker measured there, its picture the frame before's): it
                # moved on for gap frames at the same step, and its streak is one exposure's, not longer
                guess, speed = (x1 + vx * gap, y1 + vy * gap), step
            else:  # after lost frames: along the arc when known, the window bounded
                if arc.circle is not None and step > 0:
                    guess = arc.predict(x1, y1, x1 - vx, y1 - vy, gap)
                else:
                    guess = (x1 + vx * gap, y1 + vy * gap)
                cap = max(6.0 * r, 1.5 * max_step + 2.0 * r)
                speed = min(step + settings.max_lost_step_radii * (gap - 1) * r, cap)
            if window is not None and window[0] == index - 1 and len(history) >= 3 and history[-3][0] == f1 - 2:
                # The marker should have moved (a constant-acceleration step ≥ 0.5 px, and two frames or more
                # from its turning point: a short period's turn comes sooner than a parabola through six frames
                # says), yet its window did not change: a repeated frame (re-encoded), its content the one before's.
                ux, uy = x0 - history[-3][1], y0 - history[-3][2]  # the step before the last
                if len(history) == 6 and history[0][0] == f1 - 5:  # the step of a parabola through six
                    expected = math.hypot(*(STEP_WEIGHTS @ np.array([h[1:] for h in history])))
                else:  # through three: 3.7 times the positions' noise (1.0 times through six)
                    expected = math.hypot(2 * vx - ux, 2 * vy - uy)
                if expected >= 0.5 and math.hypot(2 * vx - ux, 2 * vy - uy) >= math.hypot(vx - ux, vy - uy):
                    duplicate |= float(np.abs(image[window[1]].astype(np.float32) - window[2]).mean()) < 0.5
        coverage_expected = scene_behind is not None and marker_grey is not None
        m = measure_marker(
            image,
            guess[0],
            guess[1],
            settings,
            blur_px=speed,
            marker_level=marker_level,
            direction=direction,
            background=scene_behind if marker_grey is not None else None,
            bounds=bounds,
        )
        if m is None or near_any(m.x, m.y, distractors, keep_off):  # a known distractor is not the marker
            rows.append((index, t, np.nan, np.nan, 0.0, 0.0, "lost"))
            lost_run += 1
            continue
        if marker_level is None:
            marker_level = m.level
        if marker_grey is None and background is not None:
            marker_grey = inner_grey(image, m.x, m.y, r, settings.polarity)
            marker_level = marker_grey
        kind = m.mode_coverage
        ratio = signal.ratio(len(rows), kind, m.signal, m.x, m.y, steady=not (duplicate or m.at_edge))
        if not math.isfinite(width_ref):
            widths.append(m.width2_px2)
            if len(widths) >= 5:
                width_ref = float(np.median(widths))
                signal.width.base = width_ref
        if not math.isfinite(disagreement_ref) and math.isfinite(m.disagreement_px):
            disagreements.append(m.disagreement_px)
            if len(disagreements) >= 5:
                disagreement_ref = float(np.median(disagreements))
        # a long streak's mask takes in more of the scene's noise across it: r²/100 per radius of streak
        streak_width2 = 0.01 * r * max(speed - r, 0.0)
        quality = float(np.clip(min(ratio, 1.0 / ratio) if ratio > 0 else 0.0, 0.0, 1.0))
        biased = (  # the measured position is not the marker's alone
            # (a thresholded streak's centroid sits on its plateau: 2 % of the streak's excess length off)
            m.disagreement_px
            > settings.max_centroid_disagreement_px
            + (disagreement_ref if math.isfinite(disagreement_ref) else 0.0)
            + 0.02 * max(speed - r, 0.0)
            or m.margin_shift_px > settings.max_margin_shift_px
            or m.unresolved > settings.max_unresolved
            # a free marker not measurable against the scene (something else around it): biased
            or (coverage_expected and not m.mode_coverage)
            or near_any(m.x, m.y, distractors, intrudes)  # a distractor inside the marker's window or ring
        )
        wide = m.width2_px2 > settings.max_width_ratio * signal.width.value(m.x, m.y) + streak_width2
        width = None if biased else (m.width2_px2 - streak_width2, wide, speed >= 1.0)  # judged again if wide
        biased = biased or wide
        if ratio < 0.5:
            flag, x, y, quality = "lost", np.nan, np.nan, 0.0
        elif duplicate:
            flag, x, y = "duplicate", m.x, m.y
        elif m.at_edge:
            flag, x, y = "edge", m.x, m.y
        elif biased or ratio < settings.min_signal_ratio:
            flag, x, y = "occluded", m.x, m.y
        elif ratio > settings.max_signal_ratio:
            flag, x, y = "glare", m.x, m.y
        else:
            flag, x, y = "ok", m.x, m.y
        # A flagged measurement off the marker's circle is likely another object's (the window slid onto a
        # second object): it must not steer the next prediction, and counts towards re-acquisition.
        astray = flag not in ("ok", "lost") and arc.off(x, y, off_arc_px)
        if flag == "lost" or astray:
            lost_run += 1
        else:
            lost_run = 0
            # Flagged but measured frames still tell where the marker went (for the next prediction).
            if flag in ("ok", "edge") or (flag in ("occluded", "glare") and 0.7 <= ratio <= 1.4):
                if history and history[-1][0] == index - 1:
                    max_step = max(max_step, math.hypot(x - history[-1][1], y - history[-1][2]))
                history.append((index, x, y))
                del history[:-6]
                if flag == "ok":
                    arc.add(x, y)
                    signal.width.add(x, y, m.width2_px2 - streak_width2)
                if flag in ("ok", "edge"):
                    xi, yi, half = int(round(x)), int(round(y)), int(r + 4)
                    box = np.s_[max(yi - half, 0) : yi + half + 1, max(xi - half, 0) : xi + half + 1]
                    window = (index, box, image[box].astype(np.float32))
        if flag != "lost" and not astray:
            signal.judged(len(rows), kind, m.signal, x, y, ratio, flag, biased, width)
        rows.append((index, t, x, y, quality, ratio, flag))
        streak2[index] = m.streak2_px2
        if progress and index % progress_every == 0 and index:
            rate = index / (time.perf_counter() - started)
            progress(f"{path}: tracked frame {index} ({rate:.0f} frames/s)")
    table = pd.DataFrame(rows, columns=["frame", "time_s", "x_px", "y_px", "quality", "signal_ratio", "flag"])
    table.attrs["video"] = dict(video_report)
    table.attrs["detection"] = None if detection is None else detection.summary()
    table.attrs["marker"] = {
        "polarity": settings.polarity,
        "marker_radius_px": round(float(r), 3),
        "start_px": None if settings.start_px is None else [round(float(v), 2) for v in settings.start_px],
        "found_by": found_by,
    }
    if reference_contrast is None:
        score = "no disk-like spot at all" if best_seen is None else f"the best spot scores {best_seen.score:.2f}"
        seen = ""
        if detection is not None and detection.polarity != settings.polarity:
            start = detection.start_px
            where = "" if start is None else f" at ({start[0]:.0f}, {start[1]:.0f}) px"
            seen = (
                f"; detection finds a {detection.polarity} marker (radius ≈ {detection.marker_radius_px:.1f} px)"
                f"{where}: the polarity given ({settings.polarity}, in config tracking or the trial's sidecar) "
                "looks wrong"
            )
        if asked.polarity == "auto" and asked.marker_radius_px is None and asked.start_px is None:  # none given
            advice = (
                f"detection's {settings.polarity} spot (radius {settings.marker_radius_px:.3g} px) is not a disk in "
                "any frame (a part of the body, where it has no marker dot)"
            )
        else:
            advice = (
                f"check tracking polarity ({settings.polarity}) and marker_radius_px ({settings.marker_radius_px:.3g})"
                + (", or give start_px in the trial's sidecar" if asked.start_px is None else ", and start_px (given)")
            )
        raise VideoError(
            f"{path}: no marker found in any of its {n_frames} frames ({score}; a marker needs "
            f"{settings.min_acquire_score:g}); {advice}{seen}"
        )
    signal.finish(table)  # the first frames' ratios; frames flagged for their signal alone judged again
    table.attrs["marker"].update(signal.summary())
    usable = (table.flag == "ok").to_numpy()
    jumps = flag_jumps(table.x_px.to_numpy(), table.y_px.to_numpy(), usable, settings, table.time_s.to_numpy())
    table.loc[jumps, "flag"] = "jump"
    exposure = settings.exposure_fraction
    if settings.centroid == "linear" and len(table):
        usable = table.flag.isin(("ok", "edge")).to_numpy()
        if exposure is None:
            s2 = table.frame.map(streak2).to_numpy(float)
            exposure = estimate_exposure_fraction(
                table.x_px, table.y_px, s2, usable, min_step_px=0.5 * settings.marker_radius_px
            )
            if exposure is None:  # too slow to measure (and so to matter much): the 180° shutter rule
                exposure = 0.5
        if exposure:
            table["x_px"] += exposure_centre_correction(table.x_px.to_numpy(), usable, exposure)
            table["y_px"] += exposure_centre_correction(table.y_px.to_numpy(), usable, exposure)
    table.attrs["exposure_fraction"] = exposure
    counts = table.flag.value_counts().to_dict()
    if progress:
        rate = n_frames / max(time.perf_counter() - started, 1e-9)
        progress(f"{path}: tracked {n_frames} frames ({rate:.0f} frames/s); flags {counts}")
    usable_fraction = counts.get("ok", 0) / max(len(table), 1)
    if usable_fraction < settings.min_usable_fraction:
        raise VideoError(f"{path}: {unusable_reason(counts, len(table), video_report, found_by == 'detection')}")
    return table


def unusable_reason(counts: dict, n_frames: int, video_report: dict | None = None, detected: bool = False) -> str:
    """Why a track with too few usable frames cannot give a record (for the error message); ``detected``: the
    marker is detection's spot, which may be no marker at all."""
    ok = counts.get("ok", 0)
    out = counts.get("edge", 0) + counts.get("lost", 0)
    hidden = counts.get("occluded", 0) + counts.get("glare", 0)
    damaged = (video_report or {}).get("damaged_frames", 0)
    if damaged >= max(out - damaged, hidden):
        cause = f"{damaged} frames are damaged in the file; copy it again"
    elif out >= hidden:
        cause = "the marker is out of view (outside the frame or behind something) in most frames" + (
            ", or detection's spot is no marker (a ripple, a bubble, a part of the body)" if detected else ""
        )
    else:
        cause = (
            "in most frames the marker stands out from its surround much less (occluded) or more (glare) than "
            "at the start: something covers it, or the background behind its path (stripes, edges) changes "
            "what it is measured against; film it before a plain background, or if it is in full view "
            "throughout, widen tracking min_signal_ratio/max_signal_ratio in config.yaml (frames so kept may "
            "be biased)"
        )
    flags = ", ".join(f"{k} {v}" for k, v in sorted(counts.items()) if k != "ok")
    share = f"{100 * ok / max(n_frames, 1):.0f} %"
    return f"the marker is usable in only {ok} of {n_frames} frames ({share}; {flags}): {cause}"
