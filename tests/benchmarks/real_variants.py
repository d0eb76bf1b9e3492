"""Study: the real apple clip as other labs would film it — the tracker's test against reality, widened.

    nice -n 10 .venv/bin/python tests/benchmarks/real_variants.py [--workdir DIR] [--only NAME ...]

`../shared/data/real-video/redapple_480p.mov` (real phone footage, MIT licence) is turned into the
variants a lab's footage differs by — half, double and triple (1080p) size, 30 and 15 fps, a 6 s record, a
record that starts later in the swing, a phone on its side, upside down or 5° off level, a swing that
leaves the frame at one end, a camera knocked at 10 s (turned by 1° and moved: ``knocked_roll``; at 30 fps, 4.8 s
before the end: ``knocked_roll_30fps_late``), exposure
drift, mains flicker (a light's bands rolling down the frame), defocus, a low bitrate, the sensor noise of a
dim room, a
dark backdrop, a letterbox, a burnt-in timestamp, a post in front of the swing, an uncalibrated fisheye
lens, a phone held upright (the swing out of view most of the time: a refusal that says so), a soft dark
band across the wall (on the wall only, or on the apple too), the apple's own soft shadow beside it, a
glossy apple, the apple made a two-tone ball (alone, before the band, and that at 1080p: as one of the
held-out clips), the apple and the two-tone ball (its lower half dark blue) before the band in colour, as a
phone films (``..._colour``, the ball also at 1080p and at 550×310, and before a lamp's hard-edged bluish shadow:
``two_tone_hard_band_colour``; a sphere in the apple's place whose seam is tilted 25° and that turns on its
string by ±150°, before the band, at 640×360, 550×310 and 1080p: ``two_tone_turning_shadow_band_colour...``, its
drawn centre the truth, :func:`ball_centres`; and the apple under a water tank's caustics, a drifting net of
bright lines: ``caustics_colour``; every other variant is the clip's luma), a
release by hand in view (``hand_release``, a darker hand holding it for 10 s: ``hand_release_long_dark``, and
fingers alone: ``hand_release_fingers``; their ``ok%`` counts the frames after the release), two pendulums
side by side (with and without ``start_px``), a white dot on the apple (``dot_on_bob``; two such pendulums with
``start_px`` at the left one's dot: as the held-out clock pendulums; the same hung closer, their bobs meeting at
the inner ends of their swings: ``two_pendulums_close_dots_start_px``), and someone else in view (an arm reaching in
at a corner: ``arm_in_view``; someone walking behind the swing: ``person_behind``) — and each is tracked
with config.yaml's defaults (no hints), as a new user would. Per variant: the method used, the share of
frames ``ok`` (and ``edge``), the vertical found, the angle record's period from its zero crossings
against the independently measured 2.078 s (issue 23: within 0.3 %) and the record's own noise figure; and θ
against the original clip's own record by the same method, frame by frame (:func:`_against_the_original`: what a
transformation does to the angles, which ``pass`` does not count).
The variants are real footage transformed, not renders: what they change is known exactly, and the rest
is what a camera saw (the wall's shading composited as a camera sees it: :func:`_on_the_wall`).
Measured 2026-12-03: 44 of 46 pass (37 of 39 before the dot and the people; 36 of 38 on 2026-11-29): not the post in
front (90.8 % ok, every frame it hides part of the apple in flagged), nor the apple before a shadow band in grey
(93.6 % of frames ok, below 95 %; in colour it is measured by its colour, 99.8 %; docs/footage-notes.md).
2026-12-05: 45 of 47 (the same two; ``knocked_roll`` passes these criteria, its θ 0.069° RMS off the original's,
0.49° before its knock was found from the swing's centre); θ against the original's record in docs/footage-notes.md
(*θ against the clip's own record*). 2026-12-05, with the turning ball (three sizes): 48 of 50, the same two; the
turning ball measured by its outline's centre (docs/footage.md, *A ball seen in part*), refused or 0.6° off before.
"""

from __future__ import annotations

import argparse
import math
import sys
from pathlib import Path

import numpy as np
import yaml

ROOT = Path(__file__).resolve().parents[2]
sys.path.insert(0, str(ROOT / "workflow"))
sys.path.insert(0, str(ROOT / "tests"))

APPLE = ROOT.parent / "shared" / "data" / "real-video" / "redapple_480p.mov"
APPLE_PERIOD_S = 2.078
APPLE_FPS = 60000 / 1001  # the clip's frame rate (59.94 fps): variants are stamped at it
APPLE_START_PX = (73.0, 172.1)  # the apple's centre in the clip's first frame (find_body)
SECOND_SPEED = 1.25  # the second pendulum: the clip mirrored and played 1.25× faster (period 1.662 s)


def _resize(factor):
    import cv2

    def apply(image, index, n):
        h, w = image.shape
        size = (int(round(w * factor)) // 2 * 2, int(round(h * factor)) // 2 * 2)
        return cv2.resize(image, size, interpolation=cv2.INTER_AREA if factor < 1 else cv2.INTER_CUBIC)

    return apply


def _drift(image, index, n):
    gain = 0.75 + 0.4 * index / max(n - 1, 1)  # auto-exposure creeping over the clip
    return np.clip(image.astype(np.float32) * gain, 0, 255).astype(np.uint8)


def _flicker(image, index, n):
    """A light's bands rolling down a rolling-shutter frame: 60 fps under 50 Hz mains (the light at 100 Hz beats
    with the frame rate at 20 Hz), ±12 % of the brightness, bands 240 px apart."""
    rows = np.arange(image.shape[0], dtype=np.float32)[:, None]
    gain = 1 + 0.12 * np.sin(2 * np.pi * (20.0 * index / APPLE_FPS + rows / 240.0))
    return np.clip(image.astype(np.float32) * gain, 0, 255).astype(np.uint8)


def _defocus(image, index, n):
    import cv2

    return cv2.GaussianBlur(image, (0, 0), 2.0)


def _noisy(image, index, n):
    rng = np.random.default_rng(index)
    return np.clip(image + rng.normal(0, 4.0, image.shape), 0, 255).astype(np.uint8)


def _tilted(image, index, n):
    import cv2

    h, w = image.shape
    turn = cv2.getRotationMatrix2D((w / 2, h / 2), 5.0, 1.0)  # a phone 5° off level
    return cv2.warpAffine(image, turn, (w, h), flags=cv2.INTER_CUBIC, borderMode=cv2.BORDER_REPLICATE)


def _cropped(image, index, n):
    return np.ascontiguousarray(image[:, 96:])  # the first swings leave the frame on the left


def _inverted(image, index, n):
    return 255 - image  # a light body before a dark backdrop


def _bar_in_front(image, index, n):
    out = image.copy()
    out[:, 296:308] = 40  # a dark post of the tank's frame between the camera and the swing
    return out


def _letterbox(image, index, n):
    return np.pad(image, ((60, 60), (0, 0)), constant_values=16)  # 640×360 padded into 640×480


def _timestamp(image, index, n):
    import cv2

    out = image.copy()
    text = f"2026-11-27 10:{index // 3600:02d}:{index // 60 % 60:02d}.{index % 60:02d}"  # burnt in, every frame
    cv2.putText(out, text, (12, 340), cv2.FONT_HERSHEY_SIMPLEX, 0.6, 255, 2, cv2.LINE_AA)
    return out


def _portrait(image, index, n):
    return np.ascontiguousarray(image[:, 186:390])  # a phone held upright: 204×360, the swing leaves both sides


def _fisheye(image, index, n):
    import cv2

    h, w = image.shape  # an action camera's barrel distortion, no calibration given (k1 = -0.25)
    camera = np.array([[w, 0, w / 2], [0, w, h / 2]], float)
    ys, xs = np.mgrid[0:h, 0:w].astype(np.float32)
    u, v = (xs - camera[0, 2]) / camera[0, 0], (ys - camera[1, 2]) / camera[1, 1]
    scale = 1 - 0.25 * (u * u + v * v)
    mx = (u / scale * camera[0, 0] + camera[0, 2]).astype(np.float32)
    my = (v / scale * camera[1, 1] + camera[1, 2]).astype(np.float32)
    return cv2.remap(image, mx, my, cv2.INTER_CUBIC, borderMode=cv2.BORDER_REPLICATE)


KNOCK_S, KNOCK_ROLL_DEG, KNOCK_SHIFT_PX = 10.0, 1.0, (3.0, -2.0)  # knocked_roll: the stand bumped at 10 s


def _knocked_roll(image, index, n, at_s=KNOCK_S, roll_deg=KNOCK_ROLL_DEG, shift_px=KNOCK_SHIFT_PX, every=1):
    """The camera's stand knocked at :data:`KNOCK_S`: the picture turned by :data:`KNOCK_ROLL_DEG` about its centre
    and moved by :data:`KNOCK_SHIFT_PX`, with a 7 Hz ring that settles in about 0.3 s (as a reviewer's variant);
    ``every``: the clip kept at every so many frames (``index`` counts those kept)."""
    import cv2

    after = index * every / APPLE_FPS - at_s
    if after < 0:
        return image
    ring = 1 - math.exp(-after / 0.08) * math.cos(2 * math.pi * 7.0 * after)
    h, w = image.shape
    turn = cv2.getRotationMatrix2D((w / 2, h / 2), roll_deg * ring, 1.0)
    turn[:, 2] += np.array(shift_px) * ring
    return cv2.warpAffine(image, turn, (w, h), flags=cv2.INTER_CUBIC, borderMode=cv2.BORDER_REPLICATE)


def _knocked_late(image, index, n):
    """The clip at 30 fps knocked 4.8 s before its end (at 14 s: turned −0.7°, moved (−3, 2) px; a reviewer's
    variant): two pairs of swing centres after the knock (docs/footage-notes.md)."""
    return _knocked_roll(image, index, n, at_s=14.0, roll_deg=-0.7, shift_px=(-3.0, 2.0), every=2)


def _arm(image, index, n):
    """Someone's arm reaching in at the bottom right and back (5–8 s; 40 px wide, grey 110, soft-edged), away from
    the swing."""
    import cv2

    t = index / APPLE_FPS
    if not 5.0 <= t <= 8.0:
        return image
    reach = math.sin(math.pi * (t - 5.0) / 3.0)
    tip = (int(640 - 200 * reach), int(360 - 60 * reach))
    cover = np.zeros(image.shape, np.float32)
    cv2.line(cover, (700, 420), tip, 1.0, 40, cv2.LINE_AA)
    cv2.circle(cover, tip, 24, 1.0, -1, cv2.LINE_AA)
    cover = cv2.GaussianBlur(cover, (0, 0), 2.0)
    return np.clip(image * (1 - cover) + 110.0 * cover, 0, 255).astype(np.uint8)


def _person_behind(frames: list) -> list:
    """Someone walking behind the swing, across the whole frame (10–11.5 s; a body 120 × 280 px and a head, grey
    110 on the wall, soft-edged): on the wall only, the apple before them."""
    import cv2

    wall = _wall(frames)

    def shade(k, apple):
        t = k / APPLE_FPS
        if not 10.0 <= t <= 11.5:
            return 1.0
        x = int(-100 + (t - 10.0) / 1.5 * 840)
        cover = np.zeros(wall.shape, np.float32)
        cv2.ellipse(cover, (x, 260), (60, 140), 0, 0, 360, 1.0, -1, cv2.LINE_AA)
        cv2.circle(cover, (x, 90), 40, 1.0, -1, cv2.LINE_AA)
        cover = cv2.GaussianBlur(cover, (0, 0), 2.0)
        return 1.0 - cover * (1.0 - 110.0 / np.maximum(wall, 1.0))

    return _on_the_wall(frames, shade)


def _wall(frames: list) -> np.ndarray:
    """The clip's median image: the wall without the apple."""
    return np.median(np.stack(frames[:: max(len(frames) // 60, 1)]), axis=0).astype(np.float32)


def _apple_share(image: np.ndarray, wall: np.ndarray) -> np.ndarray:
    """How much of each pixel is apple, 0–1: 1 inside the apple's outline (the pixels that differ from the wall
    by at least half the apple's contrast, the difference's 99.9th percentile, holes filled, less the outline's
    own pixels: its lighter cap is apple too), elsewhere the pixel's difference over that contrast (the edge
    pixels' coverage)."""
    import cv2

    difference = np.abs(image - wall)
    share = np.minimum(difference / max(np.percentile(difference, 99.9), 1.0), 1.0)  # difference ≥ 0
    outlines, _ = cv2.findContours((share >= 0.5).astype(np.uint8), cv2.RETR_EXTERNAL, cv2.CHAIN_APPROX_NONE)
    filled = np.zeros(share.shape, np.uint8)
    cv2.drawContours(filled, outlines, -1, 1, -1)
    share[cv2.erode(filled, np.ones((3, 3), np.uint8)) > 0] = 1.0
    return share


def _apples(frames: list, wall: np.ndarray, shares: list | None = None):
    """Per frame: the image, its share of apple (:func:`_apple_share`, or ``shares``' already measured), the pixel
    grid (xs, ys) and the centroid (cx, cy) of the pixels at least half apple, weighted by their share."""
    h, w = frames[0].shape
    ys, xs = np.mgrid[0:h, 0:w]
    for k, image in enumerate(frames):
        apple = _apple_share(image, wall) if shares is None else shares[k]
        solid = np.where(apple >= 0.5, apple, 0.0)
        yield image, apple, xs, ys, float((solid * xs).sum() / solid.sum()), float((solid * ys).sum() / solid.sum())


def _on_the_wall(frames: list, shade, shares: list | None = None) -> list:
    """``shade(index, apple) → gain`` applied to the wall only, composited as a camera would see it: a pixel
    that is a fraction ``f`` apple becomes ``image − (1 − f)·wall·(1 − gain)``, the wall being the clip's
    median image and ``f`` the pixel's share of apple (:func:`_apple_share`, or ``shares``' already measured)."""
    wall = _wall(frames)
    out = []
    for k, image in enumerate(frames):
        apple = _apple_share(image, wall) if shares is None else shares[k]
        shaded = image - (1.0 - apple) * wall * (1.0 - shade(k, apple))
        out.append(np.clip(np.round(shaded), 0, 255).astype(np.uint8))
    return out


def _band(shape, hard: bool = False) -> np.ndarray:
    """A soft dark band across the wall (a shelf's shadow: 45 % darker at its middle, σ 30 px, slanted) that
    the swing crosses: the gain per pixel. ``hard``: the shadow of a small lamp instead, 45 % darker over 70 px
    with edges 1.5 px wide, in the same place."""
    h, w = shape
    ys, xs = np.mgrid[0:h, 0:w]
    distance = (xs - 0.45 * w) + 0.35 * (ys - h / 2)
    if hard:
        return 1 - 0.45 / (1 + np.exp(-(35.0 - np.abs(distance)) / 0.75))
    return 1 - 0.45 * np.exp(-0.5 * (distance / 30.0) ** 2)


def _shadow_band(frames: list, shares: list | None = None, hard: bool = False) -> list:
    """:func:`_band` on the wall only (the apple in front of it stays lit)."""
    gain = _band(frames[0].shape, hard)
    return _on_the_wall(frames, lambda k, apple: gain, shares)


def _cast_shadow(frames: list) -> list:
    """The apple's own soft shadow on the wall beside it (a lamp to the upper left): up to 40 % darker, the
    apple's silhouette offset (+22, +14) px and blurred σ 8 px, moving with it."""
    import cv2

    def shade(k, apple):
        shifted = np.roll(np.roll((apple > 0.5).astype(np.float32), 14, axis=0), 22, axis=1)
        return 1 - 0.4 * cv2.GaussianBlur(shifted, (0, 0), 8.0)

    return _on_the_wall(frames, shade)


def _glossy(frames: list) -> list:
    """A shiny apple (a bauble): a lamp's highlight on it, a bright spot (σ 2.5 px, up to white) 7 px up and
    left of its centre in every frame, where the lamp's reflection stays while the apple swings."""
    out = []
    for image, apple, xs, ys, cx, cy in _apples(frames, _wall(frames)):
        apple[apple < 0.5] = 0.0
        spot = np.exp(-0.5 * ((xs - cx + 7) ** 2 + (ys - cy + 7) ** 2) / 2.5**2)
        out.append(np.clip(image + 200.0 * spot * apple, 0, 255).astype(np.uint8))
    return out


SEAM_TILT_DEG = 25.0  # the turning two-tone ball: its seam's plane tilted 25° from level ...
TURN_DEG, TURN_PERIOD_S = 150.0, 7.0  # ... and the ball turning to and fro on its string, ±150° every 7 s


def _grid(shape, scale: float):
    """Luma coordinates (x, y) of a grid ``scale`` times the luma's (the chroma's, 0.5, sited as H.264's default)."""
    h, w = shape
    return np.arange(w)[None, :] / scale, (np.arange(h)[:, None] + 0.5) / scale - 0.5


def _ball_share(shape, cx: float, cy: float, radius: float, scale: float = 1.0) -> np.ndarray:
    """A sphere's share of each pixel of a grid (:func:`_grid`): a disk of ``radius`` (luma px) at (cx, cy)."""
    columns, rows = _grid(shape, scale)
    return np.clip((radius - np.hypot(columns - cx, rows - cy)) * scale + 0.5, 0.0, 1.0)


def _top_share(k: int, body: np.ndarray, cx: float, cy: float, radius: float | None, scale: float = 1.0) -> np.ndarray:
    """The share of each pixel (:func:`_grid`) that is the two-tone ball's upper half: split at its centre's height
    (a 2 px soft seam), or, given the sphere's ``radius``, by its seam's plane through the centre, tilted
    :data:`SEAM_TILT_DEG` from level and turned about the string (the vertical) by φ = :data:`TURN_DEG` · sin(2π t /
    :data:`TURN_PERIOD_S`): a pixel (x, y) of the ball seen from the front, at (u, v, w) = ((x − cx) / r, (cy − y) /
    r, √(1 − u² − v²)), is upper where sin α cos φ · u + cos α · v + sin α sin φ · w > 0 (the seam seen as a
    tilted line that turns into an arc, the half in view from a third to two thirds of the ball)."""
    columns, rows = _grid(body.shape, scale)
    if radius is None:
        return np.clip((rows - cy) / -2.0 + 0.5, 0.0, 1.0) * body
    u, v = (columns - cx) / radius, (cy - rows) / radius
    depth = np.sqrt(np.clip(1.0 - u**2 - v**2, 0.0, 1.0))
    tilt = math.radians(SEAM_TILT_DEG)
    phi = math.radians(TURN_DEG) * math.sin(2 * math.pi * k / APPLE_FPS / TURN_PERIOD_S)
    side = math.sin(tilt) * math.cos(phi) * u + math.cos(tilt) * v + math.sin(tilt) * math.sin(phi) * depth
    return np.clip(side * radius / 2.0 + 0.5, 0.0, 1.0) * body  # a soft seam ~2 px wide on the ball's face


def _ball_radius(shares: list) -> float:
    """The turning ball's radius: the disk of the apple's area in the first frame (luma px)."""
    return math.sqrt(float((shares[0] >= 0.5).sum()) / math.pi)


def _two_tone(frames: list, behind: list | None = None, shares: list | None = None, turning: bool = False) -> list:
    """The apple as a two-tone ball: its upper half bright and patterned (the wall's grey +10 %, 6 px squares ±25
    grey levels), its lower half its own dark red; the halves split at its centre's height. Painted over
    ``behind`` (the same frames with the wall changed, e.g. a shadow band) when given, the ball's place and share
    of each pixel still taken from ``frames``, lit as before the change. ``turning``: a sphere instead (a disk of
    the apple's area at its centre, the apple painted out with the wall behind it, its lower half the apple's
    median dark red), whose seam is tilted and turns (:func:`_top_share`)."""
    wall = _wall(frames)
    lit = 1.1 * wall
    h, w = wall.shape
    columns, rows = np.arange(w)[None, :], np.arange(h)[:, None]  # the squares per row and column
    if turning:
        shares = shares if shares is not None else [_apple_share(image, wall) for image in frames]
        radius, backdrop = _ball_radius(shares), wall if behind is None else _wall(behind)
        dark = float(np.median(frames[0][shares[0] >= 0.99]))
    out = []
    for k, (image, apple, _, _, cx, cy) in enumerate(_apples(frames, wall, shares)):
        squares = 25.0 * np.where(((columns - cx) // 6 + (rows - cy) // 6) % 2 == 0, 1.0, -1.0)
        bright = np.minimum(lit + squares, 255.0)
        base = image if behind is None else behind[k]
        if turning:
            ball = _ball_share(wall.shape, cx, cy, radius)
            top = _top_share(k, ball, cx, cy, radius)
            clean = base * (1 - apple) + backdrop * apple
            out.append(np.clip(clean * (1 - ball) + bright * top + dark * (ball - top), 0, 255).astype(np.uint8))
            continue
        top = _top_share(k, apple, cx, cy, None)
        out.append(np.clip(base * (1 - top) + bright * top, 0, 255).astype(np.uint8))
    return out


_MEMO: dict = {}  # what variants share within one process (tests that share it run on one worker)


def _two_tone_before_band(
    frames: list, shares: list | None, last: int | None, hard: bool = False, turning: bool = False
) -> list:
    """The two-tone ball before the band (its luma, as the grey variants and the colour ones have it): made once
    per process from the clip's luma ``frames`` (its first ``last``), with ``shares`` of apple if measured."""
    key = ("two_tone_before_band", last, hard, turning)
    if key not in _MEMO:
        if shares is None:
            wall = _wall(frames)
            shares = [_apple_share(image, wall) for image in frames]  # measured once, for both
        _MEMO[key] = _two_tone(frames, _shadow_band(frames, shares, hard), shares, turning)
    return _MEMO[key]


HOLD_FRAMES = 90  # the hand_release variant: the apple held still for 1.5 s before it is let go
# the hand variants: (frames held, the hand's grey, its forearm's width in px): lighter than the apple and darker
# than the wall; for 10 s, and darker than the apple's lit side (a sleeve, a glove); fingers alone reaching in
# (a forearm 8 px wide: apple and fingers together are ~1.5 times the apple's area, not 2.5–4.4 times)
HANDS = {
    "hand_release": (HOLD_FRAMES, 150.0, 34),
    "hand_release_long_dark": (600, 90.0, 34),
    "hand_release_fingers": (HOLD_FRAMES, 150.0, 8),
}


def _hand_release(frames: list, hold: int = HOLD_FRAMES, level: float = 150.0, arm_px: int = 34) -> list:
    """The swing released by hand in view: for ``hold`` frames the apple is held at its place in the first
    frame (near the end of its swing) by a hand from the upper left, fingers over its edge (``level`` grey levels,
    a faint texture, soft edges; 150: skin lighter than the apple, darker than the wall; a forearm ``arm_px``
    wide), trembling by ±0.6 px; then let go (the clip from its first frame), the hand drawn back out of the frame
    over 0.4 s (25 frames)."""
    import cv2

    h, w = frames[0].shape
    rng = np.random.default_rng(23)
    texture = cv2.GaussianBlur(rng.normal(0, 6.0, (h, w)).astype(np.float32), (0, 0), 2.0)

    def hand(dx: float, dy: float) -> np.ndarray:
        """The hand's coverage 0–1: a forearm from beyond the top-left corner to fingers at the apple's upper left."""
        cover = np.zeros((h, w), np.float32)
        fingers = (int(round(62 + dx)), int(round(156 + dy)))
        cv2.ellipse(cover, fingers, (20, 12), 35, 0, 360, 1.0, -1, cv2.LINE_AA)
        cv2.line(cover, fingers, (int(round(-40 + dx)), int(round(20 + dy))), 1.0, arm_px, cv2.LINE_AA)
        return cv2.GaussianBlur(cover, (0, 0), 1.2)

    out = []
    for k in range(hold + len(frames)):
        if k < hold:
            image, (dx, dy) = frames[0], rng.uniform(-0.6, 0.6, 2)
        else:
            image, gone = frames[k - hold], (k - hold) / 25.0
            dx = dy = -160.0 * gone**1.5  # drawn back up and to the left, faster as it goes
            if gone > 1.0:
                out.append(image)
                continue
        cover = hand(dx, dy)
        out.append(np.clip(image * (1 - cover) + (level + texture) * cover, 0, 255).astype(np.uint8))
    return out


def _colour_planes(last: int | None = None) -> tuple[list, list, list]:
    """The clip's frames as they were filmed, in colour: their Y, U and V planes (4:2:0), uint8."""
    import av

    ys, us, vs = [], [], []
    with av.open(str(APPLE)) as container:
        for k, frame in enumerate(container.decode(video=0)):
            if last is not None and k >= last:
                break
            planes = frame.to_ndarray(format="yuv420p")
            h, w = frame.height, frame.width
            ys.append(planes[:h])
            us.append(planes[h : h + h // 4].reshape(h // 2, w // 2))
            vs.append(planes[h + h // 4 :].reshape(h // 2, w // 2))
    return ys, us, vs


def _in_colour(name: str, last: int | None = None) -> list:
    """A colour variant (``..._colour``, ``..._colour_1080p``, ``..._colour_550``), packed yuv420p for
    ``write_video(colour=True)``: its luma made as the grey variant's, its chroma composited with the same shares of
    apple (at chroma resolution). A shadow scales the wall's light, so its chroma's distance from grey (128) too:
    ``shadow_band_colour``; ``two_tone_shadow_band_colour`` (as the held-out clip: a bright patterned top, a dark
    blue bottom) paints the ball's lower half dark blue (U 165, V 117) and its top grey (U = V = 128), before the
    band. ``two_tone_hard_band_colour``: the same ball before a lamp's hard-edged shadow (:func:`_band`), bluish
    where daylight fills it (U +6, V −4 at its full depth)."""
    import cv2

    ys, us, vs = _colour_planes(last)
    if name.startswith("caustics"):
        return _caustics(ys, us, vs)
    shares = _clip_shares(ys, last)
    hard = "hard_band" in name
    gain = _band(ys[0].shape, hard)
    h, w = ys[0].shape
    small = (w // 2, h // 2)
    gain_c = cv2.resize(gain.astype(np.float32), small, interpolation=cv2.INTER_AREA)
    tints = [(1 - gain_c) / 0.45 * shift for shift in ((6.0, -4.0) if hard else (0.0, 0.0))]
    walls_c = [_wall(planes) for planes in (us, vs)]
    turning = "turning" in name
    radius = _ball_radius(shares) if turning else None  # the sphere's, in luma px
    if name.startswith("two_tone"):
        luma = _two_tone_before_band(ys, shares, last, hard, turning)
    else:
        luma = _shadow_band(ys, shares)
    out = []
    for k, image in enumerate(luma):
        apple = cv2.resize(shares[k].astype(np.float32), small, interpolation=cv2.INTER_AREA)
        if name.startswith("two_tone"):  # its centre from the luma's apple (rows halved, chroma sited)
            solid = np.where(shares[k] >= 0.5, shares[k], 0.0)
            cx = float((solid * np.arange(w)[None, :]).sum() / solid.sum())
            cy = float((solid * np.arange(h)[:, None]).sum() / solid.sum())
        chroma = []
        for plane, wall_c, paint, tint in zip((us[k], vs[k]), walls_c, (165.0, 117.0), tints, strict=True):
            shaded = plane - (1 - apple) * ((wall_c - 128) * (1 - gain_c) - tint)
            if name.startswith("two_tone"):
                body = apple
                if turning:  # the apple painted out (the banded wall's chroma), a sphere in its place
                    shaded = shaded * (1 - apple) + (wall_c - ((wall_c - 128) * (1 - gain_c) - tint)) * apple
                    body = _ball_share(apple.shape, cx, cy, radius, 0.5)
                top = _top_share(k, body, cx, cy, radius, 0.5)
                shaded = shaded * (1 - body) + 128.0 * top + paint * (body - top)
            chroma.append(np.clip(np.round(shaded), 0, 255).astype(np.uint8))
        if name.endswith("_1080p"):  # every plane 3× (the held-out clip's size)
            image, *chroma = (cv2.resize(p, None, fx=3, fy=3, interpolation=cv2.INTER_CUBIC) for p in (image, *chroma))
        if name.endswith("_550"):  # the held-out clip's other size, 550×310 (its chroma 275×155: odd rows)
            image = cv2.resize(image, (550, 310), interpolation=cv2.INTER_AREA)
            chroma = [cv2.resize(p, (275, 155), interpolation=cv2.INTER_AREA) for p in chroma]
        width = image.shape[1]
        out.append(np.concatenate([image.reshape(-1), chroma[0].reshape(-1), chroma[1].reshape(-1)]).reshape(-1, width))
    return out


def _clip_shares(ys: list, last: int | None) -> list:
    """The apple's share of each pixel in the clip's luma ``ys`` (its first ``last``), measured once per process."""
    key = ("shares", last)
    if key not in _MEMO:
        wall = _wall(ys)
        _MEMO[key] = [_apple_share(image, wall) for image in ys]
    return _MEMO[key]


def ball_centres(last: int | None = None) -> np.ndarray:
    """The truth of the turning ball's variants (``two_tone_turning_...``): its centre per frame (x, y in the
    clip's luma pixels), the apple's centroid it is drawn at (:func:`_apples`)."""
    ys = _colour_planes(last)[0]
    wall = _wall(ys)
    return np.array([(cx, cy) for *_, cx, cy in _apples(ys, wall, _clip_shares(ys, last))])


def _caustics(ys: list, us: list, vs: list, amp: float = 25.0, scale: float = 40.0, speed: float = 0.6) -> list:
    """The clip as filmed in a lit water tank (a reviewer's variant): a rippling net of bright wavy lines, 0 to
    ``amp`` grey levels of light on a surface of the wall's brightness, ``scale`` px apart, drifting ``speed`` px per
    frame and changing as the surface moves (three plane waves, warped, their zero set sharpened into ridges),
    falling on the wall and the apple alike: each pixel's light scaled by it, its chroma's distance from grey too.
    Packed yuv420p."""
    import cv2

    h, w = ys[0].shape
    yy, xx = np.mgrid[0:h, 0:w].astype(np.float32)
    rng = np.random.default_rng(0)
    angles = rng.uniform(0, np.pi, 3) + np.array([0.0, 2.1, 4.2])
    phases = rng.uniform(0, 2 * np.pi, 6)
    s = scale / (2 * np.pi)
    reference = float(np.median(ys[0])) - 16.0
    out = []
    for k, (y, u, v) in enumerate(zip(ys, us, vs, strict=True)):
        x_, y_ = xx - 0.48 * speed * k / 0.6, yy - 0.36 * speed * k / 0.6
        qx = x_ + 0.175 * scale * np.sin(y_ / (1.7 * s) + 0.135 * k + phases[0])
        qy = y_ + 0.175 * scale * np.cos(x_ / (1.9 * s) - 0.105 * k + phases[1])
        f = sum(
            np.sin((qx * np.cos(a) + qy * np.sin(a)) / s + phases[2 + i] + 0.05 * k * (i - 1))
            for i, a in enumerate(angles)
        )
        gain = 1 + amp * np.exp(-(f**2) / 0.12) / reference
        gain_c = cv2.resize(gain, (w // 2, h // 2), interpolation=cv2.INTER_AREA)
        planes = [16 + (y - 16.0) * gain, 128 + (u - 128.0) * gain_c, 128 + (v - 128.0) * gain_c]
        packed = [np.clip(np.round(p), 0, 255).astype(np.uint8).reshape(-1) for p in planes]
        out.append(np.concatenate(packed).reshape(-1, w))
    return out


def _rotate(code):
    import cv2

    return lambda image, index, n: cv2.rotate(image, code)


def variants():
    """name: (frame transform or None, keep every k-th frame, first frame kept, crf)."""
    import cv2

    return {
        "original": (None, 1, 0, 18),
        "half_size": (_resize(0.5), 1, 0, 18),
        "double_size": (_resize(2.0), 1, 0, 18),
        "1080p": (_resize(3.0), 1, 0, 18),
        "30fps": (None, 2, 0, 18),
        "15fps": (None, 4, 0, 18),
        "short_6s": (None, 1, 0, 18),
        "later_start": (None, 1, 200, 18),
        "sideways": (_rotate(cv2.ROTATE_90_CLOCKWISE), 1, 0, 18),
        "upside_down": (_rotate(cv2.ROTATE_180), 1, 0, 18),
        "tilted_5deg": (_tilted, 1, 0, 18),
        "knocked_roll": (_knocked_roll, 1, 0, 18),
        "knocked_roll_30fps_late": (_knocked_late, 2, 0, 18),
        "swing_leaves_the_frame": (_cropped, 1, 0, 18),
        "exposure_drift": (_drift, 1, 0, 18),
        "mains_flicker": (_flicker, 1, 0, 18),
        "defocus": (_defocus, 1, 0, 18),
        "low_bitrate": (None, 1, 0, 34),
        "dim_room_noise": (_noisy, 1, 0, 18),
        "dark_backdrop": (_inverted, 1, 0, 18),
        "post_in_front": (_bar_in_front, 1, 0, 18),
        "letterbox": (_letterbox, 1, 0, 18),
        "timestamp_overlay": (_timestamp, 1, 0, 18),
        "portrait_crop": (_portrait, 1, 0, 18),
        "fisheye": (_fisheye, 1, 0, 18),
        "shadow_band": (None, 1, 0, 18),
        "cast_shadow": (None, 1, 0, 18),
        "shadow_band_on_all": (None, 1, 0, 18),
        "glossy": (None, 1, 0, 18),
        "two_tone": (None, 1, 0, 18),
        "two_tone_shadow_band": (None, 1, 0, 18),
        "two_tone_shadow_band_1080p": (None, 1, 0, 18),
        "shadow_band_colour": (None, 1, 0, 18),
        "two_tone_shadow_band_colour": (None, 1, 0, 18),
        "two_tone_shadow_band_colour_1080p": (None, 1, 0, 18),
        "two_tone_shadow_band_colour_550": (None, 1, 0, 18),
        "two_tone_hard_band_colour": (None, 1, 0, 18),
        "two_tone_turning_shadow_band_colour": (None, 1, 0, 18),
        "two_tone_turning_shadow_band_colour_1080p": (None, 1, 0, 18),
        "two_tone_turning_shadow_band_colour_550": (None, 1, 0, 18),
        "caustics_colour": (None, 1, 0, 18),
        "hand_release": (None, 1, 0, 18),
        "hand_release_long_dark": (None, 1, 0, 18),
        "hand_release_fingers": (None, 1, 0, 18),
        "two_pendulums": (None, 1, 0, 18),
        "two_pendulums_start_px": (None, 1, 0, 18),
        "dot_on_bob": (None, 1, 0, 18),
        "arm_in_view": (_arm, 1, 0, 18),
        "person_behind": (None, 1, 0, 18),
        "two_pendulums_dots_start_px": (None, 1, 0, 18),
        "two_pendulums_close_dots_start_px": (None, 1, 0, 18),
    }


DOT_RADIUS_PX = 5.0  # the dot_on_bob variants: a sticker on the bob, 5 px in radius, 5 px below the apple's centre
DOT_GREY = 235.0


def _dotted(frames: list) -> tuple[list, np.ndarray]:
    """A white sticker on the bob (as the held-out clock pendulums have a dot on each): a soft-edged disk of
    :data:`DOT_RADIUS_PX` at 235 grey, fixed 5 px below the apple's centre (its pixels at least half apple, weighted
    by their share of apple), moving with it; on the dark apple before the light wall. The frames, and the apple's
    centre (x, y) in each."""
    out, centres = [], []
    for image, _, xs, ys, cx, cy in _apples(frames, _wall(frames)):
        cover = np.clip(DOT_RADIUS_PX + 0.5 - np.hypot(xs - cx, ys - cy - 5.0), 0.0, 1.0)
        out.append(np.clip(image * (1 - cover) + DOT_GREY * cover, 0, 255).astype(np.uint8))
        centres.append((cx, cy))
    return out, np.asarray(centres)


def _two_pendulums(frames: list) -> list:
    """Each frame beside the clip mirrored and played SECOND_SPEED× faster (nearest frames): two pendulums of
    different periods side by side, 1280 px wide."""
    n = int((len(frames) - 1) / SECOND_SPEED)
    return [np.hstack([frames[k], frames[int(round(k * SECOND_SPEED))][:, ::-1]]) for k in range(n)]


CLOSE_PX = 350  # two_pendulums_close_...: the second pendulum's frame this far right of the first's (not 640)


def _two_pendulums_close(frames: list, shares: list) -> list:
    """Two pendulums hung :data:`CLOSE_PX` apart, so that their bobs meet (touching, hardly overlapping) at the
    inner ends of both swings: the clip and the clip mirrored and played SECOND_SPEED× faster, the second's frame
    CLOSE_PX to the right of the first's, their walls cross-faded where they overlap and each apple pasted over
    both by its own ``shares`` (measured before any dot was painted on it)."""
    h, w = frames[0].shape
    wall = _wall(frames)
    ramp = np.clip((np.arange(w + CLOSE_PX) - CLOSE_PX) / (w - CLOSE_PX), 0, 1)[None, :]
    out = []
    for k in range(int((len(frames) - 1) / SECOND_SPEED)):
        k2 = int(round(k * SECOND_SPEED))
        left, left_share = frames[k].astype(np.float32), shares[k]
        right, right_share = frames[k2][:, ::-1].astype(np.float32), shares[k2][:, ::-1]
        walls = [left * (1 - left_share) + wall * left_share, right * (1 - right_share) + wall[:, ::-1] * right_share]
        behind = np.hstack([walls[0], walls[1][:, w - CLOSE_PX :]]) * (1 - ramp)
        behind += np.hstack([walls[0][:, :CLOSE_PX], walls[1]]) * ramp
        for image, share, x0 in ((left, left_share, 0), (right, right_share, CLOSE_PX)):
            part = behind[:, x0 : x0 + w]
            part += share * (image - part)
        out.append(np.clip(np.round(behind), 0, 255).astype(np.uint8))
    return out


def make(name: str, workdir: Path) -> Path:
    from pendulum.camera.video import iter_luma
    from pendulum.synthetic.experiment import write_video

    transform, every, first, crf = variants()[name]
    out = workdir / f"apple_{name}.mp4"
    if out.is_file():
        return out
    last = 360 if name == "short_6s" else None
    if "_colour" in name:
        write_video(_in_colour(name), out, APPLE_FPS, crf, "veryfast", colour=True)
        return out
    frames = [
        image.copy()
        for index, _, image in iter_luma(APPLE)
        if index >= first and (index - first) % every == 0 and (last is None or index < last)
    ]
    if transform is not None:
        frames = [transform(image, k, len(frames)) for k, image in enumerate(frames)]
    if name.startswith("two_pendulums_close"):
        wall = _wall(frames)
        shares = [_apple_share(image, wall) for image in frames]
    if "dot" in name:  # the apple's centre per frame beside the video (the left one's, where two are in view)
        frames, centres = _dotted(frames)
        np.savetxt(out.with_suffix(".csv"), centres, fmt="%.4f", delimiter=",", header="x_px,y_px", comments="")
    if name.startswith("two_pendulums_close"):
        frames = _two_pendulums_close(frames, shares)
    elif name.startswith("two_pendulums"):
        frames = _two_pendulums(frames)
    if name == "shadow_band":
        frames = _shadow_band(frames)
    if name == "cast_shadow":
        frames = _cast_shadow(frames)
    if name == "person_behind":
        frames = _person_behind(frames)
    if name == "shadow_band_on_all":  # the band falls on the apple too
        frames = [np.clip(image * _band(image.shape), 0, 255).astype(np.uint8) for image in frames]
    if name == "two_tone":
        frames = _two_tone(frames)
    if name.startswith("two_tone_shadow_band"):  # the band on the wall, the ball before it lit as outside it
        frames = _two_tone_before_band(frames, None, last)
    if name == "glossy":
        frames = _glossy(frames)
    if name in HANDS:
        frames = _hand_release(frames, *HANDS[name])
    if name.endswith("_1080p"):
        frames = [_resize(3.0)(image, k, len(frames)) for k, image in enumerate(frames)]
    write_video(frames, out, APPLE_FPS / every, crf, "veryfast")
    return out


def _against_the_original(name: str, method: str, table, workdir: Path) -> dict:
    """θ against the original clip's own record by the same ``method`` (the original's, by each method, kept in
    ``workdir`` when it is judged; judge it first: a string-hung apple turns, and its disk's centre and its
    silhouette's are not one point), frame by frame (a variant that keeps every k-th frame: its frame j against the
    clip's frame j k): ``theta_rms_deg``, the RMS of the difference less its median (the vertical each estimates),
    ``theta_worst_deg`` its largest size, ``theta_scale_pct`` the part of it proportional to θ (a pivot found at
    another distance along the arm), and ``timing_frames``: frames whose time differs from the original's by over
    a quarter of a frame period (the phone's lost and repeated frames judged otherwise); {} where fewer than 100
    frames match (a record that starts later, a hand's hold before it, the original not judged). Not part of
    ``pass``: a transformed clip's record is not the truth either, but it should not differ from the original's
    beyond their noise (a lens left uncalibrated does, by design)."""
    import pandas as pd

    keep = table.loc[table.flag == "ok", ["frame", "video_time_s", "theta_rad"]].dropna()
    reference = workdir / f"apple_original.{method}.angles.csv"
    if name == "original":
        keep.to_csv(reference, index=False)
    if not reference.is_file():
        return {}
    original = pd.read_csv(reference)
    _, every, first, _ = variants()[name]
    if first or name in HANDS:  # its times start elsewhere in the clip: no common clock
        return {}
    # frame j of the variant is the clip's frame j × every (the two pendulums': the left one is the clip's own)
    joined = keep.assign(frame=keep.frame * every).merge(original, on="frame", suffixes=("", "_original"))
    if len(joined) < 100:
        return {}
    difference = np.degrees(joined.theta_rad - joined.theta_rad_original).to_numpy(copy=True)
    difference -= float(np.median(difference))
    design = np.column_stack([np.degrees(joined.theta_rad_original.to_numpy()), np.ones(len(joined))])
    (scale, _), *_ = np.linalg.lstsq(design, difference, rcond=None)
    return {
        "theta_rms_deg": round(float(np.sqrt(np.mean(difference**2))), 4),
        "theta_worst_deg": round(float(np.abs(difference).max()), 4),
        "theta_scale_pct": round(100 * float(scale), 3),
        "timing_frames": int((np.abs(joined.video_time_s - joined.video_time_s_original) > 0.25 / APPLE_FPS).sum()),
    }


def judge(name: str, workdir: Path) -> dict:
    from test_real_footage import zero_crossing_period

    from pendulum.angles.geometry import estimate_rig_geometry
    from pendulum.angles.record import angles_from_track
    from pendulum.camera.video import VideoError
    from pendulum.tracking.method import track_trial
    from pendulum.tracking.path_shape import path_departure
    from pendulum.tracking.settings import TrackerSettings

    video = make(name, workdir)
    config = yaml.safe_load((ROOT / "config.yaml").read_text())["tracking"]
    if name == "two_pendulums_start_px":  # the user points at the left one (the original clip's apple)
        config = {**config, "start_px": list(APPLE_START_PX)}
    if name in ("two_pendulums_dots_start_px", "two_pendulums_close_dots_start_px"):  # ... at the left one's dot
        config = {**config, "start_px": [APPLE_START_PX[0], APPLE_START_PX[1] + 5.0]}
    settings = TrackerSettings.from_config(config)
    row = {"variant": name}
    try:
        track = track_trial(video, settings)
    except VideoError as error:
        # two pendulums in view and no start_px: a refusal that asks for it is the right answer; a swing out of
        # view most of the time (a phone held upright, 204 px wide): a refusal that says so
        right = (name == "two_pendulums" and "start_px" in str(error)) or (
            name == "portrait_crop" and "out of view" in str(error)
        )
        return {**row, "method": "refused", "ok%": 0.0, "pass": right, "error": str(error)[:300]}
    corrected, path = path_departure(track)
    geometry = estimate_rig_geometry({"v": corrected})
    table, info = angles_from_track(
        corrected,
        pivot_px=geometry["pivot_px"],
        vertical_deg=geometry["vertical_deg"],
        length_m=1.0,
        source=name,
        knock=(path.get("creep") or {}).get("knock"),
    )
    period = zero_crossing_period(table.time_s.to_numpy(float), table.theta_rad.to_numpy(float))
    row.update(
        method=track.attrs["method"]["used"],
        view=(track.attrs.get("body") or {}).get("view", "brightness"),
        # of the frames after the release (issue 23): all but the hand variants' held frames
        **{"ok%": round(100 * float((track.flag[HANDS.get(name, (0,))[0] :] == "ok").mean()), 2)},
        vertical_deg=round(float(geometry["vertical_deg"]), 2),
        vertical_estimated=geometry["vertical_source"].startswith("estimated"),
        edge_pct=round(100 * float((track.flag == "edge").mean()), 2),
        period_err_pct=round(100 * (period / APPLE_PERIOD_S - 1), 3),
        noise_deg=round(float(info.noise_deg), 4),
        knock_s=((path.get("creep") or {}).get("knock") or {}).get("time_s"),
        turn_deg=(info.camera_turn or {}).get("turn_deg") if (info.camera_turn or {}).get("taken_out") else None,
        **_against_the_original(name, track.attrs["method"]["used"], table, workdir),
    )
    # where the swing leaves the frame, the frames with the body partly out of view are flagged `edge`: the
    # rest (83 % of this clip) must be usable
    least = 80 if name == "swing_leaves_the_frame" else 95
    row["pass"] = row["ok%"] >= least and abs(row["period_err_pct"]) <= 0.3 and row["noise_deg"] <= 0.03
    if path.get("not_a_pendulum"):  # the tracks job refuses it: no angle record
        row["refused_by_path"], row["pass"] = True, False
    if name == "original":  # the reference by the other method too (variants differ in which one they take)
        other = "body" if row["method"] == "marker" else "marker"
        track = track_trial(video, TrackerSettings.from_config({**config, "method": other}))
        corrected, path = path_departure(track)
        geometry = estimate_rig_geometry({"v": corrected})
        table, _ = angles_from_track(
            corrected, pivot_px=geometry["pivot_px"], vertical_deg=geometry["vertical_deg"], length_m=1.0, source=name
        )
        _against_the_original(name, other, table, workdir)
    return row


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--workdir", type=Path, default=Path("/tmp/real_variants"))
    parser.add_argument("--only", nargs="*")
    args = parser.parse_args(argv)
    args.workdir.mkdir(parents=True, exist_ok=True)
    names = args.only or list(variants())
    rows = []
    for name in names:
        row = judge(name, args.workdir)
        rows.append(row)
        print(row, flush=True)
    failed = [r["variant"] for r in rows if not r.get("pass")]
    print(f"passed {len(rows) - len(failed)} of {len(rows)}" + (f"; failed: {', '.join(failed)}" if failed else ""))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
