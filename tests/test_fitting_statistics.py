"""Statistical claims about the fitter, each tested over many noise realisations.

No claim rests on one lucky seed. Seeds come from fixed, contiguous ranges (never
hand-picked), so every run is reproducible, and each claim has a pass rule
derived from the binomial distribution:

* A claim that holds with probability p per realisation (a 95 % interval covers
  the truth, p = 0.95) is checked by counting the realisations where it holds,
  X ~ Binomial(n, p). The test fails when X < k with k = binom.ppf(α', n, p), so
  P(fail | claim true) = P(X < k) < α'. α = 0.001 per test, split evenly
  (Bonferroni) over the parameters or sides checked, α' = α / (number of checks).
  A correct change that redraws the realisations (other noise, other fit
  settings) therefore fails a test at most once in a thousand.
* A deterministic assertion on every realisation is used only where its
  tolerance is so wide that failure is negligible for any seed; each docstring
  gives the offline check over ≥ 20 (usually 60–300) seeds behind it.

The truth records are synthetic (pendulum.synthetic.experiment, which shares
pendulum.model.physics with the fitter); tests/test_physics_reference.py checks both
against physics written out independently.
"""

import json
import math

import numpy as np
import pytest
from scipy.stats import binom

from paper_rig import PAPER_RIG, TRUTH, VARIANTS, truth_for
from pendulum.fit.decay import decay_analysis
from pendulum.fit.output_error import fit_joint, fit_trials
from pendulum.fit.records import FitSettings, load_record
from pendulum.io import write_json
from pendulum.model.physics import PendulumModel
from pendulum.model.rig import Rig
from pendulum.synthetic.records import synthetic_angle_table

ALPHA = 1e-3  # probability that a test fails although its claim is true
SETTINGS = FitSettings()


def record(release_deg, terms, seed, truth=None, **kwargs):
    model = PendulumModel(Rig(**PAPER_RIG), terms)
    table = synthetic_angle_table(
        model, truth or truth_for(terms), release_deg, rng=np.random.default_rng(seed), **kwargs
    )
    return load_record(table, f"r{release_deg:+g}s{seed}", PAPER_RIG, SETTINGS)  # exact rig: no systematic part


def min_hits(n, p, alpha):
    """k such that P(X < k) < alpha for X ~ Binomial(n, p): fewer than k successes fail the test."""
    k = int(binom.ppf(alpha, n, p))
    assert binom.cdf(k - 1, n, p) < alpha <= binom.cdf(k, n, p) or k == 0
    return k


def max_hits(n, p, alpha):
    """k such that P(X > k) ≤ alpha: more than k successes fail the test."""
    return int(binom.isf(alpha, n, p))


def covers(entry, true):
    low, high = entry["ci95"]
    return low <= true <= high


# --- recovery of the generating coefficients, 9 cases × 12 realisations

RECOVERY_CASES = [(v, r) for v in sorted(VARIANTS) for r in (75, 20, -15)]
RECOVERY_SEEDS = 12


@pytest.fixture(scope="module")
def recovery_fits():
    """Each case its own block of seeds (100·case + 0…11), so the cases' noise is independent."""
    fits = {}
    for index, (variant, release_deg) in enumerate(RECOVERY_CASES):
        terms = VARIANTS[variant]
        fits[variant, release_deg] = [
            fit_trials([record(release_deg, terms, 100 * index + i, rest_offset_deg=-0.2)], terms, SETTINGS)
            for i in range(RECOVERY_SEEDS)
        ]
    return fits


@pytest.mark.parametrize(("variant", "release_deg"), RECOVERY_CASES)
def test_recovers_the_generating_coefficients(recovery_fits, variant, release_deg):
    """Every realisation: estimates close to the truth, the noise level left, the camera offset found.

    Offline over 60 seeds per case (540 fits): |m_a/2.5 − 1| ≤ 0.03 %, |C_dA/0.02576 − 1| ≤ 0.4 %,
    rms 0.00455–0.00532° (noise 0.005°), offset error ≤ 0.001°, never at a bound or unidentifiable,
    always converged. The tolerances (2 %, 5 %, ±30 %, 0.01°) are > 10× those extremes. Whether
    the intervals contain the truth is a 95 % claim: pooled over all cases below.
    """
    for fit in recovery_fits[variant, release_deg]:
        assert fit["optimiser"]["converged"]
        for name in truth_for(VARIANTS[variant]):
            entry = fit["parameters"][name]
            assert not entry["at_bound"] and entry["identifiable"], (name, entry)
        assert fit["parameters"]["added_mass_kg"]["value"] == pytest.approx(2.5, rel=0.02)
        assert fit["parameters"]["drag_area_m2"]["value"] == pytest.approx(0.02576, rel=0.05)
        assert fit["parameters"]["drag_coefficient"]["value"] == pytest.approx(0.8, rel=0.05)
        assert fit["rms_deg"] == pytest.approx(0.005, rel=0.3)  # the noise, nothing systematic left
        assert fit["trials"][next(iter(fit["trials"]))]["rest_offset_deg"] == pytest.approx(-0.2, abs=0.01)


# Measured offline (seeds 0–299 of the 20° friction case, before the systematic-interval change):
# the added mass's 95 % interval covered 270/300 = 90 % (z = (m̂_a − m_a)/σ̂ had sd 1.18), the other
# coefficients 91–93 %. With today's code the seeds below give 181–185 of 200 (90.5–92.5 %) and
# 99/108 pooled: above k₉₅ = 177, so the nominal rule passes; at n = 200 it detects a coverage
# below ≈ 88 % reliably, not one of 90 %.


def check_coverage(fits, name, true):
    """Hits of the 95 % interval over the fits, against Binomial(n, 0.95) and Binomial(n, 0.90).

    Nominal rule (the claim itself): fail if hits < k₉₅ = binom.ppf(α/8, n, 0.95), two-sided with
    hits > binom.isf(α/8, n, 0.95) (intervals far too wide); α/8: four parameters, two sides.
    """
    n = len(fits)
    hits = sum(covers(f["parameters"][name], true) for f in fits)
    low, high = min_hits(n, 0.95, ALPHA / 8), max_hits(n, 0.95, ALPHA / 8)
    assert low <= hits <= high, f"{name}: {hits}/{n} intervals cover the truth; 95 % intervals need {low}…{high}"


def check_not_far_below_90(fits, name, true):
    """Floor: coverage not significantly below 90 %: hits ≥ binom.ppf(α/4, n, 0.90)."""
    n = len(fits)
    hits = sum(covers(f["parameters"][name], true) for f in fits)
    low = min_hits(n, 0.90, ALPHA / 4)
    assert hits >= low, f"{name}: {hits}/{n} intervals cover the truth; coverage ≥ 90 % needs ≥ {low}"


def pooled(recovery_fits, name):
    return [f for fits in recovery_fits.values() for f in fits if name in f["parameters"]]


@pytest.mark.parametrize("name", sorted(TRUTH))
def test_pooled_interval_coverage_of_the_recovery_cases(recovery_fits, name):
    """All 9 recovery cases pooled (108 realisations for m_a and C_dA, 72 for c, 36 for τ_f)."""
    check_coverage(pooled(recovery_fits, name), name, TRUTH[name])


@pytest.mark.parametrize("name", sorted(TRUTH))
def test_pooled_interval_coverage_is_at_least_90_percent(recovery_fits, name):
    check_not_far_below_90(pooled(recovery_fits, name), name, TRUTH[name])


# --- interval coverage on one case, 200 realisations

COVERAGE_SEEDS = range(1000, 1200)


@pytest.fixture(scope="module")
def coverage_fits():
    """200 realisations of a 20° friction-variant trial with coloured (AR) tracking-like noise."""
    terms = VARIANTS["friction"]
    return [fit_trials([record(20, terms, seed)], terms, SETTINGS) for seed in COVERAGE_SEEDS]


@pytest.mark.parametrize("name", sorted(TRUTH))
def test_interval_coverage_over_noise_realisations(coverage_fits, name):
    """n = 200: the nominal rule fails below 177 hits (88.5 %) or at 200; P(fail | 95 %) < 1.25e-4 per side."""
    check_coverage(coverage_fits, name, TRUTH[name])


@pytest.mark.parametrize("name", sorted(TRUTH))
def test_interval_coverage_is_at_least_90_percent(coverage_fits, name):
    """n = 200: fails below binom.ppf(2.5e-4, 200, 0.90) = 164 hits (82 %)."""
    check_not_far_below_90(coverage_fits, name, TRUTH[name])


# --- other claims


@pytest.mark.slow
def test_white_noise_intervals_would_be_too_narrow():
    """The AR correction matters: on coloured noise (ρ = 0.9) the sandwich errors exceed the white-noise ones.

    Offline over seeds 0–59: the ratio per parameter is 1.40–2.9, median 2.0; it is below 1.5 in
    2–3 of 60 seeds. Rule: every ratio > 1.2 (deterministic: below the smallest of 240 measured),
    and the median over the 20 seeds > 1.5 (it fails only if ≥ 10 of 20 ratios are < 1.5; with a
    per-seed rate ≤ 0.15, P(X ≥ 10 | 20, 0.15) = 2e-4).
    """
    terms = VARIANTS["friction"]
    ratios = []
    for seed in range(20):
        fit = fit_trials([record(20, terms, seed=seed, correlation=0.9)], terms, SETTINGS)
        ratio = fit["uncertainty"]["stderr_over_white_noise_stderr"]
        assert all(r > 1.2 for r in ratio.values()), (seed, ratio)
        ratios.append([ratio[k] for k in TRUTH])
    assert binom.sf(9, 20, 0.15) < ALPHA
    assert np.all(np.median(ratios, axis=0) > 1.5), np.median(ratios, axis=0)


@pytest.mark.slow
def test_parameter_at_its_bound_is_flagged_and_printed_as_the_bound(tmp_path):
    """No linear damping in the truth: the fitted c often wants to go negative and stops at 0.

    Every realisation at the bound is reported as exactly the bound with a one-sided interval and a
    warning; every other has c > 0 (deterministic: held in all of 100 seeds offline). The bound is
    hit in 30 of 100 seeds offline; rule: at least min_hits(40, 0.2, α) = 1 of 40 (P(none | rate
    0.2) = 1.3e-4). The one-sided intervals contain c = 0 in 96 of 100: checked as a 95 % claim.
    """
    terms = VARIANTS["linear"]
    truth = {"added_mass_kg": 2.5, "drag_area_m2": 0.02576, "linear_damping_nm_s": 0.0}
    n, at_bound, covered = 40, 0, 0
    for seed in range(n):
        fit = fit_trials([record(20, terms, seed, truth=truth)], terms, SETTINGS)
        entry = fit["parameters"]["linear_damping_nm_s"]
        covered += covers(entry, 0.0)
        if entry["at_bound"]:
            at_bound += 1
            assert entry["value"] == 0.0 and entry["ci95"][0] == 0.0 and entry["ci95"][1] > 0
            assert any("lower bound" in w for w in fit["warnings"])
            write_json(fit, tmp_path / "fit.json")
            written = json.loads((tmp_path / "fit.json").read_text())["parameters"]["linear_damping_nm_s"]
            assert written["value"] == 0.0 and written["at_bound"] is True  # never 4.3e-14
        else:
            assert entry["value"] > 0
    assert at_bound >= min_hits(n, 0.2, ALPHA / 2), at_bound
    assert covered >= min_hits(n, 0.95, ALPHA / 2), covered


@pytest.mark.slow
def test_drag_at_a_small_release_with_paper_like_noise_is_usually_not_identifiable():
    """5° release, 0.2° white noise (paper: RMS 0.08–0.4°), 12 s: the drag is lost in the noise.

    Offline over seeds 0–59: σ̂(C_dA) is 0.38–0.81 of the true C_dA (median 0.66), and the drag is
    flagged (at its bound or not identifiable, with a warning) in 50 of 60. Rules: σ̂ > 0.25 of the
    truth in every realisation (deterministic); every unidentifiable flag carries the reason; flagged
    in at least min_hits(16, 0.7, α) = 5 of 16 (0.7 is below the measured 0.83's 95 % lower limit).
    """
    terms = VARIANTS["friction"]
    n, flagged = 16, 0
    for seed in range(n):
        rec = record(5, terms, seed, white_deg=0.2, correlated_deg=0.0, duration_s=12.0)
        fit = fit_trials([rec], terms, SETTINGS)
        drag = fit["parameters"]["drag_area_m2"]
        assert drag["stderr"] > 0.25 * TRUTH["drag_area_m2"], (seed, drag)
        if not drag["identifiable"]:
            assert "too small" in drag["reason"]
        if drag["at_bound"] or not drag["identifiable"]:
            flagged += 1
            assert any("drag_area_m2" in w for w in fit["warnings"])
    assert flagged >= min_hits(n, 0.7, ALPHA), flagged


def test_decay_analysis_gives_starting_values_near_the_truth():
    """Decay analysis (starting values) on 20 realisations with a 0.3° camera offset.

    Offline over seeds 0–59: m_a is +1.9 % ± 0.9 % off (max 4.2 %), the offset ≤ 0.009° off, the
    damping coefficients 0.91–1.35 × the truth. Tolerances 8 % (6.8σ from the mean bias), 0.03°
    (3× the largest) and 0.3–3× make a failure negligible for any seed.
    """
    terms = VARIANTS["friction"]
    model = PendulumModel(Rig(**PAPER_RIG), terms)
    for seed in range(20):
        start = decay_analysis(model, record(20, terms, seed, rest_offset_deg=0.3))
        assert start["physical"]["added_mass_kg"] == pytest.approx(2.5, rel=0.08), seed
        assert start["rest_offset_rad"] == pytest.approx(math.radians(0.3), abs=math.radians(0.03)), seed
        # the extinction curve separates the damping terms only roughly: a start, not an answer
        for name in ("drag_area_m2", "linear_damping_nm_s", "friction_torque_nm"):
            assert 0.3 * TRUTH[name] < start["physical"][name] < 3 * TRUTH[name], (seed, name)


@pytest.mark.slow
def test_joint_fit_and_consistency_on_the_true_and_the_paper_model():
    """Friction truth, 8 sets of 4 trials (75°, 20°, −15°, 5°; seeds 4s … 4s+3, s = 0…7).

    The friction joint fit should agree with its trials: the consistency test has size ≤ 5 %
    (Bonferroni), so "consistent" is a ≥ 95 % claim per set, as is each joint interval containing
    the truth: hits ≥ min_hits(8, 0.95, α/10) (five claims, two-sided budget). The paper's
    quadratic model should be found inconsistent, with drag among the culprits, and its per-trial
    drags should swing with the release: offline over 30 sets, always, with the largest drag ≥ 3.15×
    the smallest, so these are asserted for every set (ratio > 1.5).
    """
    terms = VARIANTS["friction"]
    n = 8
    consistent, hits = 0, dict.fromkeys(TRUTH, 0)
    for s in range(n):
        records = [record(r, terms, 4 * s + i) for i, r in enumerate((75, 20, -15, 5))]
        for variant in ("friction", "quadratic"):
            per_trial = {r.trial: fit_trials([r], VARIANTS[variant], SETTINGS) for r in records}
            joint = fit_joint(records, VARIANTS[variant], per_trial, SETTINGS)
            assert joint["n_samples"] == sum(r.n_samples for r in records)
            assert set(joint["trials"]) == {r.trial for r in records}
            if variant == "friction":
                consistent += joint["consistency"]["verdict"] == "consistent"
                for name, true in TRUTH.items():
                    hits[name] += covers(joint["parameters"][name], true)
            else:
                assert joint["consistency"]["verdict"] == "inconsistent", (s, joint["consistency"])
                assert "drag_area_m2" in joint["consistency"]["inconsistent_parameters"]
                drags = [f["parameters"]["drag_area_m2"]["value"] for f in per_trial.values()]
                assert max(drags) > 1.5 * min(drags)  # the paper's symptom: drag swings with the release
    k = min_hits(n, 0.95, ALPHA / 10)
    assert consistent >= k, (consistent, k)
    assert all(h >= k for h in hits.values()), (hits, k)
