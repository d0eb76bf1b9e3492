"""Body tracking: the swinging object itself, where there is no marker disk to measure.

What a Tracker (Open Source Physics) user does by hand, made precise for real footage (an apple, a ball, a vehicle):

1. **Scene.** ≤ 2 × :data:`SCENE_SAMPLES` frames spread over the clip, each brought to one exposure
   (gain and offset against their median: auto-exposure drift), and their per-pixel median (where it holds a
   body at rest over half the clip, from the samples that show its ghost: ``body_scene.scene_states``); then
   again, up to :data:`SCENE_PASSES` times, with each sample's moving objects (by their hulls) left out;
   pixels almost no sample shows clear (a swing narrower than the body) filled from around them, refused where
   that fill is likely off by max(3σ, :data:`UNSEEN_FILL_SHARE` C) or cannot be checked (a rigid body is then
   followed by its look: :mod:`pendulum.tracking.look`), else warned of where the silhouette changes mid-swing.
   Static shadows, wall gradients and stripes are part of the scene; σ is the MAD of I − B.
2. **Body.** In a window around the predicted position, the difference D = |I − B − o| (o: the
   window's offset, a line in the row fitted to its border, which follows slow exposure drift and a light's
   bands rolling down the frame: :func:`pendulum.tracking.scene_stack.border_offset`), or for a one-sided body
   (``body_scene.body_polarity``: at least 80 % of its first-frame pixels' |I − B| on one side of the scene,
   an apple or a two-tone ball's dark half before a light wall, where that side alone finds the same body)
   that side's only, D = −(I − B − o) or I − B − o clipped at 0 (a part of nearly the wall's grey then stays
   out wherever the wall behind it is darker or lighter; a wall darker than a dark body hides it), above
   T = max(5σ, ¼ C), C the body's contrast, closed by a disk of about half the body's inner radius (a print's
   dark patches are one object), its holes filled where together under a tenth of it (a dot or a label on it:
   ``body_scene.fill_markings``) and opened by one of about two thirds of it (a string, a stem, a thin rod is cut off; a
   soft shadow is below T); the connected component nearest the prediction (where that is over
   :data:`MAX_AREA_RATIO` of the body's area and another is the body's size: that one, a hand drawn back
   after the release), with every component within two closing widths of it and within 1.3 × the body's reach of
   the prediction (a part of it, not a light blinking beside it); where that is over MAX_AREA_RATIO of the body (a
   hand, a second bob it meets), the prediction goes on from the body's own centre in it (``body_parts.own_centre``).
   The first frame's body is the heaviest moving object above a quarter of its own contrast (its part at its
   thickest point; one that is no compact body or spans the frame's width and moves in place in most samples, a
   tank's wavy water surface, is set aside: ``body_parts.in_place_set_aside``), or the one at
   ``start_px``; its size, contrast and silhouette split are the first frame's, or, where that differs from the
   median-sized body of samples spread over the clip by more than :data:`~.body_parts.TYPICAL_AREA_RATIO` (a hand
   holding it) or touches the border, that sample's. Where the
   body's contrast in a frame is below :data:`FAINT_CONTRAST` of C (before a darker band of wall), it is found
   again above ¼ of its own contrast there. A one-sided body's I − B (where over its noise) is divided by the
   wall's gain (``body_scene.wall_gain``: under 1 where the body keeps less than 0.8 of its contrast before the
   light wall): about the difference it would make before the light wall, so that its part before a darker band
   stays in its silhouette.
3. **Position.** The silhouette: the component's pixels that differ by more than a share of its
   contrast C_f fixed for the clip (``body_scene.silhouette_fraction``: ¼, or the Otsu split of a
   two-tone body), filled to their convex hull (a part that hardly differs from the wall, a bright half before
   a bright wall, is left out the same way in every frame); its soft-edged centroid x̂ = Σ w x / Σ w,
   w = 1 in the hull's core, the pixel's coverage D / C_local within 2 px of its outline (no pixel
   locking). Any point fixed to a rigid pendulum turns about the pivot with it, so its angle about the
   pivot is θ up to a constant (the vertical). Beside it, its round outline's centre (a ball seen in part:
   :mod:`pendulum.tracking.outline`), kept where the path says the centroid moves on the body.

Flags from the measurement's own evidence (never thresholds fitted to renders): ``edge`` (the body itself, within
1.2 inner radii of its thickest point, not a rod or thread leaving the frame, touches the frame's border),
``occluded`` (its covered area departs from its running median by 6 robust σ and 10 %, or lies beyond 1.5× or ½ of
its median where it moves, or the soft and plain silhouette's centroids disagree by 6 robust σ and 1.5 % of its
radius (≥ 0.3 px), and the frames within 0.2 s of a size flag in its run off 1.2× its size either way, a merge
coming and going: :func:`pendulum.tracking.checks.grown_runs`; or it reaches a place something in front of the
swing hides: :mod:`pendulum.tracking.occluders`), ``jump`` (leave-one-out cubic, as for the marker), ``held``
(over 1.5× that median before the body's first free frame or after its last: a hand before the release, or one that
catches it; or, still, over 1.2× it from the record's first frame or to its last: fingers alone over its edge) and
``lost`` (no body near the prediction).

A scene that holds the body (a narrow swing: it covers its rest place, or its swing's ends, in most samples) shows
as a silhouette smaller or larger mid-swing than at the ends
(:func:`pendulum.tracking.path_shape.rest_place_area_ratio` outside 0.9–1/0.9): the scene there is taken again
from the two ends of the swing (:func:`pendulum.tracking.body_scene.rest_place_scene`) and the body tracked again,
up to :data:`REST_PLACE_REPAIRS` times; then refused, unless the scene from the swing's ends saw the rest place
and is the median's there (``rest_place_clear``: it never held the body; the body's look changes with the wall
behind it, a two-tone ball's light half before a shadow band): then a one-sided body is measured by its side only
(as in step 2, where that was not taken), and a silhouette still smaller or larger mid-swing is kept with a
``warning`` in the track's body facts.

``view`` (in :func:`find_body` and :func:`track_body`): the image taken of each frame, its luma by default
(:func:`pendulum.tracking.colour.colour_view`: its colour's difference from the wall's)."""

from __future__ import annotations

import logging
import math
from dataclasses import dataclass, field, replace
from functools import partial

import cv2
import numpy as np
import pandas as pd

from pendulum.camera.video import VideoError, iter_luma
from pendulum.tracking.body_parts import (
    CONTRAST_FRACTION,
    MAX_AREA_RATIO,
    MIN_AREA_RATIO,
    MIN_SOLIDITY,
    NOISE_SIGMAS,
    TYPICAL_AREA_RATIO,
    Seen,
    body_close_size,
    body_component,
    body_core,
    body_reach,
    first_and_usual,
    in_place_set_aside,
    open_size,
    own_centre,
    silhouette_cut,
    solidity,
    start_missed,
)
from pendulum.tracking.body_scene import (
    STRONG_FRACTION,
    body_polarity,
    close_size,
    filled_warning,
    moving_objects,
    one_sided,
    reduced,
    rest_place_scene,
    sample_clip,
    scene_states,
    soft_centroid,
    two_objects_where,
    unseen_behind,
    wall_gain,
)
from pendulum.tracking.checks import STILL_PX, flag_jumps, grown_runs, held_still_runs, robust_outliers
from pendulum.tracking.limb import LIMB_RAYS, edge_points
from pendulum.tracking.occluders import SilhouetteCounts, hidden_frames
from pendulum.tracking.outline import OUTLINE_COLUMNS, outline_centres
from pendulum.tracking.path_shape import rest_place_area_ratio
from pendulum.tracking.scene_stack import (
    EnlargedMasks,
    border_offset,
    masked_median,
    median_scene,
    noise_sigma,
    same_exposure,
    unseen,
)
from pendulum.tracking.settings import TrackerSettings

log = logging.getLogger(__name__)

SCENE_SAMPLES = 60  # frames spread over the clip for the static scene
EDGE_REACH = 1.2  # in view or not: what lies within this many inner radii of its thickest point (not its rod)
SCENE_PASSES = 4  # scene estimates, each leaving out the moving pixels the previous one showed
FAINT_CONTRAST = 0.6  # a body below this share of its first contrast is found again above ¼ of its own
AREA_SIGMAS, MIN_AREA_CHANGE = 6.0, 0.10  # a fault: the covered area changes by 6 σ and this fraction in ~1 s
MOVING_PX = 0.3  # the body moves (px per frame): its area there is its own (MAX_AREA_RATIO, MIN_AREA_RATIO)
MERGE_S = 0.2  # a merge with a shadow or a hand comes and goes over this long (s): ``checks.grown_runs``
CENTROID_SIGMAS = 6.0
MIN_CENTROID_DISAGREEMENT = 0.015  # ... and this share of the body's radius (0.3 px at 20 px), at least 0.3 px
CLEAR_REST_PLACE = 0.2  # the scene from the swing's ends changes < this share of the body's area: it held none
REST_PLACE_REPAIRS = 2  # scenes taken again from the swing's ends before a body that holds its place is refused
MIN_MID_SWING_AREA_RATIO = 0.9  # below (or above its inverse): the scene holds the body (rest_place_area_ratio)
FILLED_CLEAN_RATIO = 0.96  # mid_swing_area_ratio of a clean scene: 0.96–1.02; beyond, with a fill behind: a warning
WIDE_SWING_RADII = 6.0  # a path this many body radii across hides no place of the scene in most frames
UNSEEN_FILL_SHARE = 0.8 * CONTRAST_FRACTION  # a scene filled in behind the body: off by less than the silhouette cut


class BodyError(VideoError):
    """No single moving body can be followed; the message says what was seen (``refused``: the track and scene)."""


@dataclass(frozen=True)
class BodyScene:
    """The static scene and the body as the sampled frames show them."""

    background: np.ndarray  # float32, the scene without the body (full resolution)
    noise_grey: float  # σ of I − B over static pixels
    start_px: tuple[float, float]  # the body's soft-silhouette centre in the first frame
    radius_px: float  # √(area / π) of the body's silhouette in the first frame
    inner_radius_px: float  # largest inscribed radius (distance transform) of the silhouette
    contrast_grey: float  # 90th percentile of D inside the body in the first frame
    moving_samples: int  # samples in which a moving object was seen
    n_samples: int
    silhouette_fraction: float = STRONG_FRACTION  # share of the body's contrast a silhouette pixel needs
    rest_place_clear: bool | None = None  # the ends' scene is the median's at the rest place (None: not taken)
    polarity: str = "both"  # measured by |I − B| ("both"), −(I − B) ("dark") or I − B ("bright")
    one_sided: str | None = None  # the side of the scene the first-frame body lies on (body_polarity)
    unseen: np.ndarray | None = field(default=None, repr=False, compare=False)  # pixels no sample shows clear
    reach_px: float | None = None  # its silhouette's farthest pixel from its centre (body_parts.body_reach)
    # medians of the body and of the wall behind it as the clip usually shows it (the first frame, or a sample where a
    # hand holds it there), and of the wall behind its swing (wall_gain)
    first_grey: tuple | None = None
    set_aside: list = field(default_factory=list)  # moving objects in place taken for no body (x_px, y_px, hull_fill)

    def to_dict(self) -> dict:
        return {
            "start_px": [round(self.start_px[0], 3), round(self.start_px[1], 3)],
            "radius_px": round(self.radius_px, 2),
            "inner_radius_px": round(self.inner_radius_px, 2),
            "contrast_grey": round(self.contrast_grey, 1),
            "noise_grey": round(self.noise_grey, 2),
            "moving_samples": self.moving_samples,
            "n_samples": self.n_samples,
            "silhouette_fraction": round(self.silhouette_fraction, 3),
            "polarity": self.polarity,
            "one_sided": self.one_sided,
            "rest_place_clear": self.rest_place_clear,
            "reach_px": None if self.reach_px is None else round(self.reach_px, 2),
        } | ({"set_aside": self.set_aside} if self.set_aside else {})


def find_body(
    path, start_px=None, n_samples: int = SCENE_SAMPLES, track=None, radius_px=None, polarity="both", view=None
) -> BodyScene:
    """The static scene and the swinging body in the first frame (see the module docstring), the body measured by
    the difference ``polarity`` names (:func:`pendulum.tracking.body_scene.one_sided`).

    With ``track`` (a first track of the body, whose silhouette shrank mid-swing) and the body's ``radius_px``, the
    scene at its rest place is taken from the two ends of its swing (:func:`~.body_scene.rest_place_scene`). Raises
    :class:`BodyError` when nothing moves, when two objects of similar weight move in most samples and ``start_px``
    does not say which one is the pendulum, or when ``start_px`` is on no moving body (:func:`~.start_missed`).
    """
    samples = sample_clip(path, n_samples, view)
    stack = same_exposure([s for _, s in samples])
    images = list(stack)  # views of the stack
    first_pass = median_scene(stack)
    sigma = noise_sigma(images, first_pass)
    threshold = silhouette_cut(sigma)
    # Each sample's moving objects leave the scene; again against the new scene, as a body that overlaps
    # itself over many samples (large, slow near its turning points) is only partly seen moving at first.
    # Found on samples reduced to ≤ ~640 px (the masks then enlarged): the scene itself at full resolution.
    scale = max(1, int(round(max(first_pass.shape) / 640)))
    small = [reduced(im, scale) for im in images] if scale > 1 else images
    small_stack = np.stack(small) if scale > 1 else stack
    small_first = reduced(first_pass, scale) if scale > 1 else first_pass
    small_threshold = silhouette_cut(noise_sigma(small, small_first)) if scale > 1 else threshold
    others = scene_states(small, small_stack, small_first, small_threshold)
    if others is not None:  # a body at rest over half the clip, in the median's scene: the samples that show it clear
        small_first = masked_median(small_stack, others, small_first)
        first_pass = masked_median(stack, EnlargedMasks(others, first_pass.shape), first_pass)
    small_background = small_first
    excluded = np.zeros(small_stack.shape, bool)
    for _ in range(SCENE_PASSES):
        found, moving, two_objects, seen = moving_objects(small, small_background, small_threshold)
        grown = excluded | found
        if grown.sum() <= 1.02 * excluded.sum():
            break
        excluded = grown
        small_background = masked_median(small_stack, excluded, small_first)
    seen = [((ax * scale, ay * scale), (bx * scale, by * scale)) for (ax, ay), (bx, by) in seen]
    excluded = EnlargedMasks(excluded, first_pass.shape)  # at full size a band at a time
    background = masked_median(stack, excluded, first_pass) if excluded.any() else first_pass
    hidden = unseen(excluded)
    scene_median = background
    if track is not None:
        frames = [frame for frame, _ in samples]
        background, ends_clear = rest_place_scene(frames, images, background, track, radius_px, threshold, hidden)
    if moving < max(3, len(images) // 4):
        raise BodyError(
            f"{path}: nothing moves against the static scene in {len(images) - moving} of {len(images)} sampled "
            f"frames (noise {sigma:.1f} grey levels): no swinging body to track"
        )
    if start_px is None and two_objects > moving // 2:
        where = two_objects_where(images[0], background, threshold, seen[0])
        raise BodyError(
            f"{path}: two moving objects of similar size in {two_objects} of {moving} sampled frames ({where}): give "
            "start_px of the pendulum to follow in the trial's sidecar (its centre in the first frame)"
        )
    # The body in the first frame; its size and contrast from the nearest sample that shows all of it (a record
    # that starts with the body partly out of view would otherwise learn a smaller, fainter body).
    near = None if start_px is None else (float(start_px[0]), float(start_px[1]))
    close_px = close_size(background.shape)

    def measured(polarity: str, aside=None) -> tuple[Seen | None, Seen | None]:
        return first_and_usual(images, background, excluded, polarity, threshold, close_px, near, view is None, aside)

    first, whole = measured(polarity)
    aside, set_aside = None, []
    if near is None:  # a mover in place that is no body (a tank's water surface): set aside
        first, whole, aside, set_aside = in_place_set_aside(
            first, whole, partial(measured, polarity), excluded, close_px
        )
    if first is None and set_aside:
        where = f"({set_aside[0]['x_px']:.0f}, {set_aside[0]['y_px']:.0f}) px"
        raise BodyError(
            f"{path}: the only moving object in the first frame, near {where}, moves in place in most samples and is "
            "no body (a tank's water surface, light rippling off water): give start_px at the body's centre, if any"
        )
    if first is None:
        raise BodyError(
            f"{path}: no moving body in the first frame (nothing differs from the static scene by more than "
            f"{threshold:.0f} grey levels)" + ("" if near is None else f" near start_px ({near[0]:.0f}, {near[1]:.0f})")
        )
    if first.component is None:
        raise BodyError(f"{path}: the moving object in the first frame is thinner than a body (a thread or rod only)")
    hull = cv2.convexHull(cv2.findNonZero(first.component.astype(np.uint8)))
    if near is not None and track is None and (missed := start_missed(first.component, hull, near)):  # the user's
        raise BodyError(f"{path}: {missed}")
    if (solid := solidity(first.component)) < MIN_SOLIDITY:  # not a body: its colour?
        raise VideoError(
            f"{path}: the heaviest moving object in the first frame, near ({first.x:.0f}, {first.y:.0f}) px, is no "
            f"compact body (it fills {100 * solid:.0f} % of its outline's convex hull): the still scene moves (a "
            "tank's water surface, light rippling off water, caustics on a tank's wall, a flickering or moving light); "
            "light the scene evenly, or give start_px at the body's centre (or a marker dot's) in the first frame"
        )
    # the side of the scene the body lies on, voted by its own pixels in the first frame (not a rod's or a second
    # pendulum's) above a quarter of its contrast
    side = body_polarity([images[0]], background, [first.component], silhouette_cut(sigma, first.contrast))
    if polarity == "both" and side in ("dark", "bright"):  # a one-sided body: measured by its own side throughout
        first_side, whole_side = measured(side, aside)
        found = first_side is not None and first_side.component is not None and whole_side.component is not None
        # the same body (its centre and most of its area), not a shadow or another object
        if found and math.dist(first_side[:2], first[:2]) <= max(2, first.inner_radius_px / 2):
            if whole_side.component.sum() >= 0.5 * whole.component.sum():
                first, whole, polarity = first_side, whole_side, side
    return BodyScene(
        background=background,
        noise_grey=sigma,
        start_px=(first.x, first.y),
        radius_px=math.sqrt(whole.component.sum() / math.pi),
        inner_radius_px=whole.inner_radius_px,
        contrast_grey=whole.contrast,
        moving_samples=moving,
        n_samples=len(images),
        unseen=hidden,
        silhouette_fraction=whole.fraction,
        polarity=polarity,
        one_sided=side,  # the vote above a quarter of the body's contrast, not its soft shadow nor the noise
        reach_px=body_reach(whole.component),
        set_aside=set_aside,
        first_grey=_greys(images[whole.sample], background, whole, excluded),
        # the swing's ends saw its rest place, and their scene differs from the median's there by less than a
        # ghost of the body would (its contrast over CLEAR_REST_PLACE of its area): the median held no body
        rest_place_clear=None
        if track is None
        else bool(
            ends_clear
            and np.count_nonzero(np.abs(background - scene_median) > CONTRAST_FRACTION * whole.contrast)
            < CLEAR_REST_PLACE * whole.component.sum()
        ),
    )


def _greys(image: np.ndarray, background: np.ndarray, body: Seen, moving) -> tuple[float, float, float]:
    """Medians of the body as the clip usually shows it (the first frame's, or a sample's where a hand holds it
    there: ``image`` that sample), of the wall behind it there and of the wall behind what moved in the samples
    (its swing), for :func:`pendulum.tracking.body_scene.wall_gain`."""
    window = (
        np.s_[:, :] if body.window is None else np.s_[body.window[0] : body.window[1], body.window[2] : body.window[3]]
    )
    pixels, behind = image[window][body.component], background[window][body.component]
    swept = background[moving.any_over_samples()] if moving.any() else behind
    return float(np.median(pixels)), float(np.median(behind)), float(np.median(swept))


def track_body(
    path, settings: TrackerSettings, progress=None, scene: BodyScene | None = None, rest_place_from=None, view=None
) -> pd.DataFrame:
    """Follow the body through the whole video in one decode pass (columns as :func:`.marker.track_video`, and
    its outline's circle per frame: :data:`~pendulum.tracking.outline.OUTLINE_COLUMNS`, for ``method.track_trial``).

    ``quality``, ``signal_ratio``: the body's covered area over its median; ``attrs["body"]``: the scene's facts
    (:meth:`BodyScene.to_dict`); ``view``: the colour view's (its outline's faint rays at their own level). Raises
    :class:`~pendulum.camera.video.VideoError` when fewer than ``min_usable_fraction`` of the frames are usable."""
    if scene is None:
        scene = find_body(path, settings.start_px, view=view)
    background = scene.background
    height, width = background.shape
    contrast = scene.contrast_grey
    threshold = silhouette_cut(scene.noise_grey, contrast)
    open_px = open_size(scene.inner_radius_px)
    close_px = max(close_size(background.shape), body_close_size(scene.inner_radius_px))
    edge_px = EDGE_REACH * scene.inner_radius_px + 2
    reach, body_area, extent = 2.5 * scene.radius_px + 12, math.pi * scene.radius_px**2, scene.reach_px
    x_prev, y_prev = scene.start_px
    vx, vy, lost_run = 0.0, 0.0, 0
    rows, binary, outlines, report = [], [], [], {}
    seen = SilhouetteCounts(background.shape, scene.radius_px)
    gain = (
        None
        if view is not None or scene.first_grey is None
        else wall_gain(background, scene.polarity, *scene.first_grey)
    )
    for index, time_s, image in iter_luma(path, report=report, view=getattr(view, "windowed", view)):
        half = reach + 2.0 * math.hypot(vx, vy) + 6 * lost_run
        px, py = x_prev + vx, y_prev + vy
        x0, x1 = max(int(px - half), 0), min(int(px + half) + 1, width)
        y0, y1 = max(int(py - half), 0), min(int(py + half) + 1, height)
        flag, x, y, mass, bx, by = "lost", math.nan, math.nan, 0.0, math.nan, math.nan
        own, edges = None, np.full((LIMB_RAYS, 2), np.nan, np.float32)
        if x1 - x0 > 4 and y1 - y0 > 4:
            signed = image[y0:y1, x0:x1].astype(np.float32) - background[y0:y1, x0:x1]
            signed -= border_offset(signed)
            here_gain = None if gain is None else gain[y0:y1, x0:x1]
            if here_gain is not None and here_gain.min() < 1.0:  # before a darker band: as before the light wall
                signed /= np.where(np.abs(signed) < NOISE_SIGMAS * scene.noise_grey, 1.0, here_gain)
            diff = one_sided(signed, scene.polarity)
            component, box = body_component(diff, threshold, open_px, close_px, (px - x0, py - y0), body_area, extent)
            if component is not None:
                here = float(np.percentile(diff[component], 90))
                if here < FAINT_CONTRAST * contrast:  # before a darker (or lighter) patch of wall: its own contrast
                    low = silhouette_cut(scene.noise_grey, here)
                    component, box = body_component(diff, low, open_px, close_px, (px - x0, py - y0), body_area, extent)
            if component is not None:
                _, box = body_core(component, edge_px)  # in view or not: the body itself, without its rod
                if np.count_nonzero(component) > MAX_AREA_RATIO * body_area:  # with a hand, another bob
                    own = own_centre(component, scene.inner_radius_px, (px - x0, py - y0))
                    own = None if own is None else (own[0] + x0, own[1] + y0)
                sx, sy, mass, bx, by = soft_centroid(diff, component, scene.silhouette_fraction)
                if math.isfinite(sx) and math.hypot(sx + x0 - px, sy + y0 - py) <= half:
                    x, y, bx, by = sx + x0, sy + y0, bx + x0, by + y0
                    edges = edge_points(diff, component, signed, scene.polarity, view is not None)  # its outline
                    edges += np.float32((x0, y0))
                    bx0, by0, bw, bh = box
                    touches = (
                        (bx0 + x0 <= 1 and x0 == 0)
                        or (by0 + y0 <= 1 and y0 == 0)
                        or (bx0 + bw + x0 >= width - 1 and x1 == width)
                        or (by0 + bh + y0 >= height - 1 and y1 == height)
                    )
                    flag = "edge" if touches else "ok"
                    if not touches:
                        seen.add(len(rows), component, x0, y0, x, y)
        if math.isfinite(x):
            ox, oy = (x, y) if own is None else own  # merged with something else: its own centre, not the pair's
            if lost_run == 0 and rows and rows[-1][6] != "lost":
                vx, vy = ox - x_prev, oy - y_prev
            x_prev, y_prev, lost_run = ox, oy, 0
        else:
            lost_run += 1
        rows.append([index, float(time_s), x, y, mass, mass, flag])
        binary.append((bx, by))
        outlines.append(edges)
        if progress and index and index % 500 == 0:
            progress(f"{path}: body tracked through frame {index}")
    table = pd.DataFrame(rows, columns=["frame", "time_s", "x_px", "y_px", "quality", "signal_ratio", "flag"])
    if table.empty:
        raise VideoError(f"{path}: no frame could be decoded")
    flags = table.flag.to_numpy(object)
    x = table.x_px.to_numpy(float)
    y = table.y_px.to_numpy(float)
    mass = table.quality.to_numpy(float)
    usable = flags == "ok"
    reference = float(np.median(mass[usable])) if usable.any() else 1.0
    table["quality"] = table["signal_ratio"] = np.where(np.isfinite(x), mass / reference, 0.0)
    table[OUTLINE_COLUMNS] = outline_centres(np.stack(outlines))  # chosen or dropped by method.track_trial
    window = max(5, int(round(len(table) / max(table.time_s.iloc[-1], 1e-9))) | 1)  # about one second
    area_fault = robust_outliers(mass / reference, usable, window, AREA_SIGMAS, MIN_AREA_CHANGE)
    bxy = np.asarray(binary, float)
    disagreement = np.hypot(x - bxy[:, 0], y - bxy[:, 1])
    least = max(0.3, MIN_CENTROID_DISAGREEMENT * scene.radius_px)
    centroid_fault = robust_outliers(disagreement, usable & np.isfinite(disagreement), window, CENTROID_SIGMAS, least)
    moving = usable & (np.hypot(np.diff(x, prepend=np.nan), np.diff(y, prepend=np.nan)) > MOVING_PX)
    own = np.median(mass[moving]) if moving.sum() >= 0.2 * usable.sum() else reference  # a hold: no outlier
    merged = usable & ((mass > MAX_AREA_RATIO * own) | (mass < MIN_AREA_RATIO * own))
    grown = grown_runs(area_fault | merged, mass / own, usable, TYPICAL_AREA_RATIO, round(MERGE_S * window))
    flags[grown | centroid_fault] = "occluded"
    # fingers alone over its edge add less than MAX_AREA_RATIO: a still run over the body's usual size, at either end
    flags[held_still_runs(mass / own, x, y, TYPICAL_AREA_RATIO, STILL_PX)] = "held"
    elsewhere = getattr(view, "hidden_box", None)  # a place the brightness view found hidden, for a colour view
    hidden, in_front = hidden_frames(seen, x, y, background, silhouette_cut(scene.noise_grey), elsewhere)
    flags[hidden & (flags == "ok")] = "occluded"
    usable = flags == "ok"
    # the body with what holds it before the first free frame or after the last (a hand before the release, one
    # that catches it): ``held``, also where that touches the border
    order = np.arange(len(flags))
    free = order[usable]
    with_more = np.isin(flags, ("occluded", "edge")) & (mass > MAX_AREA_RATIO * own)
    flags[with_more & ((order < free[0]) | (order > free[-1]) if free.size else with_more)] = "held"
    jumps = flag_jumps(x, y, usable, settings, table.time_s.to_numpy())
    flags[jumps & usable] = "jump"
    table["flag"] = flags
    counts = table.flag.value_counts().to_dict()
    n_ok = int(counts.get("ok", 0))
    table.attrs["video"] = report
    table.attrs["body"] = {**scene.to_dict(), **({"in_front": in_front} if in_front["hidden_px"] else {})}
    if gain is not None and usable.any():  # the least gain of the wall behind the body where it was usable
        side = 2 * int(scene.radius_px) + 1
        at_y = np.clip(np.round(y[usable]).astype(int), 0, height - 1)
        at_x = np.clip(np.round(x[usable]).astype(int), 0, width - 1)
        least = cv2.erode(gain, np.ones((side, side), np.uint8))[at_y, at_x]
        if least.min() < 1.0:
            table.attrs["body"]["wall_gain"] = round(float(least.min()), 3)
    fill_limit = max(3 * scene.noise_grey, UNSEEN_FILL_SHARE * contrast)
    unseen_facts, refusal = (
        unseen_behind(background, scene.unseen, np.column_stack([x, y])[usable], scene.radius_px, fill_limit)
        if scene.unseen is not None
        else ([], None)
    )
    if unseen_facts:
        table.attrs["body"]["unseen_scene"] = unseen_facts
    if refusal:
        (error := BodyError(f"{path}: {refusal}")).refused = (table, scene)
        raise error
    if rest_place_from:  # earlier scenes held the body (their tracks' mid-swing area ratios)
        table.attrs["body"]["scene_from_swing_ends"] = {"earlier_mid_swing_area_ratios": list(rest_place_from)}
    table.attrs["marker"] = None
    free = len(table) - int(counts.get("held", 0))  # a hand holding it: no swing there to measure
    if n_ok < settings.min_usable_fraction * free:
        faults = ", ".join(f"{k} {v}" for k, v in sorted(counts.items()) if k not in ("ok", "held"))
        raise VideoError(
            f"{path}: the body is usable in only {n_ok} of {free} frames{' not held' if free < len(table) else ''} "
            f"({100 * n_ok / max(free, 1):.0f} %; {faults}): the video cannot give an angle record"
        )
    ratio = rest_place_area_ratio(table)
    table.attrs["body"]["mid_swing_area_ratio"] = None if ratio is None else round(ratio, 4)
    held = ratio is not None and not MIN_MID_SWING_AREA_RATIO <= ratio <= 1 / MIN_MID_SWING_AREA_RATIO
    tries = [] if rest_place_from is None else list(rest_place_from)
    if held and len(tries) < REST_PLACE_REPAIRS and not scene.rest_place_clear:
        # the scene holds the body where it spends most samples (its rest place, or the ends of a narrow
        # swing): the scene there again, from the two ends of the swing as this track finds them
        start = settings.start_px or scene.start_px
        radius = max(scene.radius_px, scene.inner_radius_px)
        repaired = find_body(path, start, track=table, radius_px=radius, polarity=scene.polarity, view=view)
        return track_body(path, settings, progress, repaired, [*tries, round(ratio, 4)], view)
    if held and scene.rest_place_clear and scene.polarity == "both" and scene.one_sided in ("dark", "bright"):
        # the swing's ends show the scene at the rest place as the median has it (it never held the body): the
        # silhouette changes with the wall behind it (a two-tone ball's light half before a shadow band); the
        # body measured by its own side of the scene only
        start = settings.start_px or scene.start_px
        try:
            one = find_body(path, start, track=table, radius_px=scene.radius_px, polarity=scene.one_sided, view=view)
            one = replace(one, rest_place_clear=True)
            return track_body(path, settings, progress, one, [*tries, round(ratio, 4)], view)
        except VideoError as error:
            log.info(
                "%s: measured by its %s side only, the body could not be tracked (%s)", path, scene.one_sided, error
            )
    if held and scene.rest_place_clear:
        table.attrs["body"]["warning"] = (
            f"the body's silhouette is {abs(100 * (1 - ratio)):.0f} % {'smaller' if ratio < 1 else 'larger'} mid-swing "
            "than at its swing's ends, the scene there clear (the same from the ends): its contrast changes with the "
            "wall behind it (or a wide-angle lens shrinks it at the edges); its positions may be biased a few pixels"
        )
        return table
    if held:  # not a refusal of the clip: its colour may do (method.py)
        ok = table[table.flag == "ok"]
        reach = np.ptp(np.hypot(ok.x_px - ok.x_px.median(), ok.y_px - ok.y_px.median())) / max(scene.radius_px, 1)
        why = (
            "the body covers the same place in most frames (a swing narrower than about twice the body's width), so "
            "the scene behind it is never seen clearly and its positions would be biased; film a wider swing, or "
            "give start_px at a marker dot on it"
            if reach < WIDE_SWING_RADII
            else f"the swing is {reach:.0f} body radii wide, so the still scene itself changes (light rippling off "
            "water, caustics, a flickering or moving light) and its positions would be biased; light it evenly"
        )
        error = VideoError(
            f"{path}: the body's silhouette is {abs(100 * (1 - ratio)):.0f} % {'smaller' if ratio < 1 else 'larger'} "
            f"mid-swing than at the ends of its swing, also with the scene taken from the ends of the swing: {why}"
        )
        error.refused = (table, scene)  # a rigid body's look may do (pendulum.tracking.look)
        raise error
    if unseen_facts and ratio is not None and not FILLED_CLEAN_RATIO <= ratio <= 1 / FILLED_CLEAN_RATIO:
        table.attrs["body"]["warning"] = filled_warning(ratio)
    return table
