"""A round body's centre from its outline: a sphere seen in part, such as a two-tone ball turning on its string.

The body tracker measures a body by its silhouette's centroid. Where only part of a sphere stands out (a two-tone
ball's coloured half, its light half lost against a light wall), that centroid is the visible part's, and it wanders
by up to half the radius as the ball turns on its string (a seam tilted from level shows a third to two thirds
of the ball). The sphere's outline does not: a half of it bounded by a great circle always shows a semicircle of
the sphere's limb, its ends diametrically opposite, so the circle through the outermost edge is the sphere's own.

Per frame, the limb's edge points (:func:`pendulum.tracking.limb.edge_points`). Per clip (:func:`outline_centres`):
a circle through each frame's edge points, started from their enclosing circle and refitted (algebraic least
squares) to the points within :data:`ON_CIRCLE_PX` of it, and then the centre alone refitted (Gauss–Newton) at the
clip's median radius, from that circle or, where it holds under half the rays (a crescent's may have nearly the
radius and not the centre), from a vote, whichever holds more points: points inside the circle (a seam, the part
that does not stand out) are left out, the limb kept. A frame whose circle holds :data:`MIN_LIMB_SHARE` of the rays
or more showed its limb (a sphere shows at least half of it whatever its markings); one that holds
:data:`PART_LIMB_SHARE` showed it in part (a print's light squares lost against a wall of their grey), and is used
only where the swing puts it (:func:`_taken_back`).

A track measured by its colour is offered its brightness view's outline (:func:`sharper_outline`: the luma's limb,
sharper than the chroma's). :func:`centre_by_outline` keeps the outline's centres where the measurement itself says
so (:func:`pendulum.tracking.path_shape.path_departure` on each track): the centroid's path wanders off one circle
about a fixed or creeping pivot by more than :data:`WANDER_NOISE_RATIO` times its own noise (the RMS beyond the
noise, √(RMS² − noise²): on a 6 s clip of a clock's bob, 1.2 times, the outline was 8 times worse), and the
outline's by at most :data:`OUTLINE_GAIN` of that, with a smaller RMS; or the outline's path is the better pendulum
on both counts, at most :data:`OUTLINE_GAIN` as far off its circle as the centroid's and no noisier, whatever the
cause (a print's centroid wanders mostly along the swing, where a circle sees only part of it, and is noisier: seed
7031 of the body study, off its circle by 1.3 times its noise, its angles 0.054° off the truth, 0.020° by its
outline; a ball whose outline is half as noisy as its centroid); or the two paths need different creeps of the
camera (by more than path_shape's own least creep, and five of their standard errors: a wander slow enough to pass
for a creep), the outline's path no farther off its circle than the centroid's plus its noise; or the two centres
move apart as the body swings (:func:`centres_apart`: by over :data:`APART_NOISE_RATIO` times their difference's
noise and :data:`APART_MIN_DEG` of θ on the arm; a two-tone ball blurred by its motion, body study scene 7227), the
outline's path no farther off its circle and its noise at most :data:`APART_NOISE_SLACK` times the centroid's. The
camera moves both centres alike; only a centre that moves on the body makes them differ, and a sphere's outline
cannot. An apple (its outline no circle, its centre 2–4 times noisier) and a uniform ball (both centres on one path,
equally noisy) keep the centroid."""

from __future__ import annotations

import math

import cv2
import numpy as np
import pandas as pd
from scipy.ndimage import find_objects, label, maximum_filter1d

from pendulum.tracking.arcs import fit_circle
from pendulum.tracking.checks import JUMP_HALF_WINDOW, STILL_PX, flag_jumps
from pendulum.tracking.limb import LIMB_RAYS
from pendulum.tracking.path_shape import MIN_MOTION_PX, MOTION_SIGMAS, path_departure
from pendulum.tracking.settings import TrackerSettings

ON_CIRCLE_PX = (1.5, 1.0, 0.75)  # the successive fits' tolerances: |distance from the centre − radius|
MIN_LIMB_SHARE = 1 / 3  # of the rays on its circle: its limb seen (a sphere shows at least half of it)
CONFIRMED_LIMB_SHARE = 1 / 4  # … a brightness circle where the colour view's silhouette confirms its place
WHOLE_LIMB_QUANTILE = 0.1  # of the usable frames' rays on their circle: a limb seen as whole as theirs
ALONG_NOISE = 3.0  # a frame taken back along the path: within this × the path's noise (and ON_PATH_PX) of the swing
ALONG_RUN_S = 0.25  # … in a run this long at most
ALONG_WINDOW_S = 0.5  # … the swing fitted to the usable frames this near on each side
ALONG_SIDE_FRAMES = 4  # … at least this many on each side, in unbroken stretches of as many
CROSSING_REACH = 0.2  # of the swing's reach (its 95th percentile): a crossing of the path's middle counted (ω)
PART_LIMB_SHARE = 1 / 6  # … a limb seen in part, taken where its centre keeps to the path (outline._taken_back)
MIN_SEEN_SHARE = 0.9  # of the usable frames, with their limb seen, for the outline to be tried
MIN_POINTS = 8  # edge points a circle is fitted to
VOTE_RAY_STEP = 6  # the vote's circles pass through pairs of every sixth ray's points
VOTE_FRAMES = 64  # frames voted on at once (memory: 64 × 240 circles × 96 points)
MAX_UNSEEN_SHARE = 0.025  # of a colour track's usable frames, the brightness view's outline may not see
OUTLINE_REACH = 0.6  # radii: a brightness circle farther from the colour silhouette's centroid is another thing's
OUTLINE_GAIN = 0.5
WANDER_NOISE_RATIO = 2.0  # a centroid's wander off the circle, beyond its noise, that the outline is tried against
APART_NOISE_RATIO = 3.0  # the two centres' difference wandering by this × its noise: one of them moves on the body
APART_NOISE_SLACK = 1.25  # ... the outline then kept if no more than this × as noisy (an apple's: 2–4 ×)
APART_MIN_DEG = 0.01  # ... and by this much of θ on the path's arm at least: a smaller wander is not worth a change
ON_PATH_NOISE, ON_PATH_PX = 4.0, 0.3  # … its centre this near the usable frames' circle (× their noise, and px)
OUTLINE_COLUMNS = ["outline_x_px", "outline_y_px", "outline_r_px", "outline_rays"]


def _circles(x: np.ndarray, y: np.ndarray) -> np.ndarray:
    """Per frame (rows of edge points x, y; NaN where a ray found none), the limb circle with its radius free
    (module docstring): x, y, radius and the points on it; from their enclosing circle, which is the limb's where it
    shows a semicircle or more, refitted (algebraic least squares) to the points within each of
    :data:`ON_CIRCLE_PX` of it in turn."""
    out = np.full((x.shape[0], 4), np.nan)
    for k in np.nonzero(np.isfinite(x).sum(axis=1) >= MIN_POINTS)[0]:
        good = np.isfinite(x[k])
        (out[k, 0], out[k, 1]), out[k, 2] = cv2.minEnclosingCircle(
            np.column_stack([x[k, good], y[k, good]]).astype(np.float32)
        )
    origin = out[:, :2].copy()  # each frame's points about its enclosing circle's centre (a well-posed fit)
    x, y = x - origin[:, :1], y - origin[:, 1:2]
    out[:, :2] = 0.0
    for tolerance in ON_CIRCLE_PX:
        keep = np.abs(np.hypot(x - out[:, :1], y - out[:, 1:2]) - out[:, 2:3]) < tolerance  # NaN: not kept
        w = keep.astype(float)
        xs, ys = np.where(keep, x, 0.0), np.where(keep, y, 0.0)
        moments = [(w * a * b).sum(axis=1) for a, b in ((xs, xs), (xs, ys), (xs, w), (ys, ys), (ys, w), (w, w))]
        sxx, sxy, sx, syy, sy, n = moments
        rhs = np.stack([((xs**2 + ys**2) * c).sum(axis=1) for c in (xs, ys, w)], axis=1)
        normal = np.stack([np.stack(r, axis=1) for r in ((sxx, sxy, sx), (sxy, syy, sy), (sx, sy, n))], axis=1)
        fits = (n >= MIN_POINTS) & (np.abs(np.linalg.det(normal)) > 1e-9)
        out[~fits] = np.nan
        solved = np.linalg.solve(normal[fits], rhs[fits][..., None])[..., 0]
        cx, cy = solved[:, 0] / 2, solved[:, 1] / 2
        out[fits, 0], out[fits, 1] = cx, cy
        out[fits, 2] = np.sqrt(np.maximum(solved[:, 2] + cx**2 + cy**2, 0.0))
        out[fits, 3] = n[fits]
    out[:, :2] += origin
    return out


def _voted(x: np.ndarray, y: np.ndarray, radius_px: float) -> tuple[np.ndarray, np.ndarray]:
    """Per frame, the centre of the circle of ``radius_px`` through its edge points by a vote: of the two circles
    through each pair of every :data:`VOTE_RAY_STEP`-th ray's points, the one with the most points within
    :data:`ON_CIRCLE_PX` [−1] of it less those beyond it (the limb is the outermost edge); NaN with none."""
    tolerance = ON_CIRCLE_PX[-1]
    i, j = np.triu_indices(LIMB_RAYS // VOTE_RAY_STEP, 1)
    i, j = i * VOTE_RAY_STEP, j * VOTE_RAY_STEP
    cx, cy = np.full(x.shape[0], np.nan), np.full(x.shape[0], np.nan)
    for rows in np.array_split(np.arange(x.shape[0]), max(1, -(-x.shape[0] // VOTE_FRAMES))):
        x1, y1, x2, y2 = x[rows][:, i], y[rows][:, i], x[rows][:, j], y[rows][:, j]
        half = np.hypot(x2 - x1, y2 - y1) / 2
        with np.errstate(invalid="ignore", divide="ignore"):
            reach = np.where((half > 0) & (half < radius_px), np.sqrt(radius_px**2 - half**2) / half, np.nan)
        mx, my, nx, ny = (x1 + x2) / 2, (y1 + y2) / 2, -(y2 - y1) / 2 * reach, (x2 - x1) / 2 * reach
        ox, oy = np.concatenate([mx + nx, mx - nx], axis=1), np.concatenate([my + ny, my - ny], axis=1)
        off = np.hypot(x[rows][:, None, :] - ox[..., None], y[rows][:, None, :] - oy[..., None]) - radius_px
        score = (np.abs(off) < tolerance).sum(axis=2) - (off > 2 * tolerance).sum(axis=2)
        score = np.where(np.isfinite(ox), score, -LIMB_RAYS)  # a pair with a ray that found no edge: none
        best = np.argmax(score, axis=1)
        cx[rows], cy[rows] = (
            np.take_along_axis(ox, best[:, None], 1)[:, 0],
            np.take_along_axis(oy, best[:, None], 1)[:, 0],
        )
    return cx, cy


def _refined(x: np.ndarray, y: np.ndarray, radius_px: float, cx: np.ndarray, cy: np.ndarray) -> np.ndarray:
    """Per frame, the centre of the circle of ``radius_px`` through the points within :data:`ON_CIRCLE_PX` [−1] of
    it from (cx, cy), three Gauss–Newton steps: x, y and the points on it (0 where under :data:`MIN_POINTS`)."""
    tolerance = ON_CIRCLE_PX[-1]
    for _ in range(3):
        dx, dy = x - cx[:, None], y - cy[:, None]
        distance = np.maximum(np.hypot(dx, dy), 1e-9)
        keep = np.abs(distance - radius_px) < tolerance
        ux, uy = np.where(keep, dx / distance, 0.0), np.where(keep, dy / distance, 0.0)
        r = np.where(keep, radius_px - distance, 0.0)
        a, b, c = (ux * ux).sum(axis=1), (ux * uy).sum(axis=1), (uy * uy).sum(axis=1)
        gx, gy = -(ux * r).sum(axis=1), -(uy * r).sum(axis=1)  # J = −u: JᵀJ s = Jᵀ (R − d)
        n = keep.sum(axis=1)
        with np.errstate(invalid="ignore", divide="ignore"):
            det = np.where(n >= MIN_POINTS, a * c - b * b, np.nan)
            cx, cy = cx + (c * gx - b * gy) / det, cy + (a * gy - b * gx) / det
    n = (np.abs(np.hypot(x - cx[:, None], y - cy[:, None]) - radius_px) < tolerance).sum(axis=1)  # after the last
    n = np.where(np.isfinite(cx) & (n >= MIN_POINTS), n, 0)
    return np.column_stack([np.where(n > 0, cx, np.nan), np.where(n > 0, cy, np.nan), n])


def outline_centres(points: np.ndarray) -> np.ndarray:
    """Per frame, from its edge points (frames × :data:`LIMB_RAYS` × 2): the limb circle's centre x, y, radius and
    the rays on it, at the clip's median radius (module docstring); NaN where it was not seen. Each centre refitted
    (:func:`_refined`) from the frame's free circle (:func:`_circles`) and, where that holds under half the rays,
    from a vote (:func:`_voted`), the one with more points on it kept (a crescent's free circle may have nearly the
    radius and not the centre)."""
    x, y = points[..., 0].astype(float), points[..., 1].astype(float)
    free = _circles(x, y)
    radii = free[free[:, 3] >= MIN_LIMB_SHARE * LIMB_RAYS, 2]
    if radii.size == 0:
        return np.full((len(points), 4), np.nan)
    radius = float(np.median(radii))
    best = _refined(x, y, radius, free[:, 0], free[:, 1])
    doubt = np.nonzero(best[:, 2] < LIMB_RAYS / 2)[0]  # under half the rays on it: a vote too
    if doubt.size:
        voted = _refined(x[doubt], y[doubt], radius, *_voted(x[doubt], y[doubt], radius))
        best[doubt] = np.where((voted[:, 2] >= best[doubt, 2])[:, None], voted, best[doubt])
    return np.column_stack([best[:, :2], np.where(best[:, 2] > 0, radius, np.nan), best[:, 2]])


def _rounded(value: float) -> float | None:
    """A figure for the tracks JSON: 4 decimals, None where a path's fit gave none."""
    return round(value, 4) if math.isfinite(value) else None


def _creep(document: dict) -> tuple[np.ndarray, float]:
    """The camera's creep a path's fit found, first to last frame (px), and its standard error; none: 0, 0."""
    creep = document.get("creep") or {}
    if creep.get("start_to_end_px") is None:
        return np.zeros(2), 0.0
    return np.asarray(creep["start_to_end_px"], float), float(creep["motion_stderr_px"])


def _outline_path(track: pd.DataFrame, least_rays: float) -> tuple[pd.DataFrame, np.ndarray, np.ndarray]:
    """The track with its outline's centres for positions wherever a circle was found, its ``ok`` frames whose
    outline was not seen (fewer than ``least_rays`` on its circle) flagged ``occluded``; and its ok frames, and
    those with their outline seen."""
    ok = (track.flag == "ok").to_numpy()
    seen = ok & (track.outline_rays.to_numpy(float) >= least_rays)
    outline = track.drop(columns=OUTLINE_COLUMNS)
    found = np.isfinite(track.outline_x_px.to_numpy(float))  # every frame with a circle, flagged or not: one measure
    outline["x_px"] = np.where(found, track.outline_x_px, track.x_px)
    outline["y_px"] = np.where(found, track.outline_y_px, track.y_px)
    outline.loc[ok & ~seen, "flag"] = "occluded"
    return outline, ok, seen


def sharper_outline(colour: pd.DataFrame, brightness: pd.DataFrame) -> pd.DataFrame:
    """The colour view's track with the brightness view's outline in place of its own where that is the better
    pendulum, at most :data:`OUTLINE_GAIN` as far off one circle (:func:`~pendulum.tracking.path_shape.path_departure`'s
    unexplained RMS: the real apple clip painted two-tone and turning, 0.45 against 0.48 px, keeps its colour
    view's), and seen in all but :data:`MAX_UNSEEN_SHARE` of the colour track's usable frames (each frame whose
    outline is not seen is flagged: a red ball whose brightness nearly matches a band of wall lost its limb in 8 %).

    The colour view's chroma is sampled at half the luma's resolution: a two-tone ball's limb in it was 0.34 px RMS
    off its path at 1080p and 0.57 px at 550 × 310 (a helper's renders), in brightness 0.11 and 0.06 px, where the
    brightness silhouette, fooled by a shadow band, was usable in fewer frames. A brightness circle counts where that
    view followed the body (not ``lost``, ``held`` or at the ``edge``) within :data:`OUTLINE_REACH` radii of the
    colour silhouette's centroid, from :data:`CONFIRMED_LIMB_SHARE` of the rays: where the band darkens the wall
    behind part of the navy half, 24–31 of 96 remain, their centres as near the truth as from 32–40 (0.12 ± 0.06 px
    against 0.09 ± 0.06 px at 550 × 310). ``attrs["body"]["outline_view"]``: which was kept, the figures, and the
    ``least_rays`` a frame's limb then needs."""
    if OUTLINE_COLUMNS[0] not in colour.columns or OUTLINE_COLUMNS[0] not in brightness.columns:
        return colour
    other = colour.copy()
    matched = brightness.set_index("frame").reindex(colour.frame)
    other[OUTLINE_COLUMNS] = matched[OUTLINE_COLUMNS].to_numpy()
    # its circle where the brightness view followed the body (not lost, held, at the border) and on it: its centre
    # within OUTLINE_REACH radii of the colour silhouette's (a part's centroid is within half a radius of it)
    off = np.hypot(other.outline_x_px - colour.x_px, other.outline_y_px - colour.y_px).to_numpy(float)
    unfit = matched.flag.isin(["lost", "held", "edge"]).to_numpy() | ~(off <= OUTLINE_REACH * other.outline_r_px)
    other.loc[unfit, OUTLINE_COLUMNS] = np.nan
    ok = (colour.flag == "ok").to_numpy()
    left, seen = {}, {}
    least = {"colour": MIN_LIMB_SHARE * LIMB_RAYS, "brightness": CONFIRMED_LIMB_SHARE * LIMB_RAYS}
    for name, track in (("colour", colour), ("brightness", other)):
        path, _, shown = _outline_path(track, least[name])
        seen[name] = int(shown.sum())
        enough = ok.any() and shown.sum() >= (MIN_SEEN_SHARE if name == "colour" else 1 - MAX_UNSEEN_SHARE) * ok.sum()
        left[name] = path_departure(path)[1].get("unexplained_rms_px", math.inf) if enough else math.inf
    kept = "brightness" if left["brightness"] <= OUTLINE_GAIN * left["colour"] else "colour"
    out = other if kept == "brightness" else colour
    out.attrs = {**colour.attrs, "body": dict(colour.attrs.get("body") or {})}
    out.attrs["body"]["outline_view"] = {
        "used": kept,
        "usable_frames": int(ok.sum()),  # the colour track's; an outline seen in too few: no figure
        "seen_frames": seen,
        "unexplained_rms_px": {name: _rounded(value) for name, value in left.items()},
        "least_rays": least[kept],  # on a frame's circle for its limb to be seen (centre_by_outline)
    }
    return out


def _taken_back(
    track: pd.DataFrame,
    corrected: pd.DataFrame,
    seen: np.ndarray,
    least_rays: float,
    noise_px: float,
    settings: TrackerSettings,
) -> tuple[np.ndarray, np.ndarray]:
    """Frames usable again by their outline: (flagged, part). *Flagged*: frames the silhouette flagged ``occluded``
    or ``jump`` whose limb is seen (``least_rays`` or more on its circle). *Part*: frames the silhouette found usable
    whose limb was seen in part (at least :data:`PART_LIMB_SHARE` of the rays on its circle, under the share that
    counts as seen: a print's light squares lost against the wall where they meet the limb). Each only where its
    outline centre keeps to the usable frames' path: within :data:`ON_PATH_NOISE` times its noise (and
    :data:`ON_PATH_PX`) of the circle through them (``corrected``: the outline's path with the camera's creep taken
    out), and no jump (:func:`~pendulum.tracking.checks.flag_jumps` on the path with them) in a run of them or
    within its stencil of one (a run of shifted frames makes its usable neighbours the jumps). A limb seen whole (half
    the rays, and the :data:`WHOLE_LIMB_QUANTILE` of the usable frames' count) is taken so, before the first usable
    frame or after the last only where it moves by over :data:`STILL_PX` a frame (a hand may hold it still there);
    any other frame also where the swing puts it along the path (:func:`_along_the_path`).

    A silhouette's flag there is its own: its area or centroid changed (a two-tone ball's light half standing out where
    the wall behind it darkens, seed 7149 of the body study: 1.35 times the area at one end of the swing; its dark half
    lost against a dark band, 7411: 0.3 times, 40–70 of the rays on its limb), which does not move a sphere's limb. A
    thing in front of the body hides part of the limb, whose rest still gives its circle, or pulls the circle along the
    swing (a reviewer's runs: a bump of 1–20 px that builds and recedes, a drift into frames whose limb is lost, none
    taken back over 0.5 px off); one merged with it at half its contrast or more bends the limb off the circle (fewer
    rays on it, a centre off the path); one fainter (a soft shadow merged with it) can shift a whole limb by under the
    circle's tolerance and the centre by up to 1.6 px (a reviewer's renders), across the path seen here, along it by
    under the jump test's 1 px only."""
    nothing = np.zeros(len(track), bool)
    if not seen.any():
        return nothing, nothing
    rays = track.outline_rays.to_numpy(float)
    flagged = track.flag.isin(["occluded", "jump"]).to_numpy() & (rays >= least_rays)
    part = (track.flag == "ok").to_numpy() & ~seen & (rays >= PART_LIMB_SHARE * LIMB_RAYS)
    whole = flagged & (rays >= max(LIMB_RAYS / 2, float(np.quantile(rays[seen], WHOLE_LIMB_QUANTILE))))
    candidates = flagged | part
    x, y = corrected.x_px.to_numpy(float), corrected.y_px.to_numpy(float)
    order, free = np.arange(len(track)), np.flatnonzero(seen)
    for end in (order < free[0], order > free[-1]):  # before the first usable frame or after the last: swinging
        steps = np.hypot(np.diff(x[end & whole]), np.diff(y[end & whole]))
        if not (steps.size and np.median(steps) > STILL_PX):  # held still there (a hand), or too short to tell
            candidates &= ~end
    if not candidates.any() or seen.sum() < MIN_POINTS or not math.isfinite(noise_px):
        return nothing, nothing
    jumps = flag_jumps(x, y, seen | candidates, settings, track.time_s.to_numpy())
    near_jump = maximum_filter1d(jumps.astype(np.uint8), 2 * JUMP_HALF_WINDOW + 1) > 0
    runs, _ = label(candidates)
    candidates &= ~np.isin(runs, np.unique(runs[near_jump & (runs > 0)]))  # a run with a jump in or beside it
    cx, cy, radius = fit_circle(x[seen], y[seen])
    tolerance = max(ON_PATH_NOISE * noise_px, ON_PATH_PX)
    with np.errstate(invalid="ignore"):
        back = candidates & (np.abs(np.hypot(x - cx, y - cy) - radius) <= tolerance)
    turn = np.arctan2(x - cx, y - cy) - math.atan2(float(np.nanmean(x[seen])) - cx, float(np.nanmean(y[seen])) - cy)
    arc = radius * np.angle(np.exp(1j * turn))  # along the path from its middle (px; a pivot below too); NaN: no centre
    along = max(ALONG_NOISE * noise_px, ON_PATH_PX)
    back &= whole | _along_the_path(arc, track.time_s.to_numpy(float), seen, back & ~whole, along)
    return back & flagged, back & part


def _swing_rate(arc: np.ndarray, t: np.ndarray, seen: np.ndarray) -> float | None:
    """The swing's angular frequency ω (rad/s) from the usable frames' place along the path: π per crossing of its
    median between the first crossing and the last, a crossing counted where the path goes from a fifth of its
    swing's reach on one side to as far on the other (the noise of a swing dying to rest crosses nothing); None with
    fewer than three."""
    at = np.flatnonzero(seen & np.isfinite(arc))
    if at.size < MIN_POINTS:
        return None
    centred = arc[at] - np.median(arc[at])
    reach = CROSSING_REACH * float(np.quantile(np.abs(centred), 0.95))
    side, crossings = 0, []
    for k in np.flatnonzero(np.abs(centred) > reach):
        now = 1 if centred[k] > 0 else -1
        if side and now != side:
            crossings.append(t[at[k]])
        side = now
    if len(crossings) < 3:
        return None
    return math.pi * (len(crossings) - 1) / (crossings[-1] - crossings[0])


def _swing_terms(tau: np.ndarray, omega: float) -> np.ndarray:
    """The columns of s = a + b τ + Σ_{n = 1, 3} (cₙ + dₙ τ) sin nωτ + (eₙ + fₙ τ) cos nωτ at times ``tau`` (s, from
    the middle of a run): a swing whose amplitude and phase drift, and its third harmonic (a large swing's)."""
    columns = [np.ones_like(tau), tau]
    for n in (1, 3):
        wave = np.column_stack([np.sin(n * omega * tau), np.cos(n * omega * tau)])
        columns += [wave, wave * tau[:, None]]
    return np.column_stack(columns)


def _along_the_path(arc: np.ndarray, t: np.ndarray, seen: np.ndarray, candidates: np.ndarray, tolerance: float):
    """The ``candidates`` whose place along the path (``arc``, px) is where the usable frames on both sides put it. Per
    run of them no longer than :data:`ALONG_RUN_S`: the swing :func:`_swing_terms` at its own ω (:func:`_swing_rate`)
    fitted to the ``seen`` frames within :data:`ALONG_WINDOW_S` before and after it that lie in unbroken stretches of
    :data:`ALONG_SIDE_FRAMES` or more (a usable frame among flagged ones may share their fault), at least that many
    on each side and twice the swing's terms in all, the fit within ``tolerance`` of them (RMS); each frame of the
    run within ``tolerance`` of it is kept. Across a run of 0.25 s that swing is out by 0.13–0.29 px at worst on arms
    of 450–900 px swinging 0.3–1 rad (the frames' noise, 0.08 px, included; across 0.5 s by up to 1 px). A frame that
    a hand holds, or whose circle a thing in front of it pulls along the swing, is not where the swing is."""
    keep = np.zeros(len(arc), bool)
    omega = _swing_rate(arc, t, seen)
    if omega is None:
        return keep
    usable = seen & np.isfinite(arc)
    stretches, _ = label(usable)
    anchors = np.flatnonzero(usable & (np.bincount(stretches)[stretches] >= ALONG_SIDE_FRAMES))
    times = t[anchors]
    runs, _ = label(candidates)
    for found in find_objects(runs):
        inside = np.arange(found[0].start, found[0].stop)
        start, end = t[inside[0]], t[inside[-1]]
        before = anchors[np.searchsorted(times, start - ALONG_WINDOW_S) : np.searchsorted(times, start)]
        after = anchors[np.searchsorted(times, end, "right") : np.searchsorted(times, end + ALONG_WINDOW_S, "right")]
        if end - start > ALONG_RUN_S or min(before.size, after.size) < ALONG_SIDE_FRAMES:
            continue
        around, middle = np.concatenate([before, after]), 0.5 * (start + end)
        terms = _swing_terms(t[around] - middle, omega)
        if around.size < 2 * terms.shape[1]:  # twice the swing's terms: its fit to them a test of it
            continue
        fitted, *_ = np.linalg.lstsq(terms, arc[around], rcond=None)
        if np.sqrt(np.mean((terms @ fitted - arc[around]) ** 2)) > tolerance:
            continue
        keep[inside] = np.abs(_swing_terms(t[inside] - middle, omega) @ fitted - arc[inside]) <= tolerance
    return keep


def centres_apart(centroid: pd.DataFrame, outline: pd.DataFrame, both: np.ndarray) -> tuple[float, float]:
    """How far the silhouette's centroid and the outline's centre move apart over the frames ``both`` measured
    well (and finite): the RMS of their 2-D difference about its mean beyond its noise, √(RMS² − noise²), and that
    noise (px, 2-D: √2 × each axis's), from the difference's second differences Δ = d(k) − (d(k−1) + d(k+1)) / 2
    over consecutive frames (σ² = mean(|Δ|²) / 1.5, as of white noise); ``(0, inf)`` with too few of them. A
    constant offset is no bias of θ's swing (the pivot takes it); a difference that comes and goes as the body
    swings or turns (a two-tone ball blurred by its motion, its faint half's edge cut by the silhouette's threshold;
    its coloured half turned away) is one centre moving on the body."""
    x = centroid.x_px.to_numpy(float) - outline.x_px.to_numpy(float)
    y = centroid.y_px.to_numpy(float) - outline.y_px.to_numpy(float)
    index = np.flatnonzero(both & np.isfinite(x) & np.isfinite(y))
    if index.size < 8:
        return 0.0, math.inf
    apart = np.column_stack([x[index], y[index]])
    runs = (index[1:-1] - index[:-2] == 1) & (index[2:] - index[1:-1] == 1)
    if runs.sum() < 4:
        return 0.0, math.inf
    second = apart[1:-1] - 0.5 * (apart[:-2] + apart[2:])
    noise = math.sqrt(float(np.mean(np.sum(second[runs] ** 2, axis=1))) / 1.5)
    spread = float(np.mean(np.sum((apart - apart.mean(axis=0)) ** 2, axis=1)))
    return math.sqrt(max(spread - noise**2, 0.0)), noise


def centre_by_outline(track: pd.DataFrame, settings: TrackerSettings | None = None) -> pd.DataFrame:
    """The track with its outline's centres where they make the better pendulum (module docstring), without the
    outline columns; ``attrs["body"]["centre"]``: what each gave and which was kept. Measured by its outline, the
    frames the silhouette flagged for its area or centroid but whose limb is seen are usable again
    (:func:`_taken_back`, with ``settings``' jump test), and so are the usable frames whose limb was seen in part."""
    if OUTLINE_COLUMNS[0] not in track.columns:
        return track
    centroid = track.drop(columns=OUTLINE_COLUMNS)
    centroid.attrs = {**track.attrs, "body": dict(track.attrs.get("body") or {})}
    least_rays = (track.attrs.get("body") or {}).get("outline_view", {}).get("least_rays", MIN_LIMB_SHARE * LIMB_RAYS)
    outline, ok, seen = _outline_path(track, least_rays)
    facts = {"by": "silhouette", "outline_seen_frames": int(seen.sum())}
    centroid.attrs["body"]["centre"] = facts
    if not ok.any() or seen.sum() < MIN_SEEN_SHARE * ok.sum():
        facts["why"] = (
            f"its outline was seen as a circle's in {int(seen.sum())} of its {int(ok.sum())} usable frames "
            f"({100 * MIN_SEEN_SHARE:.0f} % needed to be measured by it): by its silhouette's centroid"
        )
        return centroid
    radius = float(np.nanmedian(track.outline_r_px.to_numpy(float)[seen]))
    _, by_centroid = path_departure(centroid)
    on_path, by_outline = path_departure(outline)
    left_centroid = by_centroid.get("unexplained_rms_px", math.inf)
    left_outline = by_outline.get("unexplained_rms_px", math.inf)
    noise_centroid, noise_outline = by_centroid.get("noise_px", math.inf), by_outline.get("noise_px", math.inf)
    wander_centroid = math.sqrt(max(left_centroid**2 - noise_centroid**2, 0.0))  # beyond each path's own noise
    wander_outline = math.sqrt(max(left_outline**2 - noise_outline**2, 0.0))
    facts.update(
        outline_radius_px=round(radius, 3),
        unexplained_rms_px={"silhouette": _rounded(left_centroid), "outline": _rounded(left_outline)},
        noise_px={"silhouette": _rounded(noise_centroid), "outline": _rounded(noise_outline)},
    )
    (creep_centroid, sigma_centroid), (creep_outline, sigma_outline) = _creep(by_centroid), _creep(by_outline)
    creeps_apart = float(np.hypot(*(creep_centroid - creep_outline)))
    # a centre that moves on the body moves by less than its radius: a larger difference is a creep fitted to a
    # short or odd path, not evidence
    creeps_differ = (
        max(MIN_MOTION_PX, MOTION_SIGMAS * math.hypot(sigma_centroid, sigma_outline)) < creeps_apart < radius
    )
    facts["creep_px"] = {"silhouette": creep_centroid.round(3).tolist(), "outline": creep_outline.round(3).tolist()}
    wanders = (
        wander_centroid > WANDER_NOISE_RATIO * noise_centroid
        and wander_outline <= OUTLINE_GAIN * wander_centroid
        and left_outline < left_centroid
    )
    better = (  # the outline's path the better pendulum on both counts (a wander mostly along the swing, and noise)
        math.isfinite(left_outline + noise_outline + left_centroid + noise_centroid)  # both paths fitted
        and left_outline <= OUTLINE_GAIN * left_centroid
        and noise_outline <= noise_centroid
    )
    # the two centres moving apart as the body swings or turns (by enough to move θ), the outline's path no worse
    apart, apart_noise = centres_apart(centroid, outline, seen)
    facts["apart_px"] = {"wander": _rounded(apart), "noise": _rounded(apart_noise)}
    least_apart = math.radians(APART_MIN_DEG) * by_outline.get("radius_px", math.inf)
    moves_apart = (
        math.isfinite(left_outline + noise_outline + left_centroid + noise_centroid)  # both paths fitted
        and apart > max(APART_NOISE_RATIO * apart_noise, least_apart)
        and left_outline <= left_centroid
        and noise_outline <= APART_NOISE_SLACK * noise_centroid
    )
    # a wander slow enough to pass for the camera creeping: the centroid's creep not the outline's
    creeping = creeps_differ and left_outline <= left_centroid + noise_centroid
    if not (wanders or better or creeping or moves_apart):
        facts["why"] = (
            "its two centres' paths could not both be fitted (too few usable frames): by its silhouette's centroid"
            if not math.isfinite(left_centroid + left_outline + noise_centroid + noise_outline)
            else f"its silhouette's centroid {left_centroid:.2f} px RMS off a circle about the pivot (noise "
            f"{noise_centroid:.2f} px), its round outline's centre {left_outline:.2f} px (noise "
            f"{noise_outline:.2f} px): no better pendulum, by its silhouette's centroid"
        )
        return centroid
    restored, in_part = _taken_back(track, on_path, seen, least_rays, noise_outline, settings or TrackerSettings())
    outline.loc[restored | in_part, "flag"] = "ok"
    unseen = int((ok & ~seen & ~in_part).sum())
    facts["by"] = "outline"
    turns = ": a ball seen in part (one half of a two-tone ball, a print's dark patches) that turns on its string"
    if wanders or better:
        evidence = (
            f"the silhouette's centroid leaves its path {left_centroid:.2f} px RMS off a circle about the pivot, the "
            f"centre of its round outline ({radius:.1f} px in radius) {left_outline:.2f} px"
        )
        if not wanders:  # the centroid's own wander within its noise: the outline's path the better pendulum
            evidence += f", and its noise {noise_outline:.2f} px against the centroid's {noise_centroid:.2f} px"
            turns = ": the outline's path the better pendulum (a centroid that wanders along the swing, or noisier)"
    elif creeping:
        (sx, sy), (ox, oy) = creep_centroid, creep_outline
        evidence = (
            f"the silhouette's centroid needs the camera to creep by ({sx:+.1f}, {sy:+.1f}) px over the clip, the "
            f"centre of its round outline ({radius:.1f} px in radius) by ({ox:+.1f}, {oy:+.1f}) px"
        )
    else:
        evidence = (
            f"the silhouette's centroid and the centre of its round outline ({radius:.1f} px in radius) move apart "
            f"by {apart:.2f} px RMS as it swings or turns (their difference's noise {apart_noise:.2f} px), the "
            f"outline's path no farther off a circle about the pivot ({left_outline:.2f} px against "
            f"{left_centroid:.2f} px), its noise {noise_outline:.2f} px against {noise_centroid:.2f} px"
        )
        turns = (
            ": the centroid moves on the body (a part of it not always in the silhouette: a two-tone ball's faint half "
            "turned away, or blurred by its motion under the threshold)"
        )
    if (track.attrs.get("body") or {}).get("outline_view", {}).get("used") == "brightness":
        turns += " (its outline in the brightness view)"
    facts["why"] = (
        f"{evidence}{turns}, measured by its outline's centre"
        + (
            f"; {int(in_part.sum())} frames whose limb was seen in part are usable by it (where the swing puts them)"
            if in_part.any()
            else ""
        )
        + (
            f"; {unseen} frames whose outline was not seen (or seen in part off the swing) are flagged occluded"
            if unseen
            else ""
        )
        + (
            f"; {int(restored.sum())} frames its silhouette flagged (its area or centroid changed) are usable by "
            "their outline, seen as a circle's"
            if restored.any()
            else ""
        )
    )
    facts["limb_seen_frames"], facts["limb_in_part_frames"] = int(restored.sum()), int(in_part.sum())
    outline.attrs = {**centroid.attrs, "body": {**centroid.attrs["body"], "centre": facts}}
    if "method" in outline.attrs:  # said where the method is
        method = outline.attrs["method"]
        outline.attrs["method"] = {**method, "reason": f"{method['reason']}; {facts['why']}"}
    return outline
