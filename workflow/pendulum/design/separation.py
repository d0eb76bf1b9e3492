"""Telling two indistinguishable effects apart: the candidate trial that separates them most (for
:mod:`pendulum.design.next_trials`, whose designer it is given)."""

from __future__ import annotations

import math

import numpy as np
from scipy import sparse

from pendulum.design.candidates import Candidate
from pendulum.fit.group import GroupProblem, ordered
from pendulum.fit.output_error import working_jacobian
from pendulum.fit.uncertainty import compressed_rows
from pendulum.model.effects import TERMS


def _unexplained(rows: list[tuple[np.ndarray, np.ndarray]]) -> float:
    """‖(I − P) s‖² of the stacked (J, s): the part of the signal no rival coefficient absorbs."""
    jac = np.vstack([j for j, _ in rows])
    signal = np.concatenate([s for _, s in rows])
    coef, *_ = np.linalg.lstsq(jac, signal, rcond=None)
    rest = signal - jac @ coef
    return float(rest @ rest)


def _compressed(rows: list[tuple]) -> list[tuple[np.ndarray, np.ndarray]]:
    """The (J, s) blocks of a large group (J sparse) as one dense block with the same ‖(I − P) s‖²: the trials'
    [J_k | s_k] reduced by a QR each (:func:`pendulum.fit.uncertainty.compressed_rows`), in memory that grows as
    the trials where the stacked J grows as their square."""
    stacked = sparse.vstack([sparse.hstack([jac, sparse.csr_matrix(signal[:, None])]) for jac, signal in rows])
    upper = compressed_rows(stacked.tocsr(), np.cumsum([0] + [signal.size for _, signal in rows]))
    return [(upper[:, :-1], upper[:, -1])]


def _signal_and_rival(problem: GroupProblem, rival: GroupProblem, x: np.ndarray, effect_column: int):
    """Per trial: the effect's signal θ(x) − θ(x with its coefficient 0), and the rival model's J at the same
    shared coefficients (its own at 0), columns as ``rival.columns`` then its nuisances."""
    off = x.copy()
    off[effect_column] = 0.0
    values = {c: float(v) for c, v in zip(problem.columns, x[: problem.n_phys], strict=True)}
    n_trials = len(problem.records)
    nuisance = [x[problem.n_phys + 3 * k : problem.n_phys + 3 * k + 3] for k in range(n_trials)]
    x_rival = rival.start({c: v for c, v in values.items() if c in rival.columns}, nuisance)
    for j, column in enumerate(rival.columns):
        if column not in values:
            x_rival[j] = 0.0
    jac = working_jacobian(rival, x_rival)  # sparse for a large group
    rows = np.cumsum([0] + [m.sum() for m in rival.masks])
    out = []
    for k in range(n_trials):
        signal = (problem.simulate_trial(k, x) - problem.simulate_trial(k, off))[problem.masks[k]]
        out.append((jac[rows[k] : rows[k + 1]], signal))
    return out


def separations(d, groups: list[dict]) -> list[dict]:
    """``d``: a :class:`pendulum.design.next_trials.Designer`. For each indistinguishable group of discovery
    (``effects``, the one ``carried_in_model`` first): how many σ apart its effects would be with each candidate
    trial added, and the trial that separates them most.

    Separation = √Λ with Λ = ‖(I − P_rival) s‖² / (κ² σ²), s the carried effect's signal in the records
    (θ with its coefficient less θ without), P_rival the projection on the rival model's sensitivities (the
    rival effect in its place), σ² = RSS/n of today's fit and κ² its residual-correlation factor: the
    likelihood ratio discovery compares with its threshold (n_eff ln(RSS_rival/RSS) ≈ Λ), linearised about
    today's fit. At one swing frequency the history force is an added mass plus a linear damping whatever
    the amplitude, so for that pair only a rig with another length or payload (config ``design.rigs``) counts.
    """
    fit, problem = d.fit, d.fit.problem
    cov, white, _ = fit.covariance(d.settings_max_ar)
    coefficients = range(problem.n_phys)
    kappa2 = max(float(np.mean([cov[j, j] / white[j, j] for j in coefficients if white[j, j] > 0] or [1.0])), 1.0)
    scale = 1.0 / math.sqrt(kappa2 * fit.rss / fit.n)
    out = []
    for group in groups:
        carried = group.get("carried_in_model") or group["effects"][0]
        if carried not in problem.terms:
            continue
        column = next(j for j, (p, _) in enumerate(problem.columns) if p == TERMS[carried].parameter)
        one_frequency = str(group.get("reason", "")).startswith("at one swing frequency")
        for other in [e for e in group["effects"] if e != carried]:
            terms = tuple(t for t in problem.terms if t != carried) + (other,)
            rival = GroupProblem(problem.records, problem.rig_of, ordered(terms), problem.masks, problem.max_step_s)
            today_rows = [(j * scale, s * scale) for j, s in _signal_and_rival(problem, rival, fit.x, column)]
            if sparse.issparse(today_rows[0][0]):
                today_rows = _compressed(today_rows)
            n_cols = today_rows[0][0].shape[1]
            today = math.sqrt(_unexplained(today_rows))
            best = None
            for cand in d.sensitivities:
                if one_frequency and not cand.hypothetical:
                    continue
                rows = _candidate_rows(d, cand, carried, rival, n_cols, scale)
                width = rows[0].shape[1]
                padded = [(np.pad(j, ((0, 0), (0, width - n_cols))), s) for j, s in today_rows]
                separation = math.sqrt(_unexplained([*padded, rows]))
                if best is None or separation > best[0]:
                    best = (separation, cand)
            labels = f"{TERMS[carried].label} and {TERMS[other].label}"
            entry = {"effects": [carried, other], "separation_sigma_today": today}
            if best is None:
                entry["sentence"] = (
                    f"{labels} cannot be told apart at this arm length whatever the release: describe a rig with "
                    "another arm length or payload in config design.rigs to see the trial that would separate them"
                )
            else:
                separation, cand = best
                where = f"the described rig {cand.rig}" if cand.hypothetical else f"rig {cand.rig}"
                entry.update(
                    {
                        "rig": cand.rig,
                        "described_rig": cand.hypothetical,
                        "release_deg": cand.release_deg,
                        "separation_sigma": separation,
                        "sentence": (
                            f"to tell {labels} apart: one trial on {where}, released from {cand.release_deg:+g}°, "
                            f"would set them {separation:.1f}σ apart (today {today:.1f}σ"
                            + (
                                ", from the release transient alone, which discovery does not count: at one swing "
                                "frequency the two are one effect)"
                                if one_frequency
                                else ")"
                            )
                        ),
                    }
                )
            out.append(entry)
    return out


def _candidate_rows(d, cand: Candidate, carried: str, rival: GroupProblem, n_cols: int, scale: float):
    """The candidate's rival sensitivities (columns: today's rival columns, any new rig's own, then its θ0, θ̇0,
    δ) and its signal of the carried effect, both times ``scale`` (its record as the designer simulated it)."""
    problem = d.fit.problem
    record, nuisance, params = d.records[cand]
    final = GroupProblem([record], [cand.rig], problem.terms, None, problem.max_step_s)
    x = np.array([params.get(p, 0.0) for p, _ in final.columns] + list(nuisance))
    off = x.copy()
    off[next(j for j, (p, _) in enumerate(final.columns) if p == TERMS[carried].parameter)] = 0.0
    signal = final.simulate_trial(0, x) - final.simulate_trial(0, off)
    single = GroupProblem([record], [cand.rig], rival.terms, None, problem.max_step_s)
    jac = single.jacobian(np.array([params.get(p, 0.0) for p, _ in single.columns] + list(nuisance)))
    new = [c for c in single.columns if c not in rival.columns]
    total = n_cols + len(new) + 3
    full = np.zeros((jac.shape[0], total))
    for j, col in enumerate(single.columns):
        full[:, rival.columns.index(col) if col in rival.columns else n_cols + new.index(col)] = jac[:, j]
    full[:, total - 3 :] = jac[:, single.n_phys :]
    return full * scale, signal * scale
