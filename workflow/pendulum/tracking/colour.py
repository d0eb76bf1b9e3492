"""The body by its colour, where its brightness against the wall changes with the wall behind it.

A shadow or a darker band on a wall changes the wall's brightness and hardly its colour; a coloured body (a
red apple, a blue ball, a red bauble) keeps its colour before any part of the wall. Where the body's
brightness silhouette shows that dependence (frames flagged ``occluded`` or ``lost``, or a silhouette
smaller or larger mid-swing: :func:`brightness_depends_on_wall`), the body is tracked again in the clip's
**colour view**

    P = 255 − g · max(|U − U_w| + |V − V_w| − z, 0)

on the luma grid: U, V the frame's chroma planes (4:2:0, sited as H.264's default: with the even columns,
between the rows), U_w, V_w the wall's (their per-pixel median over the spread samples, moved by each frame's own
white balance: :func:`_balanced`), z a dead zone of
:data:`DEAD_ZONE_NOISE` × the chroma noise (a codec's chroma moves by whole blocks of a level or two), g
putting the body's colour contrast C_c at :data:`COLOUR_CONTRAST` grey levels — by the same body tracker
(:func:`pendulum.tracking.body.track_body` with ``view``), against a scene in which the wall's shading,
shadows and the thread are all but gone. Taken only for a body whose colour stands out of the chroma noise
(C_c ≥ :data:`MIN_COLOUR_SNR` × the mean chroma difference of the samples); a grey body, a grey video or a
render has no colour view. :func:`pendulum.tracking.method.track_trial` keeps the colour view's track where
it is usable in more frames (and, where the brightness silhouette fails
with too few frames usable, not where it refuses, the colour view alone).
"""

from __future__ import annotations

import math
from contextlib import closing
from dataclasses import replace

import cv2
import numpy as np
import pandas as pd

from pendulum.camera.video import VideoError, iter_luma, plane_8bit
from pendulum.tracking.body import SCENE_SAMPLES, track_body
from pendulum.tracking.marker import track_video
from pendulum.tracking.samples import spread_frames
from pendulum.tracking.settings import TrackerSettings

COLOUR_CONTRAST = 150.0  # the body's colour contrast in the colour view, grey levels
MIN_COLOUR_SNR = 10.0  # the body's colour contrast over the chroma noise below which there is no colour view
GREY_SPREAD = 4  # a first frame whose chroma spans no more than this many levels has no colour (a grey video)
DEAD_ZONE_NOISE = 3.0  # chroma differences up to this many times the chroma noise are left out (compression's blocks)
WALL_DEPENDENT_SHARE = 0.01  # frames `occluded` or `lost` beyond this share: the brightness silhouette may be biased
WALL_DEPENDENT_GAIN = 0.8  # ... or a wall gain below this on its path (the body kept under 0.64 of its contrast)
# luma (x, y) → chroma (x / 2, (y − ½) / 2): 4:2:0 chroma sited with the even columns, between the rows
_TO_CHROMA = np.array([[0.5, 0.0, 0.0], [0.0, 0.5, -0.25]])


def chroma_planes(frame) -> tuple[np.ndarray, np.ndarray] | None:
    """The U and V planes of a planar 4:2:0 frame (``yuv420p``, ``yuvj420p``, their 9–16-bit forms reduced to
    the top 8 bits), each (⌈height/2⌉, ⌈width/2⌉) uint8; None for any other format (grey, 4:2:2, RGB, …)."""
    if not frame.format.name.startswith(("yuv420p", "yuvj420p")) or len(frame.planes) < 3:
        return None
    return plane_8bit(frame, 1), plane_8bit(frame, 2)


def _distance(uv: np.ndarray, wall_uv: np.ndarray) -> np.ndarray:
    """|U − U_w| + |V − V_w| (uint8, saturating at 255) of (h, w, 2) chroma planes, the wall's chroma moved first by
    the frame's own white balance (:func:`_balanced`)."""
    ad = cv2.absdiff(uv, _balanced(uv, wall_uv))
    return cv2.add(ad[..., 0], ad[..., 1])


BALANCE_REACH = 16  # levels: how far a phone's white balance is looked for in a frame's chroma


def _balanced(uv: np.ndarray, wall_uv: np.ndarray) -> np.ndarray:
    """The wall's chroma as this frame shows it: moved by the most common U − U_w and V − V_w within
    ±:data:`BALANCE_REACH` levels over the frame (every fourth pixel: the static scene's, however much of the frame
    the body covers). A phone's automatic white balance moves the whole picture's chroma by a few levels as it
    settles; unmoved, the wall itself would stand out of the view. Modelled as one shift for the whole frame
    (a balance scales the colour with the light: a wall half as bright keeps about half of it). Unchanged (the same
    array) where the frame's white balance is the wall's."""
    return _shifted(wall_uv, _balance_shift((uv[..., 0], uv[..., 1]), wall_uv))


def _balance_shift(planes: tuple[np.ndarray, np.ndarray], wall_uv: np.ndarray) -> tuple[int, int]:
    """The most common U − U_w and V − V_w within ±:data:`BALANCE_REACH` levels over every fourth row and column of
    the frame's chroma ``planes`` (U, V) (:func:`_balanced`)."""
    shift = []
    for channel, plane in enumerate(planes):
        step = plane[::4, ::4].astype(np.int16) - wall_uv[::4, ::4, channel]
        near = step[np.abs(step) <= BALANCE_REACH] + BALANCE_REACH
        counts = np.bincount(near, minlength=2 * BALANCE_REACH + 1)
        shift.append(int(np.argmax(counts)) - BALANCE_REACH if near.size else 0)
    return shift[0], shift[1]


def _shifted(wall_uv: np.ndarray, shift: tuple[int, int]) -> np.ndarray:
    """The wall's chroma moved by a white balance's ``shift`` (saturating); the same array where it is none."""
    return cv2.add(wall_uv, (float(shift[0]), float(shift[1]), 0.0, 0.0)) if any(shift) else wall_uv


def _chroma(frame) -> np.ndarray:
    """The frame's U and V planes stacked (h/2, w/2, 2) uint8; empty where the frame carries no 4:2:0 colour."""
    planes = chroma_planes(frame)
    return np.zeros((0, 0, 2), np.uint8) if planes is None else np.dstack(planes)


_chroma.key = "chroma"


def _on_luma_grid(shown: np.ndarray, size: tuple[int, int], luma_at=(0, 0), chroma_at=(0, 0)) -> np.ndarray:
    """An image on the chroma grid, resampled (bilinear) onto the luma grid at H.264's chroma sites: the luma window
    of ``size`` (width, height) whose corner is luma (x, y) ``luma_at``, from ``shown`` whose first pixel is chroma
    (x, y) ``chroma_at`` (a cut of the whole chroma plane: the offsets, multiples of ¼ px, are exact in OpenCV's
    arithmetic, float32 in 5.x, 1/32 px fixed point in 4.x)."""
    (x0, y0), (cx0, cy0) = luma_at, chroma_at
    to_cut = _TO_CHROMA - np.array([[0.0, 0.0, cx0 - 0.5 * x0], [0.0, 0.0, cy0 - 0.5 * y0]])
    flags = cv2.INTER_LINEAR | cv2.WARP_INVERSE_MAP
    return cv2.warpAffine(shown, to_cut, size, flags=flags, borderMode=cv2.BORDER_REPLICATE)


def _first_chroma(path) -> np.ndarray:
    """The clip's first frame's U and V planes (:func:`_chroma`); empty where it carries no 4:2:0 colour."""
    with closing(iter_luma(path, view=_chroma)) as frames:
        return next(frames, (0, 0.0, np.zeros((0, 0, 2), np.uint8)))[2]


class ColourView:
    """A decoded frame → its colour view P (module docstring), uint8 (height, width)."""

    def __init__(self, wall_uv: np.ndarray, gain: float, dead_zone: int, hidden_box: list | None = None):
        self.wall = wall_uv
        self.gain, self.dead_zone = float(gain), int(dead_zone)
        self.key = ("colour", round(self.gain, 6), self.dead_zone)
        self.hidden_box = hidden_box  # where the brightness view found something in front (occluders.hidden_frames)

    def __call__(self, frame) -> np.ndarray:
        return self.window(frame, 0, int(frame.height), 0, int(frame.width))

    def windowed(self, frame) -> ViewWindows:
        """The frame's view made only where it is looked at (:class:`ViewWindows`)."""
        return ViewWindows(self, frame)

    def window(self, frame, y0: int, y1: int, x0: int, x1: int) -> np.ndarray:
        """Rows ``y0:y1``, columns ``x0:x1`` of the frame's view, from the chroma about them alone: the same bytes
        as that window of the whole view (each step is per pixel but the resampling, :func:`_on_luma_grid`, whose
        2 × 2 chroma neighbours lie within the cut). Every fourth row and column of the whole frame gives its white
        balance. An empty window (``y1 <= y0`` or ``x1 <= x0``) is an empty image."""
        planes = chroma_planes(frame)
        if planes is None or planes[0].shape != self.wall.shape[:2]:
            raise VideoError("a frame without the clip's colour planes: no colour view")
        if y1 <= y0 or x1 <= x0:  # (warpAffine would take a size of 0 for the source's)
            return np.empty((max(y1 - y0, 0), max(x1 - x0, 0)), np.uint8)
        # the chroma grid: luma (x, y) at (x / 2, y / 2 − ¼); the bilinear step reads chroma rows y0 // 2 − 1 to
        # (y1 − 1) // 2 + 1 and columns x0 // 2 to (x1 − 1) // 2 + 1: one more on each side is cut
        h, w = self.wall.shape[:2]
        cy0, cy1 = max(y0 // 2 - 2, 0), min((y1 - 1) // 2 + 3, h)
        cx0, cx1 = max(x0 // 2 - 1, 0), min((x1 - 1) // 2 + 3, w)
        wall = _shifted(self.wall[cy0:cy1, cx0:cx1], _balance_shift(planes, self.wall))
        ad = cv2.absdiff(np.dstack([plane[cy0:cy1, cx0:cx1] for plane in planes]), wall)
        difference = cv2.subtract(cv2.add(ad[..., 0], ad[..., 1]), self.dead_zone)
        shown = cv2.bitwise_not(cv2.convertScaleAbs(difference, alpha=self.gain))
        return _on_luma_grid(shown, (x1 - x0, y1 - y0), (x0, y0), (cx0, cy0))


class ViewWindows:
    """One frame's colour view, made where it is looked at: ``windows[y0:y1, x0:x1]`` is that window of the whole
    view (:meth:`ColourView.window`). The body tracker looks at a window about the body in each frame: at 1080p
    the whole view cost it more than its decoding."""

    __slots__ = ("view", "frame")

    def __init__(self, view: ColourView, frame):
        self.view, self.frame = view, frame

    def __getitem__(self, key) -> np.ndarray:
        if not (isinstance(key, tuple) and len(key) == 2 and all(isinstance(k, slice) for k in key)):
            raise TypeError("a colour view's window is [y0:y1, x0:x1]")
        (y0, y1, y_step), (x0, x1, x_step) = (
            key[0].indices(int(self.frame.height)),
            key[1].indices(int(self.frame.width)),
        )
        if y_step != 1 or x_step != 1:
            raise ValueError("a colour view's window is [y0:y1, x0:x1], without a step")
        return self.view.window(self.frame, y0, y1, x0, x1)


def colour_view(path, luma_track: pd.DataFrame | None) -> tuple[ColourView | None, dict]:
    """The clip's colour view for the body the brightness track followed, and its facts (``colour_contrast``,
    ``chroma_noise``); None where the clip has no 4:2:0 colour or the body's colour does not stand out.

    C_c: the 90th percentile of |U − U_w| + |V − V_w| within the body's radius of its tracked centre, the median
    over the samples where it was tracked ``ok`` (without a track: each sample's most coloured 3 × 3 patch, the
    body where it is the only coloured thing that moves); the noise: the mean of the same difference over the
    samples."""
    first = _first_chroma(path)  # the first frame first: a grey video ends here
    if first.size == 0:
        return None, {"colour": "the video carries no 4:2:0 colour planes"}
    if int(first.max()) - int(first.min()) <= GREY_SPREAD:
        return None, {"colour": "the video's first frame has no colour"}
    samples = spread_frames(path, SCENE_SAMPLES, view=_chroma)[0]
    wall = np.round(np.median(np.stack([uv for _, uv in samples]), axis=0)).astype(np.uint8)
    difference = np.stack([_distance(uv, wall) for _, uv in samples])  # uint8, saturating
    noise = max(float(difference.mean()), 0.5)
    contrasts = [] if luma_track is None else _body_contrasts(samples, difference, luma_track)
    if not contrasts:  # no brightness track to say where the body is: each sample's most coloured 3 × 3 patch
        contrasts = [float(cv2.blur(d.astype(np.float32), (3, 3)).max()) for d in difference]
    contrast = float(np.median(contrasts)) if contrasts else 0.0
    facts = {"colour_contrast": round(contrast, 1), "chroma_noise": round(noise, 2)}
    if contrast < MIN_COLOUR_SNR * noise:
        return None, {**facts, "colour": "the body's colour does not stand out from the wall's"}
    dead_zone = max(1, int(round(DEAD_ZONE_NOISE * noise)))
    in_front = {} if luma_track is None else (luma_track.attrs.get("body") or {}).get("in_front") or {}
    hidden_box = in_front.get("box_px")  # where the brightness view lost the body: hidden in colour too?
    return ColourView(wall, COLOUR_CONTRAST / (contrast - dead_zone), dead_zone, hidden_box), facts


def _body_contrasts(samples, difference: np.ndarray, luma_track: pd.DataFrame) -> list[float]:
    """Per sample where the brightness track is ``ok``: the 90th percentile of the chroma difference within the
    body's radius of its tracked centre (on the chroma grid)."""
    radius = float(luma_track.attrs.get("body", {}).get("radius_px", 0.0)) / 2
    rows = luma_track.set_index("frame")
    h, w = difference.shape[1:]
    yy, xx = np.mgrid[0:h, 0:w]
    contrasts = []
    for k, (index, _) in enumerate(samples):
        if index in rows.index and rows.at[index, "flag"] == "ok" and radius > 1:
            cx, cy = rows.at[index, "x_px"] / 2, (rows.at[index, "y_px"] - 0.5) / 2
            inside = (xx - cx) ** 2 + (yy - cy) ** 2 <= radius**2
            if inside.sum() >= 5:
                contrasts.append(float(np.percentile(difference[k][inside], 90)))
    return contrasts


def brightness_depends_on_wall(track: pd.DataFrame) -> bool:
    """Whether a brightness silhouette's track shows it changing with the wall behind the body: more than
    :data:`WALL_DEPENDENT_SHARE` of its frames ``occluded`` or ``lost``, a warning that it is smaller or larger
    mid-swing, or its differences scaled by the wall's gain where it passed a darker band of wall (``wall_gain``
    under :data:`WALL_DEPENDENT_GAIN`: :func:`pendulum.tracking.body_scene.wall_gain`)."""
    unseen = float(track.flag.isin(["occluded", "lost"]).mean()) if len(track) else 0.0
    body = track.attrs.get("body", {})
    return unseen > WALL_DEPENDENT_SHARE or bool(body.get("warning")) or scaled_by_wall(track)


def scaled_by_wall(track: pd.DataFrame) -> bool:
    """Whether a brightness track's differences were scaled by a wall gain under :data:`WALL_DEPENDENT_GAIN`."""
    return (track.attrs.get("body") or {}).get("wall_gain", 1.0) < WALL_DEPENDENT_GAIN


def track_by_colour(path, settings: TrackerSettings, luma_track: pd.DataFrame | None, progress=None):
    """The body tracked in the clip's colour view (:func:`colour_view`): ``(track or None, what it gave)``."""
    facts: dict = {}
    try:
        view, facts = colour_view(path, luma_track)
        if view is None:
            return None, facts
        track = track_body(path, settings, progress=progress, view=view)
    except VideoError as error:
        return None, {**facts, "colour": f"failed: {error}"}
    body = {**track.attrs["body"], "view": "colour", **facts}
    if body.get("warning"):  # the colour view's silhouette, not the brightness one's
        body["warning"] = "in its colour view, " + body["warning"]
    track.attrs["body"] = body
    return track, facts


# A coloured marker dot (a red sticker on a brass clock bob): its colour against its surround, not its brightness.
MARKER_BASE = 48.0  # the surround's level in the marker's colour view, grey levels
MARKER_MIN_CONTRAST = 12.0  # chroma levels between the dot and its surround below which there is no colour view
MARKER_MIN_SNR = 5.0  # … or below this many times the robust spread of the surround's colour along the same line
MARKER_MAX_REACH = 16.0  # chroma pixels (32 luma px) within which the dot's edge is looked for


class MarkerColourView:
    """A decoded frame → P = B + g ((U − U_s) d_u + (V − V_s) d_v) on the luma grid, uint8: the chroma planes
    projected on the unit line d from the marker's surround's colour (U_s, V_s) to the marker's, g putting the
    marker at :data:`COLOUR_CONTRAST` grey levels above the surround's B = :data:`MARKER_BASE`, smoothed by
    [1 2 1]/4 across and along on the chroma grid (the chroma's noise, magnified by g, would otherwise widen and
    narrow the dot from frame to frame beyond what the marker's checks allow). Shading, a highlight or a shadow
    moves a shiny bob's brightness much more than its colour."""

    def __init__(self, matrix: np.ndarray):
        self.matrix = np.asarray(matrix, np.float32).reshape(1, 3)
        self.key = ("marker colour", *(round(float(v), 6) for v in self.matrix.ravel()))

    def __call__(self, frame) -> np.ndarray:
        planes = chroma_planes(frame)
        if planes is None:
            raise VideoError("a frame without the clip's colour planes: no colour view")
        # [1 2 1]/4 in each direction on the chroma grid: the chroma noise ×0.375, the dot ~1 luma px softer
        shown = cv2.GaussianBlur(cv2.transform(np.dstack(planes), self.matrix), (3, 3), 0)
        return _on_luma_grid(shown, (int(frame.width), int(frame.height)))


def marker_colour_view(path, start_px, radius_px: float | None = None) -> tuple[MarkerColourView | None, dict]:
    """The colour view (:class:`MarkerColourView`) of the marker dot at ``start_px`` in the first frame and its facts
    (``marker_radius_px``, ``start_px``: the dot's centre found there, ``colour_contrast``: |c_dot − c_s| in chroma
    levels, ``surround_spread``); None where the clip has no 4:2:0 colour or the dot's colour does not stand out of
    its surround's (the reason in ``facts["colour"]``).

    Measured (:func:`_dot_at`) about each chroma point within 1.5 chroma px of ``start_px`` (a click a few pixels
    off, or between the chroma samples), the one whose colour stands out most kept, and its centre moved to the
    centroid of what is nearer the dot's colour than the surround's until it stays (≤ 3 times, while its colour
    contrast keeps 90 % of the best)."""
    first = _first_chroma(path)
    if first.size == 0:
        return None, {"colour": "the video carries no 4:2:0 colour planes"}
    cx, cy = _TO_CHROMA @ np.array([start_px[0], start_px[1], 1.0])
    reach = int(MARKER_MAX_REACH + 4)  # the window about start_px that is measured
    x0, y0 = max(int(cx) - reach, 0), max(int(cy) - reach, 0)
    uv = first[y0 : int(cy) + reach + 1, x0 : int(cx) + reach + 1].astype(np.float32)
    if uv.shape[0] < 4 or uv.shape[1] < 4:
        return None, {"colour": "start_px is outside the picture"}
    grid = np.mgrid[0 : uv.shape[0], 0 : uv.shape[1]].astype(np.float32)[::-1]  # x, y of each chroma sample
    offsets = [
        (dx, dy) for dx in np.arange(-1.5, 1.6, 0.5) for dy in np.arange(-1.5, 1.6, 0.5) if dx * dx + dy * dy <= 2.25
    ]
    found = [_dot_at(uv, grid, (cx - x0 + dx, cy - y0 + dy), radius_px) for dx, dy in offsets]
    found = [f for f in found if f is not None]
    if not found:
        return None, {"colour": "no coloured dot at start_px: its colour does not differ from around it"}
    best = max(found, key=lambda f: f["contrast"] / max(f["spread"], 1.0))
    for _ in range(3):  # its centre: the centroid of what is nearer the dot's colour than the surround's
        line = best["centre_uv"] - best["surround_uv"]
        rho = np.hypot(grid[0] - best["x"], grid[1] - best["y"])
        nearer = ((uv - best["surround_uv"]) @ (line / best["contrast"]) >= 0.5 * best["contrast"]) & (
            rho <= best["edge"] + 1.0
        )
        if not nearer.any():
            break
        moved = _dot_at(uv, grid, (float(grid[0][nearer].mean()), float(grid[1][nearer].mean())), radius_px)
        if moved is None or moved["contrast"] < 0.9 * best["contrast"]:  # the centroid wandered off the dot
            break
        done = math.dist((moved["x"], moved["y"]), (best["x"], best["y"])) < 0.1
        best = moved
        if done:
            break
    contrast, spread = best["contrast"], best["spread"]
    facts = {
        "marker_radius_px": round(2.0 * best["edge"], 2),
        "start_px": [round(2.0 * float(best["x"] + x0), 2), round(2.0 * float(best["y"] + y0) + 0.5, 2)],
        "colour_contrast": round(contrast, 1),
        "surround_spread": round(spread, 2),
    }
    if contrast < max(MARKER_MIN_CONTRAST, MARKER_MIN_SNR * spread):
        return None, {
            **facts,
            "colour": f"the dot's colour does not stand out from its surround's: {contrast:.1f} chroma levels apart, "
            f"under max({MARKER_MIN_CONTRAST:g}, {MARKER_MIN_SNR:g} × the surround's spread {spread:.1f}); "
            "a dot whose colour differs more from the bob's, or start_px at the dot's centre",
        }
    line = best["centre_uv"] - best["surround_uv"]
    gain, d = COLOUR_CONTRAST / contrast, line / contrast
    matrix = [gain * d[0], gain * d[1], MARKER_BASE - gain * float(d @ best["surround_uv"])]
    return MarkerColourView(matrix), facts


def _dot_at(uv: np.ndarray, grid: np.ndarray, at, radius_px: float | None) -> dict | None:
    """The dot seen from the chroma point ``at`` (x, y on the chroma grid): c_dot, the chroma there (bilinear); its
    edge (chroma px: ``radius_px`` / 2, or :func:`_dot_edge`); c_s, the median chroma over the ring 1–2.5 chroma px
    beyond the edge; |c_dot − c_s| and the robust spread of the ring's chroma along that line. None where no edge."""
    x, y = at
    centre = np.array([cv2.getRectSubPix(uv[..., c], (1, 1), (float(x), float(y)))[0, 0] for c in (0, 1)])
    rho = np.hypot(grid[0] - x, grid[1] - y)
    edge = radius_px / 2.0 if radius_px is not None else _dot_edge(np.abs(uv - centre).sum(axis=2), rho)
    if edge is None:
        return None
    ring = (rho > edge + 1.0) & (rho <= edge + 2.5)
    if np.count_nonzero(ring) < 8:
        return None
    surround = np.median(uv[ring], axis=0)
    contrast = float(np.hypot(*(centre - surround)))
    along = uv[ring] @ ((centre - surround) / max(contrast, 1e-6))
    spread = 1.4826 * float(np.median(np.abs(along - np.median(along))))
    return {
        "x": x,
        "y": y,
        "edge": edge,
        "centre_uv": centre,
        "surround_uv": surround,
        "contrast": contrast,
        "spread": spread,
    }


def _dot_edge(distance: np.ndarray, rho: np.ndarray) -> float | None:
    """The dot's edge (chroma px) from the colour distance to its centre: the median over rings 1 chroma px wide,
    every ½ px, first reaching half its first plateau (a ring at which it grows by under 10 % over the next 1 px,
    and at least :data:`MARKER_MIN_CONTRAST`); None where it never reaches that contrast."""
    steps = np.arange(0.5, MARKER_MAX_REACH, 0.5)
    profile = np.array([np.median(distance[np.abs(rho - s) < 0.5]) for s in steps])  # each ring holds samples
    rising = np.nonzero(profile >= MARKER_MIN_CONTRAST)[0]
    if rising.size == 0:
        return None
    k = int(rising[0])
    while k + 2 < len(profile) and profile[k + 2] > 1.1 * profile[k]:
        k += 1
    half = 0.5 * profile[k]
    j = int(np.argmax(profile >= half))
    if j == 0:
        return 0.5
    return float(steps[j] - 0.5 * (profile[j] - half) / max(profile[j] - profile[j - 1], 1e-6))


def track_marker_by_colour(path, settings: TrackerSettings, start_px, progress=None):
    """The marker dot at ``start_px`` tracked in its colour view (:func:`marker_colour_view`): ``(track or None,
    what it gave)``; the track's ``attrs["marker"]`` says ``view: colour`` and the view's facts."""
    facts: dict = {}
    try:
        view, facts = marker_colour_view(path, start_px, settings.marker_radius_px)
        if view is None:
            return None, facts
        start = tuple(facts["start_px"])  # the dot's centre found about the given start_px
        spot = replace(settings, polarity="bright", marker_radius_px=facts["marker_radius_px"], start_px=start)
        track = track_video(path, spot, progress=progress, view=view)
    except VideoError as error:
        return None, {**facts, "colour": f"failed: {error}"}
    track.attrs["marker"] = {**track.attrs["marker"], "found_by": "its colour at start_px", "view": "colour", **facts}
    return track, facts
