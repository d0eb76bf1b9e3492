"""Discovery on angle tables with hidden effects (the workflow never sees the truth), and its error rates.

Every case is a group of two 20 s records at 30 fps with the demo's tracking-like noise
(pendulum.synthetic.records.hidden_effect_table), released at 20° and −10°: on the paper's rig,
or, for "two lengths", one on the paper's rig (L = 0.76 m) and one on a 0.40 m arm
declared as the same body. The baseline is the paper's quadratic-drag model; the true
physics adds what the case hides. Magnitudes are the demo's (τ_f = 0.02 N·m, c = 0.15
N·m·s), K_h = 0.2 kg/√s (a sphere of 0.13 m radius in water), a periodic torque of
0.05 N·m at 1.3 s (off the swing's 4.2 s) and a zero drifting 0.3° over the record.

Error rates (pass rules from the binomial distribution, α = 0.001 per claim, as in
tests/test_fitting_statistics.py): a false naming rate ≤ 5 % (the issue's "at most 1 of
20"), a naming rate ≥ 95 % for each single hidden effect ("at least 19 of 20"). The
suite runs a small sample of seeds; the issue's 20-seed studies are this file run as a
script (counts in docs/discovery.md):

    .venv/bin/python tests/test_discovery_statistics.py --seeds 20

Seeds come from fixed contiguous ranges (never hand-picked). Runs are spread over two
processes started afresh with one BLAS thread each (OpenBLAS threads fighting over two
cores slow the fits' SVDs a hundredfold).
"""

from __future__ import annotations

import argparse
import math
import multiprocessing
import os
import sys
import time
from concurrent.futures import ProcessPoolExecutor
from pathlib import Path

import numpy as np
import pytest
from scipy.stats import binom

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "workflow"))
sys.path.insert(0, str(ROOT / "tests"))

from paper_rig import PAPER_RIG  # noqa: E402

ALPHA = 1e-3
BASE = {"added_mass_kg": 2.5, "drag_area_m2": 0.02576}
SHORT_ARM = {**PAPER_RIG, "length_m": 0.40}
ONE_RIG = ((PAPER_RIG, 20.0, "paper"), (PAPER_RIG, -10.0, "paper"))
TWO_LENGTHS = ((PAPER_RIG, 20.0, "long"), (SHORT_ARM, -10.0, "short"))
CASES = {
    "null": (BASE, ONE_RIG, {}),
    "coulomb": ({**BASE, "friction_torque_nm": 0.02}, ONE_RIG, {}),
    "linear": ({**BASE, "linear_damping_nm_s": 0.15}, ONE_RIG, {}),
    "both": ({**BASE, "friction_torque_nm": 0.02, "linear_damping_nm_s": 0.15}, ONE_RIG, {}),
    "history_two_lengths": ({**BASE, "history_coefficient_kg_per_sqrt_s": 0.2}, TWO_LENGTHS, {}),
    "history_one_length": ({**BASE, "history_coefficient_kg_per_sqrt_s": 0.2}, ONE_RIG, {}),
    "disturbance": (BASE, ONE_RIG, {"disturbance": (0.05, 1.3, 0.4)}),
    "drift": (BASE, ONE_RIG, {"zero_drift_deg": 0.3}),
    "null_two_lengths": (BASE, TWO_LENGTHS, {}),
}
HIDDEN = {"coulomb": "coulomb_friction", "linear": "linear_damping", "history_two_lengths": "history_force"}
CANDIDATES = ("linear_damping", "coulomb_friction", "quadratic_drag", "history_force", "restoring_correction")


def case_records(name: str, seed: int):
    """The records of one realisation of a case, and their rigs' names."""
    from pendulum.fit.records import FitSettings, load_record
    from pendulum.synthetic.records import hidden_effect_table
    from pendulum.synthetic.specs import PeriodicTorque

    truth, rigs, extra = CASES[name]
    options = dict(extra)
    if "disturbance" in options:
        options["disturbance"] = PeriodicTorque(*options["disturbance"])
    records = []
    for i, (rig, release, _) in enumerate(rigs):
        table = hidden_effect_table(rig, truth, release, seed=1000 * seed + i, duration_s=20.0, **options)
        records.append(load_record(table, f"{name}{seed}_{i}", rig, FitSettings()))
    return records, [r for _, _, r in rigs]


def run_case(name: str, seed: int) -> dict:
    """Discovery on one realisation of a case: what it named, and per step the RMS before and after."""
    from pendulum.discovery.selection import discover

    records, rigs = case_records(name, seed)
    start = time.perf_counter()
    document = discover(records, rigs, ("quadratic_drag",), CANDIDATES)
    return {
        "case": name,
        "seed": seed,
        "seconds": time.perf_counter() - start,
        "named": document["named_effects"],
        "final_terms": document["final_terms"],
        "unexplained": document["unexplained"],
        "indistinguishable": [g["effects"] for g in document["indistinguishable"]],
        "steps": [
            {
                "effect": s["effect"],
                "named": s["named"],
                "shrink": s["rms_before_rad"] / s["rms_after_rad"],
                "held_out_shrink": s["held_out_rms_before_rad"] / s["held_out_rms_after_rad"],
            }
            for s in document["steps"]
        ],
        "rms_over_noise": document["residual_check"]["rms_over_noise"],
        "verdict": document["verdict"],
    }


def null_statistics(seed: int) -> dict:
    """Λ (with n_eff) and the white-noise likelihood ratio of linear damping added to a null record's baseline."""
    from pendulum.discovery.selection import Discovery

    records, rigs = case_records("null", seed)
    run = Discovery(records, rigs, ("quadratic_drag",), CANDIDATES)
    base = run.fit(("quadratic_drag",))
    evidence = run.evidence(base, run.fit(("quadratic_drag", "linear_damping")), 1)
    return {
        "case": "calibration",
        "seed": seed,
        **{k: evidence[k] for k in ("likelihood_ratio", "likelihood_ratio_white_noise")},
    }


def _run(job):
    name, seed = job
    return null_statistics(seed) if name == "calibration" else run_case(name, seed)


def run_many(jobs: list[tuple[str, int]], workers: int = 2) -> list[dict]:
    """``run_case`` (or ``null_statistics`` for "calibration") over (case, seed) jobs in fresh processes with one
    BLAS thread each."""
    saved = {k: os.environ.get(k) for k in ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS")}
    os.environ.update(OPENBLAS_NUM_THREADS="1", OMP_NUM_THREADS="1")
    try:
        with ProcessPoolExecutor(workers, mp_context=multiprocessing.get_context("spawn")) as pool:
            return list(pool.map(_run, jobs))
    finally:
        for key, value in saved.items():
            if value is None:
                os.environ.pop(key, None)
            else:
                os.environ[key] = value


def min_hits(n, p, alpha=ALPHA):
    """Fewer than this many successes fail a claim of rate ≥ p: P(X < k | n, p) < alpha."""
    return int(binom.ppf(alpha, n, p))


def max_hits(n, p, alpha=ALPHA):
    """More than this many fail a claim of rate ≤ p: P(X > k | n, p) ≤ alpha."""
    return int(binom.isf(alpha, n, p))


# --- the suite: one realisation of every case, and small error-rate samples

STUDY = {"null": range(100, 110), "coulomb": range(200, 204), "linear": range(300, 304), "calibration": range(400, 440)}


@pytest.fixture(scope="module")
def results():
    jobs = [(name, s) for name, seeds in STUDY.items() for s in seeds] + [(name, 0) for name in CASES]
    out = {}
    for r in run_many(jobs):
        out.setdefault(r["case"], {})[r["seed"]] = r
    return out


def check_shrinks(result):
    """Each named effect shrinks the residual RMS at least 3× in sample and on held-out data."""
    for step in result["steps"]:
        if step["effect"] in result["named"]:
            assert step["shrink"] >= 3 and step["held_out_shrink"] >= 3, step


@pytest.mark.parametrize(("case", "effect"), sorted(HIDDEN.items()))
def test_a_hidden_effect_is_named(results, case, effect):
    result = results[case][0]
    assert result["named"] == [effect] and not result["unexplained"] and not result["indistinguishable"], result
    check_shrinks(result)


def test_both_hidden_damping_effects_are_named(results):
    result = results["both"][0]
    assert sorted(result["named"]) == ["coulomb_friction", "linear_damping"] and not result["unexplained"], result
    check_shrinks(result)


def test_history_force_at_one_length_is_reported_indistinguishable_not_named(results):
    """One swing frequency: the history force is an added mass plus a linear damping; neither is named."""
    result = results["history_one_length"][0]
    assert result["named"] == [] and not result["unexplained"], result
    assert any({"history_force", "linear_damping"} <= set(group) for group in result["indistinguishable"]), result
    assert "another pendulum length" in result["verdict"]


@pytest.mark.parametrize("case", ["null", "null_two_lengths"])
def test_nothing_hidden_names_nothing(results, case):
    result = results[case][0]
    assert result["named"] == [] and result["final_terms"] == ["quadratic_drag"] and not result["unexplained"], result
    assert result["verdict"].startswith("no missing effect")


@pytest.mark.parametrize("case", ["disturbance", "drift"])
def test_an_effect_outside_the_library_is_unexplained_and_nothing_is_named(results, case):
    """A periodic torque (1.3 s) and a drifting zero: structure left (RMS > 5× the noise, not white), no name."""
    result = results[case][0]
    assert result["unexplained"] and result["named"] == [] and not result["indistinguishable"], result
    assert result["rms_over_noise"] > 5


def test_false_discovery_rate_on_null_records(results):
    """Claim: P(an effect is named | nothing hidden) ≤ 5 %. n = 10: fails above max_hits(10, 0.05) = 4 namings.

    The 20-seed study (script) found 0 of 20.
    """
    named = sum(bool(r["named"]) for r in results["null"].values() if r["seed"] in STUDY["null"])
    assert max_hits(10, 0.05) == 4
    assert named <= max_hits(10, 0.05), named


@pytest.mark.parametrize("case", ["coulomb", "linear"])
def test_power_for_single_hidden_effects(results, case):
    """Claim: P(the hidden effect is named) ≥ 95 %. n = 4 seeds: fails below min_hits(4, 0.95) = 2.

    The 20-seed study (script) found 20 of 20 for each.
    """
    hits = sum(r["named"] == [HIDDEN[case]] for r in results[case].values() if r["seed"] in STUDY[case])
    assert min_hits(4, 0.95) == 2
    assert hits >= min_hits(4, 0.95), hits


def test_the_effective_sample_size_calibrates_the_likelihood_ratio(results):
    """Under no effect, Λ = n_eff ln(RSS₀/RSS₁) follows ½χ²₀ + ½χ²₁: P(Λ > 2.706) = 5 %. The white-noise ratio
    n ln(RSS₀/RSS₁) is κ² ≈ 3.4 times larger on tracking-like (AR) noise and would name effects at will.

    n = 40 null records, linear damping added: fails above max_hits(40, 0.05, α/2) = 8 exceedances, or when the
    median κ² (white-noise ratio over Λ) is below 2. Offline over 200 records: Λ exceeds 2.706 in 6.0 %, 5.412 in
    1.0 % and 7.36 (the forward threshold for three candidates) in 0.5 %; Λ > 0 in 54 %, its mean over those
    0.98 (½χ²₁: 5 %, 1 %, 0.33 %, 50 %, 1); the white-noise ratio's mean over those 3.4.
    """
    rows = list(results["calibration"].values())
    assert len(rows) == 40 and max_hits(40, 0.05, ALPHA / 2) == 8
    assert sum(r["likelihood_ratio"] > 2.706 for r in rows) <= max_hits(40, 0.05, ALPHA / 2)
    kappa2 = [r["likelihood_ratio_white_noise"] / r["likelihood_ratio"] for r in rows if r["likelihood_ratio"] > 1e-6]
    assert np.median(kappa2) > 2, kappa2


# --- the 20-seed studies, as a script


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--seeds", type=int, default=20)
    parser.add_argument("--workers", type=int, default=2)
    parser.add_argument("--calibration", type=int, default=0, help="also this many null records for Λ's tails")
    args = parser.parse_args(argv)
    cases = ("null", "null_two_lengths", "coulomb", "linear", "history_two_lengths")
    started = time.perf_counter()
    jobs = [(c, 1000 + s) for c in cases for s in range(args.seeds)]
    results = run_many(jobs + [("calibration", 20000 + s) for s in range(args.calibration)], args.workers)
    n = args.seeds
    print(f"{n} realisations per case, {time.perf_counter() - started:.0f} s on {args.workers} processes")
    print("issue's rules: at most 1 of 20 null groups names an effect; at least 19 of 20 name a hidden one")
    for case in cases:
        rows = [r for r in results if r["case"] == case]
        if case.startswith("null"):
            hits = sum(bool(r["named"]) for r in rows)
            added = sum(bool(r["named"] or r["indistinguishable"]) for r in rows)
            rule = f"claim ≤ 5 %: pass if ≤ {max_hits(n, 0.05)}"
            print(f"{case}: {hits}/{n} name an effect ({rule}), {added}/{n} add any term")
            for r in rows:
                if r["named"] or r["indistinguishable"]:
                    print(f"   seed {r['seed']}: {r['verdict']}")
        else:
            hits = sum(r["named"] == [HIDDEN[case]] for r in rows)
            shrinks = [s for r in rows for s in r["steps"] if s["effect"] == HIDDEN[case]]
            worst = min((min(s["shrink"], s["held_out_shrink"]) for s in shrinks), default=math.nan)
            rule = f"claim ≥ 95 %: pass if ≥ {min_hits(n, 0.95)}"
            print(f"{case}: {hits}/{n} name {HIDDEN[case]} ({rule}); least RMS shrink {worst:.1f}× (in, out of sample)")
            for r in rows:
                if r["named"] != [HIDDEN[case]]:
                    print(f"   seed {r['seed']}: {r['verdict']}")
        print(f"   median time per group {sorted(r['seconds'] for r in rows)[len(rows) // 2]:.1f} s")
    rows = [r for r in results if r["case"] == "calibration"]
    if rows:
        lam = np.array([r["likelihood_ratio"] for r in rows])
        tails = ", ".join(
            f"P(Λ > {x:.3g}) = {np.mean(lam > x):.3f} ({p})" for x, p in ((2.706, 0.05), (5.412, 0.01), (7.361, 0.0033))
        )
        print(f"calibration over {len(rows)} null records (linear damping added; ½χ²₀ + ½χ²₁ in brackets): {tails}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
