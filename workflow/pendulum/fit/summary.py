"""Fit documents as written to results/fits, the fitted curves and half-cycle tables, and the summary table."""

from __future__ import annotations

import math
from dataclasses import asdict, fields, replace

import numpy as np
import pandas as pd

from pendulum.angles.swings import swing_centre_track
from pendulum.fit.decay import half_cycles, loss_at_amplitude
from pendulum.fit.records import (
    DEFAULT_RELATIVE_TOLERANCES,
    FitSettings,
    characteristic_length_m,
    keulegan_carpenter_number,
    kinematic_viscosity_m2_s,
    load_record,
)
from pendulum.model.effects import ADDED_MASS, TERMS
from pendulum.model.physics import PendulumModel, simulate
from pendulum.model.rig import Rig


def fit_document(fit: dict, *, variant: str, rig: dict, sources: list[str], settings: FitSettings) -> dict:
    """A fit as written to results/fits: what was fitted, to what, with which settings, then the fit and the
    covariance of its coefficients with every error in it (:func:`combined_covariance`)."""
    document = {
        "variant": variant,
        "terms": fit["terms"],
        "rig": rig,
        "sources": list(sources),
        "settings": asdict(settings),
        **{k: v for k, v in fit.items() if k != "terms"},
    }
    if fit.get("parameters") and fit.get("correlation"):
        tolerances = fit.get("uncertainty", {}).get("systematic_inputs", {}).get("rig_tolerances")
        document["covariance"] = combined_covariance(fit["parameters"], fit["correlation"], tolerances)
    return document


def combined_covariance(parameters: dict, statistical: dict, tolerances: dict | None = None) -> dict:
    """The coefficients' covariance with every error in it, and with the rig values they were fitted with, what
    carrying them into a vehicle model needs (its m, V and ρ are the rig's: a volume read too large moves m_a the
    other way, and the weight-to-inertia ratio is known far better than either).

    Coefficients: Σ = D R D + Σ_i b_i b_iᵀ, R the fit's statistical correlation (``statistical``: its parameters
    and matrix), D = diag(S σ_stat) (S the joint fit's consistency scale factor, 1 elsewhere) and b_i each
    systematic input's 1σ shifts of all the coefficients at once (their ``error_budget``); C_d takes C_dA's
    statistical correlation (C_d = C_dA / A); the diagonal is each coefficient's ``stderr``². Rig values (those of
    ``tolerances``, their stated 1σ u_i, that move a coefficient): var u_i², cov(coefficient, value) = b_i u_i,
    independent of each other. The estimated pivot's inputs enter the coefficients' block only. A coefficient at
    its bound is in it as fitted, and listed under ``at_bound``: its interval is one-sided, no normal law's."""
    index = {n: k for k, n in enumerate(statistical["parameters"])}
    source = {n: index.get("drag_area_m2" if n == "drag_coefficient" else n) for n in parameters}
    names = [n for n in parameters if source[n] is not None]
    r = np.asarray(statistical["matrix"], float)[np.ix_([source[n] for n in names], [source[n] for n in names])]
    sigma = np.array([parameters[n]["stderr_statistical"] * (parameters[n].get("scale_factor") or 1.0) for n in names])
    budgets = [parameters[n].get("error_budget") or {} for n in names]
    keys = sorted({k for b in budgets for k in b})
    shifts = {k: np.array([b.get(k, 0.0) for b in budgets], float) for k in keys}
    order = [*DEFAULT_RELATIVE_TOLERANCES, *keys]  # Table 1's order: m, L, A, V, ...
    rig = sorted((k for k in keys if (tolerances or {}).get(k) and shifts[k].any()), key=order.index)
    n = len(names)
    cov = np.zeros((n + len(rig), n + len(rig)))
    cov[:n, :n] = r * np.outer(sigma, sigma) + sum((np.outer(v, v) for v in shifts.values()), np.zeros((n, n)))
    for i, key in enumerate(rig, start=n):
        cov[i, i] = float(tolerances[key]) ** 2
        cov[:n, i] = cov[i, :n] = shifts[key] * float(tolerances[key])
    return {
        "quantities": names + rig,
        "rig_values": rig,
        "at_bound": [n for n in names if parameters[n].get("at_bound")],  # their intervals are one-sided
        "matrix": cov.tolist(),
        "method": "coefficients: statistical covariance (each σ widened by the joint fit's scale factor S) plus, for "
        "each systematic input, the outer product of its 1σ shifts of the coefficients (error_budget); rig values: "
        "their stated 1σ squared, with each coefficient its 1σ shift times that 1σ",
    }


PHYSICAL_COLUMNS = (ADDED_MASS, "drag_area_m2", "drag_coefficient", "linear_damping_nm_s", "friction_torque_nm")


def _coefficient_columns(documents: list[dict]) -> list[str]:
    """The paper's coefficients always; other library effects' coefficients when some fit has them."""
    present = {name for doc in documents for name in doc.get("parameters", {})}
    extra = [t.parameter for t in TERMS.values() if t.parameter in present and t.parameter not in PHYSICAL_COLUMNS]
    return [*PHYSICAL_COLUMNS, *extra]


def _label(document: dict) -> str:
    if "trial" in document:
        return document["trial"]
    return f"joint:{document['rig']['name']}"


def summary_table(documents: list[dict]) -> pd.DataFrame:
    """One row per (variant, trial or joint fit): the paper's Tables 2 and 3 with intervals and flags.

    ``documents``: per-trial fit documents (with ``trial``) and per-rig joint ones
    (results/fits/<variant>/joint/<rig>.json, labelled ``joint:<rig>``). Failed
    fits (``status: failed``) have no row; the status table lists them.
    """
    documents = [doc for doc in documents if doc.get("status") != "failed"]
    columns = _coefficient_columns(documents)
    rows = []
    for doc in documents:
        fits = [(_label(doc), doc)]
        for label, fit in fits:
            kc = keulegan_carpenter_number(fit)
            first = next(iter(fit["trials"].values()))
            row = {
                "variant": fit["variant"],
                "fit": label,
                "n_trials": len(fit["trials"]),
                "theta0_deg": first["theta0_deg"] if len(fit["trials"]) == 1 else None,
                "kc_min": min(kc) if isinstance(kc, list) else kc,
                "kc_max": max(kc) if isinstance(kc, list) else kc,
                "n_samples": fit["n_samples"],
                "rms_deg": fit["rms_deg"],
                "rms_arc_m": fit["rms_arc_m"],
                "aic": fit["aic"],
                "bic": fit["bic"],
                "samples_digest": fit.get("samples_digest"),
                "consistency": fit.get("consistency", {}).get("verdict"),
                "reliable": fit.get("reliable", True),  # False: garbage in (record_checks.record_checks)
                "n_warnings": len(fit["warnings"]),
                "warnings": " | ".join(fit["warnings"]),
            }
            for name in columns:
                entry = fit["parameters"].get(name)
                row[name] = entry["value"] if entry else None
                row[f"{name}_stderr"] = entry["stderr"] if entry else None
                row[f"{name}_ci95_low"] = entry["ci95"][0] if entry else None
                row[f"{name}_ci95_high"] = entry["ci95"][1] if entry else None
                row[f"{name}_at_bound"] = entry["at_bound"] if entry else None
                row[f"{name}_identifiable"] = entry["identifiable"] if entry else None
                row[f"{name}_stderr_statistical"] = entry.get("stderr_statistical") if entry else None
                row[f"{name}_stderr_systematic"] = entry.get("stderr_systematic") if entry else None
            rows.append(row)
    return _information_criteria_differences(pd.DataFrame(rows))


def _information_criteria_differences(table: pd.DataFrame) -> pd.DataFrame:
    """ΔAIC, ΔBIC against the best variant of the same fit, only among fits of the same samples.

    Outlier rejection may drop different samples for different variants; AIC and
    BIC of fits to different samples are not comparable, so such a fit gets no
    Δ (empty) and ``same_samples_as_best`` False.
    """
    table = table.copy()
    table["delta_aic"] = np.nan
    table["delta_bic"] = np.nan
    table["same_samples_as_best"] = False
    if table.empty:
        return table
    for _, group in table.groupby("fit", sort=False):
        best = group.loc[group.aic.idxmin()]
        same = group.samples_digest == best.samples_digest
        index = group.index[same.to_numpy()]
        table.loc[index, "delta_aic"] = group.aic[same] - best.aic
        table.loc[index, "delta_bic"] = group.bic[same] - group.bic[same].min()
        table.loc[index, "same_samples_as_best"] = True
    return table


# ---------------------------------------------------------------------------
# Fitted curve and half-cycle table of one trial and variant

CURVE_COLUMNS = ("time_s", "theta_measured_rad", "theta_fitted_rad", "residual_rad", "flag")
FITTED, RELEASE_TRANSIENT, OUTLIER = "fitted", "release_transient", "outlier"


def _settings(document: dict) -> FitSettings:
    known = {f.name for f in fields(FitSettings)}
    return FitSettings(**{k: v for k, v in document.get("settings", {}).items() if k in known})


def _trial_entry(document: dict, trial: str | None) -> tuple[str, dict]:
    trials = document["trials"]
    if trial is None:
        trial = document.get("trial")
        if trial is None:
            if len(trials) != 1:
                raise ValueError(f"the fit document holds trials {sorted(trials)}: name one")
            trial = next(iter(trials))
    if trial not in trials:
        raise ValueError(f"the fit document has no trial {trial!r} (it holds {sorted(trials)})")
    return trial, trials[trial]


def fitted_physical(document: dict, model: PendulumModel) -> dict:
    """The model's physical parameters (added mass and one coefficient per term) as fitted in a document."""
    missing = [n for n in model.parameter_names if n not in document["parameters"]]
    if missing:
        raise ValueError(f"the fit document has no {missing}: it is not a fit of terms {list(model.terms)}")
    return {n: float(document["parameters"][n]["value"]) for n in model.parameter_names}


def fitted_curve(
    angle_table: pd.DataFrame,
    fit_document: dict,
    rig_values: dict | None = None,
    terms=None,
    trial: str | None = None,
) -> pd.DataFrame:
    """Every sample of an angle record with the fitted θ, the residual and what the fit did with it.

    The fitted θ is the variant's model simulated (:func:`pendulum.model.physics.simulate`,
    the fit's ``max_step_s``) from the document's parameter values and the trial's
    nuisance values (θ0, θ̇0 at ``fit_start_s``), plus the fitted rest offset;
    ``residual_rad`` = fitted − measured, as in the fit. It is empty before
    ``fit_start_s``. The samples the fit used are simulated on exactly the fit's
    time grid (:func:`pendulum.fit.records.load_record`), so the RMS residual over the
    ``fitted`` samples is the document's ``rms_rad``; other samples after the fit
    start (flagged ones) get θ from a simulation over all sample times.

    ``flag``: ``fitted``; ``release_transient`` (before the fit's ``release_skip_s``);
    ``outlier`` (dropped by the fit, ``outlier_times_s``); the record's own flag
    when not ``ok`` (``occluded``, ``lost``, …); ``missing`` (no finite θ) or
    ``repeated_time`` (a repeated time stamp: the fit keeps the first).
    """
    trial, entry = _trial_entry(fit_document, trial)
    rig_values = rig_values if rig_values is not None else fit_document["rig"]["values"]
    terms = list(terms if terms is not None else fit_document["terms"])
    settings = _settings(fit_document)
    skip_s = float(entry.get("release_skip_s", settings.release_skip_s))  # the fit's own (0: a mid-swing start)
    record = load_record(angle_table, trial, rig_values, replace(settings, release_skip_s=skip_s))
    model = PendulumModel(Rig.from_mapping(rig_values), tuple(terms))
    params = fitted_physical(fit_document, model)
    theta0 = math.radians(entry["theta0_deg"])
    omega0 = math.radians(entry["omega0_deg_s"])
    offset = math.radians(entry["rest_offset_deg"])
    start = float(entry["fit_start_s"])

    t = angle_table.time_s.to_numpy(float)
    measured = angle_table.theta_rad.to_numpy(float)
    own_flag = (
        angle_table.flag.fillna("missing").astype(str).to_numpy(object)
        if "flag" in angle_table.columns
        else np.full(t.size, "ok", object)
    )
    fitted = np.full(t.size, np.nan)
    # the fit's own grid: the samples it used (and those it dropped as outliers)
    if abs(record.time_s[0] - start) > 1e-9 * max(1.0, abs(start)):
        raise ValueError(
            f"trial {trial}: the angle record's first usable sample ({record.time_s[0]:.6g} s) is not the fit's "
            f"start ({start:.6g} s): the fit document is not from this angle record"
        )
    grid_theta, _ = simulate(model, params, theta0, omega0, record.time_s, max_step_s=settings.max_step_s)
    on_grid = dict(zip(record.time_s.tolist(), (grid_theta + offset).tolist(), strict=True))
    later = np.isfinite(t) & (t >= record.time_s[0])
    other = np.unique(t[later])
    if other.size:
        other_theta, _ = simulate(model, params, theta0, omega0, other, max_step_s=settings.max_step_s)
        by_time = dict(zip(other.tolist(), (other_theta + offset).tolist(), strict=True))
        fitted[later] = [by_time[v] for v in t[later]]

    flag = np.where(own_flag == "ok", "missing", own_flag).astype(object)
    used = set(record.time_s.tolist())
    outliers = np.asarray(entry.get("outlier_times_s") or [], float)
    seen = set()
    for i in range(t.size):
        if own_flag[i] != "ok" or not (np.isfinite(t[i]) and np.isfinite(measured[i])):
            continue
        if t[i] < skip_s:
            flag[i] = RELEASE_TRANSIENT
            fitted[i] = np.nan
        elif t[i] in used and t[i] not in seen:
            seen.add(t[i])
            fitted[i] = on_grid[t[i]]
            is_outlier = outliers.size and np.min(np.abs(outliers - t[i])) <= 1e-6 * max(1.0, abs(t[i]))
            flag[i] = OUTLIER if is_outlier else FITTED
        elif t[i] in used:
            flag[i] = "repeated_time"
    return pd.DataFrame(
        {
            "time_s": t,
            "theta_measured_rad": measured,
            "theta_fitted_rad": fitted,
            "residual_rad": fitted - measured,
            "flag": flag,
        },
        columns=list(CURVE_COLUMNS),
    )


def cycle_table(
    curve: pd.DataFrame, fit_document: dict, rig_values: dict | None = None, terms=None, trial: str | None = None
) -> pd.DataFrame:
    """Half cycles of the measured record (:func:`pendulum.fit.decay.half_cycles`) with the variant's prediction.

    Measured: the valid samples (``fitted`` and ``release_transient``; not
    outliers or flagged ones), amplitudes about the record's own swing centre
    (:func:`swing_centre_track`; the fitted rest offset where it has none: a fit
    that misses the record can misplace its offset by a fraction of a degree, and amplitudes about
    it make the losses alternate half cycle to half cycle), inertia from the fitted added mass.
    The fitted curve's half cycles are taken about the fitted rest offset. ``predicted_amplitude_loss_rad``: the same
    extremum analysis run on the fitted curve, its loss interpolated at each
    measured peak amplitude (:func:`pendulum.fit.decay.loss_at_amplitude`).
    """
    trial, entry = _trial_entry(fit_document, trial)
    rig_values = rig_values if rig_values is not None else fit_document["rig"]["values"]
    terms = list(terms if terms is not None else fit_document["terms"])
    model = PendulumModel(Rig.from_mapping(rig_values), tuple(terms))
    params = fitted_physical(fit_document, model)
    offset = math.radians(entry["rest_offset_deg"])
    length = characteristic_length_m(rig_values)
    nu = kinematic_viscosity_m2_s(rig_values)

    def cycles(column, use, centre):
        return half_cycles(
            curve.time_s.to_numpy(float)[use], curve[column].to_numpy(float)[use], centre, model, params, length, nu
        )

    valid = curve.flag.isin([FITTED, RELEASE_TRANSIENT]).to_numpy()
    centre = swing_centre_track(curve.time_s.to_numpy(float), np.where(valid, curve.theta_measured_rad, np.nan))
    measured = cycles("theta_measured_rad", valid, offset if centre is None else centre[valid])
    predicted = cycles("theta_fitted_rad", np.isfinite(curve.theta_fitted_rad.to_numpy(float)), offset)
    measured["predicted_amplitude_loss_rad"] = loss_at_amplitude(predicted, measured.amplitude_rad.to_numpy())
    return measured
