"""The rod or thread in view: the line it draws in each frame, for the pivot where the swing's arc bends too little.

A swing's arc places its pivot across the arm to a fraction of a pixel, but along it only to the tracking bias
over the arc's sagitta s = R (1 − cos(φ/2)): a clock's 4° swing at R = 615 px bends 0.4 px, and its pivot is
known to ± 30–50 % (:func:`pendulum.angles.geometry.track_bias_covariance`). A rod, or a thread, points at the
pivot in every frame: the lines it draws at the swing's angles meet there (:mod:`pendulum.angles.rod`).

Per frame (:func:`rod_lines`, in the tracker's own samples or :data:`ROD_FRAMES` spread over the :data:`SPAN_FRAMES`
from the first usable frame, :func:`_rod_frames`, whose body is ``ok``): a strip of the picture along the line from
the body towards a first pivot (the path's circle's centre, else its mirror through the path's middle: a bias larger
than a flat arc's sagitta puts the centre on the wrong side), :data:`STRIP_HALF_PX` to either side, from
:data:`START_RADII` body radii out to the frame's border (or nine tenths of the way to that pivot); its profile
across, averaged over :data:`CHUNK_PX` along it; in each chunk the rod's place is the centroid of its lobe above
half the lobe's peak, where that peak stands :data:`MIN_PEAK_SIGMAS` times the profile's own scatter above it (the
rod brighter than what is around it, or darker: each sign's lines kept where it draws enough, and the rig geometry
takes the one whose lines turn with the body); a straight line through those places, chunks off it (the body, an
edge crossing the strip) left out. A frame draws a line where :data:`MIN_CHUNKS` chunks or more and
:data:`MIN_KEPT_SHARE` of those measured lie on it within :data:`MAX_LINE_RMS_PX` RMS. No background is taken away:
a rod that swings a few pixels near its pivot is part of any background learnt from the frames, and taking it away
there turned the lines less than the rod (a helper's clocks: the pivot 72 px off along the arm against 1.5 px
without).
"""

from __future__ import annotations

import math

import cv2
import numpy as np
import pandas as pd

from pendulum.camera.video import VideoError, iter_luma
from pendulum.tracking.arcs import fit_circle
from pendulum.tracking.samples import held_spread

ROD_FRAMES = 40  # frames: the marker search's or the body tracker's samples (40 to 79), else one in SPAN_FRAMES / 40
SPAN_FRAMES = 600  # ... from the first usable frame: 10 s at 60 fps, many swings of a clock's pendulum (1–2 s)
STRIP_HALF_PX = 24.0  # the strip's reach to either side of the line towards the first pivot
CHUNK_PX = 12  # the strip's rows averaged into one profile across it
START_RADII = 2.0  # the strip starts this many body radii from the body's centre (at least MIN_START_PX)
MIN_START_PX = 10.0
BORDER_PX = 3.0  # ... and stops this far inside the frame
MIN_PEAK_SIGMAS = 2.5  # a chunk's lobe peak over its profile's robust scatter: a rod seen there
LOBE_LEVEL = 0.5  # of its peak: the part of a chunk's lobe whose centroid is the rod's place
MIN_CHUNKS = 8
MIN_KEPT_SHARE = 0.6
MAX_LINE_RMS_PX = 1.0
MIN_LINES = 12  # frames with a line: fewer, and no rod is said to be seen
MAX_SAGITTA_PX = 20.0  # an arc bending less: a tracking bias of 0.2 px leaves its pivot's scale uncertain by > 1 %


def worth_measuring(path: dict) -> bool:
    """Whether the track's arc (``path``: :func:`pendulum.tracking.path_shape.path_departure`'s document) bends too
    little to place its pivot well, s = R (1 − cos(φ/2)) under :data:`MAX_SAGITTA_PX`: its rod is looked for."""
    radius, span = path.get("radius_px"), path.get("arc_span_deg")
    if not radius or not span or not math.isfinite(radius):
        return False
    return radius * (1.0 - math.cos(math.radians(min(span, 180.0)) / 2)) < MAX_SAGITTA_PX


def _body_radius_px(track: pd.DataFrame) -> float:
    """The tracked body's (or marker's) radius in pixels, as the tracker measured it (10 px where not said)."""
    body, marker = track.attrs.get("body") or {}, track.attrs.get("marker") or {}
    for value in (body.get("radius_px"), marker.get("marker_radius_px")):
        if value:
            return float(value)
    return 10.0


def _chunk_place(profile: np.ndarray, offsets: np.ndarray, sign: float) -> float | None:
    """The centroid (in ``offsets``' units) of the profile's strongest lobe of ``sign``, above half its peak; None
    where it does not stand out of the profile's own scatter or touches the strip's ends."""
    q = sign * (profile - np.median(profile))
    i = int(np.argmax(q))
    peak = float(q[i])
    scatter = 1.4826 * float(np.median(np.abs(q - np.median(q))))
    if peak <= MIN_PEAK_SIGMAS * max(scatter, 0.5):
        return None
    lo, hi = i, i
    while lo > 0 and q[lo - 1] > LOBE_LEVEL * peak:
        lo -= 1
    while hi < q.size - 1 and q[hi + 1] > LOBE_LEVEL * peak:
        hi += 1
    if lo == 0 or hi == q.size - 1:
        return None
    w = q[lo : hi + 1] - LOBE_LEVEL * peak  # each sample by its height above that level
    return float((w * offsets[lo : hi + 1]).sum() / w.sum())


def _strip_line(image: np.ndarray, body, towards, start_px: float, sign: float):
    """The rod's line in the strip from ``body`` towards ``towards`` (x, y): its two ends in the image, the RMS of
    its places about it, and how many chunks lie on it; None where no line is drawn (module docstring)."""
    h, w = image.shape
    b = np.asarray(body, float)
    u = np.asarray(towards, float) - b
    reach = float(np.hypot(*u))
    if reach <= start_px + MIN_CHUNKS * CHUNK_PX:
        return None
    u /= reach
    n = np.array([u[1], -u[0]])
    end = 0.9 * reach
    for axis, size in ((0, w), (1, h)):  # the strip's middle stays inside the frame, its sides too
        for limit in (BORDER_PX + STRIP_HALF_PX * abs(n[axis]), size - 1 - BORDER_PX - STRIP_HALF_PX * abs(n[axis])):
            if abs(u[axis]) > 1e-9:
                s = (limit - b[axis]) / u[axis]
                if s > 0:
                    end = min(end, s)
    along = np.arange(start_px, end, 1.0)
    n_chunks = along.size // CHUNK_PX
    if n_chunks < MIN_CHUNKS:
        return None
    along = along[: n_chunks * CHUNK_PX]
    offsets = np.arange(-STRIP_HALF_PX, STRIP_HALF_PX + 1.0)
    s_grid, c_grid = np.meshgrid(along, offsets, indexing="ij")
    map_x = (b[0] + s_grid * u[0] + c_grid * n[0]).astype(np.float32)
    map_y = (b[1] + s_grid * u[1] + c_grid * n[1]).astype(np.float32)
    strip = cv2.remap(image, map_x, map_y, cv2.INTER_LINEAR, borderMode=cv2.BORDER_REPLICATE)
    profiles = strip.reshape(n_chunks, CHUNK_PX, offsets.size).mean(axis=1)
    places, where = [], []
    for k in range(n_chunks):
        place = _chunk_place(profiles[k], offsets, sign)
        if place is not None:
            places.append(place)
            where.append(float(along[k * CHUNK_PX : (k + 1) * CHUNK_PX].mean()))
    if len(places) < MIN_CHUNKS:
        return None
    places, where = np.asarray(places), np.asarray(where)
    kept = np.ones(places.size, bool)
    for _ in range(4):
        if kept.sum() < MIN_CHUNKS:
            return None
        slope, offset = np.polyfit(where[kept], places[kept], 1)
        residual = places - (offset + slope * where)
        spread = 1.4826 * float(np.median(np.abs(residual[kept])))
        kept = np.abs(residual) <= max(3.0 * spread, 0.3)
    rms = float(np.sqrt(np.mean(residual[kept] ** 2))) if kept.any() else math.inf
    if kept.sum() < max(MIN_CHUNKS, MIN_KEPT_SHARE * places.size) or rms > MAX_LINE_RMS_PX:
        return None
    first, last = where[kept].min(), where[kept].max()
    ends = [b + s * u + (offset + slope * s) * n for s in (first, last)]
    return ends[0], ends[1], rms, int(kept.sum())


def rod_lines(video, track: pd.DataFrame) -> dict:
    """The rod's (or thread's) line in a spread of the clip's frames (module docstring), in the track's
    coordinates (the image as stored, a creeping camera's motion taken out as from the body's positions):
    ``lines`` rows ``[frame, sign, x_near, y_near, x_far, y_far, body_x, body_y, rms_px]`` (the rod brighter than
    what is around it, +1, or darker, −1: each sign that draws :data:`MIN_LINES` or more; the line's ends nearest
    the body and farthest from it; the body's tracked centre), ``polarities`` (lines per sign) and how many frames
    were tried; ``lines`` empty and ``reason`` where no sign draws :data:`MIN_LINES`."""
    ok = track[(track.flag == "ok") & np.isfinite(track.x_px) & np.isfinite(track.y_px)]
    result: dict = {"lines": [], "frames_tried": 0, "polarities": {}, "chunk_px": CHUNK_PX}
    if len(ok) < 3 * MIN_LINES:
        return {**result, "reason": "too few usable frames"}
    # measured where the body was seen (x_image_px: before a creeping camera was taken out), said where the track is
    seen = pd.DataFrame({"x": ok.get("x_image_px", ok.x_px), "y": ok.get("y_image_px", ok.y_px)}).to_numpy(float)
    shift = dict(zip(ok.frame, ok[["x_px", "y_px"]].to_numpy(float) - seen, strict=True))
    cx, cy, _ = fit_circle(seen[:, 0], seen[:, 1])
    if not (np.isfinite(seen).all() and math.isfinite(cx) and math.isfinite(cy)):
        return {**result, "reason": "no circle through the track to look towards"}
    try:
        frames = _rod_frames(video, set(ok.frame), int(ok.frame.iloc[0]))
    except VideoError as error:
        return {**result, "reason": str(error)}
    start = max(START_RADII * _body_radius_px(track), MIN_START_PX)
    by_frame = dict(zip(ok.frame, map(tuple, seen), strict=True))
    tried = [(i, np.asarray(image, np.float32), by_frame[i]) for i, image in frames if i in by_frame]
    result["frames_tried"] = len(tried)
    centre = np.array([cx, cy])
    # towards the circle's centre, else its mirror through the path's middle: a bias larger than a flat arc's
    # sagitta puts the centre on the wrong side (a 4° arc on 500 px bends 0.3 px)
    tally = {}  # the first direction's lines per sign, said where neither direction draws enough
    for towards in (centre, 2 * seen.mean(axis=0) - centre):
        rows, counts = [], {}
        for sign, polarity in ((1.0, "bright"), (-1.0, "dark")):
            drawn = []
            for i, image, body in tried:
                line = _strip_line(image, body, towards, start, sign)
                if line is not None:
                    (nx, ny), (fx, fy), rms, _ = line
                    dx, dy = shift[i]
                    drawn.append([int(i), sign, nx + dx, ny + dy, fx + dx, fy + dy, body[0] + dx, body[1] + dy, rms])
            counts[polarity] = len(drawn)
            if len(drawn) >= MIN_LINES:  # each kept: a light rod's dark shadow may draw more (pendulum.angles.rod)
                rows += [[r[0], int(r[1]), *(round(float(v), 3) for v in r[2:])] for r in drawn]
        if rows:
            return {**result, "lines": rows, "polarities": counts}
        tally = tally or counts
    most = max(tally.values(), default=0)
    return {
        **result,
        "polarities": tally,
        "reason": f"a rod's line in {most} of {len(tried)} frames (fewer than {MIN_LINES})",
    }


def _rod_frames(video, usable: set, first: int) -> list:
    """The frames to look for the rod in: the tracker's own samples (:func:`held_spread`) where half of
    :data:`ROD_FRAMES` or more are usable, else :data:`ROD_FRAMES` spread over the :data:`SPAN_FRAMES` from the first
    usable one (to the last: a short clip) (a release late in the clip, after the samples)."""
    held = held_spread(video, ROD_FRAMES)
    if held and sum(i in usable for i, _ in held) >= ROD_FRAMES // 2:
        return held
    last = min(first + SPAN_FRAMES, max(usable) + 1)
    stride, kept = max((last - first) // ROD_FRAMES, 1), []
    for index, _t, image in iter_luma(video):
        if index >= last:
            break
        if index >= first and (index - first) % stride == 0 and index in usable:
            kept.append((index, image.copy()))
    return kept
