"""Failure as data (per-trial status), outlying tracks in the pooled pivot, and singular-Jacobian warnings."""

import logging
import math
from types import SimpleNamespace

import numpy as np
import pandas as pd
import pytest

from pendulum.angles.geometry import (
    estimate_rig_geometry,
    off_rig_circle,
    pooled_pivot,
    trial_geometry,
    unlike_picture,
)
from pendulum.fit.checks import misfit_warning, rig_checks
from pendulum.fit.uncertainty import jacobian_rank_warnings
from pendulum.freeze import trial_outcomes
from pendulum.outcomes import (
    failure_summary,
    misfit_trials,
    rig_mismatch_trials,
    skipped_status,
    status_table,
    trial_status,
)
from pendulum.status import (
    UpstreamFailed,
    describe,
    failed,
    failure_image,
    require_ok,
    run_stage,
)
from pendulum.trials import ConfigError, Trial, split_skipped

LOG = logging.getLogger("test_status")


def run_and_capture(work):
    written = []
    ok = run_stage("tracks", LOG, work, written.append)
    return ok, written


def test_run_stage_records_bad_input_in_the_users_words():
    def work():
        raise ValueError("data/raw/x.mp4: no marker found in any frame")

    ok, written = run_and_capture(work)
    assert not ok
    assert written == [
        {"status": "failed", "failed_stage": "tracks", "error": "data/raw/x.mp4: no marker found in any frame"}
    ]


def test_run_stage_keeps_what_a_refusal_measured_as_data():
    from pendulum.fit.output_error import RigMismatch

    facts = {"rig_mismatch": [{"trial": "apple", "period_s": 2.06, "fastest_period_s": 3.238}]}

    def work():
        raise RigMismatch("trial apple: its period 2.06 s is shorter than its rig values allow", facts)

    ok, written = run_and_capture(work)
    assert not ok and written[0]["error"].startswith("trial apple: its period 2.06 s")
    assert written[0]["rig_mismatch"] == facts["rig_mismatch"]


def test_run_stage_calls_an_unexpected_error_a_bug():
    def work():
        return {}["missing"] + 1 if False else None.shape  # AttributeError

    ok, written = run_and_capture(work)
    assert not ok and written[0]["error"].startswith("internal error (AttributeError")


def test_an_upstream_failure_keeps_its_origin_and_message():
    document = failed("frames", "data/raw/x.mp4: not a video")

    def work():
        require_ok(document, "tracks")

    ok, written = run_and_capture(work)
    assert written == [document]
    assert run_stage("tracks", LOG, lambda: None, written.append) and len(written) == 1


def test_describe_joins_lines_and_names_types_of_bugs():
    assert describe(ValueError("a\n  b")) == "a b"
    assert describe(ZeroDivisionError("division by zero")).startswith("internal error (ZeroDivisionError")
    assert isinstance(UpstreamFailed("x", "y"), Exception)


def test_a_trial_whose_fit_failed_keeps_its_usable_frames_and_period_in_the_status_table():
    """Seven real and stand-in clips refused at the fit for the default rig's values (a reviewer's run, 2026-12-02):
    trials.csv said only 'failed', the terminal '8 of 13 trial(s) failed', where their tracks (99.4-99.9 % usable)
    and periods (within 0.11 % of the truth) stood; the periods were found 15,000 px down the report."""
    tracks = {"status": "ok", "flags": {"duplicate": 2, "held": 609, "ok": 1288}}  # held by hand: not counted
    angles = {"status": "ok", "period_s": 2.0781321}
    refused = failed("fit", "trial apple: its period 2.078 s as swung (2.059 s at small amplitude) is shorter …")
    documents = [("tracks", "t.log", tracks), ("angles", "a.log", angles)]
    documents += [(f"fit:{v}", f"{v}.log", refused) for v in ("linear", "quadratic")]
    row = trial_status("apple", "data/raw/apple.mov", "rig", documents)
    assert row["status"] == "failed" and row["stage"] == "fit (every variant)"
    assert row["ok_frames_pct"] == pytest.approx(100 * 1288 / 1290, abs=0.005) and row["period_s"] == 2.078132
    lost = trial_status("star", "data/raw/star.mov", "rig", [("tracks", "t.log", failed("tracks", "not a pendulum"))])
    assert lost["ok_frames_pct"] is None and lost["period_s"] is None
    table = status_table([row, lost])
    assert list(table.columns[5:7]) == ["ok_frames_pct", "period_s"]
    text = failure_summary(table)
    assert text.startswith("2 of 2 trial(s) failed; the report says why, trial by trial:\n  - apple, at fit (every")
    stand = "(its track and angle record stand: 99.84 % of frames usable, period 2.078 s as swung): trial apple"
    assert f"  - apple, at fit (every variant) {stand}" in text
    assert "  - star, at tracks: not a pendulum" in text


def test_a_trial_that_succeeded_carries_its_warnings_and_a_model_that_misses_it_is_named():
    """The real apple in its own air rig (a reviewer, 2026-12-02): trials.csv said `ok` while every variant's fit
    missed the record 78x its noise and its angle record carried a second harmonic; only the fits' summary said."""
    misses = (
        "trial apple: residual RMS 0.235° is 78× the record's noise (0.003°) and smooth: the model misses a "
        "systematic effect"
    )
    harmonic = "the angle record carries a second harmonic of 0.2°"
    documents = [
        ("frames", "f.log", {"status": "ok", "warnings": []}),
        ("tracks", "t.log", {"status": "ok", "flags": {"ok": 99, "duplicate": 1}, "body": {"warning": "smaller"}}),
        ("angles", "a.log", {"status": "ok", "period_s": 2.078, "warnings": [harmonic]}),
        ("fit:friction", "x.log", {"status": "ok", "warnings": ["friction_torque_nm is at its lower bound", misses]}),
        ("fit:quadratic", "q.log", {"status": "ok", "warnings": [misses]}),
    ]
    row = trial_status("apple", "data/raw/apple.mov", "air", documents)
    assert row["status"] == "ok" and row["n_warnings"] == 4
    assert row["warnings"].split(" | ") == [
        f"fit (every variant): {misses}",  # first: what a reader of the table must not miss
        "tracks: smaller",
        f"angles: {harmonic}",
        "fit:friction: friction_torque_nm is at its lower bound",
    ]
    fine = [
        (s, log, {**d, "warnings": d.get("warnings", [])[:1] if s == "fit:friction" else []}) for s, log, d in documents
    ]
    one = [d for d in documents if d[0] != "fit:friction"]  # a single variant: it is every variant
    rows = [row, trial_status("fine", "f", "air", fine), trial_status("one", "o", "air", one)]
    rows.append(trial_status("lost", "l", "air", [("tracks", "t.log", failed("tracks", "x")), *documents[2:]]))
    each = [  # every variant misses, each by its own figures (the demo's quadratic and linear variants: 215x, 91x)
        ("fit:linear", "l.log", {"status": "ok", "warnings": [misses.replace("78×", "91×")]}),
        ("fit:quadratic", "q.log", {"status": "ok", "warnings": ["drag at its bound", misses.replace("78×", "215×")]}),
    ]
    rows.append(trial_status("each", "e", "air", [*documents[:3], *each]))
    rows.append(
        trial_status("half", "h", "air", [*documents[:3], each[0], ("fit:quadratic", "q.log", {"status": "ok"})])
    )
    table = status_table(rows)
    assert table.loc[table.trial == "fine", "n_warnings"].item() == 2  # the silhouette and the bound
    said = table.set_index("trial").warnings["each"].split(" | ")
    assert said[0] == (
        "fit (every variant): each of the 2 misses the record (91–215× its noise): the model misses a systematic "
        "effect; it may bias the coefficients, and their intervals do not cover it"
    )
    assert said[3].startswith("fit:linear: trial apple: residual RMS 0.235° is 91×") and len(said) == 6, said
    assert misfit_trials(table) == ["apple", "each", "one"]  # not `half` (one variant fits); a failed trial is failed
    # the fits' own words (pendulum.fit.checks), not a copy of them, are what the table looks for
    t = np.arange(600) / 60.0
    theta = np.radians(20) * np.cos(2 * np.pi * t / 2.078) + np.random.default_rng(1).normal(0, 5e-5, t.size)
    record = SimpleNamespace(trial="apple", time_s=t, theta_rad=theta, noise_rad=None)
    (said,) = misfit_warning(record, np.radians(0.2) * np.sin(2 * np.pi * t / 2.078))
    real = [("angles", "a.log", {"status": "ok"}), ("fit:quadratic", "q.log", {"status": "ok", "warnings": [said]})]
    assert misfit_trials(status_table([trial_status("apple", "a", "air", real)])) == ["apple"]


def test_trials_whose_period_and_rig_values_disagree_are_listed_from_the_fits_own_words():
    """A slow-motion clip timed by its file (the demo swing 8 times too slow: an added mass 108 times the body's)
    and a period shorter than the rig allows: each listed for the run's last lines, from the warnings
    :func:`pendulum.fit.checks.rig_checks` writes; a trial whose fit only misses its record is not."""
    from pendulum.model.rig import Rig

    rig = Rig(mass_kg=3.53, length_m=0.76, frontal_area_m2=0.0322, displaced_volume_m3=0.0025)
    slow = rig_checks(rig, {"at_bound": False, "value": 382.0}, [{"period_s": 33.95}])
    fast = rig_checks(rig, {"at_bound": True, "value": 0.0}, [{"period_s": 2.0}])
    assert len(slow) == 1 and "capture_fps" in slow[0] and len(fast) == 1
    assert rig_checks(rig, {"at_bound": False, "value": 2.5}, [{"period_s": 4.25}]) == []
    rows = [
        trial_status(name, name, "paper", [("angles", "a.log", {"status": "ok"}), ("fit:q", "q.log", fit)])
        for name, fit in (
            ("slowmo", {"status": "ok", "warnings": slow}),
            ("short", {"status": "ok", "warnings": fast}),
            ("fine", {"status": "ok", "warnings": ["trial fine: residual RMS 0.4° misses a systematic effect"]}),
        )
    ]
    assert rig_mismatch_trials(status_table(rows)) == ["short", "slowmo"]


def test_a_trial_skipped_by_its_sidecar_is_listed_with_why_and_fails_nothing(tmp_path):
    trials = {
        "star": Trial("star", "video", "data/raw/star.mov", {"skip": " spins on its thread "}, "data/raw/star.yaml"),
        "apple": Trial("apple", "video", "data/raw/apple.mov", {"rig": "air"}, "data/raw/apple.yaml"),
        "demo": Trial("demo", "video", "data/raw/demo.mp4"),
        "late": Trial("late", "video", "data/raw/late.mp4", {"skip": False}, "data/raw/late.yaml"),
        "bare": Trial("bare", "video", "data/raw/bare.mp4", {"skip": True}, "data/raw/bare.yaml"),
    }
    kept, skipped = split_skipped(trials)
    assert sorted(kept) == ["apple", "demo", "late"]
    assert skipped.pop("bare")["reason"] == "skipped by data/raw/bare.yaml (no reason given)"
    blank = Trial("blank", "video", "data/raw/blank.mp4", {"skip": "  "}, "data/raw/blank.yaml")
    with pytest.raises(ConfigError, match=r"^data/raw/blank.yaml: skip is blank; write why"):
        split_skipped({"blank": blank})
    assert skipped == {
        "star": {"source": "data/raw/star.mov", "reason": "skipped by data/raw/star.yaml: spins on its thread"}
    }
    ok = trial_status("demo", "data/raw/demo.mp4", "rig", [("angles", "a.log", {"status": "ok"})])
    lost = trial_status("bad", "data/raw/bad.mp4", "rig", [("tracks", "t.log", failed("tracks", "not a video"))])
    star = skipped_status("star", **skipped["star"])
    table = status_table([ok, star])
    assert list(table.status) == ["ok", "skipped"] and failure_summary(table) is None and misfit_trials(table) == []
    text = failure_summary(status_table([ok, lost, star]))
    assert text.startswith(
        "1 of 2 trial(s) failed; the report and the other 1 trial(s)' results were built (1 more skipped by their "
        "sidecars):"
    )  # the skipped one said too (a fresh-eyes user, 2026-12-03: only the report listed it after a failed run)
    path = tmp_path / "trials.csv"
    status_table([ok, lost, star]).to_csv(path, index=False)
    outcomes = trial_outcomes(path)  # what a frozen folder's provenance says
    assert outcomes["ok"] == ["demo"] and [f["trial"] for f in outcomes["failed"]] == ["bad"]
    assert outcomes["skipped"] == [{"trial": "star", "reason": skipped["star"]["reason"]}]


def test_trial_status_names_the_stage_where_the_failure_arose():
    ok = {"status": "ok"}
    fit_failed = failed("fit", "record too short")
    geometry_failed = failed("geometry", "no usable track")
    rows = [
        trial_status("a", "data/raw/a.mp4", "rig", [("tracks", "logs/t/a.log", ok), ("angles", "logs/a/a.log", ok)]),
        trial_status(
            "b", "data/raw/b.mp4", "rig", [("angles", "logs/a/b.log", ok), ("fit:linear", "logs/f/b.log", fit_failed)]
        ),
        trial_status("c", "data/raw/c.mp4", "rig", [("angles", "logs/a/c.log", geometry_failed)]),
    ]
    table = status_table(rows[::-1])
    assert list(table.trial) == ["a", "b", "c"]
    assert list(table.status) == ["ok", "failed", "failed"]
    assert list(table.stage) == ["", "fit:linear", "geometry"]
    assert table.loc[1, "log"] == "logs/f/b.log"
    text = failure_summary(table)
    lines = text.splitlines()  # one line per failed trial, readable above Snakemake's own error
    assert lines[0] == "2 of 3 trial(s) failed; the report and the other 1 trial(s)' results were built:"
    assert lines[1:3] == ["  - b, at fit:linear: record too short", "  - c, at geometry: no usable track"]
    assert lines[-1].startswith("See results/status/trials.csv") and lines[-1].endswith("report.html.")
    assert not any("skip:" in line for line in lines)  # a fit's or the geometry's failure is mended, not skipped
    unreadable = trial_status("e", "data/raw/e.mp4", "rig", [("tracks", "logs/t/e.log", failed("tracks", "no body"))])
    lines = failure_summary(status_table([*rows, unreadable])).splitlines()
    assert "`skip: <why>` in its sidecar (data/raw/e.yaml for e, or the sidecar it already has)" in lines[-2]
    # two pendulums in view: the reason asks for start_px, which mends it; skipping it is not the advice (a reviewer)
    # (the tracks stage's own words in auto mode, marker and body tried)
    reason = (
        "x.mp4: neither a marker disk nor the body could be followed. Marker: two objects swing: a dark spot … Body: "
        "x.mp4: two moving objects of similar size in 47 of 63 sampled frames (in the first frame near (824, 195) and "
        "(78, 164) px): give start_px of the pendulum to follow in the trial's sidecar (its centre in the first frame)"
    )

    def at_tracks(trial, why):  # a trial the tracks stage refused, ``why``
        return trial_status(
            trial, f"data/raw/{trial}.mp4", "rig", [("tracks", f"logs/t/{trial}.log", failed("tracks", why))]
        )

    def summary_lines(*trials):
        return failure_summary(status_table([*rows, *trials])).splitlines()

    two = at_tracks("f", reason)
    lines = summary_lines(two)
    assert "is tracked once its sidecar gives its start_px (data/raw/f.yaml for f)" in lines[-2], lines
    assert not any("skip:" in line for line in lines), lines
    lines = summary_lines(unreadable, two)  # both: both pieces of advice
    assert "data/raw/f.yaml for f" in lines[-3] and "`skip: <why>` in its sidecar (data/raw/e.yaml" in lines[-2]
    # a clip with nothing swinging offers hints too (polarity, radius, start_px), but no value makes it a pendulum
    still = (
        "x.mp4: neither a marker disk nor the body could be followed. Marker: no object swings back and forth about a "
        "fixed point in 60 sampled frames; give tracking polarity, marker_radius_px and start_px (the marker's centre "
        "in the first frame) in the trial's sidecar. Body: x.mp4: nothing moves against the static scene in 60 of 60 "
        "sampled frames (noise 0.5 grey levels): no swinging body to track"
    )
    lines = summary_lines(at_tracks("g", still))
    assert "`skip: <why>` in its sidecar (data/raw/g.yaml for g" in lines[-2], lines
    assert not any("once its sidecar gives" in line for line in lines), lines
    refused = {
        "status": "failed",
        "failed_stage": "fit",
        "error": "trial d: its period 2.078 s as swung (2.06 s at small amplitude) …",
    }
    variants = [(f"fit:{v}", f"logs/fits/{v}/d.log", refused) for v in ("friction", "linear", "quadratic")]
    assert trial_status("d", "data/raw/d.mp4", "rig", [("angles", "logs/a/d.log", ok), *variants])["stage"] == (
        "fit (every variant)"
    )
    every = failure_summary(table[table.status != "ok"])  # no other trial to build from: the report says why
    assert every.startswith("2 of 2 trial(s) failed; the report says why, trial by trial:")
    assert failure_summary(table[table.status == "ok"]) is None


def test_a_trial_failed_by_its_cameras_calibration_points_at_that_log():
    """The status table's log column named the trial's angles log for a failure whose cause is in the camera's
    calibration log (a reviewer, 2026-12-07)."""
    cause = failed("calibration", "data/calibration/g.mp4: no such file (…)", log="logs/calibration/g.log")
    row = trial_status(
        "a", "data/raw/a.mp4", "rig", [("frames", "f.log", {"status": "ok"}), ("angles", "a.log", cause)]
    )
    assert row["stage"] == "calibration" and row["log"] == "logs/calibration/g.log"
    row = trial_status("a", "data/raw/a.mp4", "rig", [("angles", "logs/angles/a.log", failed("angles", "bad"))])
    assert row["log"] == "logs/angles/a.log"


def arc_track(centre, radius, amplitude_deg, n=600, noise_px=0.2, seed=0):
    rng = np.random.default_rng(seed)
    angle = np.radians(amplitude_deg) * np.cos(np.linspace(0, 12 * np.pi, n)) * np.exp(-np.linspace(0, 1, n))
    x = centre[0] + radius * np.sin(angle) + rng.normal(0, noise_px, n)
    y = centre[1] + radius * np.cos(angle) + rng.normal(0, noise_px, n)
    return pd.DataFrame({"x_px": x, "y_px": y, "flag": "ok"})


PIVOT = (640.0, 80.0)


@pytest.mark.parametrize("seed", range(5))
def test_a_track_from_a_moved_camera_is_left_out_of_the_pooled_pivot(seed):
    tracks = {f"good{k}": arc_track(PIVOT, 520, a, seed=10 * seed + k) for k, a in enumerate((5, 20, 60))}
    tracks["moved"] = arc_track((PIVOT[0] + 6, PIVOT[1] - 4), 520, 30, seed=10 * seed + 9)
    circle, rejected = pooled_pivot(tracks)
    assert set(rejected) == {"moved"} and "px RMS off" in rejected["moved"]
    assert abs(circle.pivot_x_px - PIVOT[0]) < 1.0 and abs(circle.pivot_y_px - PIVOT[1]) < 1.0
    geometry = estimate_rig_geometry(tracks, vertical_deg=0.0)
    assert set(geometry["rejected_trials"]) == {"moved"} and "3 trial(s)" in geometry["pivot_source"]
    # a later trial filmed from the moved camera cannot use the rig's pivot either; a good one can
    assert "off the rig's pivot circle" in off_rig_circle(tracks["moved"], geometry)
    assert off_rig_circle(arc_track(PIVOT, 520, 40, seed=99), geometry) is None
    # its angles use its own pivot instead (not a refusal), and say so; the others the rig's
    assert geometry["shared"]
    own, why = trial_geometry(tracks["moved"], geometry, vertical_deg=0.0)
    assert "off the rig's pivot circle" in why and "its own track" in why
    assert np.hypot(own["pivot_px"][0] - PIVOT[0] - 6, own["pivot_px"][1] - PIVOT[1] + 4) < 3.0
    rig, why = trial_geometry(tracks["good1"], geometry, vertical_deg=0.0)
    assert why is None and rig["pivot_px"] == geometry["pivot_px"]


def test_a_cropped_copy_left_out_of_the_pooled_pivot_is_told_by_its_frames_size():
    """A clip of the rig exported cropped (its pixels shifted by the crop's corner) lies off the rig's circle as a
    moved camera's would: the reason names its frames' size against the others' (a reviewer's 480×270 crop was
    called only "the camera moved"); a moved camera at the rig's size is told as before."""
    tracks = {f"good{k}": arc_track(PIVOT, 520, a, seed=k) for k, a in enumerate((5, 20, 60))}
    tracks["crop"] = arc_track((PIVOT[0] - 80, PIVOT[1] - 45), 520, 30, seed=9)
    _, rejected = pooled_pivot(tracks)
    assert set(rejected) == {"crop"}
    kept = [k for k in tracks if k not in rejected]
    pictures = {name: (1280, 720, 0.0) for name in tracks}
    assert unlike_picture("crop", pictures, kept) is None  # same size: a camera that moved, nothing more to say
    pictures["crop"] = (1120, 630, 0.0)
    said = unlike_picture("crop", pictures, kept)
    assert said.startswith("its frames are 1120×630 px where the rig's other trials' are 1280×720 px")
    pictures["crop"] = (720, 1280, 90.0)
    assert "720×1280 px, shown turned by 90°" in unlike_picture("crop", pictures, kept)
    pictures["crop"] = (1280, 720, 90.0)  # the rotation flag alone: a camera turned (a phone held upright)
    assert unlike_picture("crop", pictures, kept) is None
    pictures["crop"] = (1120, 630, 0.0)
    # the trial's own angles say it too, not "the camera moved" (a reviewer found it only in the geometry JSON)
    geometry = estimate_rig_geometry({k: tracks[k] for k in kept}, vertical_deg=0.0)
    geometry["unlike_picture"] = {"crop": unlike_picture("crop", pictures, kept)}
    said = off_rig_circle(tracks["crop"], geometry, "crop")
    assert "its frames are 1120×630 px" in said and "the camera moved" not in said
    assert "the camera moved" in off_rig_circle(tracks["crop"], geometry)  # a trial not named: as before
    _, why = trial_geometry(tracks["crop"], geometry, vertical_deg=0.0, name="crop")
    assert "its frames are 1120×630 px" in why
    pictures.pop("good0")  # an older tracks file without its frames' size: judged by the others
    assert "1280×720" in unlike_picture("crop", pictures, kept)
    assert unlike_picture("crop", {"crop": (1120, 630, 0.0)}, kept) is None  # nothing to compare with


def released_track(centre, radius, amplitude_deg, n, decay, seed):
    """A swing released at +amplitude and decaying as exp(−decay·t/T) over the record, 0.03 px noise."""
    rng = np.random.default_rng(seed)
    t = np.linspace(0, 1, n)
    angle = np.radians(amplitude_deg) * np.cos(10 * np.pi * t) * np.exp(-decay * t)
    x = centre[0] + radius * np.sin(angle) + rng.normal(0, 0.03, n)
    y = centre[1] + radius * np.cos(angle) + rng.normal(0, 0.03, n)
    return pd.DataFrame({"x_px": x, "y_px": y, "flag": "ok"})


@pytest.mark.parametrize("seed", range(5))
def test_a_long_clip_of_another_pendulum_is_left_out_and_the_rest_still_share_their_pivot(seed):
    """The real apple clip (1,300 frames, ±22°, its pivot 500 px from the demo's) dropped among the five demo
    videos without a sidecar: it pulled the pooled circle 57 px RMS off every path, three of the demo's lay
    farther off it than the apple, and the vote that left out the farthest left out none (2026-12-02): every
    trial then used its own pivot and the rig warned of a 90° tilted swing plane. Measured the same way here
    (65 px RMS before); the apple is left out, the demo's five keep their shared pivot."""
    amplitudes = (5, 15, 5, 20, 75)
    tracks = {
        f"demo{k}": released_track((640.0, 70.0), 560, a, 660, 3.0, 10 * seed + k) for k, a in enumerate(amplitudes)
    }
    tracks["apple"] = released_track((301.0, -338.0), 554, 22, 1300, 0.2, 10 * seed + 9)
    circle, rejected = pooled_pivot(tracks)
    assert set(rejected) == {"apple"} and "another pendulum" in rejected["apple"], rejected
    assert math.hypot(circle.pivot_x_px - 640.0, circle.pivot_y_px - 70.0) < 0.2 and circle.rms_px < 0.1
    geometry = estimate_rig_geometry(tracks, vertical_deg=0.0)
    assert geometry["shared"] and geometry["warnings"] == [], geometry["warnings"]
    assert "not used" not in geometry["pivot_source"]
    own, why = trial_geometry(tracks["apple"], geometry, vertical_deg=0.0)
    assert "its own track" in why and math.hypot(own["pivot_px"][0] - 301.0, own["pivot_px"][1] + 338.0) < 3.0


@pytest.mark.parametrize("seed", range(5))
def test_the_most_trials_that_share_a_pivot_keep_it_among_clips_of_other_pendulums(seed):
    """Seven clips of other pendulums dropped beside the five demo videos, no sidecars (a reviewer's run,
    2026-12-02: the real apple clip and six made from it, four about the apple's pivot, three at other scales or
    mirrored): they lay 131 px RMS off the pooled circle, no one clip's leaving out helped, and all twelve trials
    used their own pivots, a ±5° demo trial's 6 px off its true one. The demo's five, the most that share one
    pivot, keep it (0.03 px RMS, as alone); the seven are left out, each with its own pivot. Two sets of three
    leave no largest: the rig says its trials share no pivot, as before."""
    demo = (640.0, 70.0)
    tracks = {
        f"demo{k}": released_track(demo, 560, a, 660, 3.0, 10 * seed + k) for k, a in enumerate((5, 15, 5, 20, 75))
    }
    others = [((301.0, -338.0), 554)] * 4 + [((904.0, -1014.0), 1662), ((260.0, -290.0), 475), ((979.0, -338.0), 554)]
    for k, (pivot, arm) in enumerate(others):
        tracks[f"other{k}"] = released_track(pivot, arm, 22, 1300, 0.2, 10 * seed + 5 + k)
    circle, rejected = pooled_pivot(tracks)
    assert sorted(rejected) == [f"other{k}" for k in range(7)], rejected
    assert all("the most that share one pivot" in why and "another pendulum" in why for why in rejected.values())
    assert math.hypot(circle.pivot_x_px - demo[0], circle.pivot_y_px - demo[1]) < 0.2 and circle.rms_px < 0.1
    geometry = estimate_rig_geometry(tracks, vertical_deg=0.0)
    assert geometry["shared"] and geometry["warnings"] == [], geometry["warnings"]
    for k, (pivot, _) in enumerate(others):
        own, why = trial_geometry(tracks[f"other{k}"], geometry, vertical_deg=0.0)
        assert "its own track" in why and math.hypot(own["pivot_px"][0] - pivot[0], own["pivot_px"][1] - pivot[1]) < 3
    tied = {
        f"{side}{k}": released_track(pivot, 560, a, 660, 3.0, 10 * seed + k)
        for side, pivot in (("left", (300.0, 70.0)), ("right", (1000.0, 70.0)))
        for k, a in enumerate((10, 20, 30))
    }
    assert not estimate_rig_geometry(tied, vertical_deg=0.0)["shared"]


@pytest.mark.parametrize("seed", range(5))
def test_clips_filmed_from_different_places_do_not_share_a_pivot(seed):
    """Clips of one rig from different camera placements (pivots apart, arms at other scales): none lies
    farther off the pooled circle than the rest, so no vote leaves one out, and before 2026-11-28 every
    trial used that circle's centre, no pivot at all. Now the rig says its trials share none and each
    trial's angles use its own pivot, found within a few px."""
    pivots = [(640.0, 80.0), (300.0, -200.0), (900.0, 40.0)]
    tracks = {
        f"clip{k}": arc_track(p, r, a, seed=10 * seed + k)
        for k, (p, r, a) in enumerate(zip(pivots, (520, 300, 700), (20, 30, 15), strict=True))
    }
    geometry = estimate_rig_geometry(tracks, vertical_deg=0.0)
    assert not geometry["shared"] and "do not share one pivot" in geometry["warnings"][0], geometry["warnings"]
    assert "not used" in geometry["pivot_source"]  # the pooled circle's pivot, kept for the record, said unused
    for (name, track), pivot in zip(tracks.items(), pivots, strict=True):
        own, why = trial_geometry(track, geometry, vertical_deg=0.0)
        assert "do not share one pivot" in why
        assert np.hypot(own["pivot_px"][0] - pivot[0], own["pivot_px"][1] - pivot[1]) < 3.0, (name, own)


@pytest.mark.parametrize("seed", range(5))
def test_two_narrow_swings_side_by_side_do_not_share_a_pivot(seed):
    """Two clock pendulums 400 px apart, each swinging ±4° (two trials of one video, each with its start_px):
    a circle of radius ~234,000 px passes within 0.34 px RMS of both arcs, so the paths' RMS does not tell;
    each arc's own pivot lies across its swing within a pixel of its true one, and the pooled one 200 px
    aside of both."""
    pivots = [(300.0, 50.0), (700.0, 50.0)]
    tracks = {f"bob{k}": arc_track(p, 500, 4, seed=10 * seed + k) for k, p in enumerate(pivots)}
    geometry = estimate_rig_geometry(tracks, vertical_deg=0.0)
    assert not geometry["shared"] and "own pivot is" in geometry["warnings"][0], geometry["warnings"]
    # the pooled circle's scale uncertainty is no trial's: not said (a helper's two clips of one rig, 2026-12-05)
    assert not any("known along the arm" in w for w in geometry["warnings"]), geometry["warnings"]
    for (name, track), pivot in zip(tracks.items(), pivots, strict=True):
        own, why = trial_geometry(track, geometry, vertical_deg=0.0)
        assert "do not share one pivot" in why
        assert abs(own["pivot_px"][0] - pivot[0]) < 1.0, (name, own)


def bowed_clock_track(bias_px: float, seed: int, amplitude_deg: float = 3.0) -> pd.DataFrame:
    """A clock's bob swinging on a 300 px arm about (640, 80), its track biased slowly across the arc: the arc's
    middle ``bias_px`` further out than its ends (0.03 px noise)."""
    rng = np.random.default_rng(seed)
    amplitude = math.radians(amplitude_deg)
    angle = amplitude * np.cos(np.linspace(0, 40 * np.pi, 1200))
    radius = 300.0 + bias_px * (0.5 - (angle / amplitude) ** 2)
    return pd.DataFrame(
        {
            "x_px": 640 + radius * np.sin(angle) + rng.normal(0, 0.03, angle.size),
            "y_px": 80 + radius * np.cos(angle) + rng.normal(0, 0.03, angle.size),
            "flag": "ok",
        }
    )


@pytest.mark.parametrize("bias_px", [-0.1, 0.1])
def test_a_clocks_short_arc_says_how_little_its_pivot_fixes_the_angles_scale(bias_px):
    """A clock's bob swinging ±3° on a 300 px arm: the arc bends 0.41 px from its chord, so a slow tracking bias of
    0.1 px across it (a glass's reflection, a bob's shading: 0.06–0.15 px in a helper's clock renders) moves the
    fitted pivot along the arm by a fifth to a third of the arm, and every angle's scale with it. The circle fit's
    scatter alone said ±0.5–0.8 % and no warning where the scale was 20–32 % off (a helper's 1080p clock: 15 % off,
    no warning); the pivot's σ now holds the bias too (±19–32 %), covers the error and is said."""
    geometry = estimate_rig_geometry({"clock": bowed_clock_track(bias_px, 7)}, vertical_deg=0.0)
    scale_error_pct = 100 * abs(geometry["circle"]["radius_px"] - 300.0) / 300.0
    circle_only = 100 * math.sqrt(geometry["circle"]["pivot_covariance_px2"][1][1]) / geometry["circle"]["radius_px"]
    assert scale_error_pct >= 10 and circle_only <= 0.2 * scale_error_pct, (scale_error_pct, circle_only)
    stated = geometry["angle_scale_stderr_pct"]
    assert scale_error_pct <= 2 * stated, (scale_error_pct, stated)
    assert any("is known along the arm only" in w and "sagitta" in w for w in geometry["warnings"]), geometry


def test_an_arc_too_short_for_any_scale_says_so_and_its_bias_term_is_held_to_half_the_arm():
    """±0.3° on a 300 px arm (0.01 px of sagitta): the bias term alone would put the pivot's σ 9 arms off, and the
    fits' budget, which moves each angle by its linear change with the pivot, would turn every angle's sign. Held
    to half the arm, it says the scale is unknown (± 50 % or more); a reviewer's case."""
    from pendulum.angles.geometry import MAX_BIAS_ARM_SHARE, track_bias_covariance

    assert math.sqrt(track_bias_covariance(300.0, 0.6, 0.0)[1, 1]) == pytest.approx(MAX_BIAS_ARM_SHARE * 300.0)
    assert math.sqrt(track_bias_covariance(300.0, 6.0, 0.0, 0.1)[1, 1]) == pytest.approx(300 * 0.1 / 0.411, rel=0.01)
    assert np.allclose(track_bias_covariance(300.0, 6.0, 90.0, 0.1), [[73.0**2, 0], [0, 0]], rtol=0.01, atol=1e-9)
    angle = math.radians(0.3) * np.cos(np.linspace(0, 40 * np.pi, 1200))
    rng = np.random.default_rng(3)
    track = pd.DataFrame(
        {
            "x_px": 640 + 300 * np.sin(angle) + rng.normal(0, 0.03, angle.size),
            "y_px": 80 + 300 * np.cos(angle) + rng.normal(0, 0.03, angle.size),
            "flag": "ok",
        }
    )
    geometry = estimate_rig_geometry({"clock": track}, vertical_deg=0.0)
    assert geometry["angle_scale_stderr_pct"] >= 50
    assert any("% or more (1σ" in w for w in geometry["warnings"]), geometry["warnings"]


def test_a_track_s_own_slow_departure_from_its_circle_widens_its_pivot_s_uncertainty():
    """A clock's bob tracked by its silhouette, a highlight sliding over it: its track bends off the circle by a
    slow pattern of 0.3 px (0.21 px RMS) across its ±8° arc that no pivot explains, as its centroid also bends the
    arc as a moved pivot would (a helper's clocks, 2026-12-06: 0.15–0.3 px measured so, their pivots 2–21 % off
    along the arm where ±1.4–2.8 % was said). Its slow departure is measured within 25 % over 10 seeds (noise 0.1 px)
    and taken for the bias where larger than the least assumed; a track without one measures under 0.02 px."""
    from pendulum.angles.geometry import TRACK_BIAS_PX, CircleFit, slow_bias_px

    for seed in range(10):
        rng = np.random.default_rng(seed)
        amplitude = math.radians(8.0)
        angle = amplitude * np.exp(-np.linspace(0, 1, 1200)) * np.cos(np.linspace(0, 40 * np.pi, 1200))
        bend = 0.3 * np.sin(3 * np.pi * angle / amplitude)  # three wiggles across the arc, 0.21 px RMS
        for wiggle, least, most in ((bend, 0.75 * 0.212, 1.25 * 0.212), (0.0 * bend, 0.0, 0.02)):
            radius = 500.0 + wiggle
            track = pd.DataFrame(
                {
                    "x_px": 640 + radius * np.sin(angle) + rng.normal(0, 0.1, angle.size),
                    "y_px": -100 + radius * np.cos(angle) + rng.normal(0, 0.1, angle.size),
                    "flag": "ok",
                }
            )
            geometry = estimate_rig_geometry({"clock": track}, vertical_deg=0.0)
            measured = slow_bias_px({"clock": track}, CircleFit(**geometry["circle"]))
            assert least <= measured <= most, (seed, measured)
            assert geometry["pivot_track_bias_px"] == round(max(TRACK_BIAS_PX, measured), 4)


@pytest.mark.parametrize("seed", range(5))
def test_two_clips_of_one_short_arc_biased_apart_still_share_their_pivot(seed):
    """Two clips of one clock's ±3° arc whose tracks bend ∓0.1 px (a glass's reflection, the bob's shading): their
    own pivots lie 150 px apart along the arm, 30–50 σ of the circle fits' scatter, and the rig said the camera
    had moved between them. The slow bias their scatter does not show is in the test: one pivot for both, the
    scale's uncertainty said; two such clocks side by side still share none."""
    tracks = {"a": bowed_clock_track(-0.1, seed), "b": bowed_clock_track(0.1, seed + 50)}
    geometry = estimate_rig_geometry(tracks, vertical_deg=0.0)
    assert geometry["shared"], geometry["warnings"]
    assert abs(geometry["circle"]["radius_px"] - 300.0) < 0.1 * 300.0
    assert any("is known along the arm only" in w for w in geometry["warnings"]), geometry["warnings"]
    apart = {"a": tracks["a"], "b": tracks["b"].assign(x_px=tracks["b"].x_px + 400)}
    assert not estimate_rig_geometry(apart, vertical_deg=0.0)["shared"]


@pytest.mark.parametrize("seed", range(5))
def test_good_tracks_are_never_left_out(seed):
    tracks = {f"t{k}": arc_track(PIVOT, 520, a, seed=seed * 7 + k) for k, a in enumerate((3, 5, 20, 75))}
    circle, rejected = pooled_pivot(tracks)
    assert rejected == {}
    assert np.hypot(circle.pivot_x_px - PIVOT[0], circle.pivot_y_px - PIVOT[1]) < 0.5
    assert estimate_rig_geometry(tracks, vertical_deg=0.0)["shared"]


def test_two_tracks_are_pooled_without_a_vote():
    tracks = {"a": arc_track(PIVOT, 520, 20), "b": arc_track((PIVOT[0] + 6, PIVOT[1]), 520, 30, seed=1)}
    _, rejected = pooled_pivot(tracks)
    assert rejected == {}  # with two tracks there is no majority to say which one moved


def test_jacobian_rank_warnings_name_the_inseparable_parameters():
    rng = np.random.default_rng(1)
    a, b, c = rng.normal(size=(3, 200))
    assert jacobian_rank_warnings(np.column_stack([a, b, c]), ["m_a", "C_dA", "c"]) == []
    warnings = jacobian_rank_warnings(np.column_stack([a, b, 2 * b]), ["m_a", "C_dA", "c"])
    assert len(warnings) == 1 and "C_dA and c cannot be told apart" in warnings[0]
    warnings = jacobian_rank_warnings(np.column_stack([a, b, 0 * c]), ["m_a", "C_dA", "tau_f"])
    assert warnings == ["tau_f has no effect on the fitted record (zero sensitivity)"]


def test_a_failure_image_holds_the_whole_message():
    """The star's refusal (about 450 characters) was cut after six lines of 70 characters: now every word, the
    image as tall as it needs and as wide as the contact sheet it sits above."""
    message = " ".join(f"word{k:03d}" for k in range(80))  # 640 characters
    rows_with_text = []
    for width in (960, 640):
        image = failure_image(message, width, header="REFUSED:")
        assert image.shape[1] == width and image.dtype == np.uint8
        text_rows = np.flatnonzero((image > 150).any(axis=1))  # the light text on grey
        rows_with_text.append(text_rows.max() - text_rows.min())
        assert text_rows.max() < image.shape[0] - 4  # the last line inside the image
        assert (image[:, -8:] == 60).all()  # no line runs off the right edge
    assert rows_with_text[1] > rows_with_text[0]  # narrower: more lines, a taller image
    assert failure_image("short", 960).shape == (200, 960)  # a short message keeps the old size


def test_what_the_check_logged_this_run_is_read_back_for_the_last_lines_of_the_terminal(tmp_path, capsys):
    """The Snakefile's onsuccess and onerror print it after Snakemake's own lines: the trials no variant fits, then
    the failed ones or the count ok and skipped (a reviewer, 2026-12-02: after a successful run the apple's note
    stood 60 lines up, behind the last job's listing, and 'all 6 ok, 1 skipped' only in the log). A log of an
    earlier run prints nothing."""
    import time

    from pendulum.outcomes import outcome_logged, print_outcome

    log = tmp_path / "check.log"
    text = "1 of 2 trial(s) failed; the report and the other 1 trial(s)' results were built:\n  - b, at tracks: bad"
    misfit = "1 trial(s) ok whose every model variant misses the record far beyond its noise (…): apple"
    log.write_text(f"2026-12-02 11:27:40,466 WARNING {misfit}\n2026-12-02 11:27:40,468 ERROR {text}\n")
    assert outcome_logged(log, since_s=time.time() - 60) == f"{misfit}\n{text}"
    assert outcome_logged(log, since_s=time.time() + 60) is None  # written before this run
    assert outcome_logged(tmp_path / "missing.log", since_s=0) is None
    log.write_text("2026-12-02 11:27:40,468 INFO all 2 trial(s) ok, 1 skipped by their sidecars\n")
    print_outcome(log, since_s=0)
    assert capsys.readouterr().err.endswith(":\nall 2 trial(s) ok, 1 skipped by their sidecars\n")


def test_a_rigs_geometry_is_kept_when_a_trial_it_did_not_rest_on_leaves_for_its_own_rig():
    """A reviewer's apple (2026-12-02) failed in the demo's rig (another pendulum: left out of its pooled pivot),
    then got its own rig by a sidecar: the demo rig's geometry was estimated again and its 5 angle records and 15
    fits rebuilt, byte for byte the same. Kept now; estimated again where a trial its pivot rests on leaves or a
    trial it read is gone."""
    from pendulum.trials import kept_geometry_trials

    demo = ["d1", "d2", "d3"]
    document = {"input_trials": [*demo, "apple"], "trials": [*demo, "apple"], "rejected_trials": {"apple": "off"}}
    videos = {*demo, "apple"}
    assert kept_geometry_trials(document, demo, videos) == sorted([*demo, "apple"])  # apple now in its own rig
    assert kept_geometry_trials(document, [*demo, "apple", "new"], videos | {"new"}) == sorted([*demo, "apple"])
    assert kept_geometry_trials(document, demo, set(demo)) == demo  # the apple's video deleted: its track is gone
    assert kept_geometry_trials(document, ["d1", "d2"], videos) == ["d1", "d2"]  # a trial it rests on left
    assert kept_geometry_trials(None, demo, videos) == demo


def test_the_same_recording_under_two_names_is_said_in_the_status_table():
    """A copy of a clip under another name (a fresh-eyes user, 2026-12-03): the group fits counted it once, but
    trials.csv called it a plain ok; it now says whose record it is, once, on the later-named trial."""
    from pendulum.outcomes import mark_copies

    def documents(digest):
        return [("angles", "a.log", {"status": "ok", "period_s": 2.078, "record_sha256": digest, "warnings": []})]

    rows = [trial_status(n, f"data/raw/{n}.mov", "air", documents(d)) for n, d in (("b", "x"), ("a", "x"), ("c", "y"))]
    mark_copies(rows, {"a": "x", "b": "x", "c": "y"})
    table = status_table(rows).set_index("trial")
    assert table.loc["b", "n_warnings"] == 1 and table.loc["b", "warnings"].startswith(
        "angles: the same angle record as a, sample for sample"
    )
    assert table.loc["a", "n_warnings"] == 0 and table.loc["c", "n_warnings"] == 0
    assert list(table.status) == ["ok", "ok", "ok"]


def test_the_last_line_of_a_run_counts_the_trials_no_variant_fits_among_those_ok(tmp_path, monkeypatch):
    """A run whose trials all built but one misses every variant (the real apple in air) ended "1 trial(s) ok whose
    every model variant misses …" and then "all 1 trial(s) ok" (a new user: contradictory at first). The last line
    now counts it among the ok ones, as it counts those with the rig values in doubt."""
    import runpy

    from conftest import ROOT, FakeSnakemake
    from pendulum.outcomes import EVERY_VARIANT, MISFIT_MARK, STATUS_COLUMNS

    table = tmp_path / "trials.csv"
    row = dict.fromkeys(STATUS_COLUMNS, "")
    row.update(trial="apple", status="ok", warnings=f"{EVERY_VARIANT}residual RMS 0.236° … {MISFIT_MARK}; …")
    pd.DataFrame([row, {**row, "trial": "ball", "warnings": ""}], columns=STATUS_COLUMNS).to_csv(table, index=False)
    done = tmp_path / "all_trials_ok.txt"
    sm = FakeSnakemake({"table": str(table)}, {"done": str(done)}, str(tmp_path / "check.log"), {})
    monkeypatch.syspath_prepend(str(ROOT / "workflow" / "scripts"))
    runpy.run_path(str(ROOT / "workflow" / "scripts" / "check_trials.py"), init_globals={"snakemake": sm})
    assert done.read_text() == "all 2 trial(s) ok (1 missed by every model variant, above)\n"
    assert "where the residual lies in the discovery verdict): apple" in (tmp_path / "check.log").read_text()
