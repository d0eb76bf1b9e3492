"""Real phone footage (../shared/data/real-video, MIT licence): the tracker's test against reality.

`redapple_480p.mov`: a red apple on a thin string before a plain light wall, 640×360 at 60 fps,
21.7 s, already swinging in the first frame, the pivot ~330 px above the frame, soft shadows
beside it, the phone creeping on its stand. Its period, 2.078 s, was measured independently (a
colour-threshold track of the apple and a damped cosine fitted to its horizontal position; the
clip's README). `star_480p.mov`: a paper star spinning and twisting on its thread, not a rigid
pendulum about a fixed pivot: it must end in a clear message, never a silently wrong record.

Config defaults, no hints: exactly what a new user gets.
"""

import math
import sys
from dataclasses import replace
from pathlib import Path

import numpy as np
import pytest
import yaml

from conftest import ROOT, SHARED, FakeSnakemake, shared_file
from paper_rig import APPLE_IN_AIR

pytestmark = pytest.mark.slow
APPLE_FILE, STAR_FILE = "data/real-video/redapple_480p.mov", "data/real-video/star_480p.mov"
APPLE, STAR = SHARED / APPLE_FILE, SHARED / STAR_FILE
APPLE_PERIOD_S = 2.078  # measured independently (the clip's README)


def default_settings():
    from pendulum.tracking.settings import TrackerSettings

    config = yaml.safe_load((ROOT / "config.yaml").read_text())["tracking"]
    return TrackerSettings.from_config(config)


def zero_crossing_period(time_s: np.ndarray, theta: np.ndarray) -> float:
    """Mean period from upward crossings of the median angle (linear interpolation), by a line through them, each
    numbered by its cycle (a crossing among flagged samples is missing, not the next one's)."""
    ok = np.isfinite(theta)
    centred = theta - np.median(theta[ok])
    i = np.flatnonzero((centred[:-1] < 0) & (centred[1:] >= 0) & ok[:-1] & ok[1:])
    crossings = time_s[i] - centred[i] * (time_s[i + 1] - time_s[i]) / (centred[i + 1] - centred[i])
    gaps = np.diff(crossings)
    one_period = gaps[gaps > 0.5 * np.median(gaps)].min()  # gaps are whole periods; a noisy double crossing is not
    cycle = np.round((crossings - crossings[0]) / one_period)
    return float(np.polyfit(cycle, crossings, 1)[0])


@pytest.fixture(scope="module")
def apple():
    shared_file(APPLE_FILE)
    from pendulum.angles.geometry import estimate_rig_geometry
    from pendulum.angles.record import angles_from_track
    from pendulum.tracking.method import track_trial
    from pendulum.tracking.path_shape import path_departure

    track = track_trial(APPLE, default_settings())
    corrected, path = path_departure(track)
    geometry = estimate_rig_geometry({"apple": corrected}, vertical_deg=0.0)
    table, info = angles_from_track(
        corrected, pivot_px=geometry["pivot_px"], vertical_deg=0.0, length_m=1.0, source=str(APPLE)
    )
    return track, path, table, info


def test_apple_is_tracked_by_its_body_in_nearly_every_frame(apple):
    track, _, _, _ = apple
    assert track.attrs["method"]["used"] == "body"
    assert "marker" in track.attrs["method"]["tried"]  # the marker was tried first, and why it was not kept is said
    ok = (track.flag == "ok").mean()
    assert ok >= 0.95, track.flag.value_counts().to_dict()  # the acceptance
    assert ok >= 0.99, track.flag.value_counts().to_dict()  # measured 99.7 % (97.8 % with the stem in)
    # the silhouette is the apple: about 20 px in radius (measured on the frames by eye: 38–42 px across)
    assert 17 <= track.attrs["body"]["radius_px"] <= 23


def test_apple_angle_record_has_the_measured_period_and_low_noise(apple):
    _, _, table, info = apple
    assert not info.release_detected  # already swinging in the first frame: the record starts there
    period = zero_crossing_period(table.time_s.to_numpy(float), table.theta_rad.to_numpy(float))
    assert abs(period / APPLE_PERIOD_S - 1) <= 0.003, period
    assert info.noise_deg <= 0.03
    assert (table.flag == "ok").mean() >= 0.95


def test_apple_camera_creep_is_measured_said_and_corrected(apple):
    track, path, _, _ = apple
    # Off one fixed circle by ~3 px RMS (the README's figure), which a pivot creeping in the image
    # explains to well under 1 px; the rest is reported, not hidden.
    assert 2.5 <= path["circle_rms_px"] <= 4.0
    assert path["corrected"] and path["creep"]["degree"] >= 1
    # 0.44 px measured (0.045° on the arm); 0.85 px when the apple's stem and string crept into its silhouette
    assert path["creep"]["rms_after_px"] < 0.6
    dx, dy = path["creep"]["start_to_end_px"]
    # The wall's own marks (left of the frame) move by about (+8, −8) px from the first to the last
    # seconds (phase correlation of the scene, see the notes): the same creep.
    assert 4 <= dx <= 12 and -14 <= dy <= -5, (dx, dy)
    assert "creeping" in path["verdict"]
    assert not path["not_a_pendulum"]


def test_apple_angle_record_carries_the_second_harmonic_of_a_swing_seen_in_perspective(apple):
    """The fit of the apple's record left 0.23° of structure that no damping law removes (2026-12-02): 0.2° of it
    is a second harmonic, which a planar swing seen square-on has not, in phase with the swing (its plane turned
    against the phone's image plane) and a smaller part in quadrature (an elliptical swing); the apple's
    silhouette area changes by −3.5 % cos φ and −1.4 % sin φ with it, as a distance change of that size would
    make it (docs/footage-notes.md). Measured and said, with its sign, not absorbed silently."""
    _, _, _, info = apple
    found = info.second_harmonic
    assert found["present"] and found["windows"] >= 15, found
    assert -0.25 <= found["in_phase_deg"] <= -0.13 and -0.12 <= found["quadrature_deg"] <= -0.03, found
    assert found["stderr_deg"] < 0.02 and "the swing plane turned against the image plane" in found["verdict"]


def test_apple_frames_lost_and_repeated_by_the_phone_are_found_and_put_right(apple, tmp_path):
    """The clip's stamps are even, but its frames are not: a frame step twice the steps beside it at 7.7 and 21.5 s
    (a frame lost), no motion at all from frame 406 to 407 at full speed (a frame shown twice), a step 1.8× its
    neighbours at 4.6 s (the clock 0.8 of a period late). Found from the motion and the times put right; the same
    moments, at half the periods, in the clip kept at every second frame (30 fps): a property of the footage."""
    track, _, _, _ = apple
    timing = track.attrs["timing"]
    slips = dict(map(tuple, timing["slips"]))
    assert 407 in timing["repeated"]
    assert (track.set_index("frame").flag[timing["repeated"]] == "duplicate").all()
    assert slips.keys() >= {276, 463, 1290}, slips
    assert abs(slips[276] - 0.8) <= 0.1 and abs(slips[463] - 1) <= 0.1 and abs(slips[1290] - 1) <= 0.1
    assert timing["checked_fraction"] >= 0.85
    # its turning points stay across every slip (no picture step), and its rough spots (5–12× the usual misfit,
    # which no shift lowers) are not breaks
    assert timing["picture_steps"] == [] and timing["unexplained"] == [], timing
    # frame 407 is taken at the moment of frame 406, frame 500 as late as the slips and repeats before it make it
    times = track.set_index("frame").time_s
    assert times[407] == pytest.approx(times[406], abs=1e-9)
    late = sum(p for f, p in slips.items() if f <= 500) - sum(f <= 500 for f in timing["repeated"])
    assert times[500] - 500 * timing["period_s"] == pytest.approx(late * timing["period_s"], abs=1e-6)
    sys.path.insert(0, str(ROOT / "tests" / "benchmarks"))
    from real_variants import make

    from pendulum.tracking.method import track_trial

    half = track_trial(make("30fps", tmp_path), default_settings()).attrs["timing"]
    at_half = dict(map(tuple, half["slips"]))
    # frame k at 30 fps is frame 2k of the clip: the clip's slips, halved, between the same frames
    assert {138, 232} <= at_half.keys(), at_half
    assert abs(at_half[138] - slips[276] / 2) <= 0.1 and abs(at_half[232] - slips[463] / 2) <= 0.1


def restamped(path: Path, out: Path, ticks_per_s: int, slowed: int = 1) -> Path:
    """The clip's packets, not decoded, stored again with every time stamp rounded to 1/``ticks_per_s`` s (a
    Matroska or WebM file's milliseconds, an iPhone's 1/600 s), after multiplying it by ``slowed`` (a phone's
    slow-motion file, stored to play that many times slower than it was filmed)."""
    from fractions import Fraction

    import av

    tick = Fraction(1, ticks_per_s)
    with av.open(str(path)) as source, av.open(str(out), "w", format="mov") as target:
        stream = source.streams.video[0]
        copy = target.add_stream_from_template(stream)
        copy.time_base = tick
        for packet in source.demux(stream):
            if packet.dts is None:
                continue
            for name in ("pts", "dts"):
                value = getattr(packet, name)
                setattr(packet, name, None if value is None else round(slowed * value * stream.time_base / tick))
            packet.time_base, packet.stream = tick, copy
            target.mux(packet)
    return out


@pytest.mark.parametrize("ticks_per_s", [1000, 600])
def test_the_apple_stamped_in_a_coarse_tick_is_timed_as_the_clip_itself(apple, tmp_path, ticks_per_s):
    """The clip's own packets with their stamps rounded to milliseconds or to 1/600 s (16 and 17 ms, 10 and 11
    ticks, for its 59.94 fps): the same frames lost and repeated found, the same times within a tenth of a frame
    period, the same period (before, in milliseconds: frames said to come every 17 ms, the repeat at 309 missed,
    the period 2.0799 s; in 1/600 s every correction switched off, 2.0784 s)."""
    from pendulum.camera.video import frame_timeline
    from pendulum.tracking.method import track_trial

    track, _, table, info = apple
    video = restamped(APPLE, tmp_path / f"apple_{ticks_per_s}.mov", ticks_per_s)
    frames, _ = frame_timeline(video)
    assert frames.rounded_stamps_tick_s == pytest.approx(1 / ticks_per_s) and not frames.warnings
    assert frames.frame_interval_s == pytest.approx(1001 / 60000, rel=1e-4)
    again = track_trial(video, default_settings())
    timing, own = again.attrs["timing"], track.attrs["timing"]
    assert timing["repeated"] == own["repeated"] and [f for f, _ in timing["slips"]] == [f for f, _ in own["slips"]]
    both = (again.flag == "ok").to_numpy() & (track.flag == "ok").to_numpy()
    assert np.abs(again.time_s - track.time_s)[both].max() <= 0.1 * timing["period_s"]
    assert zero_crossing_period(again.time_s.to_numpy(), np.where(both, again.x_px, np.nan)) == pytest.approx(
        zero_crossing_period(track.time_s.to_numpy(), np.where(both, track.x_px, np.nan)), rel=1e-4
    )


@pytest.mark.slow
def test_the_apple_as_a_slow_motion_file_is_timed_at_the_cameras_rate_given(apple, tmp_path):
    """The clip's own packets stamped 8 times further apart (a slow-motion file: filmed at 59.94 fps, playing at
    7.49), tracked with ``capture_fps`` 59.94: the same frames, flags and positions as the clip itself, its times
    within a millionth of a second, the same period; the file's own stamps kept in ``stamp_s``."""
    from pendulum.tracking.method import track_trial

    track, _, _, _ = apple
    video = restamped(APPLE, tmp_path / "apple_slow.mov", 60000, slowed=8)
    fps = 60000 / 1001
    again = track_trial(video, replace(default_settings(), capture_fps=fps))
    assert again.attrs["time_base"]["file_fps"] == pytest.approx(fps / 8, rel=1e-4)
    assert again.flag.tolist() == track.flag.tolist()
    assert np.allclose(again.x_px, track.x_px, atol=1e-9, equal_nan=True)
    assert np.abs(again.time_s - track.time_s).max() <= 1e-6
    assert again.stamp_s.iloc[-1] == pytest.approx(8 * track.stamp_s.iloc[-1], rel=1e-6)
    ok = (track.flag == "ok").to_numpy()
    assert zero_crossing_period(again.time_s.to_numpy(), np.where(ok, again.x_px, np.nan)) == pytest.approx(
        zero_crossing_period(track.time_s.to_numpy(), np.where(ok, track.x_px, np.nan)), rel=1e-6
    )


@pytest.mark.parametrize("variant", ["hand_release", "hand_release_long_dark", "hand_release_fingers"])
def test_a_hand_holding_the_apple_before_the_release_is_never_taken_for_it(apple, tmp_path, variant):
    """The clip released by hand in view (``real_variants._hand_release``: held at its first place by a hand from
    the upper left, fingers over its edge, then let go and the hand drawn back): 1.5 s by a hand lighter than the
    apple, and 10 s by one darker than its lit side. Touching the hand, the apple's silhouette holds both: 2.5–4.4
    times its usual area, for the whole hold (no outlier within a second's window), and positions 25–30 px off.
    Before 2026-11-28 89 of the short hold's 90 frames and the first 4 after the release were ``ok`` at those
    positions; now every frame the hand touches is flagged, and the rest follow the apple as in the clip itself
    (measured: 99.2 % of the frames after the release ok, within 0.28 px of the clip's track). Until 2026-11-29 the
    darker hand was followed out of the frame after the release and the apple lost for 70 frames (93.8 % ok after
    it), and a hold of 5 s or more taught the tracker a body of hand and apple (its radius 35 px, not 20; a two-tone
    split): the held frames ``ok`` and the positions after the release up to 1.3 px off. Since 2026-12-03 the
    prediction goes on from the apple's own centre while the hand touches it (two pendulums whose bobs meet): the
    window then takes in less of the forearm, and a held frame whose silhouette comes out just under 1.5 times the
    apple's (1.497) is ``occluded`` rather than ``held``: never ``ok`` either way. Other hands:
    docs/footage-notes.md."""
    sys.path.insert(0, str(ROOT / "tests" / "benchmarks"))
    from real_variants import HANDS, make

    from pendulum.tracking.method import track_trial

    clip, *_ = apple
    hold = HANDS[variant][0]
    track = track_trial(make(variant, tmp_path), default_settings())
    assert track.attrs["method"]["used"] == "body"
    assert abs(track.attrs["body"]["radius_px"] - 20.2) < 1.0, track.attrs["body"]  # the apple's, not the hand's
    held, after = track.iloc[:hold], track.iloc[hold:].reset_index(drop=True)
    assert not (held.flag == "ok").any() and (held.flag == "held").mean() >= 0.97, held.flag.value_counts().to_dict()
    assert (after.flag == "ok").mean() >= 0.99, after.flag.value_counts().to_dict()
    both = (after.flag == "ok") & (clip.flag == "ok")
    off = np.hypot(after.x_px - clip.x_px, after.y_px - clip.y_px)[both]
    assert off.max() < 0.5 and off.median() < 0.1, off.describe()


def test_a_post_in_front_of_the_swing_flags_every_frame_it_hides_part_of_the_apple_in(apple, tmp_path):
    """The clip with a dark post 12 px wide (columns 296–307) between the camera and the swing
    (``real_variants._bar_in_front``): where it hides the apple whole, the frames were flagged, but until
    2026-11-29 those where it hid only the apple's edge were ``ok``, 35 of the 119 frames in which the apple comes
    within 1 px of the post, off by up to 1.6 px (0.17°). The place the apple is never seen although its path
    crosses it (``pendulum.tracking.occluders``) is the post; every frame whose apple reaches it is flagged: 2 of
    the 119 ``ok`` (measured; the apple's rim 0.2–0.4 px from the post), and no ok frame more than 0.7 px off the
    clip's own track (its constant 1.1 px offset aside)."""
    sys.path.insert(0, str(ROOT / "tests" / "benchmarks"))
    from real_variants import make

    from pendulum.tracking.method import track_trial

    clip, *_ = apple
    track = track_trial(make("post_in_front", tmp_path), default_settings())
    x0, _, width, _ = track.attrs["body"]["in_front"]["box_px"]
    assert 293 <= x0 <= 297 and 306 <= x0 + width <= 311, track.attrs["body"]["in_front"]
    ok, clip_ok = (track.flag == "ok").to_numpy(), (clip.flag == "ok").to_numpy()
    touches = np.abs(clip.x_px.to_numpy() - 301.5) < 20.2 + 6 + 1
    assert (ok & touches).sum() <= 4, (ok & touches).sum()
    far = np.abs(clip.x_px.to_numpy() - 301.5) > 20.2 + 6 + 4
    assert (ok & far).sum() >= 0.99 * far.sum()  # the post costs only the frames it touches
    dx, dy = (track.x_px - clip.x_px).to_numpy(), (track.y_px - clip.y_px).to_numpy()
    both = ok & clip_ok
    off = np.hypot(dx - np.median(dx[both]), dy - np.median(dy[both]))[both]
    assert off.max() < 0.7, off.max()


def test_a_white_dot_on_the_apple_leaves_the_body_it_is_on_unbiased(tmp_path):
    """The clip with a white sticker (radius 5 px) painted on the apple 5 px below its centre (``real_variants``:
    ``dot_on_bob``, as the held-out clock pendulums have a dot on each bob), config defaults: the body is followed
    (the dot as a marker is usable in under 95 % of the frames: its ring lies on the apple's shading and near its
    edge). Until 2026-12-03 the dot was a hole in the dark silhouette: the body's inner radius came out halved, and
    with it the opening that cuts the thread, so the apple's stem was followed in some frames and not others:
    97.5 % of the frames ok, 0.78 px RMS off the apple's centre where the dot was painted (its pixels' centroid,
    weighted by their share of apple), 2 px at the swing's ends (0.2° on its arm). The hole is now filled (a
    marking: under a tenth of the body): 99.85 % ok, 0.20 px (the clip without the dot, tracked alike: 0.20 px,
    its silhouette's centroid not quite that centre)."""
    shared_file(APPLE_FILE)
    sys.path.insert(0, str(ROOT / "tests" / "benchmarks"))
    from real_variants import make

    from pendulum.tracking.method import track_trial

    video = make("dot_on_bob", tmp_path)
    body = track_trial(video, default_settings())
    assert body.attrs["method"]["used"] == "body"
    ok = (body.flag == "ok").to_numpy()
    assert ok.mean() >= 0.99, body.flag.value_counts()
    centre = np.loadtxt(video.with_suffix(".csv"), delimiter=",", skiprows=1)
    dx, dy = body.x_px.to_numpy() - centre[:, 0], body.y_px.to_numpy() - centre[:, 1]
    off = np.hypot(dx - np.median(dx[ok]), dy - np.median(dy[ok]))[ok]
    assert np.sqrt(np.mean(off**2)) <= 0.3 and np.percentile(off, 99) <= 0.8, (np.sqrt(np.mean(off**2)), off.max())


def test_two_pendulums_whose_bobs_meet_keep_each_its_own_track(tmp_path):
    """Two dotted apples hung 350 px apart (``real_variants``: ``two_pendulums_close_dots_start_px``), their bobs
    meeting at the inner ends of both swings, ``start_px`` at the left one's dot: the left one is followed through
    every meeting. Until 2026-12-03 the pair's centroid, while they touched, carried the prediction across, and
    the track went on with the right one for 1.8 s, 96.4 % of its frames ``ok``, its period within 0.2 %: a
    wrong record that passed the study's bar (a reviewer's variant). The body's own centre, the thickest point of
    the pair nearest the prediction, now carries it: 97.7 % ``ok``, every ``ok`` position on the left apple."""
    shared_file(APPLE_FILE)
    sys.path.insert(0, str(ROOT / "tests" / "benchmarks"))
    from real_variants import APPLE_START_PX, make

    from pendulum.tracking.method import track_trial

    video = make("two_pendulums_close_dots_start_px", tmp_path)
    settings = replace(default_settings(), start_px=(APPLE_START_PX[0], APPLE_START_PX[1] + 5.0))
    track = track_trial(video, settings)
    ok = (track.flag == "ok").to_numpy()
    assert ok.mean() >= 0.96, track.flag.value_counts()
    centre = np.loadtxt(video.with_suffix(".csv"), delimiter=",", skiprows=1)[: len(track)]
    off = np.hypot(track.x_px.to_numpy() - centre[:, 0], track.y_px.to_numpy() - centre[:, 1])
    assert np.max(off[ok]) <= 3.0, (np.argmax(np.where(ok, off, 0)), np.max(off[ok]))


def test_spinning_star_is_refused_by_the_tracks_job_with_its_track_shown(tmp_path, monkeypatch):
    """The frames and tracks jobs' own scripts on the star: a failed tracks document whose error leads with what it
    is not (a rigid pendulum) and says why, and a sheet with the whole reason above the track it was measured from
    (until 2026-12-02 the sheet was the reason alone, cut after six lines)."""
    shared_file(STAR_FILE)
    import json
    import runpy

    import cv2

    monkeypatch.syspath_prepend(str(ROOT / "workflow" / "scripts"))
    config = yaml.safe_load((ROOT / "config.yaml").read_text())
    scripts = ROOT / "workflow" / "scripts"
    names = (("timeline", "t.csv"), ("summary", "f.json"), ("contact_sheet", "c.png"))
    frames = {k: str(tmp_path / n) for k, n in names}
    tiles = {"tiles": config["frames"]["contact_sheet_tiles"]}
    sm = FakeSnakemake({"video": str(STAR)}, frames, str(tmp_path / "f.log"), tiles)
    runpy.run_path(str(scripts / "frames.py"), init_globals={"snakemake": sm})
    tracks = {k: str(tmp_path / n) for k, n in (("track", "s.csv"), ("summary", "s.json"), ("sheet", "s.png"))}
    inputs = {"video": str(STAR), "frames_summary": frames["summary"], "contact_sheet": frames["contact_sheet"]}
    sm = FakeSnakemake(inputs, tracks, str(tmp_path / "t.log"), {"tracking": config["tracking"]})
    runpy.run_path(str(scripts / "tracks.py"), init_globals={"snakemake": sm})
    document = json.loads(Path(tracks["summary"]).read_text())
    assert document["status"] == "failed" and document["failed_stage"] == "tracks"
    assert document["error"].startswith(f"{STAR}: not a rigid pendulum about a fixed pivot (an object that spins")
    assert "off the best circle" in document["error"] and document["path"]["not_a_pendulum"]
    sheet, contact = cv2.imread(tracks["sheet"]), cv2.imread(frames["contact_sheet"])
    assert sheet.shape[1] == contact.shape[1] and sheet.shape[0] >= contact.shape[0] + 200  # the reason, then the sheet
    banner_rows = sheet.shape[0] - contact.shape[0]
    assert (sheet[banner_rows:] != contact).any()  # the track drawn over it


def test_zero_crossing_period_is_exact_on_a_cosine():
    t = np.arange(0, 20, 1 / 60)
    theta = 0.3 * np.cos(2 * math.pi * t / 2.078 + 0.4) + 0.01
    assert zero_crossing_period(t, theta) == pytest.approx(2.078, rel=1e-5)
    gappy = np.where(np.isin(np.floor(t / 2.078), [2, 5, 6]) & (np.abs(theta - 0.01) < 0.1), np.nan, theta)
    assert zero_crossing_period(t, gappy) == pytest.approx(2.078, rel=1e-5)  # three crossings flagged


# The real clip turned into footage filmed other ways (tests/benchmarks/real_variants.py): each case here was
# wrong before this test. Expected: (least share of frames ok, the vertical in degrees or None when it cannot be
# estimated). Upside down, the path crossed ±180° where atan2 wraps: the vertical came out -1.5° and the period
# 8.8 % short, silently. At 15 fps the apple taken as a marker disk was usable in 94.5 % of the frames (its
# turning points flagged) and the body was not tried. With the swing leaving the frame at one end, the body was
# refused (its size learnt from the first frame, where it is cut by the border) and the vertical was estimated
# from turning points that were where the body left the frame (1.4° off). Before a soft dark band on the wall
# (a shelf's shadow the swing crosses), the body's silhouette broke up where its contrast fell to a third (the
# body is now found again above a quarter of its own contrast there). The apple made a two-tone ball (its upper
# half bright and patterned) before that band was refused ("the body covers the same place in most frames"):
# its silhouette, smaller in the band, was taken for a scene that holds the body. Until 2026-11-27 (session 11)
# these two variants darkened the apple's lighter parts with the wall (its share of apple was 0.70–1.0 inside it),
# and the two-tone ball was painted over the banded frames (its halves split where the band had moved the apple's
# centroid): easier, and other, than the scenes they stand for. With the body before the band lit, the apple's
# lighter parts come within 12 grey levels of the band's wall and those frames are flagged (93.3 % ok, the flagged
# positions 1.9 px off): below the 95 % issue 23 asks of a held-out clip. The bars are what is measured, less a
# margin, so that a change that loses frames fails here.
# Under a light that flickers at 100 Hz, filmed at 60 fps, bands of ±12 % of the brightness roll down the frame:
# the scene's noise read 18.5 grey levels, only the apple's darkest part stood above 5σ, and 93.2 % of the frames
# were ok at 0.039° (2026-12-03); each sample's rows are now brought to one exposure and the window's offset is a
# line in the row (99.85 %, 0.006°).
# Two pendulums side by side with a white dot on each apple, start_px at the left one's dot (as the held-out clock
# pendulums): its body followed, 97.98 % ok until 2026-12-03, the dot a hole that halved the body's inner radius and
# let the stem in and out of the silhouette (test_a_white_dot_on_the_apple_leaves_the_body_it_is_on_unbiased).
# Filmed in colour (a phone's video is), the two-tone ball with a dark blue lower half before the band (as the
# held-out clip) is measured by its colour (pendulum.tracking.colour): 99.9 % ok, where its brightness
# silhouette gives 96.6 % and is 21 % smaller mid-swing (the apple before the band in colour: 93.5 -> 99.85 %,
# in the study only; tests/test_colour_view.py checks the colour view against truth).
# The grey apple before the band: 93.6 % ok until 2026-12-06, its silhouette losing its part over the band; with
# the wall's gain (pendulum.tracking.body_scene.wall_gain) 98.5 %, and 99.85 % for the grey two-tone ball.
SHORT_OF: dict[str, float] = {}  # issue 23's share of usable frames, not yet met by these variants
BY_COLOUR = {"two_tone_shadow_band_colour"}
REAL_VARIANTS = {
    "shadow_band": (97.5, 0.0),
    "two_tone_shadow_band": (99.0, 0.0),
    "two_tone_shadow_band_colour": (99.0, 0.0),
    "upside_down": (99.0, 180.0),
    "sideways": (99.0, -90.0),
    "15fps": (99.0, 0.0),
    "mains_flicker": (99.0, 0.0),
    "swing_leaves_the_frame": (80.0, None),
    "two_pendulums_dots_start_px": (99.0, 0.0),
}


def test_a_knocked_camera_that_turned_is_found_from_the_swings_centre_and_its_turn_taken_out(tmp_path):
    """The apple clip's camera knocked at 10 s: the picture turned by 1° about its centre and moved by (3, −2) px, with
    a 7 Hz ring (``knocked_roll``, a reviewer's variant). The pivot's step (6 px) was 4.4 of its standard errors on
    this clip's own 0.4 px departure, where 5 are asked, so a creep took it in, and the turn stayed in θ: 0.49° RMS
    off the clip's own record, 0.95° at worst. The swing's centre in the picture steps at the knock (a turning camera
    moves gravity's direction there): the knock is sought where it stepped, and its turn taken out of θ."""
    shared_file(APPLE_FILE)
    sys.path.insert(0, str(ROOT / "tests" / "benchmarks"))
    from real_variants import judge

    row = judge("knocked_roll", tmp_path)
    assert row["knock_s"] is not None and 9.9 <= row["knock_s"] <= 10.8, row
    assert row["turn_deg"] is not None and abs(abs(row["turn_deg"]) - 1.0) <= 0.1, row
    assert abs(row["period_err_pct"]) <= 0.3 and row["noise_deg"] <= 0.03 and row["ok%"] >= 99.0, row


def test_a_two_tone_ball_turning_on_its_string_is_measured_by_its_outlines_centre(tmp_path):
    """The apple clip, its apple painted out and a sphere of its size drawn at its centre: a two-tone ball, its top
    patterned as the wall's grey and its lower half dark blue, its seam tilted 25° from level and the ball turning on
    its string by ±150° (``two_tone_turning_shadow_band_colour``, as reviewers imitated a held-out clip), before the
    study's soft dark band, in colour. Its blue half's centroid wandered by up to 4 px as it turned: the path 4.1 px
    RMS off any circle, refused as "not a rigid pendulum" (the study's θ 0.59° RMS off the clip's own record). Its
    outline's centre: within 0.5 px RMS of the ball's drawn centre (measured 0.27 px), the path a pendulum's."""
    shared_file(APPLE_FILE)
    sys.path.insert(0, str(ROOT / "tests" / "benchmarks"))
    from real_variants import ball_centres, make

    from pendulum.tracking.method import track_trial
    from pendulum.tracking.path_shape import path_departure

    track = track_trial(make("two_tone_turning_shadow_band_colour", tmp_path), default_settings())
    centre = track.attrs["body"]["centre"]
    assert centre["by"] == "outline" and track.attrs["body"]["view"] == "colour", centre
    assert centre["unexplained_rms_px"]["silhouette"] >= 2.0, centre  # what the centroid gave
    ok = track[track.flag == "ok"]
    assert len(ok) >= 0.98 * len(track), track.flag.value_counts()
    truth = ball_centres()[ok.frame.to_numpy()]
    error = ok[["x_px", "y_px"]].to_numpy() - truth
    error -= np.median(error, axis=0)
    assert np.sqrt(np.mean(np.sum(error**2, axis=1))) <= 0.5
    _, path = path_departure(track)
    assert not path["not_a_pendulum"], path["verdict"]


@pytest.mark.slow
def test_a_body_held_by_hand_before_a_darker_band_is_measured_against_the_wall_behind_it(tmp_path):
    """The grey apple before the band (``shadow_band``) held by a hand for its first 1.5 s (``hand_release``): the
    body's grey and the wall behind it are taken from a sample that shows it as the clip usually does (the first
    frame's silhouette is the apple with the hand), so the band is scaled out as without the hand. Before: no wall
    gain where a hand held the first frame (1,215 of the 1,296 frames not held ok, 93.7 %); measured 1,290 (99.5 %)."""
    shared_file(APPLE_FILE)
    sys.path.insert(0, str(ROOT / "tests" / "benchmarks"))
    from real_variants import APPLE_FPS, _hand_release, _shadow_band

    from pendulum.camera.video import iter_luma
    from pendulum.synthetic.experiment import write_video
    from pendulum.tracking.method import track_trial

    video = tmp_path / "held_before_band.mp4"
    write_video(
        _hand_release(_shadow_band([image.copy() for _, _, image in iter_luma(APPLE)])),
        video,
        APPLE_FPS,
        18,
        "veryfast",
    )
    track = track_trial(video, default_settings())
    free = track[track.flag != "held"]
    assert (free.flag == "ok").mean() >= 0.98, track.flag.value_counts().to_dict()
    assert track.attrs["body"]["wall_gain"] < 0.5, track.attrs["body"]


# the grey and the colour two-tone ball share their luma (made once per process): run on one worker
SHARED_LUMA = pytest.mark.xdist_group("two_tone_before_band")


@pytest.mark.parametrize(
    "variant", [pytest.param(v, marks=SHARED_LUMA) if v.startswith("two_tone") else v for v in sorted(REAL_VARIANTS)]
)
def test_the_apple_filmed_other_ways(variant, tmp_path):
    """The same period (within 0.3 %) and record noise (≤ 0.03°) as the clip itself; the frames with the body partly
    out of view flagged ``edge``; the vertical found, or said not to be found. 50 of the study's 51 variants pass."""
    shared_file(APPLE_FILE)
    sys.path.insert(0, str(ROOT / "tests" / "benchmarks"))
    from real_variants import judge

    least_ok, vertical = REAL_VARIANTS[variant]
    row = judge(variant, tmp_path)
    assert row["ok%"] >= least_ok, row
    assert row["view"] == ("colour" if variant in BY_COLOUR else "brightness"), row
    # a known shortfall that a change mends must raise its bar (and the docs' figure) with it
    assert row["ok%"] < SHORT_OF.get(variant, math.inf), f"{variant} now meets {SHORT_OF[variant]} %: raise its bar"
    assert abs(row["period_err_pct"]) <= 0.3, row
    assert row["noise_deg"] <= 0.03, row
    if vertical is None:
        assert not row["vertical_estimated"] and row["edge_pct"] >= 10, row
    else:
        assert row["vertical_estimated"], row
        assert abs((row["vertical_deg"] - vertical + 180.0) % 360.0 - 180.0) <= 5.0, row


def test_the_apples_unexplained_residual_is_placed_by_harmonic_of_its_swing(apple):
    """The apple's record with the rig values a user would give it (0.18 kg weighed, the string's 1.04 m from its
    period, a 7.5 cm apple in air): no candidate removes the 0.24° the quadratic-drag fit leaves (80× the record's
    noise). Where that residual lies is said: mostly at the swing frequency, changing slowly over the record (measured
    65 % of its power below 3½ cycles per swing), and there 94 % in the swing's timing, not its amplitude: the swing
    runs ahead of and behind the model by 4.0 ms RMS (a quarter of a frame: the phone's frame times, whose slips the
    tracks stage found and put right, or a period that changes); and at twice it (23 %), the second harmonic the
    angles stage measured on its own (the swing plane turned against the image plane); 3 % is a slow drift of the
    zero."""
    from pendulum.discovery.selection import Discovery
    from pendulum.fit.records import FitSettings, load_record

    _, _, table, info = apple
    settings = FitSettings()
    record = load_record(table, "apple", APPLE_IN_AIR, settings, tolerances={}, angle_info=info.to_dict())
    candidates = ["linear_damping", "coulomb_friction", "history_force"]
    discovery = Discovery([record], ["apple"], ["quadratic_drag"], candidates, settings)  # its noise: the record's
    document = discovery.run()
    pattern = document["residual_pattern"]
    assert document["unexplained"] and document["named_effects"] == [], document["verdict"]
    assert pattern["dominant"] == ["swing_steady", "even_harmonic"], pattern
    assert 0.5 <= pattern["shares"]["swing_steady"] <= 0.8 and 0.15 <= pattern["shares"]["even_harmonic"] <= 0.35
    assert pattern["steady_in_timing"] >= 0.9 and 3.0 <= pattern["timing_wander_ms"] <= 6.0, pattern
    assert "in its timing" in document["verdict"] and "at twice the swing frequency" in document["verdict"]
