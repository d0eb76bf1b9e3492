"""A sphere seen in part, measured by its outline's centre (pendulum.tracking.outline).

A two-tone ball whose coloured half alone stands out, its seam tilted from level and the ball turning on its string
(reviewers' imitations of a held-out clip), was measured by that half's centroid: 0.6° off, or refused as "not a
rigid pendulum" (its path 4 px RMS off any circle). The truths here are drawn analytically, sharing no code with
the tracker: a sphere's visible half bounded by a tilted great circle, and a pendulum's path.
"""

from __future__ import annotations

import math

import cv2
import numpy as np
import pandas as pd
import pytest

from pendulum.tracking.body_scene import soft_centroid
from pendulum.tracking.limb import LIMB_RAYS, edge_points
from pendulum.tracking.outline import centre_by_outline, outline_centres, sharper_outline
from pendulum.tracking.settings import TrackerSettings

RADIUS_PX = 20.0
TILT_DEG = 25.0


def _half_ball(cx: float, cy: float, phi_deg: float, size: int = 80) -> np.ndarray:
    """The lower half's share of each pixel (supersampled 4 × 4) of a sphere of :data:`RADIUS_PX` at (cx, cy), its
    seam a great circle tilted :data:`TILT_DEG` from level and turned by ``phi_deg`` about the vertical, as a colour
    view shows it (the half × 150, blurred by σ 0.8 px as a phone's chroma is)."""
    sub = (np.arange(size * 4) + 0.5) / 4
    u, v = (sub[None, :] - cx) / RADIUS_PX, (cy - sub[:, None]) / RADIUS_PX
    inside = u**2 + v**2 <= 1.0
    w = np.sqrt(np.clip(1 - u**2 - v**2, 0, 1))
    tilt, phi = math.radians(TILT_DEG), math.radians(phi_deg)
    upper = math.sin(tilt) * math.cos(phi) * u + math.cos(tilt) * v + math.sin(tilt) * math.sin(phi) * w > 0
    share = (inside & ~upper).reshape(size, 4, size, 4).mean(axis=(1, 3))
    return cv2.GaussianBlur((150.0 * share).astype(np.float32), (0, 0), 0.8)


def test_a_turning_two_tone_balls_centre_is_its_outlines_not_its_coloured_halfs():
    """60 frames, the ball turning through ±150° and moving by sub-pixel steps: its outline's centre within 0.05 px
    RMS of the truth (less a constant), where the coloured half's centroid is off by ≥ 2 px in some (the fault it
    mends)."""
    rng = np.random.default_rng(3)
    truths, points, centroids = [], [], []
    for k in range(60):
        cx, cy = 40.0 + rng.uniform(-1, 1), 40.0 + rng.uniform(-1, 1)
        diff = _half_ball(cx, cy, 150.0 * math.sin(2 * math.pi * k / 60))
        component = diff > 0.25 * diff.max()
        truths.append((cx - 0.5, cy - 0.5))  # pixel k spans [k, k + 1) in the drawing, centred on k in the tracker
        points.append(edge_points(diff, component))
        centroids.append(soft_centroid(diff, component)[:2])
    found = outline_centres(np.stack(points))
    truth = np.array(truths)
    error = found[:, :2] - truth
    assert (found[:, 3] >= LIMB_RAYS / 3).all(), found[:, 3]  # a half sphere shows half its limb
    # measured: 0.025 and 0.008 px RMS about a constant 0.07 px down (the seam's ends, tangent to the limb, pull the
    # radius in), which moves the body along its string: no angle
    assert np.sqrt(np.mean((error - error.mean(axis=0)) ** 2, axis=0)).max() <= 0.05, error
    assert np.hypot(*error.mean(axis=0)) <= 0.15, error.mean(axis=0)
    assert abs(np.median(found[:, 2]) - RADIUS_PX) <= 0.5  # its edge at half the contrast: the limb
    assert np.hypot(*(np.array(centroids) - truth).T).max() >= 2.0  # the half's centroid wanders


def _printed_ball(cx: float, cy: float, turn_deg: float, size: int = 120) -> np.ndarray:
    """I − B of a sphere of :data:`PRINT_RADIUS_PX` at (cx, cy) printed in squares a third of its radius on a side
    (cut by planes across and along the thread), dark (−150 grey levels) and light (+65, a print's white before a
    light grey wall), turned by ``turn_deg`` about the vertical, supersampled 4 × 4 and blurred by σ 0.8 px."""
    sub = (np.arange(size * 4) + 0.5) / 4
    u, v = (sub[None, :] - cx) / PRINT_RADIUS_PX, (sub[:, None] - cy) / PRINT_RADIUS_PX
    inside = u**2 + v**2 <= 1.0
    turn = math.radians(turn_deg)
    across = u * math.cos(turn) + np.sqrt(np.clip(1 - u**2 - v**2, 0, 1)) * math.sin(turn)
    dark = (np.floor(3 * across) + np.floor(3 * v)) % 2 == 0
    signed = np.where(inside, np.where(dark, -150.0, 65.0), 0.0)
    return cv2.GaussianBlur(signed.reshape(size, 4, size, 4).mean(axis=(1, 3)).astype(np.float32), (0, 0), 0.8)


PRINT_RADIUS_PX = 45.0


@pytest.mark.parametrize("polarity, least_wander_px", [("both", 0.25), ("dark", 0.5)])
def test_a_printed_balls_limb_is_found_at_each_sides_own_contrast(polarity, least_wander_px):
    """A ball printed in dark and light squares (as seeds 7010 and 7031 of the body study: its light squares brighter
    than the wall, its dark ones far darker), turning ±40° on its string, measured by both sides of the scene
    (``both``: 7010) or by its dark side alone (``dark``: 7031, its light squares left out of its silhouette). Where
    the limb runs along a light square, half the dark squares' contrast is never reached there (``both``) or the
    light square is not looked at (``dark``), and the outline was seen on too few rays in many frames, which kept
    a wandering centroid (7010 0.056°, 7031 0.054° off the truth). Each side's edge at half its own contrast: the
    limb on more than half the rays in every frame (29–36 of 96 at least before) and the centre within 0.15 px RMS
    of the truth (measured 0.10 px), where the silhouette's centroid wanders by 0.28 / 0.98 px."""
    rng = np.random.default_rng(5)
    truths, both, one, centroids = [], [], [], []
    for k in range(60):
        cx, cy = 60.0 + rng.uniform(-1, 1), 60.0 + rng.uniform(-1, 1)
        signed = _printed_ball(cx, cy, 40.0 * math.sin(2 * math.pi * k / 60))
        diff = np.abs(signed) if polarity == "both" else np.maximum(-signed, 0.0)
        closed = cv2.morphologyEx((diff > 20).astype(np.uint8), cv2.MORPH_CLOSE, np.ones((5, 5), np.uint8))
        _, labels, stats, _ = cv2.connectedComponentsWithStats(closed)
        component = labels == 1 + np.argmax(stats[1:, cv2.CC_STAT_AREA])
        truths.append((cx - 0.5, cy - 0.5))
        both.append(edge_points(diff, component, signed, polarity))
        one.append(edge_points(diff, component))
        centroids.append(soft_centroid(diff, component, 0.5)[:2])
    truth = np.array(truths)
    found, before = outline_centres(np.stack(both)), outline_centres(np.stack(one))
    assert found[:, 3].min() > LIMB_RAYS / 2 > before[:, 3].min(), (found[:, 3], before[:, 3])
    error = found[:, :2] - truth
    assert np.sqrt(np.mean(np.sum(error**2, axis=1))) <= 0.15, error
    assert abs(np.median(found[:, 2]) - PRINT_RADIUS_PX) <= 0.3
    wander = np.array(centroids) - truth
    assert np.sqrt(np.mean(np.sum((wander - wander.mean(axis=0)) ** 2, axis=1))) >= least_wander_px


def test_a_second_side_is_sought_only_where_the_body_has_one():
    """Where the scene's other side holds no strong part of the body, the edges are the same as without it (a uniform
    ball, a faint one in noise, either side measured); a bright print measured by its bright side keeps them too,
    its dark side not sought (its shadow beside it would be taken for its limb)."""
    rng = np.random.default_rng(9)
    sub = (np.arange(480) + 0.5) / 4
    for contrast, noise in ((120.0, 2.0), (12.0, 3.0)):  # a plain ball; a faint one whose other side is noise alone
        cover = ((sub[None, :] - 61.3) ** 2 + (sub[:, None] - 58.7) ** 2 <= 30.0**2).reshape(120, 4, 120, 4)
        for sign, polarity in ((-1.0, "dark"), (1.0, "bright"), (-1.0, "both")):
            blurred = cv2.GaussianBlur((sign * contrast * cover.mean(axis=(1, 3))).astype(np.float32), (0, 0), 0.8)
            signed = blurred + rng.normal(0, noise, (120, 120)).astype(np.float32)
            diff = np.abs(signed) if polarity == "both" else np.maximum(sign * signed, 0.0)
            component = diff > 0.4 * contrast
            assert np.array_equal(
                edge_points(diff, component, signed, polarity), edge_points(diff, component), equal_nan=True
            ), (contrast, polarity)
    signed = -_printed_ball(60.0, 60.0, 10.0)  # a bright print (its light squares +150, its dark ones −65) ...
    cover = ((sub[None, :] - 67.0) ** 2 + (sub[:, None] - 67.0) ** 2 <= PRINT_RADIUS_PX**2).reshape(120, 4, 120, 4)
    shadow = cv2.GaussianBlur(-60.0 * cover.mean(axis=(1, 3)).astype(np.float32), (0, 0), 2.0)
    signed = np.where(np.abs(signed) > 1.0, signed, shadow)  # ... its soft shadow 7 px down and right on the wall
    diff = np.maximum(signed, 0.0)
    closed = cv2.morphologyEx((diff > 20).astype(np.uint8), cv2.MORPH_CLOSE, np.ones((5, 5), np.uint8))
    _, labels, stats, _ = cv2.connectedComponentsWithStats(closed)
    component = labels == 1 + np.argmax(stats[1:, cv2.CC_STAT_AREA])
    assert np.array_equal(edge_points(diff, component, signed, "bright"), edge_points(diff, component), equal_nan=True)


def _track(
    wander_px: float,
    centroid_noise_px: float,
    outline_noise_px: float,
    unseen: int = 0,
    drift_px: float = 0.0,
    blurred_px: float = 0.0,
    offset_px: float = 0.0,
) -> pd.DataFrame:
    """A body swinging 0.3 rad on a 450 px arm for 20 s at 60 fps, its silhouette's centroid wandering by
    ``wander_px`` (a 7 s turn on its string) and drifting by ``drift_px`` over the clip (a slow turn, which a creep of
    the camera would explain), shifted to the right by ``blurred_px`` × (its speed / its greatest speed)² (a
    two-tone ball's faint half cut by the threshold where the motion blurs it) and by ``offset_px`` throughout,
    each centre with its own noise; the last ``unseen`` frames' outline shows too few rays."""
    rng = np.random.default_rng(11)
    t = np.arange(1200) / 60.0
    theta = 0.3 * np.cos(2 * np.pi * t / 1.9) * np.exp(-t / 60)
    x, y = 320 + 450 * np.sin(theta), -150 + 450 * np.cos(theta)
    turn = 2 * np.pi * t / 7.0
    speed = np.abs(np.gradient(theta, t))
    rays = np.full(t.size, 50.0)
    rays[t.size - unseen :] = 10.0
    return pd.DataFrame(
        {
            "frame": np.arange(t.size),
            "time_s": t,
            "x_px": x
            + wander_px * np.sin(turn)
            + drift_px * (t / t[-1]) ** 2
            + blurred_px * (speed / speed.max()) ** 2
            + offset_px
            + rng.normal(0, centroid_noise_px, t.size),
            "y_px": y + wander_px * np.cos(turn) + rng.normal(0, centroid_noise_px, t.size),
            "quality": 1.0,
            "signal_ratio": 1.0,
            "flag": "ok",
            "outline_x_px": x + rng.normal(0, outline_noise_px, t.size),
            "outline_y_px": y + rng.normal(0, outline_noise_px, t.size),
            "outline_r_px": 20.0,
            "outline_rays": rays,
        }
    )


@pytest.mark.parametrize(
    "wander_px, drift_px, centroid_noise_px, outline_noise_px, by, why",
    [
        (3.0, 0.0, 0.1, 0.08, "outline", "turns on its string"),  # a two-tone ball turning: its half's centroid
        # wanders
        (0.0, 2.0, 0.05, 0.05, "outline", "needs the camera to creep"),  # ... turning slowly: its half's centroid
        # passes for a creeping camera
        (0.25, 0.0, 0.13, 0.06, "outline", "the better pendulum"),  # a print's centroid: off its circle by only 1.3
        # times its noise, the outline's path half as far off and half as noisy: the better pendulum on both counts
        # (seed 7031), not said to be a ball turning on its string
        (0.0, 0.0, 0.03, 0.15, "silhouette", "no better pendulum"),  # an apple: its outline no circle, its centre
        # noisier
        (0.0, 0.0, 0.05, 0.05, "silhouette", "no better pendulum"),  # a uniform ball: the two agree
    ],
)
def test_the_outline_is_kept_only_where_its_path_is_the_better_pendulum(
    wander_px, drift_px, centroid_noise_px, outline_noise_px, by, why
):
    track = _track(wander_px, centroid_noise_px, outline_noise_px, unseen=30, drift_px=drift_px)
    out = centre_by_outline(track)
    facts = out.attrs["body"]["centre"]
    assert facts["by"] == by, facts
    assert (why is None and "why" not in facts) or why in facts["why"], facts
    if why == "the better pendulum":
        assert "turns on its string" not in facts["why"] and "its noise 0.0" in facts["why"], facts
    assert not any(c.startswith("outline_") for c in out.columns)
    if by == "outline":
        assert np.allclose(out.x_px[:-30], track.outline_x_px[:-30])
        assert (out.flag[-30:] == "occluded").all() and (out.flag[:-30] == "ok").all()
        if drift_px:  # the centroid's path explained by a creep the outline's does not need
            assert abs(facts["creep_px"]["silhouette"][0] - drift_px) <= 0.3, facts
            assert math.hypot(*facts["creep_px"]["outline"]) <= 0.5, facts
        else:
            assert facts["unexplained_rms_px"]["outline"] < 0.5 * facts["unexplained_rms_px"]["silhouette"]
    else:
        assert out.x_px.equals(track.x_px) and (out.flag == "ok").all()


@pytest.mark.parametrize(
    "blurred_px, offset_px, centroid_noise_px, outline_noise_px, by",
    [
        (1.0, 0.0, 0.03, 0.035, "outline"),  # body study scene 7227: 1 px mid-swing, the outline 1.05-1.2 × as noisy
        (1.0, 0.0, 0.03, 0.1, "silhouette"),  # an apple's outline: no circle, its centre three times as noisy
        (0.0, 1.0, 0.03, 0.03, "silhouette"),  # the two centres a constant 1 px apart: no bias of the swing
        (0.1, 0.0, 0.03, 0.03, "silhouette"),  # apart by less than three times their difference's noise
        (0.25, 0.0, 0.01, 0.01, "silhouette"),  # over three times it, but under 0.01° on the 450 px arm (0.08 px):
        # scene 7132, an apple of 49 px whose two centres wander apart by 0.07 px (noise 0.024 px), which the
        # outline's centre made 0.0028 → 0.0036° off the truth and 0.006 → 0.043° with the pivot fitted
    ],
)
def test_the_outline_is_kept_where_the_two_centres_move_apart_as_the_body_swings(
    blurred_px, offset_px, centroid_noise_px, outline_noise_px, by
):
    """Body study scene 7227 (a two-tone ball of 34 px, its bright half 57 grey levels off the wall, its dark half
    105, filmed at 30 fps with exposures of half a frame): where it moves fastest its faint half's blurred edge
    falls under the silhouette's threshold before the dark half's does, and the centroid sits up to 1 px toward
    its dark half (whichever way it moves); along the swing, so both centres' paths are circles within their noise
    (0.044 and 0.039 px RMS off, noise 0.056 and 0.059 px) and the centroid was kept: θ 0.035° RMS off the truth,
    0.0076° by the outline. Their difference wandering by over three times its noise (0.47 px, noise 0.085 px)
    says one of them moves on the body; a sphere's outline cannot, so it is kept where its path is no worse, it is
    no more than 1.25 times as noisy, and the wander moves θ by 0.01° or more. (At twice its noise, two colour
    variants of the real clip took their colour outline, 0.07 → 0.23° and 0.12 → 0.35° off the clip's record.)"""
    track = _track(0.0, centroid_noise_px, outline_noise_px, blurred_px=blurred_px, offset_px=offset_px)
    out = centre_by_outline(track)
    facts = out.attrs["body"]["centre"]
    assert facts["by"] == by, facts
    wander, noise = facts["apart_px"]["wander"], facts["apart_px"]["noise"]
    if by == "outline":
        assert "move apart" in facts["why"] and np.allclose(out.x_px, track.outline_x_px), facts
        # (v/v_max)² of a decaying swing wanders by about 0.3 px RMS; the difference's noise (2-D) is √2 × √(σ₁² + σ₂²)
        assert 0.2 <= wander <= 0.4 and 0.05 <= noise <= 0.08, facts
    else:
        assert out.x_px.equals(track.x_px), facts
    if offset_px:
        assert wander <= 0.05, facts  # a constant difference does not wander
    if centroid_noise_px < 0.02:
        assert 3 * noise < wander < 0.08, facts


def test_centres_apart_needs_both_paths_fitted_and_finite_frames():
    """A reviewer's edge cases: with too few usable frames for either path to be fitted (both off their circle by
    ``inf``) the two centres' wander does not choose the outline; a lost frame (NaN) or frames flagged every other
    one leave the wander measured on the rest, or not at all."""
    from pendulum.tracking.outline import centres_apart

    short = _track(0.0, 0.01, 0.01, blurred_px=1.0).iloc[:25]
    facts = centre_by_outline(short).attrs["body"]["centre"]
    assert facts["by"] == "silhouette" and "could not both be fitted" in facts["why"], facts
    track = _track(0.0, 0.05, 0.06, blurred_px=1.0)
    outline = track.assign(x_px=track.outline_x_px, y_px=track.outline_y_px)
    every = np.ones(len(track), bool)
    wander, noise = centres_apart(track, outline, every)
    track.loc[100, "x_px"] = np.nan
    assert centres_apart(track, outline, every) == pytest.approx((wander, noise), rel=0.02)
    assert centres_apart(track, outline, np.arange(len(track)) % 2 == 0) == (0.0, math.inf)


def test_frames_the_silhouette_flagged_are_usable_by_an_outline_seen_and_no_others():
    """A two-tone ball measured by its outline: where its light half stands out (a darker wall behind it) its silhouette
    grows and those frames were flagged ``occluded`` (seed 7149 of the body study: 79.6 % usable, all of it 100 % by the
    outline), or shrinks where its dark half is lost against a dark band (7411: 0.3 times its area, 40–70 of the 96 rays
    on its limb; 88 → 100 % usable). Usable again where the limb is seen (a third of the rays on its circle); not where
    most of it is hidden (a hand in front: fewer rays on the circle), nor where the outline's own centre jumps (alone,
    or a run of frames on another ball: a reviewer's case, whose usable neighbours the jump test flagged), nor off the
    path's circle by a pixel, nor still before the first usable frame (a hand may hold it)."""
    track = _track(3.0, 0.1, 0.08)
    track.loc[100:119, ["flag", "outline_rays"]] = ["occluded", 80.0]  # the light half standing out: a whole limb
    track.loc[140:149, ["flag", "outline_rays"]] = ["occluded", 30.0]  # a hand over most of it
    track.loc[200:209, ["flag", "outline_rays"]] = ["occluded", 40.0]  # the dark half lost: its limb seen in part
    track.loc[160, ["flag", "outline_rays"]] = ["jump", 80.0]
    track.loc[160, "outline_x_px"] += 6.0  # the outline's own centre jumps there
    track.loc[170:175, ["flag", "outline_rays"]] = ["held", 80.0]  # held in a hand: not the silhouette's doubt
    track.loc[0:4, ["flag", "outline_rays"]] = ["occluded", 80.0]  # still before its first usable frame: held?
    track.loc[300:319, ["flag", "outline_rays"]] = ["occluded", 80.0]  # a limb shifted 1 px off the path's circle
    outward = np.arctan2(track.outline_x_px[300:320] - 320.0, track.outline_y_px[300:320] + 150.0)
    track.loc[300:319, "outline_x_px"] += np.sin(outward)
    track.loc[300:319, "outline_y_px"] += np.cos(outward)
    track.loc[900:914, ["flag", "outline_rays"]] = ["occluded", 60.0]  # another ball's limb: a run 24 px away
    track.loc[900:914, "outline_x_px"] += 24.0
    out = centre_by_outline(track, TrackerSettings())
    facts = out.attrs["body"]["centre"]
    assert facts["by"] == "outline" and facts["limb_seen_frames"] == 30, facts
    assert "30 frames its silhouette flagged" in facts["why"], facts
    assert (out.flag[100:120] == "ok").all() and np.allclose(out.x_px[100:120], track.outline_x_px[100:120])
    assert (out.flag[200:210] == "ok").all()
    assert (out.flag[140:150] == "occluded").all() and out.flag[160] == "jump" and (out.flag[170:176] == "held").all()
    assert (out.flag[300:320] == "occluded").all() and (out.flag[900:915] == "occluded").all()
    assert (out.flag[:5] == "occluded").all() and (out.flag == "ok").sum() == len(track) - 10 - 1 - 6 - 5 - 20 - 15


def test_usable_frames_whose_limb_was_seen_in_part_are_kept_where_their_centre_keeps_to_the_path():
    """A printed ball measured by its outline: where its light squares meet the limb, fewer rays than a seen limb's
    third lie on its circle, and those frames were flagged ``occluded`` though the silhouette found them usable
    (seeds 7259, 7294, 7412, 7416 of the body study: 91–95 % usable, 99–100 % with them). A sixth of the rays or
    more on the circle and the centre on the path (a frame lost before them or not): usable. Fewer rays, a centre a
    pixel off the path's circle, or a run whose centre steps 3 px along the path: still flagged."""
    track = _track(3.0, 0.1, 0.08)
    track.loc[150, ["flag", "x_px", "y_px", "outline_x_px", "outline_y_px"]] = ["lost", np.nan, np.nan, np.nan, np.nan]
    track.loc[200:214, "outline_rays"] = 20.0  # a limb seen in part for a quarter of a second, its centre on the path
    track.loc[300:359, "outline_rays"] = 20.0  # ... for a second: too long to tell where the swing put it
    track.loc[400:409, "outline_rays"] = 12.0  # too little of it
    track.loc[500:519, "outline_rays"] = 20.0  # ... its centre a pixel off the path's circle
    outward = np.arctan2(track.outline_x_px[500:520] - 320.0, track.outline_y_px[500:520] + 150.0)
    track.loc[500:519, "outline_x_px"] += np.sin(outward)
    track.loc[500:519, "outline_y_px"] += np.cos(outward)
    track.loc[700:709, "outline_rays"] = 20.0  # ... its centre stepping 3 px along the path
    along = np.arctan2(track.outline_x_px[700:710] - 320.0, track.outline_y_px[700:710] + 150.0)
    track.loc[700:709, "outline_x_px"] += 3.0 * np.cos(along)
    track.loc[700:709, "outline_y_px"] -= 3.0 * np.sin(along)
    out = centre_by_outline(track, TrackerSettings())
    facts = out.attrs["body"]["centre"]
    assert facts["by"] == "outline" and facts["limb_in_part_frames"] == 15 and facts["limb_seen_frames"] == 0, facts
    assert "15 frames whose limb was seen in part are usable" in facts["why"], facts
    assert "100 frames whose outline was not seen (or seen in part off the swing) are flagged occluded" in facts["why"]
    assert (out.flag[200:215] == "ok").all() and np.allclose(out.x_px[200:215], track.outline_x_px[200:215])
    assert (out.flag[300:360] == "occluded").all()
    assert (out.flag[400:410] == "occluded").all() and (out.flag[500:520] == "occluded").all()
    assert (out.flag[700:710] == "occluded").all() and (out.flag == "ok").sum() == len(track) - 101  # and the lost


def _along(track: pd.DataFrame, rows: np.ndarray, shift_px) -> None:
    """``track``'s outline centres in ``rows`` moved along the swing (its path's tangent) by ``shift_px``."""
    at = np.arctan2(track.outline_x_px[rows] - 320.0, track.outline_y_px[rows] + 150.0)
    track.loc[rows, "outline_x_px"] += shift_px * np.cos(at)
    track.loc[rows, "outline_y_px"] -= shift_px * np.sin(at)


@pytest.mark.parametrize("flag, rays", [("ok", 20.0), ("occluded", 35.0)])
@pytest.mark.parametrize(
    "shape, size_px", [("bump", 1.0), ("bump", 3.0), ("bump", 10.0), ("drift", 0.1), ("drift", 0.3)]
)
def test_a_limb_seen_in_part_is_taken_back_only_where_the_swing_puts_it(flag, rays, shape, size_px):
    """A reviewer's cases: a run of frames whose circle something in front pulls along the swing, slowly (a bump that
    builds and recedes, or a drift into frames whose limb is lost), steps no pixel at a time and stays on the path's
    circle. Each frame taken back lies where a swing fitted to the usable frames on both sides puts it: within 0.5 px
    of its true place (the bound of a usable frame), the rest flagged; a run at the end of the clip (no usable frame
    after it) is not taken back."""
    track = _track(3.0, 0.1, 0.08)
    theta = 0.3 * np.cos(2 * np.pi * track.time_s / 1.9) * np.exp(-track.time_s / 60)  # _track's swing
    truth = np.column_stack([320 + 450 * np.sin(theta), -150 + 450 * np.cos(theta)])
    rows = np.arange(200, 214)
    track.loc[rows, ["flag", "outline_rays"]] = [flag, rays]
    step = np.arange(rows.size)
    _along(track, rows, size_px * np.sin(np.pi * (step + 0.5) / rows.size) ** 2 if shape == "bump" else size_px * step)
    if shape == "drift":
        track.loc[214:233, ["flag", "outline_rays"]] = [flag, 10.0]  # ... into frames whose limb is lost
    last = np.arange(len(track) - 6, len(track))
    track.loc[last, ["flag", "outline_rays"]] = [flag, rays]  # the clip's last frames, a step along the swing
    _along(track, last, 2.0)
    out = centre_by_outline(track, TrackerSettings())
    taken = (out.flag.to_numpy() == "ok") & (track.flag.to_numpy() != "ok") | (track.outline_rays.to_numpy() < 32)
    taken &= out.flag.to_numpy() == "ok"
    error = np.hypot(*(out[["x_px", "y_px"]].to_numpy() - truth).T)
    assert taken[rows].sum() < rows.size and error[taken].max(initial=0) <= 0.5, (taken[rows].sum(), error[taken])
    assert (out.flag[last] == "occluded").all()


def test_a_track_too_short_for_a_path_fit_keeps_its_centroid():
    """Under 30 usable frames neither path is fitted (their figures unknown): no evidence for the outline."""
    out = centre_by_outline(_track(0.25, 0.13, 0.06).iloc[:20])
    assert out.attrs["body"]["centre"]["by"] == "silhouette", out.attrs["body"]["centre"]
    assert "could not both be fitted" in out.attrs["body"]["centre"]["why"], out.attrs["body"]["centre"]


def _dotted_half_ball(cx: float, cy: float, phi_deg: float, size: int = 80) -> np.ndarray:
    """A colour view of a two-tone ball (:func:`_half_ball`) whose coloured half is faint (70 levels, a navy half's
    chroma) beside two bright printed dots on its other half (220 levels, 5 px in radius, 5 px inside its limb:
    dots' edges nearer the limb are taken for it, as before)."""
    yy, xx = np.mgrid[0:size, 0:size] + 0.5
    dots = sum(((xx - (cx + dx)) ** 2 + (yy - (cy - 7.0)) ** 2 <= 25.0).astype(np.float32) for dx in (-6.5, 6.5))
    return _half_ball(cx, cy, phi_deg, size) * (70.0 / 150.0) + cv2.GaussianBlur(220.0 * dots, (0, 0), 0.8)


def test_a_faint_half_beside_bright_prints_shows_its_limb_at_its_own_level():
    """The body's contrast is its prints' (220): its faint half (70) never reaches 0.8 of it and its limb was not
    found (a helper's two-tone ball in the colour view: 19 rays of 96 in the median frame); measured at half each
    ray's own level (``own_levels``, the colour view's), the limb is seen and its centre within 0.05 px RMS of the
    truth (less a constant)."""
    rng = np.random.default_rng(5)
    truths, own, body = [], [], []
    for k in range(40):
        cx, cy = 40.0 + rng.uniform(-1, 1), 40.0 + rng.uniform(-1, 1)
        diff = _dotted_half_ball(cx, cy, 150.0 * math.sin(2 * math.pi * k / 40))
        component = diff > 0.25 * 70.0
        assert np.percentile(diff[component], 90) > 180.0  # the prints set the body's contrast
        truths.append((cx - 0.5, cy - 0.5))
        own.append(edge_points(diff, component, own_levels=True))
        body.append(edge_points(diff, component))
    found, before = outline_centres(np.stack(own)), outline_centres(np.stack(body))
    assert (np.nan_to_num(before[:, 3]) < LIMB_RAYS / 4).all(), before[:, 3]  # the limb not seen without
    assert (found[:, 3] >= LIMB_RAYS / 3).all(), found[:, 3]
    error = found[:, :2] - np.array(truths)
    assert np.sqrt(np.mean((error - error.mean(axis=0)) ** 2, axis=0)).max() <= 0.05, error
    assert np.hypot(*error.mean(axis=0)) <= 0.15, error.mean(axis=0)
    assert abs(np.median(found[:, 2]) - RADIUS_PX) <= 0.5


@pytest.mark.parametrize(
    "colour_noise_px, brightness_noise_px, used",
    [(0.5, 0.05, "brightness"), (0.05, 0.5, "colour"), (0.3, 0.25, "colour")],  # the last: not nearer by half
)
def test_the_colour_tracks_outline_is_the_sharper_views(colour_noise_px, brightness_noise_px, used):
    """A colour track's outline (its chroma at half the luma's resolution) against the brightness track's of the same
    frames: the brightness view's where at most half as far off one circle, its centres in the track's outline
    columns; the colour view's otherwise."""
    colour = _track(3.0, 0.1, colour_noise_px)
    brightness = _track(3.0, 0.1, brightness_noise_px).sample(frac=1.0, random_state=1)  # matched by frame
    colour.attrs["body"] = {"view": "colour"}
    out = sharper_outline(colour, brightness)
    facts = out.attrs["body"]["outline_view"]
    assert facts["used"] == used, facts
    left = facts["unexplained_rms_px"]
    assert (left["brightness"] <= 0.5 * left["colour"]) == (used == "brightness"), left
    source = brightness.set_index("frame").loc[colour.frame] if used == "brightness" else colour
    assert np.array_equal(out.outline_x_px.to_numpy(), source.outline_x_px.to_numpy())
    assert out.x_px.equals(colour.x_px) and out.attrs["body"]["view"] == "colour"
    assert centre_by_outline(out).attrs["body"]["centre"]["by"] == "outline"


@pytest.mark.parametrize("faint_level, found", [(40.0, False), (70.0, True)])
def test_a_ray_is_measured_at_its_own_level_only_where_that_is_a_quarter_of_the_bodys_contrast(faint_level, found):
    """A bright disk (220 levels, 9 px) above a faint lower half-disk (20 px), as a print above a navy half: at 70
    levels the half's limb is found at its radius; at 40, under a quarter of the body's contrast, it is the view's
    noise, not a part of the body: no edge. (A ray that crosses the bright part first stops at its edge.)"""
    yy, xx = np.mgrid[0:80, 0:80] + 0.5
    r = np.hypot(xx - 40.0, yy - 40.0)
    bright = np.hypot(xx - 40.0, yy - 29.0) <= 9.0
    drawn = np.where(bright, 220.0, np.where((r <= 20.0) & (yy > 40.0), faint_level, 0.0))
    diff = cv2.GaussianBlur(drawn.astype(np.float32), (0, 0), 0.8)
    points = edge_points(diff, diff > 10.0, own_levels=True)
    down = np.arange(LIMB_RAYS)[(np.arange(LIMB_RAYS) > LIMB_RAYS * 60 / 360) & (np.arange(LIMB_RAYS) < LIMB_RAYS / 3)]
    radius = np.hypot(points[down, 0] - 39.5, points[down, 1] - 39.5)
    if found:
        assert np.abs(radius - 20.0).max() <= 0.3, radius
    else:
        assert np.isnan(radius).all(), radius


def _two_views(unseen_share: float, lost_share: float = 0.0) -> tuple[pd.DataFrame, pd.DataFrame]:
    """A colour track with a noisy outline (0.5 px) and the brightness track of the same frames with a sharp one
    (0.05 px), its limb not seen (10 rays) in ``unseen_share`` of the frames, and ``lost_share`` more: half lost by
    its silhouette, half with a circle 15 px off (another thing's: a shadow merged with it)."""
    colour, brightness = _track(3.0, 0.1, 0.5), _track(3.0, 0.1, 0.05)
    rng = np.random.default_rng(8)
    frames = rng.permutation(len(brightness))
    unseen = frames[: round(unseen_share * len(brightness))]
    lost = frames[len(unseen) : len(unseen) + round(lost_share * len(brightness))]
    brightness.loc[unseen, "outline_rays"] = 10.0
    brightness.loc[lost[::2], "flag"] = "lost"
    brightness.loc[lost[1::2], ["flag", "outline_rays"]] = ["occluded", 60.0]
    brightness.loc[lost[1::2], "outline_x_px"] += 15.0
    colour.attrs["body"] = {"view": "colour"}
    return colour, brightness


@pytest.mark.parametrize("unseen_share, lost_share, used", [(0.04, 0.0, "colour"), (0.01, 0.01, "brightness")])
def test_the_brightness_outline_is_taken_only_where_it_sees_all_but_a_fortieth(unseen_share, lost_share, used):
    """The brightness view's limb is sharper, but each frame in which it is not seen is flagged: over 2.5 % of the
    usable frames (a red ball whose brightness nearly matches a band of wall: 8 %), the colour view's is kept. A frame
    whose brightness silhouette was lost, or whose circle is off the colour silhouette, has no brightness outline."""
    colour, brightness = _two_views(unseen_share, lost_share)
    out = sharper_outline(colour, brightness)
    facts = out.attrs["body"]["outline_view"]
    assert facts["used"] == used, facts
    assert facts["usable_frames"] == len(colour)
    assert facts["seen_frames"]["brightness"] == len(colour) - round((unseen_share + lost_share) * len(colour))
    if used == "brightness":
        lost = (brightness.flag != "ok").to_numpy()
        assert out.outline_x_px[lost].isna().all() and out.outline_x_px[~lost].notna().all()
        kept = centre_by_outline(out)
        assert kept.attrs["body"]["centre"]["by"] == "outline", kept.attrs["body"]["centre"]
        unseen = (brightness.outline_rays < 24).to_numpy() | lost
        assert (kept.flag[unseen] == "occluded").all() and (kept.flag[~unseen] == "ok").all()
        assert "in the brightness view" in kept.attrs["body"]["centre"]["why"]
    else:
        assert facts["unexplained_rms_px"]["brightness"] is None and out.outline_x_px.equals(colour.outline_x_px)
