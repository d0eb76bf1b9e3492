"""Body tracking and the path's shape: known truth on small renders and exact tracks.

The seeded study of renders with real footage's faults is ``tests/benchmarks/body_study.py``; a
smaller draw of it runs here with a binomial pass rule (``test_body_study_*``).
"""

import math
import re
import sys
from dataclasses import replace
from pathlib import Path

import numpy as np
import pandas as pd
import pytest

from pendulum.tracking.path_shape import path_departure


def circle_track(times, theta, pivot=(320.0, -300.0), arm=500.0, creep=(0.0, 0.0), noise=0.03, seed=0):
    rng = np.random.default_rng(seed)
    span = times[-1] - times[0]
    px = pivot[0] + creep[0] * (times - times[0]) / span
    py = pivot[1] + creep[1] * (times - times[0]) / span
    return pd.DataFrame(
        {
            "frame": np.arange(times.size),
            "time_s": times,
            "x_px": px + arm * np.sin(theta) + rng.normal(0, noise, times.size),
            "y_px": py + arm * np.cos(theta) + rng.normal(0, noise, times.size),
            "flag": "ok",
        }
    )


TIMES = np.arange(0, 20, 1 / 30)
THETA = np.radians(20) * np.exp(-TIMES / 60) * np.cos(2 * math.pi * TIMES / 2.0)


def test_a_still_camera_is_not_corrected():
    track = circle_track(TIMES, THETA)
    out, doc = path_departure(track)
    assert not doc["corrected"] and not doc["departs"] and not doc["not_a_pendulum"]
    assert doc["circle_rms_px"] == pytest.approx(0.03, rel=0.3)
    np.testing.assert_array_equal(out.x_px, track.x_px)


@pytest.mark.parametrize("creep", [(8.0, -11.0), (-5.0, 0.0), (0.0, 4.0)])
def test_a_creeping_camera_is_measured_and_corrected(creep):
    track = circle_track(TIMES, THETA, creep=creep)
    out, doc = path_departure(track)
    assert doc["corrected"]
    found = doc["creep"]["start_to_end_px"]
    assert found[0] == pytest.approx(creep[0], abs=0.3) and found[1] == pytest.approx(creep[1], abs=0.3)
    assert doc["creep"]["rms_after_px"] < 0.05 and "knock" not in doc["creep"]
    # brought to the mid-clip camera: on one circle about the pivot's middle position
    mid = (320.0 + creep[0] / 2, -300.0 + creep[1] / 2)
    radius = np.hypot(out.x_px - mid[0], out.y_px - mid[1])
    assert np.std(radius) < 0.1
    assert "x_image_px" in out and np.allclose(out.x_image_px, track.x_px)


def test_a_creep_that_turns_back_is_corrected():
    """A phone that leans 8 px one way and comes back (no straight line helps, so the search stopped before trying
    a parabola: the apple clip's first 17 s, its creep's line 4.4 standard errors long, were left 2.4 px RMS off
    the circle, 0.24° carried into the angles; 2026-12-02)."""
    track = circle_track(TIMES, THETA)
    tau = (TIMES - TIMES[0]) / (TIMES[-1] - TIMES[0])
    bend = 4 * tau * (1 - tau)  # 0 at the ends, 1 mid-clip
    track["x_px"] += 8.0 * bend
    track["y_px"] -= 6.0 * bend
    out, doc = path_departure(track)
    assert doc["corrected"] and doc["creep"]["degree"] == 2, doc
    assert doc["creep"]["rms_after_px"] < 0.05 and doc["circle_rms_px"] > 1.0
    radius = np.hypot(out.x_px - 320.0 - 8.0, out.y_px + 300.0 + 6.0)  # the mid-clip camera's pivot
    assert np.std(radius) < 0.1


@pytest.mark.parametrize(
    "shift, creep", [((6.0, -3.0), (0.0, 0.0)), ((10.0, 4.0), (5.0, -4.0)), ((-3.0, 0.0), (0.0, 0.0))]
)
def test_a_knocked_camera_is_found_corrected_and_its_shaking_flagged(shift, creep):
    """The stand knocked at 9.5 s: the picture jumps by ``shift`` with a 7 Hz ring that settles in about 0.3 s
    (a reviewer's variant of the apple clip, where it left a 0.5–0.9° step in the record, and a polynomial creep
    spread it over the whole clip: θ up to 0.82° off; a knock with a roll is not this). The step's time, size
    and the frames of its shaking are found from the path (path_shape._knock), the positions brought to one
    camera, the shaking flagged ``jump``, and the break the timing check saw there is the knock's."""
    track = circle_track(TIMES, THETA, creep=creep)
    after = np.clip(TIMES - 9.5, 0, None)
    ring = np.where(TIMES >= 9.5, 1 - np.exp(-after / 0.08) * np.cos(2 * math.pi * 7.0 * after), 0.0)
    track["x_px"] += shift[0] * ring
    track["y_px"] += shift[1] * ring
    knock_frame = int(np.searchsorted(TIMES, 9.5))
    track.attrs["timing"] = {"unexplained": [knock_frame + 1, 400]}
    out, doc = path_departure(track)
    knock = doc["creep"]["knock"]
    assert abs(knock["time_s"] - 9.5) <= 2 / 30, knock
    assert np.hypot(knock["shift_px"][0] - shift[0], knock["shift_px"][1] - shift[1]) <= 0.3, knock
    flagged = out.time_s[out.flag == "jump"]
    assert flagged.min() <= 9.5 and flagged.max() >= 9.95 and flagged.max() <= 10.6 and len(flagged) <= 40
    ok = (out.flag == "ok").to_numpy()
    x, y = out.x_px.to_numpy()[ok], out.y_px.to_numpy()[ok]
    (c0, c1, _), *_ = np.linalg.lstsq(np.column_stack([x, y, np.ones_like(x)]), x**2 + y**2, rcond=None)
    assert np.std(np.hypot(x - c0 / 2, y - c1 / 2)) < 0.1  # one camera: one circle
    assert doc["creep"]["rms_after_px"] < 0.1
    assert out.attrs["timing"] == {"unexplained": [400], "knocked": [knock_frame + 1]}
    assert "jumped by" in doc["verdict"]


def _knocked(track: pd.DataFrame, roll_deg: float, shift) -> pd.DataFrame:
    """``track`` with its camera knocked at 9.5 s: the picture turned by ``roll_deg`` about its centre (320, 180)
    and moved by ``shift`` (px), with a 7 Hz ring settling in about 0.3 s."""
    after = np.clip(TIMES - 9.5, 0, None)
    ring = np.where(TIMES >= 9.5, 1 - np.exp(-after / 0.08) * np.cos(2 * math.pi * 7.0 * after), 0.0)
    turn = np.radians(roll_deg) * ring
    x, y = track.x_px - 320.0, track.y_px - 180.0
    track["x_px"] = 320.0 + np.cos(turn) * x - np.sin(turn) * y + shift[0] * ring
    track["y_px"] = 180.0 + np.sin(turn) * x + np.cos(turn) * y + shift[1] * ring
    track["quality"] = 1.0
    return track


def _knocked_with_a_turn(seed: int, roll_deg: float):
    """circle_track :func:`_knocked`, the shift drawn from ``seed`` (3–6 px across the swing, the way the turn moves
    the pivot: a step along the arm alone is not found as a knock)."""
    rng = np.random.default_rng(seed)
    shift = math.copysign(rng.uniform(3, 6), roll_deg or rng.choice([-1, 1])), rng.uniform(-2, 2)
    return _knocked(circle_track(TIMES, THETA, seed=seed), roll_deg, shift)


@pytest.mark.parametrize("roll_deg", [1.0, -0.4, 0.0])
def test_a_knocked_cameras_turn_is_measured_from_the_swings_centre_and_taken_out(roll_deg):
    """A knock that turns the picture as well as moving it (a reviewer's variant of the apple clip: θ kept a 0.9°
    step): the path brings the positions back for the move, but a turn about the lens's axis moves every point
    along its circle, so the path cannot show it. The swing's centre in the picture is gravity's direction there,
    which only a turning camera moves: measured on either side of the knock (swings.turn_at_knock) and taken out
    of θ after it. Ten noise draws each, at least 9 within 0.01° of the truth on both sides (without a turn: none
    taken out in at least 9, and θ as it was)."""
    from pendulum.angles.record import angles_from_track

    good = 0
    for seed in range(10):
        out, doc = path_departure(_knocked_with_a_turn(seed, roll_deg))
        knock = doc["creep"]["knock"]
        pivot = (320.0, -300.0)  # the picture's pivot before the knock: the positions are brought to that camera
        with_knock = dict(pivot_px=pivot, vertical_deg=0.0, length_m=1.0, source="s", knock=knock)
        table, info = angles_from_track(out, **with_knock)
        ok = (table.flag == "ok").to_numpy()
        error = np.degrees(table.theta_rad.to_numpy()[ok] - THETA[table.frame.to_numpy()[ok]])
        turn = info.camera_turn
        if roll_deg:
            good += (
                bool(turn["taken_out"] and abs(turn["turn_deg"] + roll_deg) <= 0.01 and np.abs(error).max() <= 0.02)
                and "taken out of θ" in info.notes[-1]
            )
        else:
            plain, _ = angles_from_track(out, **{**with_knock, "knock": None})
            good += not turn["taken_out"] and np.array_equal(plain.theta_rad, table.theta_rad, equal_nan=True)
    assert good >= 9, good


@pytest.mark.parametrize("roll_deg", [1.0, -0.6])
def test_a_knock_a_creep_took_in_is_found_where_the_swings_centre_steps(roll_deg):
    """A camera creeping 19 px over the clip on a string that stretches and relaxes by 0.6 px (the apple clip's own
    slow departure: it makes the path's residuals run together, so a knock's step is a few of its wide standard
    errors), knocked at 9.5 s: turned by ``roll_deg`` about the picture's centre and moved by (3, −2) px. The creep
    took the knock in (a reviewer's variant of the apple: θ 0.49° RMS off); the swing's centre in the picture steps
    there (path_shape._centre_step), the knock is sought where it stepped and the turn taken out. Six noise draws:
    at least 5 found that way, the turn within 0.05° and θ within 0.04° RMS of the truth; the same without the knock:
    none found in at least 11 of 12."""
    from pendulum.angles.record import angles_from_track

    def stretched(seed):
        rng = np.random.default_rng(seed)
        track = circle_track(TIMES, THETA, creep=(15.0, -12.0), seed=seed)
        stretch = 0.6 * np.sin(2 * np.pi * TIMES / 6.0 + rng.uniform(0, 2 * np.pi))
        track["x_px"] += stretch * np.sin(THETA)
        track["y_px"] += stretch * np.cos(THETA)
        track["quality"] = 1.0
        return track

    good = 0
    for seed in range(6):
        out, doc = path_departure(_knocked(stretched(seed), roll_deg, (3.0, -2.0)))
        knock = doc["creep"].get("knock") or {}
        mid = (327.5, -306.0)  # the pivot at mid-clip: the positions are brought to that camera
        table, info = angles_from_track(out, pivot_px=mid, vertical_deg=0.0, length_m=1.0, source="s", knock=knock)
        ok = (table.flag == "ok").to_numpy()
        error = np.degrees(table.theta_rad.to_numpy()[ok] - THETA[table.frame.to_numpy()[ok]])
        error -= np.median(error)
        good += bool(
            "centre_step" in knock
            and abs((info.camera_turn or {}).get("turn_deg", math.inf) + roll_deg) <= 0.05
            and np.sqrt(np.mean(error**2)) <= 0.04
        )
    assert good >= 5, good
    clean = sum("knock" not in path_departure(stretched(seed))[1]["creep"] for seed in range(12))
    assert clean >= 11, clean


def test_a_camera_set_down_after_the_recording_started_has_its_hand_held_frames_flagged():
    """The phone in the hand for the first 1.4 s (shaking ±6 px), then set down 30 px lower with a jolt (a
    reviewer's variant of the apple clip: those frames were ok and pulled the pivot 21 px, the whole record about
    0.6° off; now 0.05–0.08°): the knock's side before it is far off the circle, the frames to the end of the
    jolt are flagged, and the path is judged again without them."""
    track = circle_track(TIMES, THETA)
    hand = TIMES < 1.4
    track.loc[hand, "x_px"] += 6 * np.sin(2 * math.pi * 1.7 * TIMES[hand]) + 3 * np.sin(2 * math.pi * 4.3 * TIMES[hand])
    track.loc[hand, "y_px"] += -30 + 5 * np.sin(2 * math.pi * 2.3 * TIMES[hand] + 1.0)
    out, doc = path_departure(track)
    assert doc["handled"]["handled"] == "before", doc
    flagged = out.time_s[out.flag == "jump"]
    assert flagged.min() == 0 and 1.85 <= flagged.max() <= 2.0 and (out.flag[TIMES >= 2.0] == "ok").all()
    assert not doc["corrected"] and doc["circle_rms_px"] < 0.05  # the rest: one still camera
    assert "in the hand until it was set down" in doc["verdict"]


def test_a_knock_in_a_decaying_swing_is_no_camera_in_the_hand():
    """A reviewer's case: a swing decaying from 30° (τ 4 s) whose tracking noise grows with its speed, knocked at
    3 s. The side before the knock is farther off the circle only because it swung wider and faster, and was taken
    for a camera in the hand (its 90 frames flagged, the large swings of a damping record lost). A hand's shake is
    more than a pendulum's path allows (2 % of the swing, over 5 frames' means): the knock alone now, flagged from
    when it may have been (a step along the path shows where the path turns away from it) to 0.5 s after. A track
    without frame numbers is judged the same."""
    rng = np.random.default_rng(4)
    theta = np.radians(30) * np.exp(-TIMES / 4) * np.cos(2 * math.pi * TIMES / 2.0)
    noise = 0.05 + 0.5 * np.abs(np.gradient(theta, TIMES))
    track = circle_track(TIMES, theta, noise=0.0)
    track["x_px"] += rng.normal(0, 1, TIMES.size) * noise
    track["y_px"] += rng.normal(0, 1, TIMES.size) * noise
    after = np.clip(TIMES - 3.0, 0, None)
    ring = np.where(TIMES >= 3.0, 1 - np.exp(-after / 0.08) * np.cos(2 * math.pi * 7.0 * after), 0.0)
    track["x_px"] += 8.0 * ring
    track["y_px"] += 2.0 * ring
    out, doc = path_departure(track.drop(columns=["frame"]))
    knock = doc["creep"]["knock"]
    assert "handled" not in doc and abs(knock["time_s"] - 3.0) <= 0.5, doc  # a step along the path: seen where it turns
    flagged = out.time_s[out.flag == "jump"]
    assert flagged.min() <= 3.0 and flagged.max() >= 3.3 and len(flagged) <= 45, knock  # the ring (to ~3.3 s)


def test_a_wandering_object_is_not_a_pendulum():
    rng = np.random.default_rng(3)
    track = circle_track(TIMES, THETA)
    # a body that also wobbles across its path by a few px (a star spinning on its thread)
    track["y_px"] += 4.0 * np.sin(2 * math.pi * TIMES / 0.7) + rng.normal(0, 0.2, TIMES.size)
    _, doc = path_departure(track)
    assert doc["not_a_pendulum"]
    assert "not a rigid pendulum" in doc["verdict"]


def elliptical_track(ellipse, distance_px, creep=(8.0, -11.0), arm=500.0, pivot=(320.0, -300.0), centre=(320.0, 180.0)):
    """A spherical pendulum swinging 20° in the picture's plane and ``ellipse`` × that out of it a quarter period
    later, filmed by a pinhole camera ``distance_px`` from the pivot's plane (its focal length: scale 1 there),
    about the picture's ``centre``, the camera creeping by ``creep`` px (x as a line, y as a parabola)."""
    envelope = np.radians(20) * np.exp(-TIMES / 60)
    theta = envelope * np.cos(2 * math.pi * TIMES / 2.0)
    psi = ellipse * envelope * np.sin(2 * math.pi * TIMES / 2.0)
    x, y, z = arm * np.sin(theta) * np.cos(psi), arm * np.cos(theta) * np.cos(psi), arm * np.sin(psi)
    scale = distance_px / (distance_px - z)
    rng = np.random.default_rng(5)
    tau = TIMES / TIMES[-1]
    return pd.DataFrame(
        {
            "frame": np.arange(TIMES.size),
            "time_s": TIMES,
            "x_px": centre[0] + (pivot[0] + x - centre[0]) * scale + creep[0] * tau + rng.normal(0, 0.03, TIMES.size),
            "y_px": centre[1]
            + (pivot[1] + y - centre[1]) * scale
            + creep[1] * tau**2
            + rng.normal(0, 0.03, TIMES.size),
            "flag": "ok",
        }
    )


@pytest.mark.parametrize(("ellipse", "distance_px"), [(0.3, 600.0), (0.5, 600.0), (0.5, 1500.0)])
def test_an_elliptical_swing_with_a_creeping_camera_is_a_pendulum_seen_out_of_plane(ellipse, distance_px):
    """A swing out of the picture's plane (a bauble on a thread released with a sideways push) seen from near:
    the body nears the camera on one half swing and leaves it on the other, so the path moves and scales with the
    swing's speed; with a creeping camera no moving circle explains it (2.4–3.2 px RMS, over 2 % of the swing:
    refused as no pendulum before 2026-12-03). The circle whose centre and radius also follow the speed leaves
    about 1.2 px: a pendulum, its departure said, not refused. A body wobbling across its path at another rate
    (a star spinning on its thread) stays refused (test_a_wandering_object_is_not_a_pendulum)."""
    _, doc = path_departure(elliptical_track(ellipse, distance_px))
    assert not doc["not_a_pendulum"] and doc["departs"], doc
    assert doc["unexplained_rms_px"] > 0.02 * doc["swing_sd_px"]  # what the moving circle leaves
    assert doc["out_of_plane"]["rms_left_px"] < 0.5 * doc["unexplained_rms_px"]
    assert "an elliptical swing, out of the image plane" in doc["verdict"]


def test_a_bob_circling_its_pivot_is_no_pendulum_seen_out_of_plane():
    """A conical swing (the bob circling, as far out of the picture's plane as in it; a reviewer's case, kept as an
    elliptical swing at first): its picture's angle is not its angle from the vertical. Its path's departure, 4 %
    of the swing, is over what an elliptical swing is allowed (3.5 %): refused, as before."""
    _, doc = path_departure(elliptical_track(1.0, 750.0, creep=(0.0, 0.0)))
    assert doc["not_a_pendulum"] and "out_of_plane" not in doc, doc


def test_a_small_elliptical_swing_is_a_pendulum_with_its_creep_corrected():
    _, doc = path_departure(elliptical_track(0.15, 600.0))
    assert not doc["not_a_pendulum"] and "out_of_plane" not in doc
    dx, dy = doc["creep"]["start_to_end_px"]
    assert abs(dx - 8.0) < 0.6 and abs(dy + 11.0) < 0.6


def test_a_clean_swing_is_a_pendulum_even_when_small():
    theta = np.radians(2) * np.cos(2 * math.pi * TIMES / 2.0)  # 2°: 35 px of arc on a 500 px arm
    _, doc = path_departure(circle_track(TIMES, theta, noise=0.1))
    assert not doc["not_a_pendulum"]


# Small renders (640×360, a few seconds) with their truth


def small_trial(seed: int, **wall):
    from pendulum.synthetic.wall import random_wall_trial

    trial = random_wall_trial(seed)
    spec = replace(trial.spec, duration_s=5.0)
    return replace(trial, spec=spec, wall=replace(trial.wall, **wall))


@pytest.fixture(scope="module")
def render_dir(tmp_path_factory):
    return tmp_path_factory.mktemp("wall_renders")


def render(trial, directory):
    from pendulum.synthetic.wall import write_wall_trial

    video, truth = write_wall_trial(trial, directory, directory)
    return video, truth


def test_two_swinging_objects_need_start_px(render_dir):
    """Two bodies in view: without start_px a clear refusal; with it, the one pointed at is followed."""
    from pendulum.synthetic.experiment import write_video
    from pendulum.synthetic.wall import render_wall_trial
    from pendulum.tracking.body import BodyError, find_body

    left = small_trial(11, creep_px=(0.0, 0.0), shadows=(), band_depth=0.0)
    cam = left.spec.camera
    frames, truth = render_wall_trial(left)
    shifted = [np.roll(f, -int(cam.width_px * 0.3), axis=1) for f in frames]  # the same body a third over
    darker = left.body.level < left.wall.level
    frames2 = [np.minimum(a, b) if darker else np.maximum(a, b) for a, b in zip(frames, shifted, strict=True)]
    video = render_dir / "two.mp4"
    write_video(frames2, video, cam.fps, cam.crf, cam.preset)
    x0, y0 = truth.marker_x_px[0], truth.marker_y_px[0]
    x1, r = (x0 - int(cam.width_px * 0.3)) % cam.width_px, left.body.radius_px
    with pytest.raises(BodyError, match="start_px") as refusal:
        find_body(video)
    # where the two are is said as the first frame shows them (start_px's frame), not as a later sample does
    said = [tuple(map(float, xy)) for xy in re.findall(r"\((\d+), (\d+)\)", str(refusal.value).split("near")[-1])]
    assert "in the first frame" in str(refusal.value) and len(said) == 2, refusal.value
    assert sorted(math.hypot(x - x0, y - y0) < r / 2 or math.hypot(x - x1, y - y0) < r / 2 for x, y in said) == [
        True,
        True,
    ], (said, (x0, y0), (x1, y0))
    scene = find_body(video, start_px=(x0, y0))
    assert math.hypot(scene.start_px[0] - x0, scene.start_px[1] - y0) < r  # this body, not the other
    scene = find_body(video, start_px=(x1, y0 + 1.2 * r))  # the other, pointed at just below its edge
    assert math.hypot(scene.start_px[0] - x1, scene.start_px[1] - y0) < r
    # a start_px on neither (a point on the wall, or another frame's place): refused, never the nearest followed
    # (a reviewer's two apples: start_px on the wall between them was taken for the left one, silently)
    with pytest.raises(BodyError, match="is on no moving body in the first frame"):
        find_body(video, start_px=((x0 + x1) / 2, y0))


def test_a_start_px_is_taken_on_or_near_the_body_and_its_hull_and_refused_beyond():
    """start_px is checked against the first frame's body by its silhouette's convex hull (a ring's hole and a
    two-tone ball's half left out are the body's: a reviewer's ring of radius 30 px with a hole of 20, its centre
    refused when measured to the nearest silhouette pixel), within half the body's radius or 5 px."""
    import cv2

    from pendulum.tracking.body_parts import start_missed as missed_by_mask

    def start_missed(component, near):
        return missed_by_mask(component, cv2.convexHull(cv2.findNonZero(component.astype(np.uint8))), near)

    yy, xx = np.mgrid[0:200, 0:300]
    r = np.hypot(xx - 100, yy - 100)
    ring, disk, half = (r <= 30) & (r > 20), r <= 30, (r <= 30) & (yy >= 100)  # radii 30 px (disk: √area/π)
    assert start_missed(ring, (100, 100)) is None  # its hole
    # a two-tone ball whose light half the silhouette leaves out (its radius from the area then 21 px): its centre,
    # on the hull, and 8 px into the other half, within the slack, are it
    assert start_missed(half, (100, 100)) is None and start_missed(half, (100, 92)) is None
    assert start_missed(disk, (100 + 30 + 14, 100)) is None  # 14 px off its edge: under half its radius
    missed = start_missed(disk, (100 + 30 + 17, 100))
    assert missed is not None and "lies 17 px from it" in missed and "centred at (100, 100) px" in missed, missed
    assert "30 px in radius" in missed


def test_nothing_moving_is_refused(render_dir):
    from pendulum.synthetic.experiment import write_video
    from pendulum.tracking.body import BodyError, find_body

    still = [np.full((120, 160), 150, np.uint8) for _ in range(60)]
    video = render_dir / "still.mp4"
    write_video(still, video, 30.0, 20, "veryfast")
    with pytest.raises(BodyError, match="nothing moves"):
        find_body(video)


def _tank_clip(path, body: bool):
    """A tank filmed at its water surface (a tank lab's clip, imitated by a reviewer, 2026-12-07): air above, water
    below, the surface a bright wavy line of travelling waves across the frame; with ``body``, a dark ball (radius
    12 px) on a thread swinging ±20° about a pivot above the frame. Returns its first-frame centre."""
    import cv2

    from pendulum.synthetic.experiment import write_video

    fps, width, height = 30.0, 320, 180
    pivot, arm = np.array([160.0, -150.0]), 290.0
    xs = np.arange(width)
    frames = []
    for k in range(180):
        t = k / fps
        img = np.full((height, width), 120, np.uint8)
        line = 22 + 3 * np.sin(2 * np.pi * (xs / 40 - t / 0.7)) + 2 * np.sin(2 * np.pi * (xs / 23 + t / 1.1))
        img[np.arange(height)[:, None] < line[None, :]] = 200
        for dy in (-1, 0, 1):
            img[np.clip(np.round(line).astype(int) + dy, 0, height - 1), xs] = 235
        theta = math.radians(20.0) * math.exp(-0.05 * t) * math.cos(2 * math.pi * t / 2.0)
        centre = pivot + arm * np.array([math.sin(theta), math.cos(theta)])
        if body:
            cv2.line(img, tuple(int(v) for v in pivot), tuple(int(v) for v in centre), 150, 1, cv2.LINE_AA)
            cv2.circle(img, (int(round(centre[0] * 16)), int(round(centre[1] * 16))), 12 * 16, 50, -1, cv2.LINE_AA, 4)
        frames.append(img)
        if k == 0:
            first = centre
    write_video(frames, path, fps, 18, "veryfast")
    return first


def test_a_tanks_wavy_water_surface_is_set_aside_and_the_body_below_it_found(render_dir):
    """The wavy surface moves in every sample and is the heaviest moving object: the clip was refused ("no compact
    body … light the scene evenly", the reviewer's tank clips with a waterline and bubbles, and the apple in them
    followed within 0.03° once start_px was given). It spans the frame's width (or fills under 0.3 of its hull) and
    moves in place: set aside, the ball found (its centre within 1 px) and said in the body's facts. A clip where the
    surface alone moves is still refused."""
    from pendulum.camera.video import VideoError
    from pendulum.tracking.body import find_body

    first = _tank_clip(render_dir / "tank_surface.mp4", body=True)
    scene = find_body(render_dir / "tank_surface.mp4")
    assert math.dist(scene.start_px, first) <= 1.0, (scene.start_px, first)
    assert abs(scene.radius_px - 12) <= 1.5, scene.radius_px
    (aside,) = scene.to_dict()["set_aside"]
    assert aside["y_px"] < 30, aside  # the surface: across the frame's width (a reviewer's wavier one filled 0.23)
    _tank_clip(render_dir / "tank_surface_alone.mp4", body=False)
    with pytest.raises(VideoError, match=r"tank_surface_alone\.mp4: the only moving object .* moves in place"):
        find_body(render_dir / "tank_surface_alone.mp4")
    # a hoop-like body (an open frame seen by its edges, 26 % of its hull) swinging ±4°: it too moves in place in
    # most samples, and with it set aside its thread inside it was taken for the body (a reviewer's, θ 0.86° RMS
    # off the truth, nothing said); what lies within an object set aside is part of it: refused as before
    import cv2

    from pendulum.synthetic.experiment import write_video

    frames = []
    for k in range(180):
        theta = math.radians(4.0) * math.exp(-0.05 * k / 30) * math.cos(2 * math.pi * k / 60)
        img = np.full((180, 320), 120, np.uint8)
        img[::20, :] = 110
        centre = (160.0 + 290.0 * math.sin(theta), -150.0 + 290.0 * math.cos(theta))
        cv2.line(img, (160, -150), tuple(int(v) for v in centre), 150, 1, cv2.LINE_AA)
        cv2.circle(img, (int(round(centre[0] * 16)), int(round(centre[1] * 16))), 40 * 16, 50, 4, cv2.LINE_AA, 4)
        frames.append(img)
    write_video(frames, render_dir / "hoop.mp4", 30.0, 18, "veryfast")
    with pytest.raises(VideoError, match=r"hoop\.mp4: the heaviest moving object .* is no compact body"):
        find_body(render_dir / "hoop.mp4")


# The seeded study of renders (tests/benchmarks/body_study.py): scenes 7000–7007, drawn before any was
# looked at, 6 s each, config defaults (no hints).
STUDY_SEEDS = tuple(range(7000, 7008))


@pytest.mark.slow
def test_body_study_on_unseen_renders(tmp_path):
    """Bodies (apple, two-tone ball, printed pattern; radius 15–40 px at 640 px width) before walls with
    gradients, bands, soft shadows, exposure drift, defocus, camera creep, mid-swing starts: issue 23's figures.

    Binomial rules over n = 8: ≥ 95 % of the frames ``ok`` in at least 6, and angle RMS against the truth
    (true pivot) ≤ 0.02° (issue 23's acceptance) in at least 6. The held-out draws of 2026-12-06 and 2026-12-07
    (seeds 7116–7355, 240 scenes, 8 s) found ok ≥ 95 % in 229 and RMS ≤ 0.02° in 204 (85 %: apples and two-tone
    balls nearly all, prints about 55 %): at that rate this passes with a chance of ~89 %; a tracker within 0.02°
    in half the scenes passes with 14 %. Measured on these 6 s clips (2026-12-07): ok 100 % in 8, RMS ≤ 0.02° in
    8 (0.0023–0.0195°; the prints 7000 0.011°, 7003 0.016°, 7004 0.006°, 7007 0.0195°). Until 2026-12-07 the
    rule asked ≤ 0.05° (before 2026-11-27 7 and 6 passed, the prints 7003 at 0.11° and 7007 at 0.050° failing).
    And never a record that is silently wrong: every scene ends in a record or a clear refusal, none off by more
    than 0.5°.
    """
    sys_path = str(Path(__file__).resolve().parent / "benchmarks")
    if sys_path not in sys.path:
        sys.path.insert(0, sys_path)
    from body_study import judge

    rows = [judge(seed, tmp_path, duration_s=6.0) for seed in STUDY_SEEDS]
    summary = "\n".join(str({k: v for k, v in r.items() if k != "error"}) + f" {r.get('error', '')}" for r in rows)
    usable = sum(r["ok%"] >= 95 for r in rows)
    accurate = sum(r["rms"] <= 0.02 for r in rows if math.isfinite(r["rms"]))
    wrong = [r["seed"] for r in rows if math.isfinite(r["rms"]) and r["rms"] > 0.5]
    assert usable >= 6, summary
    assert accurate >= 6, summary
    assert not wrong, summary


def test_wall_render_puts_the_body_where_its_truth_says():
    """A uniform disk (no shading, shadows or thread) on a flat wall: its coverage centroid in each rendered
    frame (before compression) is the truth's exposure-mean centre, and the truth's angle is the physics'."""
    from pendulum.synthetic.experiment import true_angle_rad
    from pendulum.synthetic.wall import Wall, WallBody, render_wall_trial

    trial = small_trial(21)
    spec = replace(trial.spec, duration_s=0.5, camera=replace(trial.spec.camera, noise_sigma=0.0))
    wall = Wall(level=200.0, gradient=0.0, vignette=0.0, shadows=(), thread_depth=0.0, start_s=trial.wall.start_s)
    body = WallBody(look="apple", radius_px=18.0, level=60.0, texture=0.0)
    frames, truth = render_wall_trial(replace(trial, spec=spec, wall=wall, body=body))
    for frame, row in zip(frames[::5], truth.iloc[::5].itertuples(), strict=True):
        x0, y0 = int(row.marker_x_px) - 30, int(row.marker_y_px) - 30  # a window around the body
        window = frame[y0 : y0 + 61, x0 : x0 + 61].astype(float)
        cover = np.clip((np.median(window[0]) - window) / 140.0, 0, 1)  # the wall's grey from its top row
        cover[cover < 0.03] = 0.0  # paint unevenness (±1–2 grey) off the body
        yy, xx = np.mgrid[y0 : y0 + 61, x0 : x0 + 61]
        # pixel k centred on k, as the trackers measure (until 2026-12-05 the wall drew it over [k, k + 1): every
        # body half a pixel right of and below its truth)
        x, y = (cover * xx).sum() / cover.sum(), (cover * yy).sum() / cover.sum()
        assert math.hypot(x - row.marker_x_px, y - row.marker_y_px) < 0.1
    start = wall.start_s  # a mid-swing start: θ continues the swing from the release
    assert start > 0.5
    dense = true_angle_rad(spec, np.arange(0, start + 0.5, 1e-3))  # from the release on, finely
    expected = np.interp(truth.time_s + start, np.arange(0, start + 0.5, 1e-3), dense)
    np.testing.assert_allclose(truth.theta_rad, expected, atol=1e-6)


def test_wall_render_gives_every_frame_its_own_sensor_noise():
    """The wall's pixels away from the body differ between any two frames by the noise of two frames (√2 σ), also
    between frames 4 or 8 apart: the every-k-th frames a scene model takes (k a power of two) are not alike. A bank
    of 4 noise images, repeated, made them identical (0 grey levels apart) until 2026-12-05."""
    from pendulum.synthetic.wall import render_wall_trial

    trial = small_trial(21)
    sigma = 2.0
    spec = replace(trial.spec, duration_s=0.3, camera=replace(trial.spec.camera, noise_sigma=sigma))
    frames, truth = render_wall_trial(replace(trial, spec=spec))
    x = int(truth.marker_x_px.min()) - 200 if truth.marker_x_px.min() > 260 else int(truth.marker_x_px.max()) + 60
    corner = [f[:60, x : x + 60].astype(float) for f in frames]  # wall, above and beside the swing
    for a, b in ((0, 1), (0, 4), (0, 8), (4, 12), (1, 17)):
        spread = np.std(corner[a] - corner[b])
        assert 0.85 * math.sqrt(2) * sigma <= spread <= 1.15 * math.sqrt(2) * sigma, (a, b, spread)


def test_a_body_on_a_thick_rod_is_tracked_without_the_rod(render_dir):
    """A dark rod (16 px wide: more than the opening removes; as dark as the body) from a pivot above the
    frame, the body swinging 60 px below the frame's top: the rod leaves the frame, but whether the body is
    in view is judged on the body itself (within 1.2 inner radii of its thickest point): every frame is
    ``edge`` when the rod counts."""
    from pendulum.angles.record import angles_from_track
    from pendulum.synthetic.wall import Wall, WallBody
    from pendulum.tracking.method import track_trial
    from pendulum.tracking.settings import TrackerSettings

    trial = small_trial(31)
    body = WallBody(look="apple", radius_px=30.0, level=70.0)
    wall = Wall(thread_depth=110.0, thread_width_px=16, start_s=1.0, shadows=())
    cam = trial.spec.camera
    high = replace(cam, pivot_px=(cam.pivot_px[0], body.radius_px + 60 - cam.marker_arm_px))  # near the top
    trial = replace(trial, wall=wall, body=body, spec=replace(trial.spec, camera=high))
    video, truth = render(trial, render_dir)
    track = track_trial(video, TrackerSettings(method="body"))
    assert (track.flag == "ok").mean() >= 0.95, track.flag.value_counts().to_dict()
    cam = trial.spec.camera
    table, _ = angles_from_track(track, pivot_px=cam.pivot_px, vertical_deg=cam.roll_deg, length_m=1.0, source="r")
    joined = table.merge(truth[["frame", "theta_rad"]], on="frame", suffixes=("", "_true"))
    ok = joined.flag == "ok"
    error = np.degrees(joined.theta_rad[ok] - joined.theta_rad_true[ok])
    assert np.sqrt(np.mean((error - error.mean()) ** 2)) < 0.03


def test_a_silhouette_shrinking_mid_swing_is_a_scene_that_holds_the_body():
    """The covered area's ratio mid-swing over the ends: 1 for a body seen whole everywhere, ~0.6 when the
    scene holds the body at its rest place (only the part outside that ghost is seen mid-swing)."""
    from pendulum.tracking.body import MIN_MID_SWING_AREA_RATIO
    from pendulum.tracking.path_shape import rest_place_area_ratio

    track = circle_track(TIMES, THETA)
    track["quality"] = 1.0 + np.random.default_rng(1).normal(0, 0.01, TIMES.size)
    assert rest_place_area_ratio(track) == pytest.approx(1.0, abs=0.01)
    offset = np.abs(track.x_px - 320.0) / np.abs(track.x_px - 320.0).max()
    track["quality"] = 0.6 + 0.4 * offset  # the ghost takes 40 % of the body at its rest place
    assert rest_place_area_ratio(track) < 0.7 < MIN_MID_SWING_AREA_RATIO
    track.loc[20:, "flag"] = "lost"
    assert rest_place_area_ratio(track) is None  # too few frames to say


def test_a_body_darker_than_the_wall_is_measured_by_its_darkness_only():
    """A body darker than the scene in its samples (a dark apple; a two-tone ball whose light half is near the
    wall's grey) is one-sided: a part brighter than the wall behind it (that light half before a shadow band)
    then adds nothing to its silhouette. Light and dark parts of equal weight (a black-and-white print before a
    grey wall): both sides count, |I − B|."""
    from pendulum.tracking.body_scene import body_polarity, one_sided

    wall = np.full((40, 60), 150.0, np.float32)
    moving = np.zeros((3, 40, 60), bool)
    moving[:, 10:30, 20:40] = True

    def samples(dark_grey, light_grey):
        images = []
        for _ in range(3):
            image = wall.copy()
            image[10:20, 20:40] = light_grey  # the upper half
            image[20:30, 20:40] = dark_grey
            images.append(image)
        return images

    assert body_polarity(samples(60.0, 160.0), wall, moving, 4.0) == "dark"  # the light half: 10 above the wall
    assert body_polarity(samples(240.0, 140.0), wall, moving, 4.0) == "bright"
    assert body_polarity(samples(60.0, 240.0), wall, moving, 4.0) == "both"
    assert body_polarity(samples(150.0, 150.0), wall, moving, 4.0) == "both"  # nothing moved: no side
    signed = np.array([-30.0, -2.0, 0.0, 5.0, 40.0])
    assert one_sided(signed, "dark").tolist() == [30.0, 2.0, 0.0, 0.0, 0.0]
    assert one_sided(signed, "bright").tolist() == [0.0, 0.0, 0.0, 5.0, 40.0]
    assert one_sided(signed, "both").tolist() == [30.0, 2.0, 0.0, 5.0, 40.0]


# Two pendulums in view, the user pointing at one (tests/benchmarks/clock_study.py): scenes 9000–9005, drawn
# before any was looked at (developed on 8000–8011), 4 s each.
PAIR_SEEDS = tuple(range(9000, 9006))


@pytest.mark.slow
def test_two_clock_pendulums_each_followed_from_its_start_px(tmp_path):
    """Two rigid pendulums side by side (rods, round bobs with a dot at the centre, swinging ±1.2–3 bob radii,
    a dark case or a light wall), each tracked with config defaults and only start_px (the dot).

    Binomial rule over the n = 12 pendulums: ≥ 95 % of the frames ok and angle RMS against the truth ≤ 0.05° in
    at least 10. On scenes 8000–8011 (6 s) 23 of 24 had ok ≥ 95 % and all 24 RMS ≤ 0.043° (median 0.013°):
    at ~95 % this passes with a chance of ~98 %; a tracker failing 40 % of the pendulums passes with 8 %.
    None may be silently wrong: every pendulum ends in a record within 0.5° or a clear refusal."""
    sys_path = str(Path(__file__).resolve().parent / "benchmarks")
    if sys_path not in sys.path:
        sys.path.insert(0, sys_path)
    from clock_study import judge

    rows = [row for seed in PAIR_SEEDS for row in judge(seed, tmp_path, duration_s=4.0)]
    summary = "\n".join(str(r) for r in rows)
    good = sum(r["ok%"] >= 95 and r["rms"] <= 0.05 for r in rows)
    wrong = [(r["seed"], r["side"]) for r in rows if math.isfinite(r["rms"]) and r["rms"] > 0.5]
    assert good >= 10, summary
    assert not wrong, summary


def _narrow_swing(seed: int, swing_radii: float, directory, dot: bool = False):
    """The left pendulum of :func:`random_clock_pair` (a round bob on a rod, no dot unless ``dot``), its release
    set so the bob swings ``swing_radii`` of its radii each way."""
    from pendulum.synthetic.wall import random_clock_pair, write_wall_trial

    left, _ = random_clock_pair(seed, 4.0)
    cam, radius = left.spec.camera, left.body.radius_px
    release = math.degrees(math.asin(swing_radii * radius / cam.marker_arm_px))
    trial = replace(
        left,
        spec=replace(left.spec, release_deg=release, name=f"narrow_{seed}_{swing_radii:g}"),
        body=left.body if dot else replace(left.body, dot_radius_px=0.0),
    )
    video, truth = write_wall_trial(trial, directory, directory)
    return video, truth, cam


@pytest.mark.slow
@pytest.mark.parametrize("seed, swing_radii", [(9100, 1.4), (9101, 1.6), (9102, 2.5)])
def test_a_body_that_mostly_covers_its_own_place_is_tracked_with_the_scene_from_its_swing_ends(
    tmp_path, seed, swing_radii
):
    """A bob swinging 1.4–2.5 of its radii each way (a clock's few degrees) covers its rest place, or the ends of
    its swing, in most samples: the median scene holds it there and its silhouette shrinks (a first track 0.35–1.9°
    off on such renders). The scene is taken again from the two ends of the swing (up to twice) until the
    silhouette is as large mid-swing as at the ends: ≥ 95 % ok and ≤ 0.02° (measured 0.006–0.009° on scenes
    8100 and the clock study's)."""
    from pendulum.angles.record import angles_from_track
    from pendulum.tracking.body import track_body
    from pendulum.tracking.settings import TrackerSettings

    video, truth, cam = _narrow_swing(seed, swing_radii, tmp_path)
    track = track_body(video, TrackerSettings())
    assert 0.9 <= track.attrs["body"]["mid_swing_area_ratio"] <= 1 / 0.9
    table, _ = angles_from_track(track, pivot_px=cam.pivot_px, vertical_deg=cam.roll_deg, length_m=1.0, source="n")
    joined = table.merge(truth[["frame", "theta_rad"]], on="frame", suffixes=("", "_true"))
    ok = joined.flag == "ok"
    error = np.degrees(joined.theta_rad[ok] - joined.theta_rad_true[ok])
    assert ok.mean() >= 0.95
    assert np.sqrt(np.mean((error - error.mean()) ** 2)) <= 0.02, track.attrs["body"]


@pytest.mark.slow
@pytest.mark.parametrize("seed, swing_radii", [(9003, 1.9), (9124, 1.64)])
def test_no_ghost_of_the_body_stays_in_the_scene_beside_its_rest_place(tmp_path, seed, swing_radii):
    """A bob with a bright dot released from one end, swinging 1.6–1.9 of its radii: a place between its release
    end and the middle is covered in over half the samples, and the scene held a lens of the bob there (off the
    middle, where the rest-place check does not look). Each sample's moving object was left out where it
    differed from that scene, which the ghost's pixels do not (a bite or a hole in it), so the ghost stayed: the
    track 0.70° and 0.69° off, 81 % and 79 % of the frames ok (body forced; in the clock study, scene 9003's left
    pendulum was kept at 0.59° off). The objects are left out by their convex hulls now, and the pixels no
    sample shows clear are filled from their surroundings: 100 % ok, 0.0202° and 0.0143°. Scene 9124 is from a
    scan of 16 such scenes drawn after the fix was made (9110–9125, 1.6–2.2 radii): before 15 of 16 ≥ 95 % ok,
    after 16; none worse by more than 0.0003°, 9111 0.107° → 0.061°."""
    track, ok, rms = _narrow_record(*_narrow_swing(seed, swing_radii, tmp_path, dot=True))
    assert ok >= 0.95, track.attrs["body"]
    assert rms <= 0.03, track.attrs["body"]


@pytest.mark.slow
def test_a_swing_dying_to_rest_before_a_patterned_wall_is_tracked_to_its_rest(tmp_path):
    """An apple-like body released at 20° with strong linear damping (c = 0.12 N·m·s: 0.95° left after 10 s)
    before a patterned wall (12 grey levels SD): it is more than two radii from its rest place in only 30 % of
    the frames, so the median scene holds it there, and every wide sample shows a ghost at its rest place. The
    samples that show that place clear were left out with the ghost, and almost no sample showed it clear: a
    refusal ("the wall around it is not plain enough to fill it in") for a record that can be measured. The
    ghost is now found for what it is (:func:`pendulum.tracking.body_scene.scene_states`) and the scene there
    taken from the wide samples: 100 % ok, 0.0046° on the render this was developed on (scenes 7200–7203: three
    as before, this one refused before). Held out, scenes 7210–7225: 13 of 16 tracked before (3 refused so),
    16 of 16 after, all ≥ 99.67 % ok and ≤ 0.0172°."""
    from pendulum.synthetic.wall import random_wall_trial, write_wall_trial

    base = random_wall_trial(7201)
    spec = replace(
        base.spec,
        name="dying_7201",
        duration_s=10.0,
        hold_s=0.0,
        release_deg=20.0,
        truth={**base.spec.truth, "linear_damping_nm_s": 0.12},
        effects=["quadratic_drag", "linear_damping"],
    )
    trial = replace(
        base,
        spec=spec,
        body=replace(base.body, look="apple"),
        wall=replace(base.wall, grain=12.0, start_s=0.0, creep_px=(0.0, 0.0)),
    )
    track, ok, rms = _narrow_record(*write_wall_trial(trial, tmp_path, tmp_path), trial.spec.camera)
    assert ok >= 0.95, track.attrs["body"]
    assert rms <= 0.02, track.attrs["body"]


def _narrow_record(video, truth, cam):
    from pendulum.angles.record import angles_from_track
    from pendulum.tracking.body import track_body
    from pendulum.tracking.settings import TrackerSettings

    track = track_body(video, TrackerSettings())
    table, _ = angles_from_track(track, pivot_px=cam.pivot_px, vertical_deg=cam.roll_deg, length_m=1.0, source="n")
    joined = table.merge(truth[["frame", "theta_rad"]], on="frame", suffixes=("", "_true"))
    ok = joined.flag == "ok"
    error = np.degrees(joined.theta_rad[ok] - joined.theta_rad_true[ok])
    return track, float(ok.mean()), float(np.sqrt(np.mean((error - error.mean()) ** 2)))


@pytest.mark.slow
def test_a_body_that_never_leaves_its_place_before_a_plain_wall_is_tracked_with_the_scene_filled_in(tmp_path):
    """A bob swinging 0.8 of its radius each way overlaps itself at both ends: the scene behind its middle is in
    no sampled frame. Before a plain wall the surroundings fill it in (Navier–Stokes inpainting), and how well is
    checked where the scene is known (the same shape moved aside: 0.9 grey levels, the body's contrast 119): 100 %
    ok, 0.005° (it was refused: "usable in only 51 of 240 frames"; a clock's bob swings like this). The filled
    place is said in the body's facts."""
    track, ok, rms = _narrow_record(*_narrow_swing(9103, 0.8, tmp_path))
    (region,) = track.attrs["body"]["unseen_scene"]
    assert region["area_px"] >= 0.5 * math.pi * track.attrs["body"]["radius_px"] ** 2
    assert region["fill_error_grey"] <= 0.1 * track.attrs["body"]["contrast_grey"]
    assert "warning" not in track.attrs["body"]
    assert ok >= 0.95
    assert rms <= 0.02


@pytest.mark.slow
def test_a_small_bob_on_a_long_rod_is_the_body_not_a_thick_piece_of_its_rod(tmp_path):
    """A 14 px bob with a dot on a 213 px rod, swinging 0.72 of its radius (scene 9143 of the narrow swings
    developed on, tests/benchmarks/narrow_study.py): the first frame's moving object is the rod and the bob;
    after the opening that cuts the rod, the part nearest the object's centre (on the rod, which pulls it off
    the bob) was a thick piece of the rod, and that was followed: 0.105° off, 95 % ok, with a warning (refused
    before the scene was filled in). The part at the object's thickest point is the bob: 100 % ok, 0.0085°, no
    warning."""
    track, ok, rms = _narrow_record(*_narrow_swing(9143, 0.72, tmp_path, dot=True))
    assert track.attrs["body"]["radius_px"] >= 12.0  # the bob's 14 px, not the rod piece's 9.6
    assert "warning" not in track.attrs["body"]
    assert ok >= 0.95
    assert rms <= 0.02


@pytest.mark.slow
def test_a_body_that_never_leaves_its_place_before_a_patterned_wall_is_refused(tmp_path):
    """The same bob before a patterned wall (a fine grain of 16 grey levels SD): the scene behind its middle cannot
    be filled from its surroundings (a fill there 26 grey levels off, where checked, above the limit of 16: a fifth
    of the body's contrast as the grain lets it be measured): a clear refusal, never a biased record. Before the
    refusal such a record was kept, 0.79° off with 66 % of the frames ok. (A grain of 8 fills to within 12–13 grey
    levels, below the cut: four such held-out scenes of 0.8–1.3 radii tracked to 0.003–0.022°. A grain of 12 was
    refused while the renders repeated 4 noise images; with each frame's own noise its contrast measures 124 grey
    levels, its fill, 17 off, is within the limit of 25, and its record is 0.011° off, 100 % ok.)"""
    from pendulum.camera.video import VideoError
    from pendulum.synthetic.wall import random_clock_pair, write_wall_trial

    left, _ = random_clock_pair(9103, 4.0)
    cam, radius = left.spec.camera, left.body.radius_px
    release = math.degrees(math.asin(0.8 * radius / cam.marker_arm_px))
    trial = replace(
        left,
        spec=replace(left.spec, release_deg=release, name="grain_9103"),
        body=replace(left.body, dot_radius_px=0.0),
        wall=replace(left.wall, grain=16.0),
    )
    video, truth = write_wall_trial(trial, tmp_path, tmp_path)
    with pytest.raises(
        VideoError, match=r"grain_9103\.mp4: the scene behind .* not plain enough .* grey levels off, above"
    ):
        _narrow_record(video, truth, cam)


@pytest.mark.slow
@pytest.mark.parametrize("seed", [9202, 9207])
def test_a_shiny_balls_highlight_is_not_taken_for_a_marker(tmp_path, seed):
    """A dark glossy ball (a bauble) lit by a lamp 250 px in front of the wall: its specular highlight is the
    brightest, most disk-like swinging spot, but it moves against the ball (less than the ball's centre, as
    the lamp's direction turns). Taken for the marker it gave a record 0.54° off with a −3.3 % slope and 97 %
    of the frames ok (scene 5003). Detection sees it move against the ball and takes the ball: ≤ 0.05° (0.011–
    0.018° measured on scenes 5003 and 5006). Of held-out scenes 9200–9207 so lit, detection took the highlight
    in 4 (9202, 9203, 9206, 9207: these two are run here) without this check, and the ball in all 8 with it."""
    from pendulum.angles.record import angles_from_track
    from pendulum.synthetic.wall import random_wall_trial, write_wall_trial
    from pendulum.tracking.method import track_trial

    sys_path = str(Path(__file__).resolve().parent / "benchmarks")
    if sys_path not in sys.path:
        sys.path.insert(0, sys_path)
    from body_study import default_settings

    trial = random_wall_trial(seed)
    cam = trial.spec.camera
    body = replace(trial.body, look="apple", level=70.0, texture=10.0, spin_deg_per_s=0.0, gloss=180.0)
    body = replace(body, lamp_px=(0.5 * cam.width_px, 0.0, 250.0 * cam.width_px / 640))
    wall = replace(trial.wall, creep_px=(0.0, 0.0))
    trial = replace(trial, body=body, wall=wall, spec=replace(trial.spec, duration_s=4.0, name=f"shiny_{seed}"))
    video, truth = write_wall_trial(trial, tmp_path, tmp_path)
    track = track_trial(video, default_settings())
    radius = (track.attrs.get("marker") or {}).get("marker_radius_px")
    assert track.attrs["method"]["used"] == "body" or radius > 0.5 * body.radius_px, track.attrs["method"]
    table, _ = angles_from_track(track, pivot_px=cam.pivot_px, vertical_deg=cam.roll_deg, length_m=1.0, source="s")
    joined = table.merge(truth[["frame", "theta_rad"]], on="frame", suffixes=("", "_true"))
    ok = joined.flag == "ok"
    error = np.degrees(joined.theta_rad[ok] - joined.theta_rad_true[ok])
    assert ok.mean() >= 0.95
    assert np.sqrt(np.mean((error - error.mean()) ** 2)) <= 0.05


def test_a_fill_of_the_unseen_scene_is_checked_where_the_scene_is_known():
    """unseen_regions moves a hidden region's shape aside by its own size and compares a fill there with the known
    scene: a plain wall exactly, a gradient of 0.2 grey levels per px to within 2.5, a patterned wall (12 grey
    levels SD, 4 px grain) no better than about its SD; a region whose every moved copy leaves the frame cannot
    be checked (NaN), nor one whose every copy lands on other hidden pixels, and unseen_behind refuses it; hidden
    pixels the body's path never covers are not its concern."""
    import cv2

    from pendulum.tracking.body_scene import unseen_behind, unseen_regions
    from pendulum.tracking.scene_stack import fill

    yy, xx = np.mgrid[0:200, 0:300].astype(np.float32)
    smooth = 100 + 0.2 * xx + 0.1 * yy
    grain = cv2.resize(np.random.default_rng(3).standard_normal((52, 77)).astype(np.float32), (300, 200))
    patterned = smooth + 12 * grain / grain.std()
    hidden = np.zeros((200, 300), bool)
    cv2.circle(hidden.view(np.uint8), (150, 100), 20, 1, -1)
    ((x, y, area, smooth_error),) = unseen_regions(smooth, hidden, hidden)
    ((_, _, _, patterned_error),) = unseen_regions(patterned, hidden, hidden)
    assert (round(x), round(y)) == (150, 100) and area == int(hidden.sum())
    assert smooth_error <= 2.5  # measured 1.71 (Navier–Stokes inpainting bends a 0.2 grey/px gradient a little)
    assert patterned_error >= 8.0  # measured 20.5
    assert np.abs(fill(smooth, hidden)[hidden] - smooth[hidden]).max() <= 3.5  # measured 2.84
    plain = np.full((200, 300), 87.0, np.float32)
    assert np.abs(fill(plain, hidden)[hidden] - 87.0).max() <= 0.01
    wide = np.zeros((200, 300), bool)
    wide[60:140, 20:280] = True  # no moved copy fits left, right, up or down
    ((_, _, _, unchecked),) = unseen_regions(smooth, wide, wide)
    assert math.isnan(unchecked)
    path = np.array([[150.0, 100.0], [140.0, 98.0]])
    band = np.zeros((200, 300), bool)
    band[:, 50:250] = True  # the body's place inside a hidden band: every moved copy lands on hidden pixels
    facts, reason = unseen_behind(smooth, band, path, 20.0, 3.0)
    assert math.isnan(facts[0]["fill_error_grey"]) and "no place nearby" in reason
    facts, reason = unseen_behind(patterned, hidden, path, 20.0, 3.0)
    assert facts[0]["fill_error_grey"] >= 8.0 and "not plain enough" in reason
    assert unseen_behind(smooth, hidden, path, 20.0, 3.0) == (
        [{"at_px": [150.0, 100.0], "area_px": area, "fill_error_grey": round(smooth_error, 2)}],
        None,
    )
    assert unseen_behind(patterned, hidden, np.array([[40.0, 40.0]]), 20.0, 3.0) == ([], None)


def _resting_samples(at_rest: int, n: int = 40, held: bool = False, spacing: float = 2.3, passer: bool = False):
    """n samples of a patterned wall (12 grey levels SD), a dark disk (radius 9, grey 60) on a swinging arc in
    the first n − at_rest (``spacing`` px apart from one sample to the next: at 1.2 it overlaps itself in many, as
    at its turning points) and at rest at (80, 60) in the last ``at_rest``; ``held``: at rest in the first instead,
    as a hand holds a body before its release; ``passer``: a bright object (grey 235) crossing samples 20–29."""
    import cv2

    rng = np.random.default_rng(5)
    grain = cv2.resize(rng.standard_normal((32, 42)).astype(np.float32), (160, 120))
    wall = 150 + 12 * grain / grain.std()
    images = []
    for k in range(n):
        resting = k < at_rest if held else k >= n - at_rest
        x = 80.0 if resting else 80 + (25 + spacing * k) * (-1) ** k
        image = wall + rng.normal(0, 1.0, wall.shape)
        disk = np.zeros(wall.shape, np.uint8)
        cv2.circle(disk, (int(round(x)), 60), 9, 1, -1)
        image = np.where(disk > 0, 60.0, image)
        if passer and 20 <= k < 30:
            x0, y0 = 5 + 4 * (k - 20), 90 - 2 * (k - 20)
            image[y0 : y0 + 14, x0 : x0 + 24] = 235.0
        images.append(np.clip(image, 0, 255).astype(np.uint8))
    return wall, images


def test_a_body_at_rest_over_half_the_clip_leaves_no_ghost_in_the_scene():
    """A body that swings wide in 15 of 40 samples and rests at one place in the other 25 is the median scene
    there, and each wide sample shows a second "moving" object at its rest place: the wall, lighter than the
    scene where the body beside it is darker. Before a wall calendar the ghost was heavier than the apple and
    was followed (a swing dying to rest: 190 of its ok frames 20–127 px off). scene_states finds it (it recurs in
    the wide samples, the body does not) and the scene there is the wide samples' median: the wall to within the
    noise. A body held still in the first 15 samples (before its release) is the only object in them: the
    scene stays the median."""
    from pendulum.tracking.body_scene import scene_states
    from pendulum.tracking.scene_stack import masked_median, median_scene

    wall, images = _resting_samples(25)
    stack = np.stack(images)
    median = median_scene(stack)
    rest = np.zeros(wall.shape, bool)
    rest[54:67, 74:87] = True  # inside the disk at rest
    assert np.abs(median[rest] - 60).max() <= 1  # the median holds the body
    others = scene_states(images, stack, median, 5.0)
    assert others is not None
    scene = masked_median(stack, others, median)
    assert np.abs(scene - wall)[rest].max() <= 3.0  # the wall (noise σ 1, median of 15)
    assert np.abs(scene - median)[~others.any(axis=0)].max() == 0  # elsewhere as it was
    _, held = _resting_samples(15, held=True)
    stack = np.stack(held)
    assert scene_states(held, stack, median_scene(stack), 5.0) is None
    # a reviewer's case: a swinging body that overlaps itself in many samples (it recurs, as near its turning
    # points) and a bright object passing: the body was taken for a ghost and painted into the scene along its arc
    # (89 grey levels too dark). A ghost's outline is the scene's; the body's is the sample's.
    _, passing = _resting_samples(0, spacing=1.2, passer=True)
    stack = np.stack(passing)
    assert scene_states(passing, stack, median_scene(stack), 5.0) is None


def test_samples_of_a_plain_wall_keep_their_bob_s_contrast_when_brought_to_one_exposure():
    """A plain wall (a dark clock case, 80 grey levels, no noise) with a static dark rod (40) and a bright bob
    (160) moving across it, one sample 3 grey levels brighter. The residuals' MAD is 0 there, so the gain fit
    kept only the pixels that fit exactly, too few grey levels to tell a gain from an offset (numpy warned
    "poorly conditioned"; on clock renders it gave gains of 0.5 and offsets of 85): the bob crossing the rod came
    out 160 grey levels above the wall. Now at least 1.5 grey levels of residual are kept, the fit is made about
    the mean grey, and a span under 4 is matched by its offset: every sample's wall at 80 and its bob 80 above."""
    import warnings

    from pendulum.tracking.scene_stack import same_exposure

    yy, xx = np.mgrid[0:120, 0:160]
    wall = np.full(yy.shape, 80.0)
    wall[:, 78:84] = 40.0
    images = []
    for k in range(12):
        image = wall + (3.0 if k == 5 else 0.0)
        image[(yy - 60) ** 2 + (xx - 20 - 10 * k) ** 2 <= 100] = 160.0 + (3.0 if k == 5 else 0.0)
        images.append(image.astype(np.uint8))
    with warnings.catch_warnings():
        warnings.simplefilter("error")  # no poorly conditioned fit
        out = same_exposure(images)
    for k, after in enumerate(out):
        wall_level = float(np.median(after[:20, :60]))
        assert abs(wall_level - 80) <= 0.6, (k, wall_level)
        assert 77 <= float(after[60, 20 + 10 * k]) - wall_level <= 83, (k, after[60, 20 + 10 * k])


def test_a_light_s_bands_rolling_down_the_samples_are_taken_out_and_clean_samples_are_left_as_they_were(monkeypatch):
    """A wall with a gradient and sensor noise (σ 2), a dark bob moving across it; in six of twelve samples a
    light's bands of ±12 % roll down the frame (mains flicker beating with the frame rate). Brought to one exposure,
    every sample's wall lies within 2.5 grey levels of the clean wall row by row (before: ±18 in the banded ones)
    and its bob keeps its contrast within 15 % (the bands scale the bob as they do the wall; an offset per row
    takes them out of the wall). Twelve clean samples come out as they did before rows were matched (none is
    taken for banded)."""
    from pendulum.tracking import scene_stack
    from pendulum.tracking.scene_stack import same_exposure

    rng = np.random.default_rng(7)
    yy, xx = np.mgrid[0:240, 0:320]
    wall = 150.0 + 0.1 * xx

    def samples(banded):
        images = []
        for k in range(12):
            image = wall + rng.normal(0, 2.0, wall.shape)
            image[(yy - 120) ** 2 + (xx - 40 - 20 * k) ** 2 <= 225] = 40.0
            if banded and k % 2:
                image = image * (1 + 0.12 * np.sin(2 * np.pi * (k / 3 + yy / 120.0)))
            images.append(np.clip(np.rint(image), 0, 255).astype(np.uint8))
        return images

    clean = samples(banded=False)
    matched = same_exposure(clean)
    monkeypatch.setattr(scene_stack, "_row_offsets", lambda *args: None)
    assert np.array_equal(matched, same_exposure(clean))
    monkeypatch.undo()
    for k, after in enumerate(same_exposure(samples(banded=True))):
        off_body = (yy - 120) ** 2 + (xx - 40 - 20 * k) ** 2 > 400
        rows = np.array([np.median((after[y] - wall[y])[off_body[y]]) for y in range(0, 240, 4)])
        assert np.abs(rows).max() <= 2.5, (k, np.abs(rows).max())
        contrast = float(np.median(after[off_body])) - float(after[120, 40 + 20 * k])
        assert abs(contrast / (float(np.median(wall)) - 40.0) - 1) <= 0.15, (k, contrast)


def test_a_body_near_the_frame_s_border_is_not_stretched_out_to_it():
    """The body's pixels are closed (a print's patches made one object) with the image continued by the wall:
    OpenCV's default border counts beyond the image as foreground for the erosion, so the closing stretched a
    body whose top was a few pixels below the border out to it, and its frames were flagged ``edge`` (scene 5008
    of the body study, an apple of 50 px radius: 44 of 480 frames, 90.8 % ok; now 12, 97.5 %). Here a ball of
    that size with the tracker's closing (27 px) and opening (35 px) for it: its component ends where it does,
    within a pixel; a ball the border cuts still reaches it."""
    import cv2

    from pendulum.tracking.body_scene import components

    radius = 50
    for top_px in (8, 3, -6):
        diff = np.zeros((160, 200), np.float32)
        cv2.circle(diff, (100, top_px + radius), radius, 90.0, -1)
        for x in range(70, 130, 14):  # a print's light squares, as grey as the wall
            diff[max(top_px + 40, 0) : top_px + 52, x : x + 7] = 0.0
        labels, stats, masses = components(diff, 20.0, open_px=35, close_px=27)
        body = int(np.argmax(masses))
        top = int(stats[body, cv2.CC_STAT_TOP])
        assert abs(top - max(top_px, 0)) <= 1, (top_px, top)
        assert stats[body, cv2.CC_STAT_AREA] <= np.count_nonzero(
            cv2.circle(np.zeros_like(diff), (100, top_px + radius), radius + 1, 1.0, -1)
        )


def test_a_light_beside_the_body_is_not_joined_to_it_but_the_body_s_own_parts_are():
    """A reviewer's bauble in a dim room before fairy lights blinking together: lit bulbs a few px beside it were
    joined to it (every component within two closing widths), its `ok` positions 2–12 px off while they were on.
    Parts are joined only within 1.3 × the body's reach (+ 4 px) of the prediction: a bulb 9 px off a ball of
    18 px radius (and a second bob 30 px off) stays out; a two-tone ball's halves, cut apart by a wall-grey band,
    are still one body."""
    import cv2

    from pendulum.tracking.body_parts import body_component, body_reach

    ball = np.zeros((120, 160), np.float32)
    cv2.circle(ball, (80, 60), 18, 60.0, -1)
    reach = body_reach(ball > 0)
    assert reach == pytest.approx(18, abs=0.6)
    lit = ball.copy()
    cv2.circle(lit, (80 + 18 + 9 + 3, 60), 3, 200.0, -1)  # a bulb beside it
    cv2.circle(lit, (80, 60 - 18 - 8 - 3), 3, 200.0, -1)  # and one above
    joined, _ = body_component(lit, 20.0, 3, 7, near=(80.0, 60.0))
    assert np.count_nonzero(joined) > np.count_nonzero(ball)  # without the reach: the bulbs are the body's
    alone, _ = body_component(lit, 20.0, 3, 7, near=(81.5, 59.0), reach_px=reach)
    assert np.array_equal(alone, ball > 0)
    halves = ball.copy()
    halves[57:63, :] = 0.0  # a band as grey as the wall across its middle
    whole, _ = body_component(halves, 20.0, 3, 3, near=(81.5, 59.0), reach_px=reach)
    both, _ = body_component(halves, 20.0, 3, 3, near=(81.5, 59.0))
    assert np.array_equal(whole, both) and np.count_nonzero(whole) >= 0.99 * np.count_nonzero(halves)


def _print_and_shadow(ball_blur_px: float, ball: bool = True) -> np.ndarray:
    """|I − B| of a printed ball (radius 21 px at (150, 70), squares of 7 px ±55 grey levels, blurred by the lens)
    and its soft shadow on the wall behind (a disk of 30 px radius 30 levels deep at (97, 122), blurred by σ 9 px and
    the lens): the shadow is the heavier, the ball's light and dark squares averaging to the wall's grey."""
    import cv2

    yy, xx = np.mgrid[:200, :260].astype(np.float32)
    signed = np.zeros((200, 260), np.float32)
    if ball:
        inside = (xx - 150) ** 2 + (yy - 70) ** 2 <= 21**2
        checker = np.where((np.floor((xx - 150) / 7) + np.floor((yy - 70) / 7)) % 2 == 0, 55.0, -55.0)
        signed[inside] = checker[inside]
        signed = cv2.GaussianBlur(signed, (0, 0), ball_blur_px)
    shadow = np.zeros_like(signed)
    cv2.circle(shadow, (97, 122), 30, 30.0, -1)
    shadow = cv2.GaussianBlur(shadow, (0, 0), math.hypot(9.0, ball_blur_px))
    return np.abs(signed - shadow * (np.abs(signed) < 1))  # the shadow seen only beside the ball


@pytest.mark.parametrize("ball_blur_px", [1.0, 1.5, 2.0])
def test_a_print_beside_its_heavier_soft_shadow_is_found_without_it(ball_blur_px):
    """A body study scene (7102: a printed ball of 21 px radius, two soft shadows of it on the wall below) was tracked
    27 px off the ball: its shadows, 30 grey levels deep where they overlap, outweighed it (the print's light and dark
    squares average to the wall's grey), and the ball's squares, within two closing widths, were joined to them;
    the path was still a circle (0.7 px RMS), θ 0.36° RMS off the truth and the camera's 3.7 px creep missed. A
    component beside a heavy one whose edge is over three times as sharp is its shadow: the ball found here at its
    drawn centre (within 0.3 px) where the shadow's component is up to three times its mass, for a lens blur up to
    σ 2 px; the shadow alone is still a body (nothing sharper beside it)."""
    from pendulum.tracking.body_parts import body_component, body_measure

    diff = _print_and_shadow(ball_blur_px)
    merged, _ = body_component(diff, 4.0, 3, 5)  # the heaviest with what lies within two closing widths
    assert merged[122, 97] and merged[70, 150], "the shadow and the print are one body without shadows_apart"
    seen = body_measure(diff, 4.0, 5, None)
    assert math.hypot(seen.x - 150.0, seen.y - 70.0) <= 0.3, (seen.x, seen.y)
    assert not seen.component[122, 97]
    alone = body_measure(_print_and_shadow(ball_blur_px, ball=False), 4.0, 5, None)
    assert math.hypot(alone.x - 97.0, alone.y - 122.0) <= 0.3, (alone.x, alone.y)


def _ball_and_shadow(shadow_depth: float, shadow_blur_px: float, gap_rows: tuple = (90, 90)) -> np.ndarray:
    """|I − B| of a two-tone ball (radius 22 px at (100, 90), its upper half 27 grey levels lighter than the wall,
    its lower half 72 darker, split at the rows ``gap_rows`` (a band of wall's grey between them where they differ),
    blurred by the lens, σ 1.4 px) and its shadow on the wall 59 px right and below (a disk of the same radius,
    ``shadow_depth`` deep, blurred by its penumbra ``shadow_blur_px`` and the lens), drawn at 4 × 4 subpixels."""
    import cv2

    yy, xx = np.meshgrid((np.arange(800) + 0.5) / 4, (np.arange(960) + 0.5) / 4, indexing="ij")
    inside = (xx - 100) ** 2 + (yy - 90) ** 2 <= 22**2
    signed = np.where(inside & (yy < gap_rows[0]), 27.0, 0.0) - np.where(inside & (yy >= gap_rows[1]), 72.0, 0.0)
    signed = cv2.GaussianBlur(signed.reshape(200, 4, 240, 4).mean(axis=(1, 3)).astype(np.float32), (0, 0), 1.4)
    shadow = ((xx - 159) ** 2 + (yy - 149) ** 2 <= 22**2).reshape(200, 4, 240, 4).mean(axis=(1, 3))
    shadow = cv2.GaussianBlur((shadow_depth * shadow).astype(np.float32), (0, 0), math.hypot(shadow_blur_px, 1.4))
    return np.abs(signed - shadow)


@pytest.mark.parametrize("shadow_depth, shadow_blur_px", [(19.0, 6.0), (19.0, 4.0), (25.0, 4.0)])
def test_a_ball_beside_its_fainter_shadow_is_found_without_it(shadow_depth, shadow_blur_px):
    """Body study scene 7253: a two-tone ball of 22 px and its shadow on the wall 59 px right and below it, 19 grey
    levels deep, σ 6 px, within the two closing widths that join a body's parts: its edge only half as sharp as the
    ball's (0.105 against 0.19 per px: not the three times that sets a shadow apart), so the two were one body, 28.9
    px in radius and reaching 69 px from its centre; at one end of every swing the shadow joined the track, 9 px off,
    and the ball's outline was not found (17 of 96 rays): θ 0.093° RMS off the truth, 2.8° with the pivot fitted. A
    component beside a heavy one whose edge is softer than two thirds of its and whose contrast is under 0.4 of its
    is a shadow too: the ball here is found as it is alone (within 0.1 px), the shadow left out. (Drawn here, at
    σ 6 px the old rule already set it apart; at σ 4 px, or 25 grey levels deep, it did not.)"""
    from pendulum.tracking.body_parts import body_component, body_measure, body_reach

    diff = _ball_and_shadow(shadow_depth, shadow_blur_px)
    merged, _ = body_component(diff, 4.0, 3, 5)
    assert merged[149, 159] and merged[90, 100], "the shadow and the ball are one body without shadows_apart"
    seen, alone = body_measure(diff, 4.0, 5, None), body_measure(_ball_and_shadow(0.0, 1.0), 4.0, 5, None)
    assert not seen.component[149, 159] and math.hypot(seen.x - alone.x, seen.y - alone.y) <= 0.1, (seen.x, seen.y)
    assert body_reach(seen.component) <= 24.0


def test_a_faint_part_of_a_body_as_sharp_as_the_rest_is_still_joined_to_it():
    """The other side of that rule: a two-tone ball's light half (27 grey levels against its dark half's 72: under
    0.4 of it) apart from its dark half by 4 rows of the wall's grey, its edge as sharp: one body, the light half in
    it, whether its shadow is beside it or not."""
    from pendulum.tracking.body_parts import body_measure

    for depth in (0.0, 19.0):
        seen = body_measure(_ball_and_shadow(depth, 6.0, gap_rows=(87, 91)), 4.0, 5, None)
        assert seen.component[78, 100] and seen.component[100, 100] and not seen.component[149, 159]


@pytest.mark.parametrize("object_radius_px, object_level", [(10, -80.0), (12, -70.0)])
def test_a_faint_defocused_ball_is_not_set_apart_for_a_smaller_sharp_object_beside_it(object_radius_px, object_level):
    """A reviewer's counter-example to the faint shadow's rule: a ball 25 grey levels off the wall, defocused by
    σ 3 px (radius 22 px), with a sharp dark object (a hand, another bob) 8 px from its rim: the ball's edge softer
    than two thirds of the object's and its contrast under 0.4 of it, so the ball was set apart and the object taken
    for the body, 40 px off. A shadow that faint is also lighter than its body: the ball, the heavier, is kept."""
    import cv2

    from pendulum.tracking.body_parts import body_measure

    yy, xx = np.meshgrid((np.arange(800) + 0.5) / 4, (np.arange(960) + 0.5) / 4, indexing="ij")

    def disk(cx, radius, level, blur):
        share = ((xx - cx) ** 2 + (yy - 90) ** 2 <= radius**2).reshape(200, 4, 240, 4).mean(axis=(1, 3))
        return cv2.GaussianBlur((level * share).astype(np.float32), (0, 0), blur)

    signed = disk(100, 22, 25.0, 3.0) + disk(100 + 22 + 8 + object_radius_px, object_radius_px, object_level, 1.4)
    noisy = np.abs(signed + np.random.default_rng(0).normal(0, 1.0, signed.shape).astype(np.float32))
    seen = body_measure(noisy, 5.0, 5, None)
    assert seen.component[90, 100] and seen.component[90, 100 - 15], (seen.x, seen.y)


def test_a_defocused_or_shaded_body_is_not_set_apart_for_a_sharper_object_elsewhere():
    """A reviewer's counter-examples to a first version, which compared every component with the sharpest heavy one
    anywhere in the frame and measured the edge over the whole component: a body defocused by σ 6 px beside a sharp
    hand 200 px away (0.6 of its mass) was taken for its shadow and the hand followed (224 px off), even with
    start_px on the body; a large sphere shaded across its face (its difference ramping 12 → 60 grey levels, radius
    160 px) beside a sharp square (0.3 of its mass) likewise (867 px off). Only a component beside a sharper heavy
    one (within the two closing widths that would join them) is set apart, its edge measured on its outline, and
    never the one start_px points at: each body here is found at its drawn centre (within 1.5 px)."""
    import cv2

    from pendulum.tracking.body_parts import body_measure

    yy, xx = np.mgrid[:540, :960].astype(np.float32)
    disk = ((xx - 400) ** 2 + (yy - 270) ** 2 <= 30**2).astype(np.float32)
    hand = np.zeros_like(disk)
    hand[250:290, 600:650] = 50.0
    defocused = np.abs(cv2.GaussianBlur(60.0 * disk, (0, 0), 6.0) + cv2.GaussianBlur(hand, (0, 0), 0.7))
    for near in (None, (400.0, 270.0)):
        seen = body_measure(defocused, 4.0, 17, near)
        assert math.hypot(seen.x - 400.0, seen.y - 270.0) <= 1.5, (near, seen.x, seen.y)
    square = np.zeros((1080, 1920), np.float32)
    square[60:200, 1500:1640] = 60.0
    yy, xx = np.mgrid[:1080, :1920].astype(np.float32)
    sphere = ((xx - 700) ** 2 + (yy - 540) ** 2 <= 160**2) * (12.0 + 48.0 * np.clip((xx - 540) / 320, 0, 1))
    shaded = np.abs(cv2.GaussianBlur(sphere.astype(np.float32), (0, 0), 1.0) + cv2.GaussianBlur(square, (0, 0), 0.7))
    seen = body_measure(shaded, 4.0, 17, None)
    assert math.hypot(seen.x - 700.0, seen.y - 540.0) <= 1.5, (seen.x, seen.y)


@pytest.mark.slow
def test_the_study_scene_whose_print_was_outweighed_by_its_shadows_is_tracked_by_the_print(tmp_path):
    """Body study scene 7102 (5 s of it): a printed ball of 21 px radius and its two soft shadows, heavier than it,
    on the wall below, the camera creeping. Measured before the shadows were set apart: the track 27 px off the
    ball, no creep found, θ 0.35° RMS off the truth (0.32° with the pivot fitted to the track); after: 0.007°, the
    creep (−3.3, −1.7) px found as (−3.5, −1.6)."""
    sys_path = str(Path(__file__).resolve().parent / "benchmarks")
    if sys_path not in sys.path:
        sys.path.insert(0, sys_path)
    from body_study import judge

    row = judge(7102, tmp_path, duration_s=5.0)
    assert row["ok%"] >= 99 and row["rms"] <= 0.02 and row["rms_fp"] <= 0.03, row
    assert math.dist(row["creep_found"], row["creep_true"]) <= 0.7, row


@pytest.mark.slow
def test_the_study_scene_whose_apple_met_its_shadows_keeps_no_frame_of_the_merge_usable(tmp_path):
    """Body study scene 7170 (5 s of it): a dark apple whose two soft shadows meet a dark band of wall at one end
    of every swing; the silhouette grows there (over 1.5 times its area: flagged), and the frames beside those,
    1.24–1.49 times it and 9–17 px off, were left usable: θ 0.073° RMS off the truth about the true pivot, 1.66°
    with the pivot fitted to the track, the camera's 4.5 px creep not found. Now flagged along the whole run (its
    usable share lower, and honest): 0.011° (0.017°), the creep found."""
    sys_path = str(Path(__file__).resolve().parent / "benchmarks")
    if sys_path not in sys.path:
        sys.path.insert(0, sys_path)
    from body_study import judge

    row = judge(7170, tmp_path, duration_s=5.0)
    assert 60 <= row["ok%"] < 95 and row["rms"] <= 0.02 and row["rms_fp"] <= 0.03, row
    assert math.dist(row["creep_found"], row["creep_true"]) <= 0.7, row


@pytest.mark.slow
def test_the_study_scene_whose_blurred_two_tone_ball_pulled_its_centroid_aside_is_measured_by_its_outline(tmp_path):
    """Body study scene 7227 (5 s of it): a two-tone ball of 34 px filmed at 30 fps with exposures of half a frame;
    where it moves fastest its faint half's blurred edge falls under the silhouette's threshold first and the
    centroid sits up to 1 px toward its dark half, along the swing (both centres' paths circles within their
    noise). Measured before: θ 0.035° RMS off the truth, 0.148° with the pivot fitted; by its outline's centre (the
    two centres moving apart by 0.38 px RMS, their difference's noise 0.07 px): 0.0076° (0.013°)."""
    sys_path = str(Path(__file__).resolve().parent / "benchmarks")
    if sys_path not in sys.path:
        sys.path.insert(0, sys_path)
    from body_study import judge

    row = judge(7227, tmp_path, duration_s=5.0)
    assert row["ok%"] >= 99 and row["rms"] <= 0.015 and row["rms_fp"] <= 0.03, row


def _flags_track(n_ok: int, n: int = 100):
    import pandas as pd

    flags = ["ok"] * n_ok + ["occluded"] * (n - n_ok)
    return pd.DataFrame({"frame": range(n), "time_s": np.arange(n) / 30.0, "x_px": 1.0, "y_px": 2.0, "flag": flags})


@pytest.mark.parametrize(
    "most, body_ok, whole_ok, body_fails, used, passes",
    [
        (0.90, 97, None, False, "body", 1),  # the body beats all the marker could have had: no second pass
        (0.90, 85, 88, False, "marker", 2),  # the marker might do as well: its whole pass decides (88 >= 85)
        (0.90, 85, 80, False, "body", 2),
        (0.90, None, 88, True, "marker", 2),  # no body: the marker's whole record, as before the early stop
        (0.90, 85, -1, False, "body", 2),  # the whole pass finds no marker: said as such, not "is failed: …"
    ],
)
def test_a_marker_pass_stopped_early_decides_as_the_whole_pass_would(
    monkeypatch, most, body_ok, whole_ok, body_fails, used, passes
):
    """``method: auto`` stops the marker pass where it can no longer reach 95 % ok; the choice between marker and
    body must be the one the whole pass would have given: the body only where it beats the most the marker could
    have had, else (or without a body) the marker's whole pass is run and compared as before."""
    from pendulum.camera.video import VideoError
    from pendulum.tracking import method
    from pendulum.tracking.marker import MarkerAbandoned
    from pendulum.tracking.settings import TrackerSettings

    calls = []

    def fake_marker(path, settings, progress=None, abandon_below=None, detection=None, asked=None):
        calls.append(abandon_below)
        if abandon_below is not None:
            raise MarkerAbandoned("stopped", most, settings, detection="found", at_frame=7)
        assert detection == "found" and asked is not None  # the stopped pass's detection, and what was asked
        if whole_ok < 0:
            raise VideoError("clip.mp4: no marker found in any of its 100 frames")
        return _flags_track(whole_ok)

    def fake_body(path, settings, progress=None):
        if body_fails:
            raise VideoError("no body")
        return _flags_track(body_ok)

    monkeypatch.setattr(method, "track_video", fake_marker)
    monkeypatch.setattr(method, "track_body", fake_body)
    track = method.track_trial("clip.mp4", TrackerSettings())
    assert track.attrs["method"]["used"] == used
    assert len(calls) == passes and calls[0] == method.MARKER_USABLE_FRACTION
    if passes == 1:
        said = track.attrs["method"]["tried"]["marker"]
        assert "under 95 %" in said and "by frame 7" in said and said in track.attrs["method"]["reason"]
    if whole_ok is not None and whole_ok < 0:
        reason = track.attrs["method"]["reason"]
        assert reason.startswith("the marker disk could not be followed (clip.mp4: no marker found"), reason


def test_masks_read_at_full_size_are_cv2_s_nearest_enlargement():
    """The body's scene reads each sample's mask, found on the reduced sample, at full size a band of rows at a
    time (a 4K clip's 60–119 full-size masks took 0.5–1 GB): as ``cv2.resize(INTER_NEAREST)`` enlarges it, for
    every size (⌊i · small / full⌋ was one row off where that is whole: 1058 rows from 352, 1440 from 480)."""
    import cv2

    from pendulum.tracking.scene_stack import EnlargedMasks, nearest_source

    for full in range(1, 2200):
        for scale in (2, 3, 5, 6):
            small = full // scale
            if small:
                line = np.arange(small, dtype=np.float32)[None, :]
                enlarged = cv2.resize(line, (full, 1), interpolation=cv2.INTER_NEAREST)[0].astype(int)
                assert np.array_equal(nearest_source(full, small), enlarged), (full, small)
    rng = np.random.default_rng(5)
    for shape in ((1058, 1920), (65, 129), (2160, 3840)):
        small = rng.random((3, shape[0] // 6, shape[1] // 6)) < 0.3
        masks = EnlargedMasks(small, shape)
        whole = np.stack(
            [cv2.resize(m.view(np.uint8), shape[::-1], interpolation=cv2.INTER_NEAREST) > 0 for m in small]
        )
        assert np.array_equal(masks.band(0, shape[0]), whole)
        assert np.array_equal(masks.band(40, 104), whole[:, 40:104])
        assert np.array_equal(masks.count_over_samples(), whole.sum(axis=0))
        rows, cols = masks.extent(1)
        assert np.array_equal(rows, np.flatnonzero(whole[1].any(axis=1)))
        assert np.array_equal(cols, np.flatnonzero(whole[1].any(axis=0)))


def test_a_bright_dot_on_a_dark_body_is_no_hole_in_its_silhouette_and_a_print_keeps_its_pattern():
    """A white sticker on a dark body (a clock's bob, a label on a vehicle) is part of the body: its one-sided
    difference from the wall is 0 there, and the components fill that hole. Until 2026-12-03 it stayed a hole: the
    body's inner radius came out halved, and with it the opening that cuts the thread, so the apple's stem was
    followed in some frames and not others (on the real clip with a painted dot, 0.78 px RMS and 2 px at the
    swing's ends: tests/test_real_footage.py). Holes that are more of the body (a print's light squares, the wall
    seen through a ring, through a loop of thread above a bob: filled, it moved the bob 5 px along its thread) stay:
    filling a print's made the printed balls of the body study 5–50 % worse."""
    import cv2

    from pendulum.tracking.body_scene import components

    yy, xx = np.mgrid[0:120, 0:120]
    disk = (xx - 60) ** 2 + (yy - 60) ** 2 <= 20**2
    diff = np.where(disk, 100.0, 0.0).astype(np.float32)
    diff[(xx - 60) ** 2 + (yy - 70) ** 2 <= 5**2] = 0.0  # the dot, 10 px below the centre: 6 % of the body
    labels, _, _ = components(diff, 4.0, open_px=13, close_px=5)
    body = labels == labels[60, 60]
    assert body[70, 60] and abs(int(body.sum()) - int(disk.sum())) <= 0.01 * disk.sum()
    ring = disk & ((xx - 60) ** 2 + (yy - 60) ** 2 > 12**2)  # the wall through it: 36 % of the filled ring
    labels, _, _ = components(np.where(ring, 100.0, 0.0).astype(np.float32), 4.0, open_px=5, close_px=5)
    assert labels[60, 60] == 0 and labels[60, 44] != 0
    # each body by its own share (a reviewer found the window's: a ring beside the dotted body kept its dot a hole,
    # and a large solid object beside a print had the print's pattern filled)
    pair = np.hstack([diff, np.where(ring, 100.0, 0.0).astype(np.float32)])
    labels, _, _ = components(pair, 4.0, open_px=5, close_px=5)
    assert labels[70, 60] != 0 and labels[60, 180] == 0
    solid = np.hstack([np.where(ring, 100.0, 0.0), np.full((120, 120), 100.0)]).astype(np.float32)
    solid[:, 120:125] = 0.0  # apart
    labels, _, _ = components(solid, 4.0, open_px=5, close_px=5)
    assert labels[60, 60] == 0
    # the wall seen through a loop of thread above a bob (tied at ±40° on its rim, 33 px above its top): not filled
    loop = np.zeros((200, 200), np.uint8)
    cv2.circle(loop, (100, 110), 30, 1, -1)
    for end in ((81, 87), (119, 87)):
        cv2.line(loop, end, (100, 47), 1, 2)
    cv2.line(loop, (100, 47), (100, 0), 1, 2)
    labels, _, _ = components(loop.astype(np.float32) * 100.0, 4.0, open_px=21, close_px=15)
    assert labels[70, 100] == 0


def test_the_body_s_components_are_the_whole_window_s():
    """The closing and opening run on the box of the pixels above the threshold grown by both kernels' reach
    (a 4K body's window is mostly wall: 87 → 81 s for 600 frames). Against the same operations over the whole
    window (the reference below): the same labels, boxes and weights, also for bodies cut by the window's edge."""
    import cv2

    from pendulum.tracking.body_scene import components, fill_markings

    def whole_window(diff, threshold, open_px, close_px):
        mask = (diff > threshold).astype(np.uint8)
        pad = close_px // 2 + 1
        padded = cv2.copyMakeBorder(mask, pad, pad, pad, pad, cv2.BORDER_CONSTANT, value=0)
        disk = cv2.getStructuringElement(cv2.MORPH_ELLIPSE, (close_px, close_px))
        closed = cv2.morphologyEx(padded, cv2.MORPH_CLOSE, disk)
        fill_markings(closed)
        mask = closed[pad:-pad, pad:-pad]
        if open_px > 1:
            mask = cv2.morphologyEx(mask, cv2.MORPH_OPEN, cv2.getStructuringElement(cv2.MORPH_ELLIPSE, (open_px,) * 2))
        return cv2.connectedComponentsWithStats(mask, connectivity=8)[1:3]

    rng = np.random.default_rng(1)
    for _ in range(600):
        h, w = rng.integers(8, 400, 2)
        yy, xx = np.mgrid[0:h, 0:w]
        diff = np.zeros((h, w), np.float32)
        for _ in range(rng.integers(0, 4)):  # disks, some cut by the edge
            cx, cy, r = rng.uniform(-10, w + 10), rng.uniform(-10, h + 10), rng.uniform(1, 80)
            diff[(xx - cx) ** 2 + (yy - cy) ** 2 <= r * r] = rng.uniform(5, 100)
        diff += (rng.random((h, w)) < rng.choice([0, 0.001, 0.02])) * 50  # specks
        open_px, close_px = int(rng.choice([1, 3, 9, 31, 71])), int(rng.choice([3, 9, 27]))
        labels, stats, masses = components(diff, 4.0, open_px, close_px)
        expected_labels, expected_stats = whole_window(diff, 4.0, open_px, close_px)
        assert np.array_equal(labels, expected_labels)
        assert np.array_equal(stats[1:], expected_stats[1:])
        assert masses.size == len(expected_stats)


def test_a_camera_in_the_hand_is_steadied_from_the_still_scene(tmp_path):
    """A reviewer's clock clips filmed from the hand (2 px of shake on a 40 px swing) were refused as no pendulum.
    A swing of ±12° on a 380 px arm before a textured wall, the camera shaking by about 2 px RMS and turning by up
    to 0.15°: the track as measured (the true positions in the moving picture, 0.05 px of noise) is no circle
    (refused before 2026-12-03); the picture's motion measured from the still scene (ECC) and taken out, its path
    is a pendulum's and its positions lie within 0.15 px RMS of the truth in the still scene's frame."""
    import cv2

    from pendulum.synthetic.experiment import write_video
    from pendulum.tracking.camera_motion import steady_camera

    rng = np.random.default_rng(12)
    wall = cv2.GaussianBlur(rng.uniform(0, 255, (240, 320)).astype(np.float32), (0, 0), 3)
    wall = 70 + 120 * (wall - wall.min()) / np.ptp(wall)
    fps, n = 30.0, 150
    t = np.arange(n) / fps
    theta = np.radians(12) * np.cos(2 * math.pi * t / 1.5)
    x, y = 160 + 380 * np.sin(theta), -200 + 380 * np.cos(theta)
    walk = np.cumsum(rng.normal(0, 0.6, (n, 3)), axis=0)
    walk -= walk.mean(axis=0)
    shift, turn = 2.0 * walk[:, :2] / walk[:, :2].std(axis=0), np.radians(0.15) * walk[:, 2] / np.abs(walk[:, 2]).max()
    frames, seen = [], []
    for k in range(n):
        world = wall.copy()
        cv2.circle(world, (int(round(x[k] * 16)), int(round(y[k] * 16))), 10 * 16, 25.0, -1, cv2.LINE_AA, 4)
        cv2.line(world, (160, 0), (int(round(x[k])), int(round(y[k]))), 40.0, 2, cv2.LINE_AA)
        c, s = math.cos(turn[k]), math.sin(turn[k])
        move = np.array([[c, -s, shift[k, 0]], [s, c, shift[k, 1]]], np.float32)
        frames.append(np.clip(cv2.warpAffine(world, move, (320, 240), borderMode=cv2.BORDER_REFLECT), 0, 255))
        seen.append(move[:, :2] @ [x[k], y[k]] + move[:, 2])
    video = tmp_path / "hand.mp4"
    write_video([f.astype(np.uint8) for f in frames], video, fps, 16, "medium")
    seen = np.asarray(seen) + rng.normal(0, 0.05, (n, 2))
    track = pd.DataFrame({"frame": np.arange(n), "time_s": t, "x_px": seen[:, 0], "y_px": seen[:, 1], "flag": "ok"})
    track.attrs["body"] = {"radius_px": 10.0}
    _, before = path_departure(track)
    assert before["not_a_pendulum"], before
    steady, document = steady_camera(video, track, before)
    assert not document["not_a_pendulum"] and document["camera_motion"]["unaligned"] <= 0.05 * n, document
    assert "the camera moved (held in the hand" in document["verdict"]
    ok = (steady.flag == "ok").to_numpy()
    error = np.column_stack([steady.x_image_px, steady.y_image_px])[ok] - seen[ok]
    assert np.abs(error).max() < 1e-9  # the positions as measured kept beside the steadied ones
    off = np.column_stack([steady.x_px, steady.y_px])[ok] - np.column_stack([x, y])[ok]
    assert np.sqrt(np.mean(np.sum((off - off.mean(axis=0)) ** 2, axis=1))) < 0.15


def test_the_walls_gain_is_the_share_of_its_contrast_a_one_sided_body_keeps_before_a_darker_band():
    """A dark body (grey 80) before a light wall (180: its contrast 100) keeps (110 − 80) / 100 of it before a band
    of wall at 110: the gain there is that over the knee (0.8), 1 on the light wall and on a wall within the knee
    (170); the same map when its first place lies in the band (the wall behind its swing is the light one);
    mirrored for a bright body before a lighter band; None for a plain wall and for a body both lighter and darker
    than the wall, or lighter than the wall it is called darker than; never below the floor (a band of the body's
    own grey)."""
    from pendulum.tracking.body_scene import MIN_WALL_GAIN, WALL_GAIN_KNEE, wall_gain

    wall = np.full((40, 100), 180.0, np.float32)
    wall[:, 40:50] = 110.0  # the band
    wall[:, 60:62] = 170.0  # within the knee
    wall[:, 70:72] = 80.0  # the body's own grey
    gain = wall_gain(wall, "dark", 80.0, 180.0, 180.0)
    assert gain[0, 45] == pytest.approx(30.0 / 100.0 / WALL_GAIN_KNEE)
    assert gain[0, 10] == gain[0, 61] == 1.0
    assert gain[0, 71] == pytest.approx(MIN_WALL_GAIN)
    np.testing.assert_allclose(wall_gain(wall, "dark", 80.0, 110.0, 180.0), gain)  # first seen in the band
    np.testing.assert_allclose(wall_gain(wall, "dark", 80.0, 180.0, math.nan), gain)  # no swing seen
    np.testing.assert_allclose(wall_gain(255.0 - wall, "bright", 175.0, 75.0, 75.0), gain)
    assert wall_gain(wall, "both", 80.0, 180.0, 180.0) is None
    assert wall_gain(wall, "dark", 200.0, 180.0, 180.0) is None
    assert wall_gain(np.full((40, 100), 180.0, np.float32), "dark", 80.0, 180.0, 180.0) is None


# A dark band of wall across the swing at its rest place (a shelf's shadow), the body there keeping 15–35 grey
# levels of its contrast: scenes 9100–9107, drawn after the wall's gain was written (developed on 30–41).
BAND_SEEDS = tuple(range(9100, 9108))


def _band_across_the_swing(seed: int, directory):
    from pendulum.synthetic.wall import random_wall_trial, render_wall_trial, write_wall_trial

    trial = random_wall_trial(seed)
    spec = replace(trial.spec, duration_s=4.0)
    kept = float(np.random.default_rng(seed + 500).uniform(15, 35))  # the body's contrast left at the band's middle
    width = 0.06 * spec.camera.width_px
    # no soft shadows beside the body: the renderer darkens the wall by a fixed depth there, in the band as on the
    # light wall, where a shadow takes a share of the light that is left
    wall = replace(trial.wall, band_depth=trial.wall.level - trial.body.level - kept, band_width_px=width, shadows=())
    trial = replace(trial, spec=spec, body=replace(trial.body, look="apple"), wall=wall)
    _, first = render_wall_trial(replace(trial, spec=replace(spec, duration_s=0.2)))
    rest_x, rest_y = float(first.marker_x_px.mean()), float(first.marker_y_px.mean())
    angle = math.radians(-80.0)  # nearly upright, across the swing, through its rest place
    band = replace(wall, band_angle_deg=-80.0, band_y_px=rest_y * math.cos(angle) - rest_x * math.sin(angle))
    video, truth = write_wall_trial(replace(trial, wall=band), directory, directory)
    return video, truth, np.abs(truth.marker_x_px - rest_x) < 1.5 * width


@pytest.mark.slow
def test_a_body_crossing_a_dark_band_of_wall_keeps_its_silhouette(tmp_path):
    """Before a band that leaves the body 15–35 grey levels of its contrast, its silhouette lost its part over the
    band, its centroid moved away from it and the frames there were flagged: 2 of these 8 scenes were ≥ 95 % usable
    and within 0.5 px RMS of the drawn centre in the band (its offset off the band taken out; 84.6–100 % usable,
    0.12–2.8 px). With the wall's gain (``body_scene.wall_gain``): at least 7 of 8 (8 of 8 when written, 100 % usable,
    0.09–0.38 px; 12 of 12 development scenes)."""
    from pendulum.tracking.body import track_body
    from pendulum.tracking.settings import TrackerSettings

    passed, rows = 0, []
    for seed in BAND_SEEDS:
        video, truth, in_band = _band_across_the_swing(seed, tmp_path)
        track = track_body(video, TrackerSettings())
        ok = (track.flag == "ok").to_numpy()
        dx, dy = (track.x_px - truth.marker_x_px).to_numpy(), (track.y_px - truth.marker_y_px).to_numpy()
        off = ok & ~in_band.to_numpy()
        error = np.hypot(dx - np.median(dx[off]), dy - np.median(dy[off]))[ok & in_band.to_numpy()]
        rms = float(np.sqrt(np.mean(error**2)))
        rows.append((seed, round(100 * ok.mean(), 1), round(rms, 3), track.attrs["body"].get("wall_gain")))
        passed += ok.mean() >= 0.95 and rms <= 0.5
    assert passed >= 7, rows
    assert all(gain is not None and gain < 0.6 for *_, gain in rows), rows  # said: the band scaled its differences
