"""What a new reader of the report stumbled on: the verdict's ± (95 %, as the tables), a failure said once per
tracking row, the camera calibration table of a rig filmed through a camera setup, and the three noise figures
each labelled for what it is."""

import json
import math

from pendulum.discovery.findings import verdict
from pendulum.model.effects import TERMS
from pendulum.report import notebook as R
from pendulum.report.checks import calibration_rows, failure_cell
from pendulum.report.discovery import residual_check_table

VARIANTS = {"quadratic": ["quadratic_drag"], "linear": ["quadratic_drag", "linear_damping"]}
RIG = {"mass_kg": 3.53, "length_m": 0.76, "frontal_area_m2": 0.0322}


def _check(rms_rad: float, floor_rad: float) -> dict:
    white = {"ljung_box_q": 24.9, "dof": 28, "p_value": 0.63, "spacing_s": 0.2}
    return {"rms_rad": rms_rad, "noise_floor_rad": floor_rad, "rms_over_noise": rms_rad / floor_rad}, white


def _discovery_document() -> dict:
    base, white = _check(math.radians(0.63), math.radians(0.0039))
    final, _ = _check(math.radians(0.0039), math.radians(0.0039))
    return {
        "group": "rig",
        "baseline": {
            "terms": ["quadratic_drag"],
            "rms_rad": base["rms_rad"],
            "held_out_rms_rad": math.radians(0.98),
            "residual_check": {**base, "whiteness": white, "structured": True},
        },
        "rms_rad": final["rms_rad"],
        "held_out_rms_rad": math.radians(0.0041),
        "residual_check": {**final, "whiteness": white, "structured": False},
        "threshold": {"misfit_ratio": 5.0, "whiteness_alpha": 0.01},
        "named_effects": ["coulomb_friction"],
        "parameters": {"coulomb_friction_torque_nm": {"value": 0.020012, "stderr": 0.0004}},
        "indistinguishable": [],
        "unexplained": False,
    }


def test_the_verdict_gives_the_95_percent_interval_of_the_tables():
    doc = _discovery_document()
    doc["parameters"] = {TERMS["coulomb_friction"].parameter: {"value": 0.020012, "stderr": 0.0004}}
    text = verdict(doc)
    # 1.96 × 0.0004 = 0.000784 → one significant digit
    assert text.startswith("missing effect: bearing (Coulomb) friction, τ_f = 0.0200 ± 0.0008 N·m (95 %); RMS")


def test_a_failure_carried_to_later_stages_is_said_once_in_its_tracking_row(tmp_path):
    said: set[str] = set()
    tracks = {"status": "failed", "failed_stage": "tracks", "error": "data/raw/a.mp4: marker lost"}
    first, again = failure_cell(tracks, said), failure_cell(dict(tracks), said, span=3)
    assert "tracks failed: data/raw/a.mp4: marker lost" in first and 'class="na fail"' in first
    assert again == '<td class="na" colspan="3">—</td>'

    frames = tmp_path / "frames.json"
    frames.write_text(json.dumps({"status": "ok", "n_frames": 300, "nominal_fps": 30.0}))
    failed = tmp_path / "failed.json"
    failed.write_text(json.dumps(tracks))
    (tmp_path / "summary.csv").write_text("variant,fit\n")
    files = {
        "summary": str(tmp_path / "summary.csv"),
        "trials": {"a": {"angles": str(failed), "frames": str(frames), "tracks": str(failed)}},
        "fits": {v: {"a": {"fit": str(failed), "curve": "", "cycles": ""}} for v in VARIANTS},
        "joint": {v: {"rig": str(failed)} for v in VARIANTS},
    }
    trials = {"a": {"rig": "rig", "kind": "video", "source": "data/raw/a.mp4", "overrides": {}}}
    report = R.Report(files=files, trials=trials, rigs={"rig": {"values": RIG, "tolerances": {}}}, variants=VARIANTS)
    html = report.tracking_section()
    assert html.count("tracks failed: data/raw/a.mp4: marker lost") == 1
    assert "calibration-table" not in html and "Camera:" not in report.rig_table()


CALIBRATION = {
    "status": "ok",
    "camera_setup": "gopro_tank",
    "models": {"rational": {"held_out_rms_px": 0.16272}, "fisheye": {"held_out_rms_px": 0.18344}},
    "chosen_model": "rational",
    "views": list(range(30)),
    "held_out_views": [3, 7, 11, 15, 19, 23, 27],
    "focal_length_px": [900.5823, 900.6539],
    "plane": {"px_per_m": 805.2, "plane_tilt_deg": 11.5886},
}


def test_a_rig_with_a_camera_gets_its_calibration_table_and_swing_plane_note(tmp_path):
    cells = calibration_rows({"gopro_tank": CALIBRATION})[0]
    assert [c.split(">", 1)[1].removesuffix("</td>") for c in cells] == [
        "gopro_tank",
        "rational",
        "0.163",
        "0.183",
        "900.6, 900.7",
        "yes, tilt 12°",
        "30 (7 held out)",
        "—",  # a calibration from before the board's coverage was measured
    ]
    square_on = {**CALIBRATION, "plane": {"plane_tilt_deg": 3.0, "square_on_tilt_deg": 3.4}}
    assert (
        "yes, square-on (tilt 3.0°: a square-on board&#x27;s corner noise reads up to 3.4°)"
        in calibration_rows({"g": square_on})[0][5]
    )
    turned = {**CALIBRATION, "plane": {"plane_tilt_deg": 11.5886, "square_on_tilt_deg": 2.3}}
    assert (
        "yes, tilt 12° (a square-on board&#x27;s corner noise reads up to 2.3°)"
        in calibration_rows({"g": turned})[0][5]
    )
    covered = {
        **CALIBRATION,
        "board_coverage": {"share": 0.40278},
        "warnings": ["lens.mp4: the board reached only 40 %"],
    }
    assert (
        calibration_rows({"g": covered})[0][-1]
        == '<td class="num fail">40 %; lens.mp4: the board reached only 40 %</td>'
    )
    no_plane = {k: v for k, v in CALIBRATION.items() if k != "plane"}
    assert '<td class="num">no</td>' in calibration_rows({"c": no_plane})[0]

    path = tmp_path / "gopro_tank.json"
    path.write_text(json.dumps(CALIBRATION))
    angles = tmp_path / "angles.json"
    angles.write_text(json.dumps({"status": "ok", "hold_angle_deg": 20.0, "noise_deg": 0.003}))
    (tmp_path / "summary.csv").write_text("variant,fit\n")
    files = {
        "summary": str(tmp_path / "summary.csv"),
        "trials": {"a": {"angles": str(angles)}},
        "calibration": {"gopro_tank": str(path)},
    }
    trials = {"a": {"rig": "rig", "kind": "video", "source": "data/raw/a.mp4", "overrides": {}}}
    rigs = {"rig": {"values": {**RIG, "camera": "gopro_tank"}, "tolerances": {}}}
    report = R.Report(files=files, trials=trials, rigs=rigs, variants=VARIANTS)
    assert "gopro_rig" not in report.rig_table() and "rig (camera setup gopro_tank)" in report.rig_table()
    assert "swing-plane coordinates" in report.rig_table()
    # the pivot's row says so too (a GoPro user read "pivot in the image" and took the lens-corrected value for one)
    assert "pivot (swing-plane px where a camera setup is calibrated)" in report.rig_table()
    assert "pivot in the image" not in report.rig_table()
    html = report.tracking_section()
    assert 'id="calibration-table"' in html and "Camera calibration" in html and "900.6, 900.7" in html


def test_the_discovery_noise_floor_is_labelled_as_pooled_over_the_group():
    html = residual_check_table(_discovery_document())
    assert "<th>pooled noise floor (°)</th>" in html and "pooled over the group's fitted samples" in html
    assert html.count(">0.0039</td>") == 3  # the floor twice, the final RMS once


def test_table_1_shows_the_estimated_pivot_and_defaults_and_the_notes_carry_geometry_warnings(tmp_path):
    """A new user's rigs from sidecars: ρ, g and ν read '—' although the fit used defaults, the estimated pivot
    was only 'not given', and 'the pivot is poorly determined' stayed in results/geometry/ out of the report."""
    warning = "rig geometry: the pivot is poorly determined by the marker paths (standard error 17 px ...)"
    angles = tmp_path / "angles.json"
    angles.write_text(
        json.dumps(
            {
                "status": "ok",
                "hold_angle_deg": 9.0,
                "noise_deg": 0.01,
                "pivot_px": [300.0714, -42.3172],
                "vertical_deg": 0.0223,
                "pivot_covariance_px2": [[0.0030, 0.02], [0.02, 0.5036]],
                "warnings": [warning],
            }
        )
    )
    (tmp_path / "summary.csv").write_text("variant,fit\n")
    files = {"summary": str(tmp_path / "summary.csv"), "trials": {"a": {"angles": str(angles)}}}
    trials = {"a": {"rig": "rig", "kind": "video", "source": "data/raw/a.mp4", "overrides": {}}}
    report = R.Report(files=files, trials=trials, rigs={"rig": {"values": RIG, "tolerances": {}}}, variants=VARIANTS)
    table = report.rig_table()
    # √0.0030 = 0.0548, √0.5036 = 0.7096
    assert "300.07 ± 0.055, −42.317 ± 0.71 (estimated from the tracked paths)" in table
    assert "0.0223 (estimated from the swings)" in table
    assert "1000 (default)" in table and "9.810 (default)" in table and "1.000×10⁻⁶ (default)" in table
    assert "± 2.0 (0.20 %, default)" in table and "not in the error budget" in table  # ρ: 0.2 %; ν: none
    assert "poorly determined by the marker paths" in report.tracking_section()


def test_own_data_and_config_do_not_dirty_the_tree_and_dirty_files_are_named():
    """A new user moved the demo truth files out of data/truth (README 'Your own videos') and every summary box
    said 'uncommitted changes' with the provenance table's bare 'yes'."""
    from pendulum.provenance import NOT_CODE
    from pendulum.report.checks import changes_text

    assert {"data/raw", "data/truth", "config.yaml"} <= set(NOT_CODE)
    assert "workflow" not in NOT_CODE and "notebooks" not in NOT_CODE
    assert changes_text(False, []) == "no" and changes_text(None, None) == "unknown"
    files = [f"workflow/pendulum/m{i}.py" for i in range(7)]
    assert changes_text(True, files) == "yes: " + ", ".join(files[:5]) + " and 2 more"


def test_a_baseline_that_is_not_white_is_not_called_free_of_structure():
    """A new user's baseline at 3.5× the noise with Ljung–Box p < 10⁻¹⁰ read 'no structure left' beside the
    linear damping discovery had just named."""
    doc = _discovery_document()
    doc["baseline"]["residual_check"].update(rms_over_noise=3.54, structured=False)
    doc["baseline"]["residual_check"]["whiteness"] = {
        "ljung_box_q": 81.6,
        "dof": 12,
        "p_value": 1e-12,
        "spacing_s": 0.2,
    }
    html = residual_check_table(doc)
    assert "not white, but within 5.0× the noise" in html
    assert html.count("no structure left") == 1  # the final model's (p = 0.63, 1.0× the noise)


def test_rig_values_every_trial_overrides_are_shown_as_used(tmp_path):
    """Table 1 says the values the fits used: where every trial of a rig gives its own value in its sidecar (a new
    user's apple trials left in the default rig), that value and what follows from it, not the rig's (a review
    read 3.530 kg and a buoyancy of 24.53 N for a 0.18 kg apple in air); trials that differ: per trial."""
    (tmp_path / "summary.csv").write_text("variant,fit\n")
    files = {"summary": str(tmp_path / "summary.csv"), "trials": {}}
    air = {"mass_kg": 0.18, "length_m": 1.053, "fluid_density_kg_m3": 1.2}
    trials = {
        t: {"rig": "rig", "kind": "video", "source": f"data/raw/{t}.mp4", "overrides": {**air, "length_m": length}}
        for t, length in (("a", 1.053), ("b", 1.053), ("c", 1.06))
    }
    report = R.Report(files=files, trials=trials, rigs={"rig": {"values": RIG, "tolerances": {}}}, variants=VARIANTS)
    table = report.rig_table()
    assert "0.1800 (the sidecars of all its trials)" in table and "3.530" not in table
    assert "per trial (sidecars): 1.053, 1.060" in table  # the arm differs between the trials
    assert "1.500×10⁻⁵ (default)" in table  # ν: air's for their fluid of 1.2 kg/m³, not water's 10⁻⁶
    trials["c"]["overrides"]["length_m"] = 1.053
    table = R.Report(files=files, trials=trials, rigs={"rig": {"values": RIG, "tolerances": {}}}, variants=VARIANTS)
    table = table.rig_table()
    assert "1.766" in table  # the weight m g of the apple (0.18 kg × 9.81), not the rig's 34.63 N
    # the tolerances as the trials' fits take them: the rig's 5 g was stated for its 3.53 kg, not for the apple
    # (its sidecars state none: the default 0.2 %); a tolerance the trials state differently: per trial
    stated = {"mass_kg": 0.005, "length_m": 0.001}
    for t in trials:
        trials[t]["tolerances"] = {"length_m": 0.001}
    table = R.Report(files=files, trials=trials, rigs={"rig": {"values": RIG, "tolerances": stated}}, variants=VARIANTS)
    table = table.rig_table()
    assert "± 3.6×10⁻⁴ (0.20 %, default)" in table and "2.8 %" not in table and "± 0.0010 (0.095 %)" in table
    trials["c"]["tolerances"] = {"length_m": 0.001, "mass_kg": 0.001}
    table = R.Report(files=files, trials=trials, rigs={"rig": {"values": RIG, "tolerances": stated}}, variants=VARIANTS)
    assert "per trial (sidecars): ± 0.0010, default" in table.rig_table()  # c states 1 g, a and b none
