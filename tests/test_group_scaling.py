"""A large group (a lab's many trials of one body): solved on its sparse Jacobian, held out in folds.

From :data:`pendulum.fit.output_error.SPARSE_FROM_TRIALS` trials a group's steps are solved iteratively on the sparse
Jacobian (each trial's rows touch only the body's, its rig's and its own coefficients), not by an SVD of the
dense one, whose cost grows as the trials cubed (discovery on 20 trials 14 s, on 40 115 s; with it 6.5 s and
13 s). Checked here against the exact solver on the same problem, and against the truth.
"""

import numpy as np
import pytest

from paper_rig import PAPER_RIG
from pendulum.fit import output_error
from pendulum.fit.group import GroupProblem, leave_trials_out, start_values
from pendulum.fit.output_error import fit_trials, stacked_jacobian
from pendulum.fit.records import FitSettings, load_record
from pendulum.synthetic.records import hidden_effect_table

SHORT_RIG = {**PAPER_RIG, "length_m": 0.40}
RIGS = {"long": PAPER_RIG, "short": SHORT_RIG}
BODY = {"added_mass_kg": 2.5, "drag_area_m2": 0.02576}
DAMPING_NM_S = {"long": 0.15, "short": 0.04}
TERMS = ("quadratic_drag", "linear_damping")
RELEASES_DEG = (25.0, -18.0, 12.0, -30.0, 20.0, -9.0)
SETTINGS = FitSettings()


def large_group(seed: int = 7, short_trials=range(1, 12, 2)):
    """12 trials (those in ``short_trials`` on the short rig, the rest on the long one) with tracking-like noise,
    and the problem started from per-rig joint fits."""
    records, rigs = [], []
    for i in range(12):
        name = "short" if i in short_trials else "long"
        truth = {**BODY, "linear_damping_nm_s": DAMPING_NM_S[name]}
        table = hidden_effect_table(RIGS[name], truth, RELEASES_DEG[i // 2], seed=100 * seed + i, duration_s=8.0)
        records.append(load_record(table, f"{name}{i}", RIGS[name], SETTINGS))
        rigs.append(name)
    starts = [fit_trials([r for r, g in zip(records, rigs, strict=True) if g == n], TERMS, SETTINGS) for n in RIGS]
    values, nuisance, masks = start_values(records, rigs, starts)
    problem = GroupProblem(records, rigs, TERMS, masks, SETTINGS.max_step_s)
    return problem, problem.start(values, nuisance)


def test_a_large_group_is_solved_on_its_sparse_jacobian_to_the_exact_solvers_estimates(monkeypatch):
    problem, x0 = large_group()
    assert len(problem.records) >= output_error.SPARSE_FROM_TRIALS  # the sparse path
    jac = problem.jacobian(x0)
    sparse = stacked_jacobian(problem.jacobian_blocks(x0), problem.masks, x0.size, as_sparse=True)
    assert np.array_equal(sparse.toarray(), jac)
    assert sparse.nnz < 0.2 * jac.size  # a trial's rows hold 2 body + 1 rig + 3 own coefficients of 29
    iterative = problem.solve(x0, SETTINGS)
    monkeypatch.setattr(output_error, "SPARSE_FROM_TRIALS", 10**6)
    exact = problem.solve(x0, SETTINGS)
    assert iterative.converged and exact.converged
    assert iterative.rss == pytest.approx(exact.rss, rel=1e-9)
    for label, value in exact.coefficients.items():
        assert iterative.coefficients[label] == pytest.approx(value, rel=1e-6), label
    truth = {**BODY, "linear_damping_nm_s[long]": 0.15, "linear_damping_nm_s[short]": 0.04}
    for label, value in truth.items():
        assert iterative.coefficients[label] == pytest.approx(value, rel=0.05), label


def test_a_large_group_is_held_out_in_folds_that_predict_each_trial_to_its_noise():
    """12 trials in 10 folds, dealt out a rig's after the other's (long 0, 2, …, 10, then short 1, 3, …, 11): 0
    and 9, 2 and 11 left out together; each predicted from the rest as closely as when left out alone, and to
    the record's noise (the model is right)."""
    problem, x0 = large_group()
    fit = problem.solve(x0, SETTINGS)
    folds = leave_trials_out(fit, SETTINGS)
    alone = leave_trials_out(fit, SETTINGS, max_folds=len(problem.records))
    fitted_rms = np.sqrt(np.mean(np.concatenate(fit.residuals) ** 2))
    for k, (a, b) in enumerate(zip(folds, alone, strict=True)):
        rms_folds, rms_alone = np.sqrt(np.mean(a**2)), np.sqrt(np.mean(b**2))
        assert rms_folds == pytest.approx(rms_alone, rel=0.05), k
        assert rms_folds < 1.3 * fitted_rms, k
    together = (0, 9, 2, 11)
    assert all(np.array_equal(folds[k], alone[k]) for k in range(12) if k not in together)  # the same refits
    assert not any(np.array_equal(folds[k], alone[k]) for k in together)


def test_no_fold_holds_every_trial_of_a_rig():
    """A rig with two trials 10 apart (0 and 10): in folds of k mod 10 both would be left out together and their
    rig's damping predicted from no trial of it."""
    problem, x0 = large_group(short_trials=(0, 10))
    fit = problem.solve(x0, SETTINGS)
    fitted_rms = np.sqrt(np.mean(np.concatenate(fit.residuals) ** 2))
    for k, residual in enumerate(leave_trials_out(fit, SETTINGS)):
        assert np.sqrt(np.mean(residual**2)) < 1.3 * fitted_rms, k


def test_a_large_groups_intervals_come_from_its_sparse_jacobian_as_from_the_dense_one(monkeypatch):
    """From SPARSE_FROM_TRIALS trials the covariance, the linearised response to a systematic input and the
    design's information are made from the sparse Jacobian, trial by trial (160 trials: the dense one and its
    products took 3.3 GB in discovery): the same numbers as from the dense Jacobian, to rounding."""
    from dataclasses import replace

    from scipy import sparse as sp

    from pendulum.design.candidates import today
    from pendulum.fit.uncertainty import linear_response

    problem, x0 = large_group()
    fit = problem.solve(x0, SETTINGS)
    assert sp.issparse(fit.jacobian)
    cov, white, info = fit.covariance(SETTINGS.max_ar_order)
    delta = np.random.default_rng(1).normal(0.0, 1e-4, fit.jacobian.shape[0])
    free = ~fit.active
    shift = linear_response(fit.jacobian, free, delta)
    design, _, ratio = today(fit, SETTINGS.max_ar_order)
    monkeypatch.setattr(output_error, "SPARSE_FROM_TRIALS", 10**6)
    dense_fit = replace(fit, _jacobian=None)
    assert isinstance(dense_fit.jacobian, np.ndarray)
    cov_d, white_d, info_d = dense_fit.covariance(SETTINGS.max_ar_order)
    assert info == info_d
    for got, want in ((cov, cov_d), (white, white_d)):
        scale = np.sqrt(np.outer(np.diag(want), np.diag(want)))
        assert np.all(np.abs(got - want) <= 1e-8 * scale), np.max(np.abs(got - want) / scale)
    design_d, _, ratio_d = today(dense_fit, SETTINGS.max_ar_order)
    np.testing.assert_allclose(design.bread, design_d.bread, rtol=1e-10, atol=1e-12 * np.abs(design_d.bread).max())
    np.testing.assert_allclose(design.meat, design_d.meat, rtol=1e-10, atol=1e-12 * np.abs(design_d.meat).max())
    np.testing.assert_allclose(ratio, ratio_d, rtol=1e-8)
    shift_d = linear_response(dense_fit.jacobian, free, delta)
    np.testing.assert_allclose(shift, shift_d, rtol=1e-6, atol=1e-9 * np.abs(shift_d).max())


def test_the_rank_check_of_a_sparse_jacobian_finds_what_the_dense_one_finds():
    """Trials' own columns and shared ones, one shared column a multiple of another (no record can tell them
    apart): the check on the trials' QR-compressed rows names the same pair as on the dense Jacobian."""
    import re

    from scipy import sparse as sp

    from pendulum.fit.uncertainty import compressed_rows, jacobian_rank_warnings

    rng = np.random.default_rng(5)
    n_trials, n_rows, shared = 14, 40, 3
    jac = np.zeros((n_trials * n_rows, shared + 3 * n_trials))
    for k in range(n_trials):
        rows = slice(k * n_rows, (k + 1) * n_rows)
        jac[rows, :shared] = rng.normal(size=(n_rows, shared))
        jac[rows, shared + 3 * k : shared + 3 * k + 3] = rng.normal(size=(n_rows, 3))
    labels = ["a", "b", "c"] + [f"{p}[{k}]" for k in range(n_trials) for p in ("theta0", "omega0", "offset")]
    bounds = np.arange(0, n_trials * n_rows + 1, n_rows)
    assert jacobian_rank_warnings(compressed_rows(sp.csr_matrix(jac), bounds), labels) == []
    jac[:, 2] = 2.5 * jac[:, 0]
    dense = jacobian_rank_warnings(jac, labels)
    compressed = jacobian_rank_warnings(compressed_rows(sp.csr_matrix(jac), bounds), labels)
    assert len(dense) == 1 and "a and c cannot be told apart" in dense[0]

    def without_value(w):
        return re.sub(r"relative singular value [0-9.e+-]+", "", w)

    assert [without_value(w) for w in compressed] == [without_value(w) for w in dense]


def test_a_large_groups_separation_is_computed_from_its_trials_compressed_rows():
    """The design's ‖(I − P) s‖² (the part of an effect's signal a rival model cannot absorb) from the trials'
    QR-compressed [J_k | s_k] is the one from the stacked rows, today and with a candidate trial added."""
    from scipy import sparse as sp

    from pendulum.design.separation import _compressed, _unexplained

    rng = np.random.default_rng(11)
    n_trials, n_rows, shared = 14, 50, 3
    n_cols = shared + 3 * n_trials
    rows = []
    for k in range(n_trials):
        jac = np.zeros((n_rows, n_cols))
        jac[:, :shared] = rng.normal(size=(n_rows, shared))
        jac[:, shared + 3 * k : shared + 3 * k + 3] = rng.normal(size=(n_rows, 3))
        signal = jac @ rng.normal(size=n_cols) + 1e-3 * rng.normal(size=n_rows)  # mostly absorbed
        rows.append((jac, signal))
    compressed = _compressed([(sp.csr_matrix(j), s) for j, s in rows])
    assert compressed[0][0].shape[0] <= n_trials * (shared + 4)
    assert _unexplained(compressed) == pytest.approx(_unexplained(rows), rel=1e-8)
    candidate = (rng.normal(size=(n_rows, n_cols + 3)), rng.normal(size=n_rows))
    padded = [(np.pad(j, ((0, 0), (0, 3))), s) for j, s in compressed]
    dense = [(np.pad(j, ((0, 0), (0, 3))), s) for j, s in rows]
    assert _unexplained([*padded, candidate]) == pytest.approx(_unexplained([*dense, candidate]), rel=1e-8)
