"""Acceptance: rendered trials with real-world faults, tracked with no marker hints.

Both polarities, marker radii 5 and 20 px, background stripes, a second moving disk of
the marker's own size and grey, and letterbox/pillarbox borders (synthetic_scene.Faults). The
tracker is given nothing (polarity auto, radius null): detection must find the marker;
angles computed as the workflow does (pivot pooled from the track, then
``angles_from_track``) must be within 0.05° RMS of the truth with ≥ 95 % of the frames
after release usable.
"""

import math
from dataclasses import replace

import numpy as np
import pandas as pd
import pytest

from pendulum.angles.geometry import estimate_rig_geometry
from pendulum.angles.record import angles_from_track
from pendulum.synthetic.experiment import generate_trial, release_time_s
from pendulum.synthetic.specs import TrialSpec
from pendulum.tracking.marker import track_video
from pendulum.tracking.settings import TrackerSettings

RIG = {"mass_kg": 2.0, "length_m": 0.3, "frontal_area_m2": 0.012, "displaced_volume_m3": 0.0005}
TRUTH = {"added_mass_kg": 0.6, "drag_area_m2": 0.01, "linear_damping_nm_s": 0.02, "friction_torque_nm": 0.005}

TRIALS = {
    # dark 5 px marker, vertical stripes, a disk moving back and forth on a line, letterbox bands top and bottom
    # (the lowest point of the swing 27 px above the bottom band)
    "dark_r5": dict(
        release_deg=25.0,
        seed=4101,
        camera=dict(pivot_px=(320.3, 20.6), marker_arm_px=275.0, marker_radius_px=5.0, polarity="dark", roll_deg=0.4),
        faults=dict(
            stripes=dict(width_px=10, period_px=56, offset_px=3.5, level=120),
            letterbox=dict(top_px=16, bottom_px=36),
            second_object=dict(path="linear", start_px=[80, 120], end_px=[160, 260], period_s=1.9),
        ),
    ),
    # bright 20 px marker, slanted stripes, a rising wobbling bubble, pillarbox bands left and right
    "bright_r20": dict(
        release_deg=-25.0,
        seed=4202,
        camera=dict(
            pivot_px=(320.3, 10.6), marker_arm_px=300.0, marker_radius_px=20.0, polarity="bright", roll_deg=-0.5
        ),
        faults=dict(
            stripes=dict(width_px=14, period_px=70, offset_px=2.5, level=120, angle_deg=20.0),
            letterbox=dict(left_px=40, right_px=40),
            second_object=dict(path="bubble", start_px=[560, 330], end_px=[540, 40], period_s=2.5, wobble_px=6),
        ),
    ),
}


def _spec(name: str) -> TrialSpec:
    values = TRIALS[name]
    camera = dict(width_px=640, height_px=360, fps=30.0, exposure_subsamples=6, **values["camera"])
    return TrialSpec.from_mapping(
        dict(
            name=name,
            release_deg=values["release_deg"],
            seed=values["seed"],
            hold_s=0.5,
            duration_s=6.0,
            rig=RIG,
            truth=TRUTH,
            effects=["quadratic_drag", "linear_damping", "coulomb_friction"],
            camera=camera,
            faults=values["faults"],
        )
    )


@pytest.fixture(scope="module")
def rendered(tmp_path_factory):
    out = tmp_path_factory.mktemp("faults")
    cache = {}

    def get(name):
        if name not in cache:
            spec = _spec(name)
            generate_trial(spec, out, out, progress=None)
            cache[name] = (spec, out / f"{name}.mp4", pd.read_csv(out / f"{name}.csv"))
        return cache[name]

    return get


@pytest.mark.slow
@pytest.mark.parametrize("name", list(TRIALS))
def test_faulty_render_is_tracked_without_hints(rendered, name):
    """Measured (2026-11-28): dark_r5 100 % usable, 0.0159° RMS (max 0.058°); bright_r20 100 %, 0.0119° (max
    0.029°; 0.0066° on its earlier render of 193 sub-exposures per frame, a bubble's wrap then counted as a
    streak; 8 now, 25 s less to render); start within 0.05 px, radius within 1 %. The previous tracker with the
    old config defaults (bright, 10 px) found no marker in either; told polarity and radius, it refused dark_r5
    ("two marker-like spots": the line mover) and kept 85 % of bright_r20 (the window touching the frame's edge:
    "edge")."""
    spec, video, truth = rendered(name)
    cam = spec.camera
    track = track_video(video, TrackerSettings(polarity="auto", marker_radius_px=None))
    found = track.attrs["detection"]
    assert found["polarity"] == cam.polarity
    assert found["marker_radius_px"] == pytest.approx(cam.marker_radius_px, rel=0.1)
    start = (truth.marker_x_px[0], truth.marker_y_px[0])
    assert math.dist(found["start_px"], start) <= 0.5
    geometry = estimate_rig_geometry({name: track})
    table, _ = angles_from_track(
        track, pivot_px=geometry["pivot_px"], vertical_deg=cam.roll_deg, length_m=RIG["length_m"], source=name
    )
    true = truth.set_index("frame").loc[table.frame]
    ok = table.flag.to_numpy() == "ok"
    err_deg = np.degrees(table.theta_rad.to_numpy()[ok] - true.theta_rad.to_numpy()[ok])
    rms = float(np.sqrt(np.mean(err_deg**2)))
    print(f"{name}: usable {ok.mean():.3f}, angle RMS {rms:.4f}°, max {np.abs(err_deg).max():.4f}°")
    assert ok.mean() >= 0.95
    assert rms <= 0.05


@pytest.mark.slow
def test_a_small_marker_blurred_over_44_px_is_tracked_without_hints(tmp_path):
    """A dark 6 px marker, shutter open the whole frame interval, a 60° release of a short rig at
    25 fps: streaks up to 45 px. Measured: 97 % of the record usable, 0.016° RMS, nothing lost
    (before: the thresholded coarse centroid found no pixel above half the marker's level on the
    dimmed streak and the track was lost for 30 frames after each fast pass)."""
    spec = TrialSpec.from_mapping(
        dict(
            name="streak",
            release_deg=60.0,
            seed=77,
            hold_s=0.5,
            duration_s=6.0,
            rig=RIG,
            truth=TRUTH,
            effects=["quadratic_drag", "linear_damping", "coulomb_friction"],
            camera=dict(
                width_px=800,
                height_px=450,
                fps=25.0,
                pivot_px=(400.3, 12.6),
                marker_arm_px=350.0,
                marker_radius_px=6.0,
                polarity="dark",
                exposure_fraction=1.0,
                exposure_subsamples=6,
            ),
        )
    )
    generate_trial(spec, tmp_path, tmp_path, progress=None)
    truth = pd.read_csv(tmp_path / "streak.csv")
    assert truth.streak_px.max() >= 44.0
    track = track_video(tmp_path / "streak.mp4", TrackerSettings(polarity="auto", marker_radius_px=None))
    assert (track.flag == "lost").sum() == 0
    geometry = estimate_rig_geometry({"streak": track})
    table, _ = angles_from_track(
        track, pivot_px=geometry["pivot_px"], vertical_deg=0.0, length_m=RIG["length_m"], source="streak"
    )
    true = truth.set_index("frame").loc[table.frame]
    ok = table.flag.to_numpy() == "ok"
    err_deg = np.degrees(table.theta_rad.to_numpy()[ok] - true.theta_rad.to_numpy()[ok])
    assert ok.mean() >= 0.95
    assert np.sqrt(np.mean(err_deg**2)) <= 0.05


def test_after_lost_frames_the_window_follows_the_arc_and_stays_inside_the_swing():
    """The prediction after a gap: on the circle, at the last angular velocity, never past the swing
    seen so far (+ 2 marker radii), however long the gap (the old linear guess ran off the arc)."""
    from types import SimpleNamespace

    from pendulum.tracking.marker_arc import MarkerArc

    pivot, arm, radius = (300.0, 20.0), 250.0, 8.0
    arc = MarkerArc(SimpleNamespace(pivot_px=pivot, arm_px=arm), radius)
    angles = 0.3 * np.cos(np.linspace(0, 2 * np.pi, 40))  # one swing of ±0.3 rad
    for a in angles:
        arc.add(pivot[0] + arm * math.sin(a), pivot[1] + arm * math.cos(a))
    # moving towards +angle at 0.02 rad per frame from 0.25 rad
    (x0, y0), (x1, y1) = [(pivot[0] + arm * math.sin(a), pivot[1] + arm * math.cos(a)) for a in (0.23, 0.25)]
    near = arc.predict(x1, y1, x0, y0, gap=2)
    assert math.dist(near, (pivot[0] + arm * math.sin(0.29), pivot[1] + arm * math.cos(0.29))) <= 1e-6
    for gap in (5, 20, 200):
        x, y = arc.predict(x1, y1, x0, y0, gap=gap)
        assert math.hypot(x - pivot[0], y - pivot[1]) == pytest.approx(arm)
        assert math.atan2(x - pivot[0], y - pivot[1]) <= 0.3 + 2 * radius / arm + 1e-9


def _marker_on_body(extra, r=12.0, cx=70.3, cy=60.6):
    """A bright marker (235) of radius r on a body (55) reaching r + 8 px, scene 40; ``extra(img, when)``
    draws behind the body (when="back") or in front of everything ("front"); noise σ = 2."""
    from pendulum.synthetic.scene import draw_disk

    img = np.full((140, 140), 40.0, np.float32)
    extra(img, "back")
    img[int(cy - r - 8) : int(cy + r + 9), int(cx - r - 8) : int(cx + r + 9)] = 55.0
    draw_disk(img, cx, cy, r, 235.0)
    extra(img, "front")
    noise = np.random.default_rng(1).normal(0.0, 2.0, img.shape)
    return np.clip(np.rint(img + noise), 0, 255).astype(np.uint8)


def test_the_centroid_checks_see_the_marker_window_only():
    """The checks behind "occluded" look inside the linear centroid's own capsule (marker + 2.5 px).

    A second disk of the marker's grey outside the body (its edge 22 px from the centre: inside the old
    thresholded centroid's ROI of 2r + 4 px, beyond the capsule) and a stripe of a grey above the threshold
    along the body's edge leave the centroid exact and no longer flag it (the old ROI-wide thresholded
    centroid disagreed by 0.81 and 2.7 px: "occluded", seeds 1035/1037/7035 of detection_study). What
    biases it is still flagged: an occluder of a grey between the marker's and the body's over the
    marker's edge (centroids disagree by 0.92 px), and a disk of the marker's grey reaching into the
    margin beyond its edge, which the thresholded centroid cannot tell (it shifts both alike) but the
    same centroid in a mask 1.5 px tighter does (0.41 px; the bias is 0.62 px)."""
    from pendulum.synthetic.scene import draw_disk
    from pendulum.tracking.centroids import measure_marker

    r, cx, cy = 12.0, 70.3, 60.6
    settings = TrackerSettings(marker_radius_px=r)
    limit = settings.max_centroid_disagreement_px

    def measure(extra):
        m = measure_marker(_marker_on_body(extra, r, cx, cy), cx + 0.4, cy - 0.3, settings, marker_level=235.0)
        return m, math.hypot(m.x - cx, m.y - cy)

    beyond = {
        "second disk": lambda img, when: when == "back" and draw_disk(img, cx - 6, cy + 38, 16.0, 235.0),
        "stripe": lambda img, when: when == "back" and img.__setitem__(np.s_[int(cy + r + 9) : int(cy + r + 17)], 180),
    }
    for name, extra in beyond.items():
        m, error = measure(extra)
        assert error <= 0.01, name
        assert m.disagreement_px <= 0.1 and m.margin_shift_px <= 0.05, name
    m, error = measure(lambda img, when: when == "front" and draw_disk(img, cx + 12, cy + 4, 6.0, 145.0))
    assert m.disagreement_px > limit
    m, error = measure(lambda img, when: when == "front" and draw_disk(img, cx + r + 9, cy + 3, 9.0, 235.0))
    assert error > settings.max_margin_shift_px  # a real bias ...
    assert m.margin_shift_px > settings.max_margin_shift_px  # ... flagged
    assert m.disagreement_px <= limit  # (which the thresholded centroid misses)


def _swing_with_a_passer_by(path, hide=range(100, 106), below_px=25.0):
    """A bright 10 px marker swinging ±0.2 rad on a 300 px arm (period 2.5 s, 30 fps, 6 s), hidden in
    frames ``hide``; a disk of its grey, radius 11 px, passes ``below_px`` below the marker's position at
    the first hidden frame, moving 1 px per frame along x, in frames 92–139. Returns the marker's truth."""
    from pendulum.synthetic.experiment import write_video
    from pendulum.synthetic.scene import draw_disk

    fps, n, r = 30.0, 180, 10.0
    theta = 0.2 * np.cos(2 * np.pi * np.arange(n) / fps / 2.5)
    mx, my = 320.0 + 300.0 * np.sin(theta), -100.0 + 300.0 * np.cos(theta)
    k0 = hide[0]
    rng = np.random.default_rng(5)
    frames = []
    for i in range(n):
        img = np.full((360, 640), 40.0, np.float32)
        if k0 - 8 <= i < k0 + 40:
            draw_disk(img, mx[k0] + (i - k0), my[k0] + below_px, 1.1 * r, 235.0)
        if i not in hide:
            draw_disk(img, mx[i], my[i], r, 235.0)
        frames.append(np.clip(np.rint(img + rng.normal(0.0, 2.0, img.shape)), 0, 255).astype(np.uint8))
    write_video(frames, path, fps, 18, "veryfast")
    return mx, my


@pytest.mark.slow
def test_flagged_frames_off_the_arc_do_not_steer_the_window(tmp_path):
    """While the marker is hidden (6 frames) the window finds a slightly larger disk 25 px below its arc:
    flagged (its signal and width are not the marker's), but off the circle the track has learnt, so it
    does not steer the next prediction, and the window finds the marker when it reappears. Measured:
    the 6 hidden frames flagged, the other 174 ok, 0.03 px RMS. Before, each flagged frame moved the
    window with the disk: 38 frames measured 20–52 px off the marker (flagged), 73 % usable."""
    mx, my = _swing_with_a_passer_by(tmp_path / "passer_by.mp4")
    track = track_video(tmp_path / "passer_by.mp4", TrackerSettings(marker_radius_px=10.0, start_px=(mx[0], my[0])))
    error = np.hypot(track.x_px - mx, track.y_px - my).to_numpy()
    ok = (track.flag == "ok").to_numpy()
    assert not ok[100:106].any()
    assert ok[106:].all()  # back on the marker as soon as it shows
    assert ok.mean() >= 0.95
    assert np.sqrt(np.mean(error[ok] ** 2)) <= 0.06
    assert error[ok].max() <= 0.25


@pytest.mark.slow
def test_a_moving_object_off_the_arc_is_not_a_static_distractor(tmp_path):
    """Scene 7009 of detection_study (``--duration 6 --margin 4``): at the first acquisition a second disk
    of the marker's grey sits off the marker's arc; it moves, so the static scene does not hold it and it
    must not become a permanent distractor (before, every later pass of the marker near that point was
    flagged "occluded": 50 % usable). Measured: 100 % of the frames after release usable, 0.06 px RMS."""
    rig = {"mass_kg": 5.0, "length_m": 0.9, "frontal_area_m2": 0.04, "displaced_volume_m3": 0.003}
    truth_values = {"added_mass_kg": 3.0, "drag_area_m2": 0.03, "linear_damping_nm_s": 0.2, "friction_torque_nm": 0.03}
    spec = TrialSpec.from_mapping(
        dict(
            name="static_or_not",
            release_deg=-19.263,
            seed=7009,
            hold_s=1.0,
            duration_s=6.0,
            rig=rig,
            truth=truth_values,
            effects=["quadratic_drag", "linear_damping", "coulomb_friction"],
            camera=dict(
                width_px=640,
                height_px=360,
                fps=30.0,
                pivot_px=(307.19, -13.67),
                marker_arm_px=254.5,
                marker_radius_px=10.79,
                polarity="bright",
                roll_deg=-0.93,
                exposure_fraction=0.5,
            ),
            faults=dict(
                stripes=dict(width_px=21.45, period_px=68.86, offset_px=39.08, level=169.74, angle_deg=22.91),
                letterbox=dict(left_px=44, right_px=52),
                second_object=dict(
                    path="linear", start_px=[270.78, 259.95], end_px=[368.26, 272.24], period_s=3.054, radius_px=13.59
                ),
            ),
        )
    )
    generate_trial(spec, tmp_path, tmp_path, progress=None)
    truth = pd.read_csv(tmp_path / "static_or_not.csv")
    track = track_video(tmp_path / "static_or_not.mp4", TrackerSettings(polarity="auto", marker_radius_px=None))
    after = (truth.time_s >= release_time_s(spec)).to_numpy()
    ok = (track.flag == "ok").to_numpy()
    error = np.hypot(track.x_px - truth.marker_x_px, track.y_px - truth.marker_y_px).to_numpy()
    assert ok[after].mean() >= 0.95
    assert np.sqrt(np.mean(error[ok] ** 2)) <= 0.1


def _swing_changing_along_the_arc(path, stripe_rad=None, n=150):
    """A bright marker swinging ±0.3 rad on a 280 px arm (period 2.5 s, 30 fps, released from −0.3 rad
    after 0.5 s at rest) whose contrast and area both grow by 10 % per 0.3 rad of angle: its signal
    (contrast × area) is 0.81 × at −0.3 rad, 1.21 × at +0.3 rad that at rest (a lens, vignetting), its
    width² 0.9 … 1.1 ×. ``stripe_rad``: a band 80 px wide across the arc at that angle dims everything
    behind it by 20 % (a shadow crossing). Returns the marker's truth (x, y) and angle."""
    from pendulum.synthetic.experiment import write_video
    from pendulum.synthetic.scene import draw_disk

    fps, amp, arm, pivot = 30.0, 0.3, 280.0, (320.0, 20.0)
    t = np.arange(n) / fps
    theta = -amp * np.cos(2 * np.pi * np.clip(t - 0.5, 0.0, None) / 2.5)
    mx, my = pivot[0] + arm * np.sin(theta), pivot[1] + arm * np.cos(theta)
    yy, xx = np.mgrid[0:360, 0:640]
    scene = (25.0 + 30.0 * xx / 640 + 10.0 * (yy // 40 % 2)).astype(np.float32)  # a wall, not letterbox bands
    shade = np.ones((360, 640), np.float32)
    if stripe_rad is not None:  # distance from the ray at stripe_rad through the pivot
        across = (xx - pivot[0]) * math.cos(stripe_rad) - (yy - pivot[1]) * math.sin(stripe_rad)
        shade[np.abs(across) <= 40.0] = 0.8
    rng = np.random.default_rng(11)
    frames = []
    for i in range(n):
        grow = 1.0 + 0.1 * theta[i] / amp
        img = scene.copy()
        draw_disk(img, mx[i], my[i], 9.0 * math.sqrt(grow), 40.0 + 180.0 * grow)
        img *= shade
        frames.append(np.clip(np.rint(img + rng.normal(0.0, 2.0, img.shape)), 0, 255).astype(np.uint8))
    write_video(frames, path, fps, 18, "veryfast")
    return mx, my, theta


@pytest.mark.slow
def test_a_smooth_change_along_the_arc_is_not_glare_but_a_sudden_one_is_flagged(tmp_path):
    """The marker's signal changes by −19 … +21 % smoothly with its place on the arc (issue 12's GoPro:
    lens magnification, 0.80 … 1.01 of the area at rest): against a reference following the arc
    (fitted to the ok frames) every frame is ok and the centre within 0.1 px; against the first frames'
    reference (``reference_along_arc=False``) most of the swing is "glare"/"occluded". A 20 % dimming
    at one place (a shadow band across the arc at +0.15 rad) is still flagged on every pass while the
    marker is wholly inside it, and the frames outside stay ok."""
    from pendulum.tracking.detection import detect_marker

    settings = TrackerSettings(polarity="auto", marker_radius_px=None)
    mx, my, theta = _swing_changing_along_the_arc(tmp_path / "smooth.mp4")
    found = detect_marker(tmp_path / "smooth.mp4")
    track = track_video(tmp_path / "smooth.mp4", settings, detection=found)
    ok = (track.flag == "ok").to_numpy()
    error = np.hypot(track.x_px - mx, track.y_px - my).to_numpy()
    assert ok.mean() >= 0.95
    assert np.sqrt(np.mean(error[ok] ** 2)) <= 0.1
    old = track_video(tmp_path / "smooth.mp4", replace(settings, reference_along_arc=False), detection=found)
    assert (old.flag == "ok").mean() < 0.6

    mx, my, theta = _swing_changing_along_the_arc(tmp_path / "stripe.mp4", stripe_rad=0.15)
    track = track_video(tmp_path / "stripe.mp4", settings)
    ok = (track.flag == "ok").to_numpy()
    inside = np.abs(280.0 * np.sin(theta - 0.15)) <= 40.0 - 9.0 * 1.1 - 7.0  # mask and ring in the band
    clear = np.abs(280.0 * np.sin(theta - 0.15)) >= 40.0 + 9.0 * 1.1 + 7.0
    assert inside.sum() >= 6 and not ok[inside].any()
    assert ok[clear].mean() >= 0.95


def test_a_track_lost_to_occluded_flags_names_the_cause_and_the_remedy():
    """Most frames occluded (a new user's bare ball over stripes, 374 of 420): the message names both causes
    (covered, or the background behind the path) and the settings that decide, not just 'partly hidden'."""
    from pendulum.tracking.marker import unusable_reason

    message = unusable_reason({"ok": 40, "occluded": 374, "lost": 6}, 420)
    assert message.startswith("the marker is usable in only 40 of 420 frames (10 %; lost 6, occluded 374)")
    assert "background behind its path" in message and "plain background" in message
    assert "min_signal_ratio/max_signal_ratio in config.yaml" in message
    lost = unusable_reason({"ok": 40, "lost": 300, "occluded": 80}, 420)
    assert "out of view" in lost and "min_signal_ratio" not in lost
