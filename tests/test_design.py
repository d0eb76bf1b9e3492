"""What to film next (pendulum.design.next_trials): predictions checked by simulation, and the workflow's design output.

The claims of issue 26 over seeds, each with a binomial pass rule (α = 0.001 per claim): a realised
half-width (the group refitted with the added trial, its reported sandwich interval) within 25 % of the
predicted one in ≥ 90 % of (trial, coefficient) pairs; the recommended trial leaving a narrower drag
interval than a naive repeat of today's release in ≥ 90 % of seeds. The offline study
(tests/benchmarks/design_study.py, seeds 100–159) measured 354 of 360 pairs (98.3 %) and 60 of 60 seeds
(docs/design.md).
"""

import json
import math
import sys
from pathlib import Path

import numpy as np
import pytest
from scipy.stats import binom

sys.path.insert(0, str(Path(__file__).resolve().parent / "benchmarks"))

import design_study  # noqa: E402

from pendulum.design.next_trials import DesignOptions, design_group  # noqa: E402
from pendulum.fit.records import FitSettings  # noqa: E402

ALPHA = 1e-3
SEEDS = range(10)


def min_hits(n: int, p: float, alpha: float = ALPHA) -> int:
    """Fewer successes than this fail a claim of rate ≥ p: P(X < k | n, p) < alpha."""
    return int(binom.ppf(alpha, n, p))


@pytest.fixture(scope="module")
def study():
    return [design_study.run_case(seed) for seed in SEEDS]


@pytest.mark.slow
def test_realised_half_widths_match_the_predicted_ones(study):
    judged = design_study.judge(study)
    assert judged["within"] >= min_hits(judged["pairs"], 0.9, ALPHA / 2), judged


@pytest.mark.slow
def test_the_recommended_trial_beats_a_naive_repeat(study):
    judged = design_study.judge(study)
    assert judged["beats"] >= min_hits(judged["seeds"], 0.9, ALPHA / 2), judged
    # the design asks for the large swing that the drag is seen in, not today's small ones
    assert all(abs(r["recommended_deg"]) >= 40 for r in study)


@pytest.fixture(scope="module")
def small_group():
    records = [design_study.record(r, 50 + i, f"g{i}") for i, r in enumerate(design_study.RELEASES_DEG)]
    return design_study.fit(records)


def test_a_tolerance_that_dominates_is_named_and_more_trials_do_not_help(small_group):
    from pendulum.fit.uncertainty import Z95

    fit = small_group
    j = fit.problem.labels.index("added_mass_kg")
    parameters = {
        "added_mass_kg": {"stderr_systematic": 0.2, "error_budget": {"displaced_volume_m3": -0.19, "mass_kg": 0.06}}
    }
    options = DesignOptions(coefficients=("added_mass_kg",), releases_deg=(10.0, 60.0), target_relative_halfwidth=0.05)
    document, rows = design_group(fit, parameters, FitSettings(), options)
    entry = document["today"]["added_mass_kg"]
    assert entry["value"] == pytest.approx(fit.x[j])
    assert entry["floor_relative_halfwidth95"] == pytest.approx(Z95 * 0.2 / fit.x[j])
    target = document["to_target"]["added_mass_kg"]
    assert target["reachable"] is False and target["limited_by"] == "displaced_volume_m3"
    assert "cannot be reached by more trials" in target["sentence"]
    # predicted widths never fall below the tolerance's own share
    widths = [r["halfwidth95_predicted"] for r in rows if r["coefficient"] == "added_mass_kg"]
    assert min(widths) >= Z95 * 0.2
    assert document["recommendations"][0]["release_deg"] is None
    assert "the displaced volume" in document["recommendations"][0]["sentence"]


def test_fewer_trials_than_asked_for_say_why(small_group):
    """`recommend: 3` gave the apple one trial and no word why (a reviewer, 2026-12-02): after it, a further trial
    narrows the interval by less than 1 %, the rest being the frontal area's tolerance. Said; with no tolerance,
    all three are given."""
    value = small_group.x[small_group.problem.labels.index("drag_area_m2")]
    options = DesignOptions(coefficients=("drag_area_m2",), releases_deg=(20.0, 60.0), recommend=3)
    budget = {"drag_area_m2": {"stderr_systematic": 0.02 * value, "error_budget": {"frontal_area_m2": 0.02 * value}}}
    document, _ = design_group(small_group, budget, FitSettings(), options)
    assert len(document["recommendations"]) == 1 and document["recommendations"][0]["release_deg"] is not None
    assert document["fewer_recommended"] == (
        "1 of the 3 trials asked for (design.recommend): a further trial would narrow the drag area C_d·A by less "
        "than 1 %; the rest of its interval is set by the rig values' tolerances (largest: the frontal area)"
    )
    document, _ = design_group(small_group, {}, FitSettings(), options)
    assert len(document["recommendations"]) == 3 and document["fewer_recommended"] is None


def test_a_repeated_trial_adds_its_information(small_group):
    """One more trial like one of today's two shrinks every coefficient's statistical half-width (ratio < 1),
    but as one trial of three, not to below 1/√3 of today's."""
    fit = small_group
    options = DesignOptions(coefficients=("drag_area_m2",), releases_deg=(10.0,), recommend=1)
    document, rows = design_group(fit, {}, FitSettings(), options)
    for row in rows:
        if row["release_deg"] == 10.0:
            ratio = row["halfwidth95_predicted"] / row["halfwidth95_today"]
            assert 1 / math.sqrt(3) < ratio < 1.0, row


def test_targets_reached_by_more_trials_are_counted(small_group):
    options = DesignOptions(coefficients=("drag_area_m2",), releases_deg=(20.0, 60.0), target_relative_halfwidth=0.01)
    document, _ = design_group(small_group, {}, FitSettings(), options)
    target = document["to_target"]["drag_area_m2"]
    today = document["today"]["drag_area_m2"]["relative_halfwidth95"]
    assert today > 0.01
    # statistical only: the half-width falls about as 1/√(information), so a finite count reaches it
    assert target["reachable"] and 1 <= target["further_trials"] <= 50, target
    json.dumps(document)  # plain JSON
    assert np.isfinite(today)


@pytest.mark.slow
@pytest.mark.parametrize("seed", [0])
def test_the_separating_trial_lets_discovery_name_the_history_force(seed):
    """At one arm length the history force is reported indistinguishable from linear damping; offered a
    described 0.40 m arm, the design recommends a trial on it, and with that trial simulated and added
    discovery names the history force. A deterministic check: offline, seeds 0–19 of
    tests/benchmarks/design_study.py --separate named it in 20 of 20 (docs/design.md)."""
    result = design_study.separate_case(seed)
    assert result["named_before"] == [], result
    separating = result["separating"][0]
    assert separating["effects"] == ["history_force", "linear_damping"]
    assert separating["rig"] == "short_arm" and separating["described_rig"], separating
    assert separating["separation_sigma"] > separating["separation_sigma_today"], separating
    assert result["named_after"] == ["history_force"], result


def test_measurement_advice_reaches_the_target_it_names():
    """The advised tolerances, put back into the budget, give exactly the target half-width (an independent sum)."""
    from pendulum.design.tolerances import measurement_advice
    from pendulum.fit.uncertainty import Z95

    value, stat = 2.5, 0.01
    budget = {"displaced_volume_m3": -0.117, "fluid_density_kg_m3": -0.029, "mass_kg": 0.024, "length_m": -0.008}
    tolerances = {
        "paper": {"displaced_volume_m3": 2e-5, "fluid_density_kg_m3": 2.0, "mass_kg": 0.005, "length_m": 1e-3}
    }
    sys_ = math.sqrt(sum(v * v for v in budget.values()))
    entry = {
        "value": value,
        "stderr_statistical": stat,
        "floor_relative_halfwidth95": Z95 * sys_ / value,
    }
    advice = measurement_advice(
        "added_mass_kg", "the added mass", entry, {"error_budget": budget}, 0.02, tolerances, {}
    )
    assert advice["limited_by"] == "displaced_volume_m3"
    assert [m["input"] for m in advice["measure"]] == ["displaced_volume_m3", "fluid_density_kg_m3", "mass_kg"]
    shifts = dict(budget)
    for item in advice["measure"]:
        shifts[item["input"]] *= item["to_1sigma"] / tolerances["paper"][item["input"]]
    half = Z95 * math.sqrt(stat**2 + sum(v * v for v in shifts.values()))
    assert half == pytest.approx(0.02 * value, rel=1e-9)
    assert "the default share of its value; state yours under rigs.paper.tolerances" in advice["sentence"]
    assert "Measuring the displaced volume to ±" in advice["sentence"]
    # a referee: volume, density and mass to be measured apart, where one weighing in the tank settles the buoyancy
    assert "or weigh the body hung in the fluid and state that reading as submerged_mass_kg" in advice["sentence"]
    assert "still to be measured" not in advice["sentence"]  # the reading stands for all three
    # the drag coefficient's: the volume and the frontal area (an ROV engineer, 2026-12-07: "or weigh the body" read
    # as reaching the target alone, where the area's tolerance alone gives ±3 %)
    advice = measurement_advice(
        "drag_coefficient",
        "the drag coefficient",
        dict(entry, floor_relative_halfwidth95=Z95 * 0.05),
        {"error_budget": {"displaced_volume_m3": -0.03 * value, "frontal_area_m2": -0.012 * value}},
        0.02,
        {"paper": {"displaced_volume_m3": 2e-5, "frontal_area_m2": 5e-4}},
        {},
    )
    assert [m["input"] for m in advice["measure"]] == ["displaced_volume_m3", "frontal_area_m2"], advice
    assert "in place of the volume" in advice["sentence"] and "(the frontal area" in advice["sentence"], advice
    assert advice["sentence"].endswith("still to be measured as above)"), advice["sentence"]
    budget_without = {"length_m": -0.1, "mass_kg": 0.02}
    advice = measurement_advice(
        "added_mass_kg",
        "the added mass",
        dict(entry, floor_relative_halfwidth95=Z95 * 0.102 / value),
        {"error_budget": budget_without},
        0.02,
        {"paper": {"mass_kg": 0.005, "length_m": 1e-3}},
        {},
    )
    assert "Measuring the arm length to ±" in advice["sentence"] and "weigh" not in advice["sentence"]
    # the density alone (a weighed rig, or the drag through ½ρC_dA): weighing settles nothing (a reviewer)
    advice = measurement_advice(
        "drag_area_m2",
        "the drag area",
        dict(entry, floor_relative_halfwidth95=Z95 * 0.102 / value),
        {"error_budget": {"fluid_density_kg_m3": -0.1, "mass_kg": 0.02}},
        0.02,
        {"paper": {"fluid_density_kg_m3": 2.0, "mass_kg": 0.005}},
        {},
    )
    assert "Measuring the fluid's density to ±" in advice["sentence"] and "weigh" not in advice["sentence"]


def test_bad_requests_are_warned_about_and_the_rest_is_designed(small_group):
    options = DesignOptions(
        coefficients=("drag_area_m2", "history_coefficient_kg_per_sqrt_s"),
        releases_deg=(20.0,),
        rigs=(
            ("light", {"mass_kg": 1.0}),
            ("paper", {"length_m": 0.5}),
            ("short", {"length_m": 0.4}),
            ("both", {"displaced_volume_m3": 0.002, "submerged_mass_kg": 1.0}),  # one buoyancy, twice
        ),
        recommend=1,
    )
    document, rows = design_group(small_group, {}, FitSettings(), options)
    warnings = " | ".join(document["warnings"])
    assert "design.coefficients: history_coefficient_kg_per_sqrt_s is not a coefficient" in warnings
    assert "design.rigs.light" in warnings and "not a pendulum" in warnings
    assert "design.rigs.paper: a rig of the group has this name" in warnings
    assert "design.rigs.both" in warnings and "not both" in warnings
    assert {r["rig"] for r in rows} == {"paper", "short"}  # the good described rig is still designed
    assert document["targets"] == ["drag_area_m2"] and document["recommendations"]
    ranks = sorted(r["rank"] for r in rows if r["coefficient"] == "drag_area_m2")
    assert ranks == list(range(1, len(ranks) + 1))


def test_a_coefficient_at_its_bound_gets_no_percentages():
    """Added mass fitted to zero (its bound): a new user's build of the apple clip showed 'today 2.665×10⁻¹⁷',
    '±0.00208 (7.8×10¹⁵ %)' and a tolerance share of '±2e+02 %'. Now: 0 at bound, no share of it, and percentages
    never in e-notation."""
    from pendulum.design.tolerances import measurement_advice, percent
    from pendulum.report.design import relative_text, today_value

    entry = {"value": 2.665e-17, "halfwidth95": 0.00208, "relative_halfwidth95": 7.8e13}
    assert today_value(entry) == "0 (at bound)" and relative_text(entry) == " (not told from 0)"
    assert (
        today_value({**entry, "value": 1.105}) == "1.105"
        and relative_text({**entry, "relative_halfwidth95": 0.11}) == " (11 %)"
    )
    advice = measurement_advice(
        "added_mass_kg",
        "the added mass m_a",
        {
            "value": 2.665e-17,
            "stderr_statistical": 0.001,
            "stderr_systematic": 0.0005,
            "floor_relative_halfwidth95": 1e13,
        },
        {"error_budget": {"length_m": 0.0004}},
        0.02,
        {"rig": {"length_m": 0.002}},
        {},
    )
    assert "at zero (its bound)" in advice["sentence"] and "e+" not in advice["sentence"]
    assert [percent(v) for v in (3.94, 99.6, 199.3, 2345.0, 4e-5)] == ["3.9", "100", "200", "2300", "0.000040"]


def test_a_tolerance_is_as_stated_for_a_rig_only_where_all_its_trials_state_it_alike():
    """The design's advice calls a tolerance "as stated" for a rig only where every trial of it states that one: a
    sidecar's own tolerance of its own value (or none, where it changes the value) is not the rig's. Before, the last
    trial's stated tolerances stood for the rig."""
    from pendulum.design.tolerances import stated_by_rig

    trial_rigs = {
        "a": {"name": "tank", "tolerances": {"mass_kg": 0.005, "length_m": 0.001}},
        "b": {"name": "tank", "tolerances": {"length_m": 0.001}},  # its sidecar changed the mass
        "c": {"name": "pool", "tolerances": {"mass_kg": 0.002}},
    }
    assert stated_by_rig(trial_rigs) == {"tank": {"length_m": 0.001}, "pool": {"mass_kg": 0.002}}


def test_today_s_drag_coefficient_is_the_fits_where_trials_state_different_frontal_areas():
    """Two trials of one body whose sidecars state frontal areas 30 % apart: discovery's C_d divides the drag
    area by their mean (and warns); the design's 'today' C_d did by the first trial's (0.802 against 0.697)."""
    from pendulum.fit.group import coefficient_entries
    from pendulum.fit.records import load_record
    from pendulum.model.physics import PendulumModel
    from pendulum.model.rig import Rig
    from pendulum.synthetic.records import synthetic_angle_table

    records = []
    areas = (design_study.PAPER_RIG["frontal_area_m2"], 1.3 * design_study.PAPER_RIG["frontal_area_m2"])
    for i, (release, area) in enumerate(zip((30.0, -25.0), areas, strict=True)):
        model = PendulumModel(Rig(**design_study.PAPER_RIG), design_study.TERMS)
        rng = np.random.default_rng(3 + i)
        table = synthetic_angle_table(
            model, design_study.TRUTH, release, duration_s=20.0, rng=rng, **design_study.NOISE
        )
        rig = dict(design_study.PAPER_RIG, frontal_area_m2=area)
        records.append(load_record(table, f"t{i}", rig, FitSettings(), tolerances={}))
    fit = design_study.fit(records)
    entries, warnings = coefficient_entries(fit, FitSettings())
    assert any("different frontal areas" in w for w in warnings)
    document, _ = design_group(fit, entries, FitSettings(), DesignOptions(coefficients=("drag_area_m2",)))
    cd = entries["drag_coefficient"]["value"]
    assert cd == pytest.approx(entries["drag_area_m2"]["value"] / (0.5 * sum(areas)))
    assert document["today"]["drag_coefficient"]["value"] == pytest.approx(cd, rel=1e-9)


def test_a_design_on_a_model_that_misses_the_records_says_its_predictions_wait_on_the_missing_effect(small_group):
    """The apple in air (2026-12-02): 'release from −45°: C_d ±0.16 → ±0.08' stood as the next step where
    discovery's final model left the residual 76× the noise floor; the document now says so, and not otherwise."""
    options = DesignOptions(coefficients=("drag_area_m2",), releases_deg=(20.0,), recommend=1)
    verdict = "unexplained: the residual (0.23° RMS) is 76× the noise floor and not white, and no candidate removes it"
    document, _ = design_group(small_group, {}, FitSettings(), options, misfit=verdict)
    assert document["model_misfit"].startswith(
        "discovery's final model does not fit these records: the residual (0.23° RMS) is 76× the noise floor"
    )
    assert "find what it misses before filming" in document["model_misfit"]
    assert design_group(small_group, {}, FitSettings(), options)[0]["model_misfit"] is None


def test_a_release_as_good_from_either_side_is_said_so(small_group):
    """The apple in air (2026-12-02): 'release from −60°' where +60° gives the same intervals (a reviewer: the
    sign was a tie-break, and another build said −45°). A symmetric pendulum learns alike from either side: the
    sentence says ± with "either side"."""
    options = DesignOptions(coefficients=("drag_area_m2",), releases_deg=(20.0, 60.0), recommend=1)
    document, rows = design_group(small_group, {}, FitSettings(), options)
    first = document["recommendations"][0]
    by_side = {
        r["release_deg"]: r["halfwidth95_predicted"]
        for r in rows
        if r["coefficient"] == "drag_area_m2" and abs(r["release_deg"]) == abs(first["release_deg"])
    }
    assert len(by_side) == 2 and min(by_side.values()) >= 0.995 * max(by_side.values()), by_side
    assert f"release from ±{abs(first['release_deg']):g}° (either side)" in first["sentence"], first
