"""The results report: number formatting, best variant, tables from result documents, and the built
report (byte-identical rebuilds, only the report reruns when its code changes, and it renders in
headless Chromium with every image decoded and a Table 3 row per trial and variant)."""

import html as html_module
import json
import os
import re
import shutil
import subprocess
import sys
import time

import nbformat
import pandas as pd
import pytest

from conftest import demo_trials
from pendulum.report import notebook as R
from pendulum.report.data import best_variant, nested_parents, variant_order
from pendulum.report.format import estimate_parts, fmt, format_estimate, photo_data_uri
from workflow_run import digest, planned_wildcards, run

VARIANTS = {"quadratic": ["quadratic_drag"], "linear": ["quadratic_drag", "linear_damping"]}


# ---------------------------------------------------------------------------
# Numbers


def test_a_coefficient_at_its_bound_is_never_printed_as_rounding_noise():
    entry = {"value": 4.2577e-14, "ci95": [0.0, 0.00118], "lower_bound": 0.0, "at_bound": True, "identifiable": True}
    assert format_estimate(entry) == "0 (at bound; < 0.0012)"


def test_a_contact_sheet_is_embedded_as_a_jpeg_an_eighth_of_its_png_and_as_it_looks():
    """Camera frames' noise makes a PNG of them large; a report of many trials carries one sheet per trial."""
    import base64

    import cv2
    import numpy as np

    rng = np.random.default_rng(0)
    scene = cv2.GaussianBlur(rng.normal(128, 40, (540, 1280)), (0, 0), 3) + rng.normal(0, 3, (540, 1280))
    sheet = cv2.cvtColor(np.clip(scene, 0, 255).astype(np.uint8), cv2.COLOR_GRAY2BGR)
    cv2.circle(sheet, (400, 300), 10, (0, 200, 0), 2)  # a track's green ring
    png = cv2.imencode(".png", sheet)[1].tobytes()
    uri = photo_data_uri(png)
    assert uri.startswith("data:image/jpeg;base64,")
    jpeg = base64.b64decode(uri.split(",", 1)[1])
    assert len(jpeg) < len(png) / 4, (len(jpeg), len(png))
    shown = cv2.imdecode(np.frombuffer(jpeg, np.uint8), cv2.IMREAD_COLOR)
    assert shown.shape == sheet.shape and np.abs(shown.astype(int) - sheet).mean() < 3.0
    assert photo_data_uri(b"not an image").startswith("data:image/png;base64,")  # as it is: the browser says


def test_estimates_keep_two_significant_figures_of_their_interval():
    added_mass = {"value": 2.500119943, "ci95": [2.258329771, 2.741910116], "at_bound": False, "identifiable": True}
    assert estimate_parts(added_mass) == ("2.50", "[2.26, 2.74]")
    drag_area = {"value": 0.02575155777, "ci95": [0.02467542841, 0.02682768713], "at_bound": False}
    assert format_estimate(drag_area) == "0.0258 [0.0247, 0.0268]"
    friction = {"value": 0.01998299443, "ci95": [0.01917203081, 0.02079395804], "at_bound": False}
    assert format_estimate(friction) == "0.01998 [0.01917, 0.02079]"
    negative = {"value": -0.1304, "ci95": [-0.2, -0.0608], "identifiable": False}
    assert format_estimate(negative) == "−0.130 [−0.200, −0.061] not identifiable"
    assert format_estimate(None) == "—"


def test_plain_numbers_use_significant_figures_and_powers_of_ten_only_when_needed():
    assert fmt(0.003859462471, 2) == "0.0039"
    assert fmt(6.736e-05, 2) == "6.7×10⁻⁵"
    assert fmt(-59523.16, 3) == "−59523"
    assert fmt(1000.0, 4) == "1000"
    assert fmt(3.53, 4) == "3.530"
    assert fmt(float("nan")) == "—" and fmt(None) == "—" and fmt(0.0) == "0"


# ---------------------------------------------------------------------------
# Best variant and nested terms


def _summary_rows(rows):
    return pd.DataFrame(rows, columns=["variant", "fit", "aic", "bic", "samples_digest"])


def test_best_variant_is_the_lowest_aic_among_fits_of_the_same_samples():
    table = _summary_rows(
        [
            ("quadratic", "joint:rig", -100.0, -90.0, "a"),
            ("linear", "joint:rig", -300.0, -280.0, "a"),
            ("friction", "joint:rig", -250.0, -260.0, "a"),
        ]
    )
    best = best_variant(table, "joint:rig", ["t1"])
    assert best["variant"] == "linear" and best["comparable"]
    assert best["delta_aic"] == {"friction": 50.0, "linear": 0.0, "quadratic": 200.0}
    assert best["bic_best"] == "linear"


def test_joint_fits_of_different_samples_are_compared_on_the_trials_fitted_alike():
    # friction's joint fit dropped samples (lower AIC, not comparable); per trial, t1 was fitted alike
    table = _summary_rows(
        [
            ("linear", "joint:rig", -300.0, -280.0, "a"),
            ("friction", "joint:rig", -900.0, -880.0, "b"),
            ("linear", "t1", -150.0, -140.0, "x"),
            ("friction", "t1", -120.0, -110.0, "x"),
            ("linear", "t2", -150.0, -140.0, "y"),
            ("friction", "t2", -700.0, -690.0, "z"),
        ]
    )
    best = best_variant(table, "joint:rig", ["t1", "t2"])
    assert best["variant"] == "linear"
    assert "per-trial fits of 1 of the rig's 2 trial(s) (t1)" in best["basis"] and best["comparable"]
    assert best_variant(table, "joint:other", ["t1"]) is None


def test_each_variant_adds_one_term_to_each_of_its_nested_parents():
    variants = {**VARIANTS, "friction": ["quadratic_drag", "linear_damping", "coulomb_friction"], "air": []}
    assert variant_order(variants) == ["air", "quadratic", "linear", "friction"]
    assert nested_parents(variants, "friction") == ["linear"]
    assert nested_parents(variants, "quadratic") == ["air"]
    assert nested_parents(variants, "air") == []
    # a reviewer's four variants: the full model has two parents, each one term short; both pairs are tests
    variants = {
        "quadratic": ["quadratic_drag"],
        "qfric": ["quadratic_drag", "coulomb_friction"],
        "nodrag": ["linear_damping", "coulomb_friction"],
        "full": ["quadratic_drag", "linear_damping", "coulomb_friction"],
    }
    assert nested_parents(variants, "full") == ["nodrag", "qfric"]
    assert nested_parents(variants, "qfric") == ["quadratic"] and nested_parents(variants, "nodrag") == []


# ---------------------------------------------------------------------------
# Tables from result documents (one failed trial)


def _entry(value, half, at_bound=False):
    low = max(0.0, value - half) if at_bound else value - half
    return {
        "value": value,
        "stderr": half / 1.96,
        "stderr_statistical": half / 2.5,
        "ci95": [low, value + half],
        "lower_bound": 0.0,
        "at_bound": at_bound,
        "identifiable": True,
        "scale_factor": 1.0,
    }


def _fit(variant, trial, drag_area, aic, warnings=()):
    parameters = {
        "added_mass_kg": _entry(2.5, 0.24),
        "drag_area_m2": _entry(drag_area, 0.003, at_bound=drag_area == 0),
        "drag_coefficient": _entry(drag_area / 0.0322, 0.1, at_bound=drag_area == 0),
    }
    if "linear_damping" in VARIANTS[variant]:
        parameters["linear_damping_nm_s"] = _entry(0.15, 0.01)
    return {
        "trial": trial,
        "status": "ok",
        "variant": variant,
        "terms": VARIANTS[variant],
        "rig": {"name": "rig"},
        "parameters": parameters,
        "rms_rad": 1e-3,
        "rms_deg": 0.0573,
        "rms_arc_m": 7.6e-4,
        "aic": aic,
        "bic": aic + 10,
        "n_samples": 600,
        "n_parameters": 5,
        "samples_digest": f"d-{trial}",
        "keulegan_carpenter_number": 6.1,
        "trials": {trial: {"theta0_deg": 19.0, "fit_start_s": 0.25, "residual_lag1_autocorrelation": 0.5}},
        "warnings": list(warnings),
    }


@pytest.fixture
def documents(tmp_path):
    """Result files of two trials (t20 fitted by both variants, bad failed at tracking) and the joint fits."""
    files = {"trials": {}, "fits": {}, "joint": {}}
    failed = {"status": "failed", "failed_stage": "tracks", "error": "data/raw/bad.mp4: not a video file"}
    for trial in ("t20", "bad"):
        files["trials"][trial] = {"angles": str(tmp_path / f"{trial}.angles.json")}
        doc = {"status": "ok", "hold_angle_deg": 20.0, "noise_deg": 0.003} if trial == "t20" else failed
        (tmp_path / f"{trial}.angles.json").write_text(json.dumps(doc))
    rows = []
    for variant, drag, aic in (("quadratic", 0.0, -100.0), ("linear", 0.0258, -300.0)):
        files["fits"][variant] = {}
        for trial in ("t20", "bad"):
            doc = _fit(variant, trial, drag, aic, ["drag_area_m2 is at its lower bound (0)"] if not drag else [])
            doc = doc if trial == "t20" else failed
            path = tmp_path / f"{variant}.{trial}.json"
            path.write_text(json.dumps(doc))
            files["fits"][variant][trial] = {"fit": str(path), "curve": "", "cycles": ""}
        joint = _fit(variant, "t20", drag, aic)
        joint.pop("trial")
        joint["consistency"] = {"verdict": "not testable", "explanation": "one trial", "parameters": {}}
        (tmp_path / f"{variant}.joint.json").write_text(json.dumps(joint))
        files["joint"][variant] = {"rig": str(tmp_path / f"{variant}.joint.json")}
        rows += [(variant, "t20", aic, aic + 10, "d-t20"), (variant, "joint:rig", aic, aic + 10, "d-t20")]
    files["summary"] = str(tmp_path / "summary.csv")
    _summary_rows(rows).to_csv(files["summary"], index=False)
    files["status"] = str(tmp_path / "trials.csv")
    pd.DataFrame(
        [
            ("bad", "data/raw/bad.mp4", "rig", "failed", "tracks", failed["error"], "logs/tracks/bad.log"),
            ("t20", "data/raw/t20.mp4", "rig", "ok", "", "", ""),
        ],
        columns=["trial", "source", "rig", "status", "stage", "reason", "log"],
    ).to_csv(files["status"], index=False)
    trials = {
        t: {"rig": "rig", "kind": "angles", "source": f"data/raw/{t}.csv", "overrides": {}} for t in ("t20", "bad")
    }
    rigs = {"rig": {"values": {"mass_kg": 3.53, "length_m": 0.76, "frontal_area_m2": 0.0322}, "tolerances": {}}}
    return R.Report(files=files, trials=trials, rigs=rigs, variants=VARIANTS)


def test_many_trials_records_are_folded_by_rig(documents, monkeypatch):
    """A lab's 88 trials (a reviewer, 2026-12-07) gave 33,000 px of record figures, one per trial; beyond
    RECORDS_SHOWN trials with figures each rig's are folded in a <details> naming the rig and its count."""
    import numpy as np

    from pendulum.report import figures

    t = np.arange(0.0, 10.0, 1 / 30)
    theta = np.radians(20.0) * np.exp(-0.1 * t) * np.cos(2 * np.pi * t / 1.75)
    curve = pd.DataFrame(
        {
            "time_s": t,
            "theta_measured_rad": theta,
            "theta_fitted_rad": theta,
            "residual_rad": 1e-4 * np.sin(t),
            "flag": "fitted",
        }
    )
    for v in VARIANTS:
        documents._tables[("curve", v, "t20")] = curve
        documents.fits[(v, "t20")].setdefault("trials", {}).setdefault("t20", {})["fit_start_s"] = 0.0
        documents.fits[(v, "t20")].setdefault("keulegan_carpenter_number", 6.0)
    shown = documents.trial_figures()
    assert shown.count("<figure") == 1 and "<details" not in shown
    monkeypatch.setattr(figures, "RECORDS_SHOWN", 0)
    folded = documents.trial_figures()
    assert folded.count("<figure") == 1 and folded.startswith("<p>1 trials' records, folded by rig")
    assert "<details><summary>Rig <b>rig</b>: the records of 1 trials</summary><figure" in folded


def test_a_figure_is_a_256_colour_png_a_third_of_the_full_colour_bytes_and_the_same_bytes_each_time():
    """A lab's 85 trials made 15.6 MB of PNG in one report (a reviewer, 2026-12-07): each figure is now quantised to
    256 colours (measured: 0.34 of the bytes on their record figures, lines and text alike to the eye)."""
    import io

    import numpy as np
    from PIL import Image

    from pendulum.report.figures import FIGURE_DPI, figure_png, new_figure

    fig = new_figure(10, 4)
    ax = fig.add_subplot()
    t = np.linspace(0, 20, 1200)
    ax.plot(t, np.sin(t), ".", ms=2)
    ax.plot(t, 0.05 * np.random.default_rng(0).standard_normal(t.size), lw=0.6)
    full = io.BytesIO()
    fig.savefig(full, format="png", dpi=FIGURE_DPI, metadata={"Software": None})
    png = figure_png(fig)
    image = Image.open(io.BytesIO(png))
    assert image.mode == "P" and len(image.getcolors(256)) <= 256 and image.size == (10 * FIGURE_DPI, 4 * FIGURE_DPI)
    assert len(png) < 0.6 * len(full.getvalue()) and png == figure_png(fig)


def test_table3_has_a_row_per_trial_and_variant_and_says_why_a_fit_is_missing(documents):
    html = documents.coefficient_table()
    for trial in ("t20", "bad"):
        for variant in VARIANTS:
            assert f'data-trial="{trial}" data-variant="{variant}" data-kind="trial"' in html
    # the reason once a trial (a reviewer counted each refusal three times, 2026-12-02); the next variant's "as above"
    assert html.count("tracks failed: data/raw/bad.mp4: not a video file") == 2  # once shown, once as its tooltip
    assert html.count(">failed, as above</td>") == 1
    assert not re.search(r"\de-\d", html) and "(at bound; &lt; 0.0030)" in html
    assert 'data-trial="joint:rig" data-variant="linear" data-kind="joint"' in html


def test_the_summary_recommends_the_best_variant_and_warns_of_the_failed_trial(documents):
    assert documents.recommended("rig") == "linear"
    box = documents.summary_box()
    assert "variant linear (quadratic drag + linear damping)" in box
    assert "1 trial(s) failed and are not in the fit: bad" in box
    assert "not built from a git commit" in box.lower()
    failures = documents.failures_section()
    assert "bad" in failures and "not a video file" in failures and "logs/tracks/bad.log" in failures
    assert "1 of 2 trial(s) failed" in failures


def test_a_trial_refused_at_the_fit_shows_its_usable_frames_and_period_among_the_failed(documents):
    """A clip whose track and angle record stand but whose fit the rig's values refused: the failed trials' table
    and the header say so (a reviewer found the periods of seven such clips only in the tracking table)."""
    refused = "trial t20: its period 2.078 s as swung (2.059 s at small amplitude) is shorter …"
    documents.status = pd.DataFrame(
        [
            ("bad", "data/raw/bad.mp4", "rig", "failed", "tracks", "", "", "not a video file", "logs/tracks/bad.log"),
            ("t20", "data/raw/t20.mp4", "rig", "failed", "fit (every variant)", 99.85, 2.078132, refused, "l.log"),
        ],
        columns=["trial", "source", "rig", "status", "stage", "ok_frames_pct", "period_s", "reason", "log"],
    )
    failures = documents.failures_section()
    assert "<th>usable frames (%)</th><th>period (s)</th>" in failures
    assert '<td class="num">99.85</td><td class="num">2.07813</td>' in failures, failures
    assert '<td>bad</td><td>tracks</td><td class="num">—</td><td class="num">—</td>' in failures
    assert "2 trial(s) failed</span> (1 of them after their angle records were made)" in documents.header()
    # beside the recommended coefficients of the others, the summary says why too (it did so only where no joint
    # fit succeeded)
    for variant in VARIANTS:
        documents.fits[(variant, "bad")] = {
            "status": "failed",
            "failed_stage": "fit",
            "error": refused,
            "rig_mismatch": [{"trial": "bad", "period_s": 2.059, "swing_period_s": 2.078, "fastest_period_s": 3.2378}],
        }
    box = documents.summary_box()
    assert "Recommended coefficients" in box and "cannot give the swing of 1 of its 2 trial(s)" in box, box
    assert "trial(s): its period 2.078 s as swung" in box


def test_the_failed_trials_section_lists_the_skipped_and_those_no_variant_fits(documents):
    """A star skipped by its sidecar and an apple that every variant misses (the status table's columns as the
    workflow writes them): both said under *Failed or skipped trials*, neither counted as failed."""
    from pendulum.outcomes import skipped_status, status_table

    misses = "fit (every variant): trial t20: residual RMS 0.235° is 78× … the model misses a systematic effect; …"
    ok = dict.fromkeys(["source", "rig", "stage", "reason", "log"], "")
    rows = [{**ok, "trial": "t20", "status": "ok", "n_warnings": 1, "warnings": misses}]
    rows.append(skipped_status("star", "data/raw/star.mov", "skipped by data/raw/star.yaml: spins on its thread"))
    documents.status = status_table(rows)
    failures = documents.failures_section()
    assert failures.startswith("<p>All ") and "succeeded at every stage" in failures
    assert "<li><code>star</code>: skipped by data/raw/star.yaml: spins on its thread</li>" in failures
    assert "<p><code>t20</code>: succeeded, but every model variant misses the record far beyond" in failures
    header = documents.header()
    assert ', <span class="warn">1 trial(s) that no variant fits</span>, 1 skipped by their sidecars.' in header


def test_the_summary_does_not_recommend_a_fit_that_misses_its_records(documents):
    """A best variant whose joint fit misses its records by far more than their noise is the best tried, not a
    recommendation (the real apple clip's quadratic fit: 78× the noise, titled "Recommended" before)."""
    assert "<h3>Recommended coefficients — rig rig" in documents.summary_box()
    documents.joint[("linear", "rig")]["warnings"] = [
        "trial t20: residual RMS 0.235° is 78× the record's noise (0.003°) and smooth (lag-1 1.00): the model misses "
        "a systematic effect; its coefficients absorb it and their intervals do not cover that error"
    ]
    box = documents.summary_box()
    assert "Recommended" not in box and "<h3>Best of the variants tried, none fits within the record's noise" in box


def test_many_trials_misfits_are_said_once_in_the_summary(documents):
    """Thirteen apple clips (a fresh-eyes user, 2026-12-03): the summary listed each trial's misfit warning, 13
    paragraphs; more than three are said in one line, with the trials and their ranges."""
    from pendulum.report.checks import misfits_together

    def misfit(trial, rms, ratio):
        return (
            f"trial {trial}: residual RMS {rms}° is {ratio}× the record's noise (0.003°) and smooth (lag-1 1.00): the "
            "model misses a systematic effect; its coefficients absorb it and their intervals do not cover that error"
        )

    warnings = ["the consistency test is not testable"] + [misfit(f"a{k}", 0.2 + k / 100, 40 + k) for k in range(5)]
    assert misfits_together(warnings[:4]) == warnings[:4]  # three trials: each said
    together = misfits_together(warnings)
    assert together == [
        warnings[0],
        "5 trials' residuals (a0, a1, a2, a3, a4) are 0.2–0.24° RMS, 40–44× their records' noise, and smooth: the "
        "model misses a systematic effect; its coefficients absorb it and their intervals do not cover that error",
    ]
    documents.joint[("linear", "rig")]["warnings"] = warnings
    box = html_module.unescape(documents.summary_box())
    assert box.count("misses a systematic effect") == 1 and "5 trials' residuals (a0, a1, a2, a3, a4)" in box


def test_a_rig_whose_values_cannot_give_its_trials_periods_says_so_in_the_summary(tmp_path):
    """Real clips dropped into the shipped rig without sidecars: every fit refused (``rig_mismatch``); the summary
    says the rig's values are another pendulum's, with the periods, and what to give (before: "No joint fit
    succeeded" alone)."""
    ok = {"status": "ok"}
    (tmp_path / "ok.json").write_text(json.dumps(ok))
    (tmp_path / "summary.csv").write_text("variant,fit\n")
    fits = {}
    for name, period in (("apple", 2.061), ("clock", 1.654)):
        refused = {
            "status": "failed",
            "failed_stage": "fit",
            "error": f"trial {name}: its period {period} s is shorter than its rig values allow (3.238 s ...)",
            "rig_mismatch": [
                {"trial": name, "period_s": period, "swing_period_s": period + 0.02, "fastest_period_s": 3.2378}
            ],
        }
        (tmp_path / f"{name}.json").write_text(json.dumps(refused))
        fits[name] = {"fit": str(tmp_path / f"{name}.json"), "curve": str(tmp_path / "none.csv"), "cycles": ""}
    doc = str(tmp_path / "ok.json")
    files = {
        "summary": str(tmp_path / "summary.csv"),
        "trials": {n: {"angles": doc, "frames": doc, "tracks": doc} for n in fits},
        "fits": {v: fits for v in VARIANTS},
        "joint": {v: {"rig": str(tmp_path / "apple.json")} for v in VARIANTS},
    }
    trials = {n: {"rig": "rig", "kind": "video", "source": f"data/raw/{n}.mp4", "overrides": {}} for n in fits}
    rigs = {"rig": {"values": {"mass_kg": 3.53, "length_m": 0.76, "frontal_area_m2": 0.0322}, "tolerances": {}}}
    box = R.Report(files=files, trials=trials, rigs=rigs, variants=VARIANTS).summary_box()
    assert "No joint fit succeeded" in box
    # the periods as swung (what the tracking table and a stopwatch give), not the small-amplitude ones
    assert "cannot give the swing of 2 of its 2 trial(s): their periods 1.674–2.081 s as swung" in box, box
    # and the length a simple pendulum of such a period has (g T₀²/4π², from the small-amplitude periods 1.654 and
    # 2.061 s): what a user needs to write the sidecar (a reviewer, 2026-12-02)
    assert "(a simple pendulum of that period is 0.68–1.06 m long)" in box, box
    assert (
        "3.238 s at the least" in box
        and "<code>rig</code>" in box
        and "<code>fluid_density_kg_m3</code>: 1.2 in air" in box
    )


def test_trial_order_puts_trials_without_a_release_angle_last(documents):
    assert documents.trial_order() == ["t20", "bad"]
    assert documents.release_deg("t20") == 20.0 and documents.release_deg("bad") is None


def test_a_build_where_every_trial_failed_still_gives_every_section(tmp_path):
    failed = {"status": "failed", "failed_stage": "frames", "error": "data/raw/a.mp4: not a video file"}
    (tmp_path / "failed.json").write_text(json.dumps(failed))
    (tmp_path / "summary.csv").write_text("variant,fit\n")
    doc = str(tmp_path / "failed.json")
    files = {
        "summary": str(tmp_path / "summary.csv"),
        "trials": {"a": {"angles": doc, "frames": doc, "tracks": doc, "contact_sheet": str(tmp_path / "none.png")}},
        "fits": {v: {"a": {"fit": doc, "curve": str(tmp_path / "none.csv"), "cycles": ""}} for v in VARIANTS},
        "joint": {v: {"rig": doc} for v in VARIANTS},
    }
    trials = {"a": {"rig": "rig", "kind": "video", "source": "data/raw/a.mp4", "overrides": {}}}
    rigs = {"rig": {"values": {"mass_kg": 3.53, "length_m": 0.76, "frontal_area_m2": 0.0322}, "tolerances": {}}}
    report = R.Report(files=files, trials=trials, rigs=rigs, variants=VARIANTS)
    sections = [
        report.header(),
        report.summary_box(),
        report.rig_table(),
        report.rms_table(),
        report.coefficient_table(),
        report.trial_figures(),
        report.consistency_figure(),
        report.extinction_figure(),
        report.model_comparison(),
        report.truth_section(),
        report.tracking_section(),
        report.failures_section(),
        report.provenance_section(),
    ]
    assert "No joint fit succeeded" in sections[1]
    assert "frames failed: data/raw/a.mp4: not a video file" in sections[4]
    assert "1 of 1 trial(s) failed" in sections[11] and "not a video file" in sections[11]
    assert all(isinstance(s, str) for s in sections)


def test_the_executed_notebook_keeps_no_timestamps_or_random_ids():
    nb = nbformat.v4.new_notebook(cells=[nbformat.v4.new_code_cell("1"), nbformat.v4.new_markdown_cell("x")])
    nb.metadata["papermill"] = {"start_time": "2026-01-01T00:00:00", "duration": 1.5, "input_path": "/tmp/a"}
    nb.cells[0].metadata["papermill"] = {"start_time": "2026-01-01T00:00:00", "duration": 0.1}
    nb.cells[0].metadata["execution"] = {"iopub.execute_input": "2026-01-01T00:00:00"}
    nb.cells[0].outputs = [nbformat.v4.new_output("stream", name="stderr", text="a warning\n")]
    assert R.normalise_notebook(nb) == ["a warning\n"]
    text = nbformat.writes(nb)
    assert "2026" not in text and "duration" not in text and "input_path" not in text
    assert [c.id for c in nb.cells] == ["cell-00", "cell-01"]


@pytest.mark.slow
def test_the_report_kernel_runs_encrypted_without_the_plain_tcp_warning(tmp_path):
    """build_report's kernel gets CurveZMQ keys: the page is built and the kernel's stderr carries
    no "running over TCP without encryption" warning (it did on every build before)."""
    nb = nbformat.v4.new_notebook(cells=[nbformat.v4.new_code_cell("print(6 * 7)")])
    nbformat.write(nb, str(tmp_path / "in.ipynb"))
    code = (
        "import sys; sys.path.insert(0, sys.argv[1]);"
        "from pendulum.report.notebook import build_report;"
        "build_report('in.ipynb', 'out.html', 'out.ipynb', {})"
    )
    library = os.path.join(os.path.dirname(__file__), "..", "workflow")
    done = subprocess.run([sys.executable, "-c", code, library], cwd=tmp_path, capture_output=True, text=True)
    assert done.returncode == 0, done.stderr
    assert "42" in (tmp_path / "out.html").read_text()
    assert "without encryption" not in done.stderr, done.stderr


def test_the_page_loads_nothing_from_outside():
    page = R.page_html("<p>body</p>", "t")
    assert "<script" not in page and "http" not in page and "@media print" in page


# ---------------------------------------------------------------------------
# The built report


@pytest.fixture(scope="module")
def report_project(tmp_path_factory, demo_project):
    """The demo build (with its synthetic truth) copied; the report rebuilt once to time it."""
    work = tmp_path_factory.mktemp("report") / "p"
    shutil.copytree(demo_project, work, symlinks=True)
    assert (work / "data/truth").is_dir()
    start = time.perf_counter()
    proc = run(["-c1", "--forcerun", "report", "results/report/report.html"], work)
    seconds = time.perf_counter() - start
    planned = {rule for rule, _ in planned_wildcards(proc.stdout + proc.stderr)}
    assert "report" in planned and planned <= {"report", "check_trials", "all"}, planned
    print(f"report rule: {seconds:.1f} s")
    return work


def test_the_report_is_byte_identical_when_built_again(report_project):
    report = report_project / "results/report"
    before = digest(report, ("*.html", "*.ipynb"))
    assert set(before) == {"report.html", "report.ipynb"}
    run(["-c1", "--forcerun", "report", "results/report/report.html"], report_project)
    assert digest(report, ("*.html", "*.ipynb")) == before


def test_the_page_opens_with_links_to_every_section(report_project):
    page = (report_project / "results/report/report.html").read_text()
    nav = re.search(r'<nav class="contents">(.*?)</nav>', page, flags=re.S)
    assert nav and page.index("</header>") < nav.start() < page.index("<h2"), "no contents line under the header"
    links = re.findall(r'<a href="#([^"]+)">([^<]+)</a>', nav.group(1))
    headings = re.findall(r'<h2 id="([^"]+)"', page)
    assert [anchor for anchor, _ in links] == headings and len(headings) >= 12
    assert ("summary", "Summary") in links and ("failed-trials", "Failed or skipped trials") in links


def test_contents_are_taken_from_the_headings_with_their_anchor_marks_removed():
    body = (
        '<header><h1>T</h1></header>\n<h2 id="a">First <a class="anchor-link" href="#a">¶</a></h2><p>x</p>'
        '<h2 id="b">B &amp; C</h2>'
    )
    page = R.with_contents(body)
    assert (
        '</header>\n<nav class="contents">Contents: <a href="#a">First</a> · <a href="#b">B &amp; C</a></nav>' in page
    )
    assert R.with_contents("<p>no sections</p>") == "<p>no sections</p>"


def test_editing_plot_code_or_the_notebook_reruns_only_the_report(report_project):
    for path, edit in (
        ("workflow/pendulum/report/figures.py", "\nMPL_STYLE['lines.linewidth'] = 1.2  # a style edit\n"),
        ("notebooks/report.ipynb", "\n"),
    ):
        path = report_project / path
        text, stat = path.read_text(), path.stat()
        path.write_text(text + edit)
        try:
            out = run(["-n"], report_project).stdout
        finally:
            path.write_text(text)
            os.utime(path, ns=(stat.st_atime_ns, stat.st_mtime_ns))
        # check_trials waits for the report so that it runs last
        assert {rule for rule, _ in planned_wildcards(out)} == {"report", "check_trials", "all"}, path
    assert "Nothing to be done" in run(["-n"], report_project).stdout


def _chromium():
    for name in ("chromium", "chromium-browser", "google-chrome", "google-chrome-stable"):
        if shutil.which(name):
            return shutil.which(name)
    if os.environ.get("CI"):
        pytest.fail("Chromium is not installed; .ci/run installs Debian's chromium package")
    pytest.skip("Chromium not found (apt-get install chromium); CI installs it and runs this test")


# Appended to a copy of the report (the report itself has no scripts): once the page has loaded
# (every image fetched and decoded: a broken one has naturalWidth 0) it writes what the test checks
# into the page, which --dump-dom prints.
CHECK_SCRIPT = """
<script>
window.addEventListener("load", () => {
  const images = [...document.images];
  const rows = [...document.querySelectorAll('#table3 tbody tr[data-kind="trial"]')];
  const result = {
    images: images.map((img) => [img.alt, img.complete, img.naturalWidth, img.naturalHeight]),
    table3: rows.map((r) => [r.dataset.trial, r.dataset.variant]),
    sections: [...document.querySelectorAll("h2[id]")].map((h) => h.id),
    external: [...document.querySelectorAll("[src], [href]")]
      .map((e) => e.getAttribute("src") || e.getAttribute("href"))
      .filter((u) => !u.startsWith("data:") && !u.startsWith("#")),
    scripts: document.scripts.length - 1,
    height: Math.ceil(document.documentElement.scrollHeight),
  };
  const out = document.createElement("pre");
  out.id = "report-check";
  out.textContent = JSON.stringify(result);
  document.body.appendChild(out);
});
</script>
"""


def _chrome(binary, profile, *args):
    command = [
        binary,
        "--headless",
        "--no-sandbox",
        "--disable-gpu",
        "--disable-dev-shm-usage",
        "--hide-scrollbars",
        "--no-first-run",
        f"--user-data-dir={profile}",
        *args,
    ]
    return subprocess.run(command, capture_output=True, text=True, timeout=180)


def test_the_report_renders_in_chromium_with_every_image_and_table3_complete(report_project, tmp_path):
    binary = _chromium()
    html = report_project / "results/report/report.html"
    check = tmp_path / "check.html"
    check.write_text(html.read_text().replace("</body>", CHECK_SCRIPT + "</body>"))
    proc = _chrome(
        binary,
        tmp_path / "profile",
        "--window-size=1280,1000",
        "--virtual-time-budget=20000",
        "--dump-dom",
        check.as_uri(),
    )
    marker = '<pre id="report-check">'
    assert marker in proc.stdout, proc.stderr[-2000:]
    result = json.loads(html_module.unescape(proc.stdout.split(marker, 1)[1].split("</pre>", 1)[0]))

    trials = demo_trials()
    variants = ("friction", "linear", "quadratic")
    # figures: one per trial, consistency, extinction, discovery's residuals and extinction; one contact sheet per video
    assert len(result["images"]) == len(trials) + 4 + len(trials), result["images"]
    for alt, complete, width, height in result["images"]:
        assert complete and width > 0 and height > 0, alt
    assert sorted(map(tuple, result["table3"])) == sorted((t, v) for t in trials for v in variants)
    assert result["sections"] == [
        "summary",
        "rig-values",
        "rms",
        "coefficients",
        "budget",
        "records",
        "consistency",
        "extinction",
        "model-comparison",
        "discovery",
        "design",
        "truth",
        "tracking",
        "failed-trials",
        "provenance",
    ]
    assert result["external"] == [] and result["scripts"] == 0

    screenshot = report_project / "results/report/report.png"
    height = min(max(result["height"], 1000), 30000)
    proc = _chrome(
        binary, tmp_path / "profile", f"--window-size=1280,{height}", f"--screenshot={screenshot}", html.as_uri()
    )
    assert screenshot.is_file() and screenshot.stat().st_size > 100_000, proc.stderr[-2000:]
    print(f"screenshot: {screenshot} (1280 × {height} px)")


def test_a_log_axis_spanning_less_than_a_factor_three_has_several_labels():
    """A new user's local-C_d panel (1.0 to 1.9) had the single label '1'; wide spans keep 1-2-5 ticks."""
    from pendulum.report.figures import log_axes, new_figure

    fig = new_figure(6, 2.5)
    narrow, wide = fig.subplots(1, 2)
    narrow.plot([0.5, 3.0], [1.05, 1.85], "s")
    wide.plot([0.1, 30.0], [0.01, 5.0], "s")
    for ax in (narrow, wide):
        log_axes(ax, "x", "y")
    fig.canvas.draw()

    def shown(ax):
        low, high = ax.get_ylim()
        return [
            float(t.get_text()) for t, v in zip(ax.get_yticklabels(), ax.get_yticks(), strict=True) if low <= v <= high
        ]

    assert len(shown(narrow)) >= 3
    assert {0.01, 0.1, 1.0, 0.2, 2.0}.issubset(shown(wide))


def test_the_summary_says_what_the_videos_records_carry(documents):
    """A creeping camera, a path off one circle and frames the phone lost are said where users read first (the real
    apple clip's were only in the tracking table's notes)."""
    assert "records carry" not in documents.summary_box()
    documents.docs[("t20", "tracks")] = {
        "status": "ok",
        "path": {
            "corrected": True,
            "departs": True,
            "creep": {"motion_px": 13.1},
            "unexplained_rms_px": 0.44,
            "unexplained_angle_deg": 0.0455,
        },
        "timing": {"slips": [[276, 0.8], [463, 0.99]], "repeated": [407]},
    }
    box = documents.summary_box()
    assert "<b>t20</b>: the camera crept by 13 px (corrected)" in box
    assert "off one circle by 0.44 px RMS (0.045°; not corrected, it stays in the angles)" in box
    assert "elliptical" not in box
    documents.docs[("t20", "tracks")]["path"]["out_of_plane"] = {"rms_left_px": 0.2}
    assert "its swing is elliptical, out of the picture" in documents.summary_box()
    del documents.docs[("t20", "tracks")]["path"]["out_of_plane"]
    documents.docs[("t20", "tracks")]["path"]["camera_motion"] = {"rms_px": 2.79, "max_turn_deg": 0.07}
    assert "the camera moved in the hand by 2.8 px RMS (measured from the still scene" in documents.summary_box()
    del documents.docs[("t20", "tracks")]["path"]["camera_motion"]
    assert (
        "1 frame(s) lost, 1 repeated, 1 slip(s) of the clock by part of a frame while the time stamps in the file"
        in box
    )
    # a trial the recommended joint fit leaves out (failed, refused) is not among the records its numbers rest on
    # (a reviewer's run, 2026-12-02: seven failed clips' notes listed under the coefficients of five others)
    for joint in documents.joint.values():
        joint["trials"] = {t: v for t, v in (joint.get("trials") or {}).items() if t != "t20"}
    assert "records carry" not in documents.summary_box()


def test_the_summary_says_a_knocked_camera_apart_from_its_creep(documents):
    """A knock (a step of the pivot in the picture, corrected, its shaking flagged) is said with its time and size,
    and the creep beside it without the step (the path's start-to-end motion holds both)."""
    documents.docs[("t20", "tracks")] = {
        "status": "ok",
        "path": {
            "corrected": True,
            "creep": {
                "degree": 2,
                "motion_px": 18.7,
                "start_to_end_px": [17.3, -6.5],
                "knock": {"time_s": 9.5105, "shift_px": [10.4, 3.2], "stderr_px": 1.1, "from_s": 9.49, "to_s": 10.01},
            },
        },
    }
    box = documents.summary_box()
    assert "<b>t20</b>: the pivot jumped by 11 px in the picture at 9.51 s (the camera knocked" in box
    assert "the camera crept by 12 px (corrected)" in box  # |(17.3 − 10.4, −6.5 − 3.2)| = 11.9


def test_the_summary_says_an_uncalibrated_wide_lens_and_a_knock_it_bent_into_the_path(documents):
    """An uncalibrated GoPro-like trial: its angles 8–17 % too large, said only in the tracking table's notes, while
    the summary said the knock its lens bent into the path was "corrected" (it was not applied)."""
    documents.docs[("t20", "tracks")] = {
        "status": "ok",
        "path": {
            "corrected": False,
            "creep": {"degree": 0, "corrected": False},
            "not_applied": {"degree": 0, "knock": {"time_s": 1.58, "shift_px": [3.5, -2.2]}},
        },
    }
    documents.docs[("t20", "angles")] = {"status": "ok", "uncalibrated_size_change": 1.167}
    box = documents.summary_box()
    assert "image is 17 % larger at one place on its path than at another" in box
    assert "scales the angles" in box and "its path read a knock that such a view bends into it (not applied)" in box
    assert "pivot jumped" not in box


def test_a_record_without_a_release_is_labelled_by_its_first_swing_extremum(documents):
    """A clip that starts mid-swing: the † angle is the measured amplitude at its first extremum (the fitted angle at
    its first sample, −11° for a 15° swing passing through, said nothing of the swing)."""
    documents.docs[("t20", "angles")] = {"status": "ok", "hold_angle_deg": None, "first_extremum_deg": 21.7}
    assert documents.angle_label("t20") == "+22°†"
    assert "first turning point" in documents.dagger_note()
    # released by hand in view, the hand hiding the hold where the free swing could not tell it: ‡, not "no release"
    documents.docs[("t20", "angles")] = {
        "status": "ok",
        "release_detected": True,
        "held_frames": 90,
        "hold_angle_deg": None,
        "first_extremum_deg": 21.7,
    }
    assert documents.angle_label("t20") == "+22°‡"
    assert "Released by hand in view" in documents.dagger_note() and "No release" not in documents.dagger_note()


def test_table1_gives_the_pivot_most_trials_share_and_counts_the_others(documents):
    """Seven clips of other pendulums beside the demo's five, each on its own pivot: Table 1 said only 'not one for
    all trials' where five trials share the rig's pooled pivot (a reviewer, 2026-12-02)."""
    shared = {"status": "ok", "pivot_px": [640.3, 70.59], "pivot_covariance_px2": [[1e-4, 0], [0, 6e-4]]}
    names = [f"d{k}" for k in range(5)] + ["apple", "clock"]
    for name in names:
        documents.docs[(name, "angles")] = dict(shared)
    documents.docs[("apple", "angles")]["pivot_px"] = [301.1, -337.6]
    documents.docs[("clock", "angles")]["pivot_px"] = [979.0, -338.0]
    documents.rig_trials = lambda rig: names
    text = documents.estimated_geometry_text("rig", "pivot_px")
    assert text.startswith("640.30 ± 0.010, 70.590 ± 0.024") and "2 other trial(s) their own" in text, text
    documents.rig_trials = lambda rig: ["d0", "apple", "clock"]  # no pivot that most share
    assert documents.estimated_geometry_text("rig", "pivot_px").startswith("not one for all trials")
    # a clock's pivot joined with where its rod's lines meet (pendulum.angles.rod): said
    documents.docs[("clock", "angles")]["pivot_rod_lines"] = 57
    documents.rig_trials = lambda rig: ["clock"]
    text = documents.estimated_geometry_text("rig", "pivot_px")
    assert text.endswith("(estimated from the tracked paths and a rod's lines in 57 frames)"), text


def test_a_term_that_trades_against_another_is_called_indistinguishable_not_unsupported(documents):
    """The apple clip in air, 22° to 18°: linear damping at its bound and −1.000 correlated with C_dA, the RMS the
    same with and without it; Table 7 said "not supported" where the record cannot tell the two laws apart (a
    reviewer, 2026-12-02). A term merely at its bound, with no such trade, stays "not supported"."""
    rows = {r["term"]: r for r in documents.term_evidence_rows("rig", documents.best.get("rig"))}
    assert rows and all(not r["verdict"].startswith("indistinguishable") for r in rows.values())
    from pendulum.model.effects import TERMS

    term = next(iter(rows))
    parameter = TERMS[term].parameter
    joint = documents.joint[(rows[term]["variant"], "rig")]
    joint["warnings"] = [f"drag_area_m2 and {parameter} are -1.000 correlated: the record hardly separates them"]
    verdict = documents.term_evidence_rows("rig", documents.best.get("rig"))[0]["verdict"]
    assert verdict.startswith("indistinguishable on these records: its coefficient trades against drag_area_m2")
    assert "a wider range of amplitudes would separate them" in verdict
    joint["warnings"] = [f"drag_area_m2 and {parameter} are -0.900 correlated: the record hardly separates them"]
    assert not documents.term_evidence_rows("rig", None)[0]["verdict"].startswith("indistinguishable")


def test_every_pair_of_variants_one_term_apart_is_a_row_of_the_term_evidence(documents):
    """A reviewer's variants quadratic, quadratic + friction, linear + friction and all three: the evidence table
    showed only linear + friction → all three (not comparable: other samples) and never quadratic + friction → all
    three, the one pair that tests linear damping."""
    documents.variants = {
        "quadratic": ["quadratic_drag"],
        "qfric": ["quadratic_drag", "coulomb_friction"],
        "nodrag": ["linear_damping", "coulomb_friction"],
        "full": ["quadratic_drag", "linear_damping", "coulomb_friction"],
    }
    documents.order = variant_order(documents.variants)
    fits = {"quadratic": (-100.0, 0.05, "a"), "qfric": (-300.0, 0.03, "a"), "nodrag": (-200, 0.04, "b")}
    fits["full"] = (-900.0, 0.004, "a")
    for variant, (aic, rms, samples) in fits.items():
        documents.joint[(variant, "rig")] = {
            "status": "ok",
            "aic": aic,
            "bic": aic + 10,
            "rms_deg": rms,
            "samples_digest": samples,
            "parameters": {"linear_damping_nm_s": _entry(0.15, 0.01), "coulomb_torque_nm": _entry(0.02, 0.002)},
            "warnings": [],
        }
    rows = {(r["parent"], r["variant"]): r for r in documents.term_evidence_rows("rig", None)}
    assert set(rows) == {("quadratic", "qfric"), ("qfric", "full"), ("nodrag", "full")}
    assert rows[("qfric", "full")]["term"] == "linear_damping"
    assert rows[("qfric", "full")]["verdict"].startswith("supported: the RMS falls 7.5×")
    assert rows[("nodrag", "full")]["verdict"].startswith("not comparable")


def test_a_tie_between_variants_and_an_unresolved_coefficient_are_said_in_the_summary(documents):
    """The apple in its own air rig (2026-12-02): linear damping ended at 0 with the RMS unchanged, so the summary's
    "chosen by ΔAIC 2" was only the parameter penalty, and linear damping traded against C_dA (−1.000); m_a 0.00037
    kg [0, 0.0011] stood in bold as a recommended measurement, its width the arm length's tolerance. A richer variant
    that fits better is no tie."""
    quadratic, linear = documents.joint[("quadratic", "rig")], documents.joint[("linear", "rig")]
    quadratic["parameters"]["drag_area_m2"] = _entry(0.0055, 0.0006)
    quadratic["parameters"]["added_mass_kg"] = {
        **_entry(0.00037, 0.00073),
        "ci95": [0.0, 0.0011],
        "stderr_statistical": 5.6e-5,
        "stderr_systematic": 3.7e-4,
        "error_budget": {"length_m": -3.6e-4, "mass_kg": 1.2e-6, "pivot_px (axis 2)": -7.4e-5},
    }
    linear["parameters"]["linear_damping_nm_s"] = _entry(0.0, 0.012, at_bound=True)
    linear["warnings"] = [
        "drag_area_m2 and linear_damping_nm_s are -1.000 correlated: the record hardly separates them"
    ]
    documents.best["rig"] = {
        **documents.best["rig"],
        "variant": "quadratic",
        "delta_aic": {"quadratic": 0.0, "linear": 2.0},
        "bic_best": "quadratic",
    }
    text = html_module.unescape(re.sub(r"<[^>]+>", "", documents.summary_box()))
    assert "their added terms (linear damping) end at their bound of 0" in text and "the variants tie" in text
    assert "(ΔAIC: linear +2.00)." in text and "BIC agrees" not in text  # BIC's difference: the penalty too
    # the rig's own evidence table, linked (its number is not known when the summary is written: "Table 5" was rig
    # paper_rig's in a report of two rigs)
    said = "These records cannot tell linear damping from quadratic drag (the evidence for each added term, rig rig:"
    assert said in text and 'href="#term-evidence-rig"' in documents.summary_box()
    assert "<b>0.00037</b>" not in documents.summary_box() and "[0.00000, 0.00110] (reaches 0)" in text
    assert "Added mass is not resolved from 0: its 95 % interval reaches 0" in text
    assert "(largest: the arm length), which more trials do not reduce" in text
    # the arm length's tolerance nobody stated: said, with where to state it (a reviewer with L = 1.05 m got m_a
    # 0.00088 kg [0.00015, 0.00161] on the default 0.2 %, with no word); stated, not said
    assert "Added mass's interval rests mostly on the arm length's tolerance, the default share of its value" in text
    assert "rigs.rig.tolerances in config.yaml" in text
    documents.rigs["rig"]["tolerances"] = {"length_m": 0.002}
    documents.trials["t20"]["tolerances"] = {"length_m": 0.002}
    documents.trials["bad"]["tolerances"] = {"length_m": 0.002}
    assert "default share" not in html_module.unescape(documents.summary_box())
    linear["rms_deg"] = quadratic["rms_deg"] / 1.5  # the richer variant fits better: no tie
    linear["warnings"] = []
    text = html_module.unescape(re.sub(r"<[^>]+>", "", documents.summary_box()))
    assert "tie" not in text and "cannot tell" not in text


def test_the_truth_table_says_which_trials_have_no_truth_file(documents, monkeypatch):
    """A lab's trials added beside synthetic ones (a reviewer's 25 copies): '5 of 5' covered, with 30 fitted."""
    monkeypatch.setattr(documents, "truth", {"t20": {"added_mass_kg": 2.5}})
    html = documents.truth_section()
    assert "1 trial(s) have no truth file (<code>truth_dir</code>) and are not counted: bad." in html
    monkeypatch.setattr(documents, "truth", {"t20": {"added_mass_kg": 2.5}, "bad": {"added_mass_kg": 2.5}})
    assert "no truth file" not in documents.truth_section()


def test_the_truth_table_tests_the_statistical_error_alone_where_the_rig_values_are_exact(documents, monkeypatch):
    """A referee's reading of the demo: renders use the rig's stated values exactly, so the combined σ (almost all
    rig-value tolerance: m_a's σ_stat 7.6e-5 kg against σ_sys 0.12 kg) covered any estimate. The table now also
    gives the error in statistical σ alone (the joint's widened by its scale factor) and the per-trial count
    within 1.96 of them. Here m_a 2.5 ± σ_stat 0.096 (half-width 0.24 / 2.5) against a truth of 2.3."""
    monkeypatch.setattr(documents, "truth", {"t20": {"truth": {"added_mass_kg": 2.3}}, "bad": {}})
    html = documents.truth_section()
    rows = [r for r in re.findall(r"<tr>(.*?)</tr>", html, re.S) if "added mass" in r.lower()]
    assert rows, html
    cells = [re.sub(r"<[^>]+>", "", c) for c in re.findall(r"<td[^>]*>(.*?)</td>", rows[0], re.S)]
    assert cells[5] == "+1.63" and cells[6] == "+2.08", cells  # 0.2 / (0.24 / 1.96); 0.2 / (0.24 / 2.5)
    assert cells[7] == "yes" and cells[8] == "1 of 1" and cells[9] == "0 of 1", cells
    assert "no error to cover here" in html


def test_variants_that_add_two_terms_at_once_say_why_no_term_is_tested_on_its_own(documents, monkeypatch):
    """A referee dropped `linear` from the demo's variants: 'No nested variants to compare term by term', with
    quadratic ⊂ friction (two terms added at once). The report now names that pair and what would test each."""
    variants = {"quadratic": ["quadratic_drag"], "friction": ["quadratic_drag", "linear_damping", "coulomb_friction"]}
    monkeypatch.setattr(documents, "variants", variants)
    monkeypatch.setattr(documents, "order", ["quadratic", "friction"])
    text = documents._no_term_evidence()
    assert text.startswith("No two variants differ by one term, so no term is tested on its own: quadratic → friction")
    assert "adds 2 at once (Coulomb friction and linear damping)" in text
    monkeypatch.setattr(documents, "variants", {"a": ["quadratic_drag"], "b": ["linear_damping"]})
    monkeypatch.setattr(documents, "order", ["a", "b"])
    assert documents._no_term_evidence().startswith("No variant holds every term of another")
    # a pair one term apart whose joint fit failed (a reviewer: it read "quadratic → linear adds 1 at once")
    monkeypatch.setattr(documents, "variants", {"a": ["quadratic_drag"], "b": ["quadratic_drag", "linear_damping"]})
    assert documents._no_term_evidence() == (
        "No term is compared on its own: the joint fits of a → b (one term apart) did not both succeed."
    )


def test_the_header_says_what_no_interval_holds_a_point_mass_and_the_rod(documents, monkeypatch):
    """A referee: 'Intervals are 95 % (statistical and rig-value systematic errors combined)' promised more than
    they hold. A rig that states no I_p is a point mass, and a body's own inertia about its centre then sits in the
    added mass, in no interval; the rod is not in the equation. Said where it applies, and not otherwise."""
    text = html_module.unescape(re.sub(r"<[^>]+>", "", documents.header()))
    assert (
        "They do not hold the equation's own form: m, B and the drag are the body's; the rod's (or string's) own mass, "
        "buoyancy and drag are not in it." in text
    )
    assert "On rig rig no Ip (body_inertia_kg_m2) is stated: the body is a point mass, Ip = mL²" in text
    # an ROV engineer read m_a as the vehicle's added mass and C_d as a steady-flow value (2026-12-07)
    assert "ma is the added mass as swung on this pendulum" in text and "not steady-flow values" in text
    # and the paper whose tables these follow is named (the same reviewer)
    assert "Tables 1–3 follow the layout of the paper this tool grew from, Identification of Hydrodynamics" in text
    monkeypatch.setitem(documents.rigs["rig"]["values"], "body_inertia_kg_m2", 2.0)
    text = html_module.unescape(re.sub(r"<[^>]+>", "", documents.header()))
    assert "the rod's (or string's) own mass" in text and "point mass" not in text


def test_a_rig_weighed_in_its_fluid_shows_its_submerged_mass_and_the_volume_it_gives(documents, monkeypatch):
    """Table 1 of a rig stated by its submerged mass (m − ρV on a scale in the tank): that row, with its default
    0.2 % tolerance, and the volume derived from it, (3.53 − 1.03)/1000 = 0.0025 m³, not the default 0; no such
    row for a rig stated by its volume."""
    text = html_module.unescape(re.sub(r"<[^>]+>", " ", documents.rig_table()))
    assert "submerged mass" not in text
    monkeypatch.setitem(documents.rigs["rig"]["values"], "submerged_mass_kg", 1.03)
    text = re.sub(r"\s+", " ", html_module.unescape(re.sub(r"<[^>]+>", " ", documents.rig_table())))
    assert "submerged mass m − ρV (weighed in the fluid) kg 1.030 ± 0.0021 (0.20 %, default)" in text, text
    assert "displaced volume V m³ 0.002500 (from the submerged mass) derived" in text, text
    assert "buoyancy B = ρgV N 24.53" in text, text


def test_the_truth_table_widens_the_joint_by_its_scale_factor_and_counts_held_fits_one_sided(documents, monkeypatch):
    """A reviewer: the fixture's S = 1 never tested the widening, and a held per-trial entry was judged ±1.96 σ_stat
    where its reported limit is one-sided. A joint with S = 2 halves its σ_stat z (+2.08 → +1.04); a per-trial drag
    area held at 0 (σ_stat 0.0012) with a truth 0.0022 above it is outside [0, 1.645 σ_stat] = [0, 0.0020], though
    within 1.96 σ_stat (0.0024) of it."""
    joint = documents.joint[("quadratic", "rig")]
    monkeypatch.setitem(joint["parameters"]["added_mass_kg"], "scale_factor", 2.0)
    monkeypatch.setattr(documents, "truth", {"t20": {"truth": {"added_mass_kg": 2.3, "drag_area_m2": 0.0022}}})
    html = documents.truth_section()
    rows = re.findall(r"<tr>(.*?)</tr>", html, re.S)
    cells = [[re.sub(r"<[^>]+>", "", c) for c in re.findall(r"<td[^>]*>(.*?)</td>", r, re.S)] for r in rows]
    added = next(c for c in cells if len(c) > 6 and "added mass" in c[2].lower())
    assert added[6] == "+1.04", added
    drag = next(c for c in cells if len(c) > 6 and "drag area" in c[2].lower() and c[1] in ("", "quadratic"))
    assert drag[9] == "0 of 1", drag


def test_rig_values_where_every_sidecar_weighs_its_body_show_no_volume_the_fits_did_not_use(documents, monkeypatch):
    """A reviewer: a rig stated by its volume whose every trial's sidecar gives a submerged mass showed the rig's
    volume (0.0025 ± 2e-5) beside it, and '—' for the weight, buoyancy, restoring torque and I_p (both keys at
    once raised). The fits take each sidecar's weighing in place of the volume: so does the table."""
    monkeypatch.setitem(documents.rigs["rig"]["values"], "displaced_volume_m3", 0.0025)
    for trial in documents.trials.values():
        monkeypatch.setitem(trial, "overrides", {"submerged_mass_kg": 1.03})
    text = re.sub(r"\s+", " ", html_module.unescape(re.sub(r"<[^>]+>", " ", documents.rig_table())))
    assert "displaced volume V m³ 0.002500 (from the submerged mass) derived" in text, text
    assert "weight mg N 34.63 derived buoyancy B = ρgV N 24.53 derived" in text, text


def test_the_correlation_of_the_recommended_coefficients_takes_every_error_in():
    """Σ = D R D + Σ_i b_i b_iᵀ by hand: statistical σ 0.1 (S = 2) and 0.2, correlated +0.5 → D R D =
    [[0.04, 0.02], [0.02, 0.04]]; the volume moves them +0.3 and −0.4 → [[0.09, −0.12], [−0.12, 0.16]]; the pivot's
    one axis +0.1 and +0.1 → [[0.01, 0.01], [0.01, 0.01]]. Sum [[0.14, −0.09], [−0.09, 0.21]]: the correlation
    −0.09 / √(0.14 · 0.21) = −0.5249, where the statistical part alone says +0.5."""
    from pendulum.fit.summary import combined_covariance
    from pendulum.report.budget import budget_sources, correlation_of, source_shift

    entries = {
        "added_mass_kg": {
            "stderr_statistical": 0.1,
            "scale_factor": 2.0,
            "error_budget": {"displaced_volume_m3": 0.3, "pivot_px (axis 1)": 0.1, "pivot_px (axis 2)": 0.0},
        },
        "drag_area_m2": {
            "stderr_statistical": 0.2,
            "error_budget": {"displaced_volume_m3": -0.4, "pivot_px (axis 1)": 0.1, "pivot_px (axis 2)": 0.0},
        },
    }
    statistical = {"parameters": ["added_mass_kg", "drag_area_m2"], "matrix": [[1.0, 0.5], [0.5, 1.0]]}
    covariance = combined_covariance(entries, statistical)
    assert sum(covariance["matrix"], []) == pytest.approx([0.14, -0.09, -0.09, 0.21], abs=1e-12)
    names, corr = correlation_of(covariance, ["drag_area_m2", "added_mass_kg"])
    assert names == ["added_mass_kg", "drag_area_m2"]  # the document's order
    assert corr[0, 1] == pytest.approx(-0.09 / (0.14 * 0.21) ** 0.5, abs=1e-12) and corr[0, 0] == pytest.approx(1)
    # C_d = C_dA / A takes C_dA's statistical correlation, with its own budget
    entries["drag_coefficient"] = {"stderr_statistical": 0.2 / 0.03, "error_budget": {"frontal_area_m2": 0.5}}
    names = combined_covariance(entries, statistical)["quantities"]
    assert names == ["added_mass_kg", "drag_area_m2", "drag_coefficient"]
    del entries["drag_coefficient"]
    # with the rig values: the volume's stated 1σ of 2 (its shifts above per 1σ): var 4, cov(m_a, V) = 0.3 · 2, the
    # correlation 0.6 / (√0.14 · 2) = 0.802; cov(C_dA, V) = −0.8, −0.8 / (√0.21 · 2) = −0.873; the pivot no rig value
    with_rig = combined_covariance(entries, statistical, {"displaced_volume_m3": 2.0, "mass_kg": 0.1})
    assert with_rig["quantities"] == ["added_mass_kg", "drag_area_m2", "displaced_volume_m3"]  # m moves nothing
    assert with_rig["at_bound"] == []
    names, corr = correlation_of(with_rig, ["added_mass_kg", "drag_area_m2", "displaced_volume_m3"])
    assert corr[0, 2] == pytest.approx(0.6 / (0.14**0.5 * 2)) and corr[1, 2] == pytest.approx(-0.8 / (0.21**0.5 * 2))
    # the pivot's axes in one column, in quadrature; the sources in Table 1's order, the pivot last
    entries["added_mass_kg"]["error_budget"]["pivot_px (axis 2)"] = 0.2
    assert source_shift(entries["added_mass_kg"], "pivot_px") == pytest.approx((0.1**2 + 0.2**2) ** 0.5)
    assert budget_sources(entries) == ["displaced_volume_m3", "pivot_px"]


def test_the_uncertainty_budget_names_each_sources_share_and_the_largest(documents, monkeypatch):
    """An ROV engineer asked where the recommended coefficients' uncertainty comes from (2026-12-07): the budget of
    the recommended joint fit, each source's 1σ part as a percentage of the estimate. The added mass 2.5 ± u, u
    from a statistical 0.01 kg (0.4 %), the volume's −0.1 kg (−4 %) and the mass's 0.02 kg (0.8 %): the volume
    holds 0.01 / (0.0001 + 0.01 + 0.0004) = 95 % of u²."""
    joint = documents.joint[("linear", "rig")]
    entry = joint["parameters"]["added_mass_kg"]
    monkeypatch.setitem(entry, "stderr_statistical", 0.01)
    monkeypatch.setitem(entry, "stderr", (0.01**2 + 0.1**2 + 0.02**2) ** 0.5)
    monkeypatch.setitem(entry, "error_budget", {"displaced_volume_m3": -0.1, "mass_kg": 0.02})
    monkeypatch.setitem(joint, "covariance", {"parameters": ["added_mass_kg"], "matrix": [[0.0105]]})
    text = re.sub(r"\s+", " ", html_module.unescape(re.sub(r"<[^>]+>", " ", documents.uncertainty_budget())))
    assert "variant linear" in text
    assert "added mass, m a 2.500 kg 0.10 kg (4.1 %) 0.4 % 0.8 % −4 % displaced volume V (95 % of u²)" in text, text
    assert "linear damping, c 0.1500 N·m·s 0.0051 N·m·s (3.4 %) 2.7 % · · statistical (100 % of u²)" in text
    assert "variant quadratic" not in text  # not the recommended variant
    assert "best of the variants tried" not in text
    misses = "trial t20: residual RMS 0.3° is 80× the record's noise (0.003°) and smooth: the model misses a"
    monkeypatch.setitem(joint, "warnings", [misses + " systematic effect"])
    text = re.sub(r"\s+", " ", html_module.unescape(re.sub(r"<[^>]+>", " ", documents.uncertainty_budget())))
    assert "coefficients of the best of the variants tried" in text and "no line of this budget holds that" in text
    # the correlation: only of coefficients the fit's covariance holds, so here none to show
    assert "Correlation of the recommended coefficients" not in text
