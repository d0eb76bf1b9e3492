"""The report says where a result rests on garbage (issue 12): fits on unreliable records are badged, struck
through and counted, joint fits name the trials they left out, and the tracking table notes what is
notable about each video's frames (trimmed clip, variable rate, rotation, bit depth) while a clean trial
stays one quiet row. Unit-level: small hand-made result documents, exact text in the produced HTML."""

import json
import re
from pathlib import Path

import pandas as pd
import pytest

from pendulum.report import notebook as R
from pendulum.report.checks import frame_notes

VARIANTS = {"quadratic": ["quadratic_drag"], "linear": ["quadratic_drag", "linear_damping"]}
PROBLEM = (
    "trial t10: fitted rest angle −12.0° from the vertical (more than 2°): the angles are not about the "
    "pendulum's vertical (wrong object tracked, wrong pivot_px or vertical_deg)"
)
NOISE_DEG = {"t20": 0.004, "t10": 0.005}
RMS_DEG = {"t20": 0.006, "t10": 0.5}  # t20: RMS/noise 1.5; t10 (garbage): 100


def _entry(value, half, identifiable=True):
    return {
        "value": value,
        "stderr": half / 1.96,
        "ci95": [value - half, value + half],
        "lower_bound": 0.0,
        "at_bound": False,
        "identifiable": identifiable,
    }


def _fit(variant, trial, rms_deg, problems=(), reliable_key=True):
    """A per-trial fit document as fitting.fit_records writes it; ``problems``: its record's garbage checks."""
    parameters = {"added_mass_kg": _entry(2.5, 0.24, not problems), "drag_area_m2": _entry(0.0258, 0.003)}
    if "linear_damping" in VARIANTS[variant]:
        parameters["linear_damping_nm_s"] = _entry(0.15, 0.01)
    if problems:
        for entry in parameters.values():
            entry["identifiable"] = False
            entry["reason"] = f"the angle record is unreliable: {problems[0]}"
    doc = {
        "trial": trial,
        "status": "ok",
        "variant": variant,
        "terms": VARIANTS[variant],
        "rig": {"name": "rig"},
        "parameters": parameters,
        "rms_rad": rms_deg / 57.29577951308232,
        "rms_deg": rms_deg,
        "rms_arc_m": 0.76 * rms_deg / 57.29577951308232,
        "aic": -300.0,
        "bic": -290.0,
        "n_samples": 600,
        "n_parameters": 5,
        "samples_digest": f"d-{trial}",
        "keulegan_carpenter_number": 6.1,
        "trials": {
            trial: {
                "theta0_deg": 19.0,
                "residual_lag1_autocorrelation": 0.5,
                "record_checks": {"problems": list(problems)},
            }
        },
        "warnings": list(problems),
    }
    if reliable_key:
        doc["reliable"] = not problems
    return doc


CLEAN_FRAMES = {
    "video": "data/raw/t20.mp4",
    "status": "ok",
    "nominal_fps": 30.0,
    "n_frames": 660,
    "mean_fps": 30.0,
    "frame_interval_s": 1 / 30,
    "variable_frame_rate": False,
    "irregular_intervals": 0,
    "dropped_frames": 0,
    "duplicate_timestamps": 0,
    "discarded_packets": 0,
    "rotation_deg": 0.0,
    "pixel_format": "yuv420p",
    "bit_depth": 8,
    "warnings": [],
}
PHONE_FRAMES = {
    **CLEAN_FRAMES,
    "video": "data/raw/t10.mov",
    "nominal_fps": 30.0,
    "n_frames": 1844,
    "mean_fps": 29.97,
    "frame_interval_s": 0.0333,
    "variable_frame_rate": True,
    "irregular_intervals": 41,
    "discarded_packets": 213,
    "rotation_deg": 90.0,
    "pixel_format": "yuv420p10le",
    "bit_depth": 10,
    "warnings": [
        "data/raw/t10.mov: trimmed clip: 213 packet(s) before the first shown frame (an edit list) are not frames "
        "the decoder yields; the timeline starts at the first shown frame",
        "data/raw/t10.mov: variable frame rate: frame intervals 30.1–36.0 ms (median 33.3 ms, 41 irregular); every "
        "frame keeps its own timestamp and no frames are counted as dropped",
        "data/raw/t10.mov: the file asks players to rotate the picture by 90°; its frames are used as stored",
        "data/raw/t10.mov: truncated: only 1844 of the 1900 frames its index lists are in the file",
    ],
}


def _report(tmp_path, garbage=True, joint_garbage=False, reliable_key=True):
    """Two video trials on one rig, two variants: t20 clean, t10 (when ``garbage``) on an unreliable record."""

    def write(name, doc):
        path = tmp_path / name
        path.write_text(json.dumps(doc))
        return str(path)

    files = {"trials": {}, "fits": {v: {} for v in VARIANTS}, "joint": {}}
    problems = {"t20": (), "t10": (PROBLEM,) if garbage else ()}
    for trial, frames in (("t20", CLEAN_FRAMES), ("t10", PHONE_FRAMES)):
        files["trials"][trial] = {
            "angles": write(
                f"{trial}.angles.json",
                {
                    "status": "ok",
                    "hold_angle_deg": float(trial[1:]),
                    "noise_deg": NOISE_DEG[trial],
                    "n_samples": 620,
                    "n_flagged": 0,
                },
            ),  # noqa: E501
            "frames": write(f"{trial}.frames.json", frames),
            "tracks": write(f"{trial}.tracks.json", {"status": "ok", "flags": {"ok": 660}}),
        }
        for v in VARIANTS:
            doc = _fit(v, trial, RMS_DEG[trial], problems[trial], reliable_key)
            files["fits"][v][trial] = {"fit": write(f"{v}.{trial}.json", doc), "curve": "", "cycles": ""}
    rows = []
    for v in VARIANTS:
        joint = _fit(v, "t20", RMS_DEG["t20"], (PROBLEM.replace("t10", "t20"),) if joint_garbage else ())
        joint.pop("trial")
        joint["consistency"] = {"verdict": "not testable", "explanation": "one trial", "parameters": {}}
        if garbage:
            joint["excluded_trials"] = {"t10": f"unreliable record: {PROBLEM}"}
        files["joint"][v] = {"rig": write(f"{v}.joint.json", joint)}
        aic = -300.0 if v == "linear" else -100.0
        rows += [(v, "joint:rig", aic, aic + 10, "d-t20")]
    files["summary"] = str(tmp_path / "summary.csv")
    pd.DataFrame(rows, columns=["variant", "fit", "aic", "bic", "samples_digest"]).to_csv(files["summary"], index=False)
    trials = {
        t: {"rig": "rig", "kind": "video", "source": f"data/raw/{t}.mp4", "overrides": {}} for t in ("t20", "t10")
    }
    rigs = {"rig": {"values": {"mass_kg": 3.53, "length_m": 0.76, "frontal_area_m2": 0.0322}, "tolerances": {}}}
    return R.Report(files=files, trials=trials, rigs=rigs, variants=VARIANTS, provenance={"commit": "a" * 40})


def _row(html, **attrs):
    """The <tr> whose attributes start with the given data-* values (in order)."""
    key = " ".join(f'data-{k}="{v}"' for k, v in attrs.items())
    match = re.search(rf"<tr[^>]*{re.escape(key)}[^>]*>(.*?)</tr>", html)
    assert match, key
    return match.group(1)


@pytest.fixture
def garbage(tmp_path):
    return _report(tmp_path)


def test_table3_strikes_the_coefficients_of_a_fit_on_an_unreliable_record(garbage):
    html = garbage.coefficient_table()
    for v in VARIANTS:
        bad = _row(html, trial="t10", variant=v, kind="trial")
        assert '<span class="v"><s>2.50</s></span><span class="q"><s>[2.26, 2.74]</s></span>' in bad
        assert bad.count('class="num unreliable"') == len(VARIANTS[v]) + 1  # m_a, C_dA (and c); C_d not fitted
        assert '<span class="v">2.50</span>' not in bad and ">garbage in</span>" in bad
        assert f'title="{PROBLEM.replace(chr(39), "&#x27;")}"' in bad
        good = _row(html, trial="t20", variant=v, kind="trial")
        assert '<span class="v">2.50</span><span class="q">[2.26, 2.74]</span>' in good and "garbage" not in good
    sentence = _row(html, trial="t10", kind="garbage")
    assert "<b>not measurements</b> (struck through): fitted rest angle −12.0° from the vertical (more" in sentence
    left_out = _row(html, trial="joint:rig", kind="left-out")
    assert "Left out of the joint fits: <b>t10</b>: unreliable record: fitted rest angle −12.0°" in left_out


def test_table2_marks_the_trial_and_greys_its_rms(garbage):
    html = garbage.rms_table()
    bad = _row(html, trial="t10")
    assert 't10 <span class="garbage-in"' in bad and bad.count('class="num unreliable"') == 3 * len(VARIANTS)
    assert ">0.50</td>" in bad  # still shown (grey), with the problem as tooltip
    assert "garbage" not in _row(html, trial="t20") and 'data-reliable="false"' in html
    assert "1 trial(s) rest on unreliable records" in html and "<b>t10</b>: fitted rest angle −12.0°" in html


def test_table2_marks_a_fit_that_leaves_more_than_its_nested_parent(tmp_path):
    """A lab's trial (a reviewer's 85, 2026-12-07): its three-term fit left 0.573° where the two-term one left
    0.094°, and Table 2 said the model missed a systematic effect; a variant with one term more can always do at
    least as well (the extra term 0), so that fit stopped short of its best. Marked ◊ and named in the caption;
    a richer fit within 1 % of its parent is not."""
    report = _report(tmp_path, garbage=False)
    assert "◊" not in report.rms_table()  # both variants leave the same RMS
    fit = report.fits[("linear", "t20")]
    fit.update(rms_deg=0.573, rms_rad=0.573 / 57.29577951308232, rms_arc_m=0.76 * 0.573 / 57.29577951308232)
    html = report.rms_table()
    row = _row(html, trial="t20")
    assert row.count("◊") == 3 and "stopped short of its best fit: quadratic, one term fewer, leaves 0.0060°" in row
    assert "◊" not in _row(html, trial="t10")
    assert "its coefficients are not that model's best: t20: linear (quadratic leaves 0.0060°)" in html
    fit.update(rms_rad=1.005 * report.fits[("quadratic", "t20")]["rms_rad"])
    assert "◊" not in report.rms_table()


def test_the_summary_box_counts_the_unreliable_fits_and_keeps_them_out_of_the_medians(garbage):
    box = garbage.summary_box()
    assert "1 of 2 fits" not in box and "2 of 4 fits rest on unreliable records</span>" in box
    assert "the joint fits leave these trials out): <b>t10</b>: fitted rest angle −12.0° from the vertical" in box
    assert "Left out of the joint fits" not in box  # said once, in the line above
    assert "<b>2.50</b>" in box and "<s>" not in box  # the recommended joint fit itself is clean
    comparison = garbage.model_comparison()
    linear = _row(comparison, variant="linear")
    assert '<td class="num">1.5</td>' in linear  # median RMS/noise over t20 only (t10 alone: 100)
    assert "leave out the per-trial fits on unreliable records (t10)" in comparison
    assert "1 trial(s) on unreliable records</span>" in garbage.header()


def test_a_joint_fit_on_an_unreliable_record_is_never_shown_as_plain_numbers(tmp_path):
    box = _report(tmp_path, garbage=False, joint_garbage=True).summary_box()
    assert '<td class="num unreliable" style="color:#8a8a8a"><s>2.50</s></td>' in box and "<b>2.50</b>" not in box
    assert "The recommended joint fit itself rests on an unreliable record" in box
    assert "fits rest on unreliable records" not in box  # the per-trial fits are clean


def test_clean_fits_and_documents_from_before_the_checks_carry_no_mark(tmp_path):
    for reliable_key in (True, False):
        report = _report(tmp_path, garbage=False, reliable_key=reliable_key)
        html = "".join(
            (report.header(), report.summary_box(), report.rms_table(), report.coefficient_table())
            + (report.model_comparison(), report.tracking_section())
        )
        assert "garbage-in" not in html and "unreliable" not in html and "<s>" not in html


def test_frame_notes_say_only_what_is_notable():
    assert frame_notes(CLEAN_FRAMES) == []
    assert frame_notes(PHONE_FRAMES) == [
        "trimmed clip: 213 packet(s) before the first shown frame discarded",
        "variable frame rate (41 irregular intervals, median 33.3 ms)",
        "rotation metadata 90°: frames used as stored",
        "10-bit (yuv420p10le)",
        "truncated: only 1844 of the 1900 frames its index lists are in the file",
    ]
    dropped = {**CLEAN_FRAMES, "dropped_frames": 3, "duplicate_timestamps": 1}
    assert frame_notes(dropped) == ["3 dropped frame(s)", "1 duplicate time stamp(s)"]


def test_the_tracking_table_keeps_a_clean_trial_quiet_and_notes_a_phone_file(garbage):
    html = garbage.tracking_section()
    clean = re.search(r'<tr data-trial="t20">(.*?)</tr>', html).group(1)
    assert '<td class="num">30.00</td>' in clean and clean.endswith(
        '<td class="warncell notes" style="max-width:30em;min-width:20em;overflow-wrap:anywhere"></td>'
    )
    phone = _row(html, trial="t10")
    assert 'data-trial="t10" data-notes="6"' in html  # garbage in + five frame notes
    assert '<td class="num">29.97 <span class="warn">variable</span></td>' in phone
    assert '<td class="num">1844</td>' in phone and "trimmed clip: 213 packet(s)" in phone
    note = '</div><div style="margin:0 0 0.5em">'
    assert (
        "</span> fitted rest angle −12.0° from the vertical (more than 2°)" + note + "trimmed clip: 213 packet(s)"
        in phone
    )
    assert phone.count(note) == 5  # six notes, each its own, the fit's verdict first


@pytest.mark.slow
def test_the_consistency_figure_leaves_out_fits_on_unreliable_records_and_says_which(garbage, tmp_path):
    html = garbage.consistency_figure()
    assert "Not plotted: the fits of t10 (unreliable records, Table 3)." in html
    (tmp_path / "clean").mkdir()
    assert "Not plotted" not in _report(tmp_path / "clean", garbage=False).consistency_figure()


def test_the_tracking_table_says_briefly_how_a_body_was_tracked():
    """The note says how and in how many frames, and what the marker gave; the full reason is its tooltip."""
    from pendulum.report.checks import method_note

    reason = "the marker disk is usable in 53.3 % of the frames; the body's silhouette is usable in 93.5 % ..."
    tried = {
        "marker": "usable in under 95 % of the frames: detection's disk-like spot (dark, radius 9.9 px) was not ...",
        "body": "usable in 93.5 % of the frames",
        "body_by_colour": "usable in 99.7 % of the frames",
    }
    method = {"used": "body", "reason": reason, "tried": tried}
    assert method_note(method, {"view": "colour"}) == (
        "tracked the body itself by its colour, usable in 99.7 % of the frames when the method was chosen; its "
        "brightness silhouette usable in 93.5 % of the frames, changing with the wall; a marker disk usable in under "
        "95 % of the frames"
    )
    assert method_note(method, {}) == (
        "tracked the body itself by its silhouette, usable in 93.5 % of the frames when the method was chosen; a "
        "marker disk usable in under 95 % of the frames"
    )
    assert method_note(method, {"wall_gain": 0.343}) == (  # the grey apple before the band
        "tracked the body itself by its silhouette, usable in 93.5 % of the frames when the method was chosen; "
        "measured against the wall behind each part of it (a darker band behind part of the swing: the body's "
        "contrast there scaled up by as much as 2.9×); a marker disk usable in under 95 % of the frames"
    )
    assert "wall behind" not in method_note(method, {"view": "colour", "wall_gain": 0.343})  # its colour's
    outline = {"view": "colour", "centre": {"by": "outline", "outline_radius_px": 18.807}}  # a turning two-tone ball
    assert method_note(method, outline).endswith(
        "; measured by the centre of its round outline (18.8 px in radius): only part of the ball stands out, and "
        "that part's centroid moves as it turns"
    )
    by_luma = {**outline, "outline_view": {"used": "brightness"}}  # its outline the brightness view's
    assert method_note(method, by_luma).endswith(
        "moves as it turns (its outline in the brightness view: the luma's limb is sharper than the chroma's)"
    )
    failed = {**method, "tried": {**tried, "marker": "failed: no marker found", "body": "failed: two objects"}}
    assert method_note(failed, {"view": "colour"}) == (
        "tracked the body itself by its colour, usable in 99.7 % of the frames when the method was chosen; its "
        "brightness silhouette could not be followed; a marker disk could not be found"
    )


def test_the_tracking_table_says_whether_the_marker_was_detected_or_given():
    from pendulum.report.checks import marker_text

    given = {"marker": {"polarity": "bright", "marker_radius_px": 12.0, "start_px": None}, "detection": None}
    found = {"marker": {"polarity": "dark", "marker_radius_px": 6.03261}, "detection": {"polarity": "dark"}}
    assert marker_text(given) == "bright, r 12.0 px, given"
    assert marker_text(found) == "dark, r 6.0 px, detected"
    assert marker_text({"status": "ok", "flags": {"ok": 660}}) == "—"  # a track from before the field existed
    colour = {"method": {"used": "body", "reason": "..."}, "body": {"radius_px": 14.5, "view": "colour"}}
    assert marker_text(colour) == "body by colour, r 14.5 px, auto"
    pointed = {**colour, "body": {"radius_px": 19.8}, "settings": {"start_px": [73, 177]}}  # one of two pendulums
    assert marker_text(pointed) == "body, r 19.8 px, auto, at start_px (73, 177)"
    dot = {"method": {"used": "marker"}, "marker": {"polarity": "bright", "marker_radius_px": 5.3, "view": "colour"}}
    assert marker_text(dot) == "dot by colour, r 5.3 px, at start_px"


def test_the_tracking_table_says_a_dot_was_followed_by_its_colour_and_what_its_brightness_gave():
    from pendulum.report.checks import dot_colour_note

    stopped = "usable in under 95 % of the frames: detection's disk-like spot (dark, radius 6.0 px: …) was not …"
    method = {"used": "marker", "tried": {"marker": stopped, "marker_by_colour": "usable in 99.8 % of the frames"}}
    assert dot_colour_note(method) == (
        "tracked the dot at start_px by its colour, usable in 99.8 % of the frames; by its brightness usable in "
        "under 95 % of the frames"
    )
    failed = {"tried": {"marker": "failed: no disk-like spot", "marker_by_colour": "usable in 100.0 % of the frames"}}
    assert dot_colour_note(failed).endswith("by its brightness it could not be followed")


def test_the_tracking_table_says_a_body_was_tracked_and_its_warning(tmp_path):
    """A trial whose body was tracked: the reason, and the body's warning (a silhouette that changes with the wall
    behind it), each a note of its own."""
    report = _report(tmp_path, garbage=False)
    warning = (
        "the body's silhouette is 20 % smaller mid-swing than at the ends of its swing, with the scene there clear"
    )
    body = {
        "status": "ok",
        "flags": {"ok": 640, "occluded": 20},
        "method": {"used": "body", "reason": "no marker disk in the video"},
        "body": {"radius_px": 14.1, "polarity": "dark", "warning": warning},
    }
    Path(report.files["trials"]["t10"]["tracks"]).write_text(json.dumps(body))
    report.__post_init__()  # the documents read again
    row = _row(report.tracking_section(), trial="t10")
    assert ">tracked the body: no marker disk in the video</span></div><div" in row
    # how it was tracked is a fact, in the page's muted ink; the body's warning in the warnings' colour (a reviewer
    # read every note of the column as an alarm, 2026-12-02)
    assert '<div style="margin:0 0 0.5em;color:var(--muted)"><span title="no marker disk' in row
    assert '<div style="margin:0 0 0.5em">' + warning.replace("'", "&#x27;") + "</div>" in row
    assert "body, r 14.1 px, auto" in row
    body["body"]["in_front"] = {"hidden_px": 436, "box_px": [295, 196, 14, 41]}  # a post before the swing
    Path(report.files["trials"]["t10"]["tracks"]).write_text(json.dumps(body))
    report.__post_init__()
    row = _row(report.tracking_section(), trial="t10")
    assert "hides part of the body at x 295–308, y 196–236 px" in row


def test_copies_left_out_for_the_same_reason_are_named_together_once():
    """A lab's 25 copies of 5 clips were 25 entries of one long reason each in the summary and Table 3."""
    from pendulum.report.data import ReportData

    same = "the same angle record as a, sample for sample (the same video under another name): counted once"
    left_out = {
        "a_1": (same, ["quadratic", "linear"]),
        "b_1": ("unreliable record: fitted rest angle −12.0°", ["quadratic", "linear"]),
        "a_2": (same, ["quadratic", "linear"]),
        "a_3": (same, ["quadratic"]),
    }
    assert ReportData.grouped(left_out) == [
        (["a_1", "a_2"], same, ["quadratic", "linear"]),
        (["b_1"], "unreliable record: fitted rest angle −12.0°", ["quadratic", "linear"]),
        (["a_3"], same, ["quadratic"]),
    ]
