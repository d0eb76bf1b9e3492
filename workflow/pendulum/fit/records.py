"""Angle records as the fitter uses them, and the numerical settings of a fit."""

from __future__ import annotations

import hashlib
import math
from dataclasses import dataclass, field

import numpy as np
import pandas as pd

from pendulum.angles.record import InputError
from pendulum.angles.swings import first_swing_rate, record_noise_floor_rad, swing_extrema
from pendulum.model.rig import Rig, tolerances_alike


@dataclass(frozen=True)
class FitSettings:
    """Numerical choices of a fit (config ``fitting``)."""

    release_skip_s: float = 0.25  # samples before this (time since release) are not fitted (none without a release)
    max_step_s: float = 0.02  # RK4 step limit of the simulation inside the fit
    outlier_sigmas: float = 6.0  # one pass: samples further than this (robust σ) are dropped, refit
    identifiable_max_relative_stderr: float = 0.5  # above: flagged not identifiable
    consistency_alpha: float = 0.05
    max_ar_order: int = 10  # highest order of the residual-noise AR model behind the intervals
    added_mass_lower_kg: float = 0.0  # < 0 only for calibration swings (e.g. in air): an inertia correction


def added_mass_floor_kg(records) -> float:
    """The least added mass that leaves every record's rig a pendulum: I_p + m_a L² ≥ 1 % of I_p."""
    return max(-0.99 * r.rig.pivot_inertia_kg_m2 / r.rig.length_m**2 for r in records)


def added_mass_lower_kg(records, settings: FitSettings) -> float:
    """The configured lower bound of the added mass, raised to :func:`added_mass_floor_kg` where it is below."""
    return max(settings.added_mass_lower_kg, added_mass_floor_kg(records))


# Standard uncertainty (1σ) of each measured rig value, relative to the value, used when a
# rig's ``tolerances`` block does not state it (absolute values there override these).
DEFAULT_RELATIVE_TOLERANCES = {
    "mass_kg": 0.002,  # kitchen/lab scale on a few kg
    "length_m": 0.002,  # tape measure, pivot to centre of the body: ≈1.5 mm on 0.76 m
    "frontal_area_m2": 0.02,  # from drawings or a photograph
    "displaced_volume_m3": 0.01,  # from CAD or displacement
    "submerged_mass_kg": 0.002,  # weighed hung in the tank's fluid (m − ρV): a scale reading, as the mass
    "body_inertia_kg_m2": 0.02,  # from CAD or a bifilar swing (only when given)
    "fluid_density_kg_m3": 0.002,  # fresh water 0–30 °C
    "gravity_m_s2": 0.0,
}
WATER_KINEMATIC_VISCOSITY_M2_S = 1.0e-6  # 20 °C
AIR_KINEMATIC_VISCOSITY_M2_S = 1.5e-5  # 20 °C, 1 atm
GAS_DENSITY_KG_M3 = 100.0  # a fluid lighter than this is a gas: air's viscosity where none is stated
GAS_DENSITY_RELATIVE_TOLERANCE = 0.02  # air's density unmeasured: ±5 K and ±2 kPa about a room's 20 °C, 1 atm


def kinematic_viscosity_m2_s(rig_values: dict) -> float:
    """The rig's stated ν, else water's at 20 °C, or air's where its fluid is a gas (ρ < 100 kg/m³): the Reynolds
    number Re = U D / ν of the half-cycle tables (a rig in air given water's ν read Re 15× too high)."""
    stated = rig_values.get("kinematic_viscosity_m2_s")
    if stated:
        return float(stated)
    density = rig_values.get("fluid_density_kg_m3")
    gas = density is not None and float(density) < GAS_DENSITY_KG_M3
    return AIR_KINEMATIC_VISCOSITY_M2_S if gas else WATER_KINEMATIC_VISCOSITY_M2_S


# Rig values the model takes when a rig does not state them (Rig's defaults): filled in before a fit, so
# that their default tolerances (fluid density 0.2 %) enter the error budget as for a stated value.
RIG_DEFAULTS = {
    "fluid_density_kg_m3": Rig.__dataclass_fields__["fluid_density_kg_m3"].default,
    "gravity_m_s2": Rig.__dataclass_fields__["gravity_m_s2"].default,
}


def with_rig_defaults(rig_values: dict) -> dict:
    """``rig_values`` with :data:`RIG_DEFAULTS` for the ones not stated (or null)."""
    return {**rig_values, **{k: v for k, v in RIG_DEFAULTS.items() if rig_values.get(k) is None}}


def rig_tolerances(rig_values: dict, stated: dict | None = None) -> dict:
    """Absolute 1σ uncertainty of every rig value that enters the model: stated, else the default fraction
    (a gas's density, ρ < 100 kg/m³: 2 %, not fresh water's 0.2 %)."""
    stated = stated or {}
    out = {}
    for name, fraction in DEFAULT_RELATIVE_TOLERANCES.items():
        value = rig_values.get(name)
        if value is None and name == "body_inertia_kg_m2":
            continue  # point mass: I_p = m L² follows mass and length
        if name in stated:
            out[name] = float(stated[name])
        elif value is not None:
            gas = name == "fluid_density_kg_m3" and abs(float(value)) < GAS_DENSITY_KG_M3
            out[name] = (GAS_DENSITY_RELATIVE_TOLERANCE if gas else fraction) * abs(float(value))
    return out


@dataclass
class AngleRecord:
    """The samples of one trial that a fit uses (valid, after the release transient).

    Besides the samples it carries what the systematic error budget needs: the
    rig values as stated with their 1σ ``tolerances``, and the geometry of the
    angle measurement (marker arm radius in pixels and the covariance of an
    estimated pivot, both None for angle tables that did not come from a track).
    """

    trial: str
    rig: Rig
    time_s: np.ndarray  # since release
    theta_rad: np.ndarray
    characteristic_length_m: float
    dropped: dict = field(default_factory=dict)
    rig_values: dict = field(default_factory=dict)
    tolerances: dict = field(default_factory=dict)
    arm_radius_px: float | None = None
    pivot_covariance_px2: list | None = None
    vertical_rad: float = 0.0  # image angle of the vertical: θ_image = θ + vertical
    noise_rad: float | None = None  # the angles stage's record noise (its noise_deg), where it came from there
    release_skip_s: float = 0.0  # the release transient left out (0: a record that starts mid-swing has none)

    @property
    def n_samples(self) -> int:
        return int(self.time_s.size)

    def measured_first_swing(self) -> dict | None:
        """The first fitted swing as the record shows it (:func:`~pendulum.angles.swings.first_swing_rate`), the
        same whatever a variant fits: U_max = L |θ̇| where it crosses the vertical, that cycle's period T and the
        Keulegan–Carpenter number KC = U_max T / D; None where the record crosses the vertical under twice."""
        rate = first_swing_rate(self.time_s, self.theta_rad)
        if rate is None:
            return None
        speed = rate[0] * self.rig.length_m
        return {
            "peak_speed_m_s": speed,
            "period_s": rate[1],
            "keulegan_carpenter_number": speed * rate[1] / self.characteristic_length_m,
        }


def record_noise_rad(record: AngleRecord) -> float:
    """The record's sample noise σ as every stage says it: the angles stage's (``noise_rad``: Table 2's record noise),
    else the same figure from its samples (:func:`~pendulum.angles.swings.record_noise_floor_rad`)."""
    if record.noise_rad is not None:
        return record.noise_rad
    return record_noise_floor_rad(record.theta_rad, record.time_s)


def keulegan_carpenter_number(fit: dict):
    """A fit document's Keulegan–Carpenter number (its trials' first fitted swings): as the records show it, else
    (a record that crosses the vertical under twice) from the variant's fitted
    curve; a number, or [least, largest] over a joint fit's trials."""
    measured = fit.get("measured_keulegan_carpenter_number")
    return fit["keulegan_carpenter_number"] if measured is None else measured


def value_or_range(values: list):
    """A fit's figure from its trials' (a Keulegan–Carpenter number): one trial's value, else [least, largest] of
    those known; None where none is."""
    known = [v for v in values if v is not None]
    if len(values) == 1 or not known:
        return values[0] if len(values) == 1 else None
    return [min(known), max(known)]


def characteristic_length_m(rig_values: dict) -> float:
    """D of the Keulegan–Carpenter number: given, else the diameter of a disc of the frontal area."""
    given = rig_values.get("characteristic_length_m")
    if given:
        return float(given)
    return math.sqrt(4 * float(rig_values["frontal_area_m2"]) / math.pi)


def _no_sample_after_the_transient(where: str, usable_time_s: np.ndarray, n_flagged: int, skip_s: float):
    """Raise the InputError for a record with no usable sample at or after ``release_skip_s``."""
    if usable_time_s.size == 0:
        raise InputError(
            f"{where}: no usable angle sample: all {n_flagged} rows are flagged or lack a time or an angle"
        )
    raise InputError(
        f"{where}: record too short to fit: its {usable_time_s.size} usable angle samples span "
        f"{usable_time_s.min():.3g} to {usable_time_s.max():.3g} s after the release, all before the release "
        f"transient ends (fitting.release_skip_s = {skip_s:g} s); is the time column in seconds, and does the "
        "record run past the release?"
    )


def load_record(
    table: pd.DataFrame,
    trial: str,
    rig_values: dict,
    settings: FitSettings,
    *,
    tolerances: dict | None = None,
    angle_info: dict | None = None,
    source: str | None = None,
) -> AngleRecord:
    """Angle-CSV rows (``time_s``, ``theta_rad``, ``flag``) → the samples to fit.

    ``tolerances``: the rig's stated 1σ uncertainties (config ``rigs.<rig>.tolerances``;
    values not stated take :data:`DEFAULT_RELATIVE_TOLERANCES`; None: the rig values
    are exact, no systematic budget — for records generated from known values);
    ``angle_info``: the angles stage's JSON (arm radius, pivot covariance, vertical);
    ``source``: the angle file, named in errors. A record with fewer than 30
    usable samples or less than about one period (two swing extrema) after the
    release transient raises :class:`~pendulum.angles.record.InputError` ("record too short").
    """
    where = f"{source} (trial {trial})" if source else f"trial {trial}"
    rig_values = with_rig_defaults(rig_values)
    for column in ("time_s", "theta_rad"):
        if column not in table.columns:
            raise InputError(f"{where}: angle table lacks column {column!r}")
    t = pd.to_numeric(table.time_s, errors="coerce").to_numpy(float)
    th = pd.to_numeric(table.theta_rad, errors="coerce").to_numpy(float)
    ok = np.isfinite(t) & np.isfinite(th)
    if "flag" in table.columns:
        ok &= table.flag.to_numpy(object) == "ok"
    n_flagged = int((~ok).sum())
    # a record that starts mid-swing (no release in view: the angles stage's release_detected false) has no
    # release transient: its fit starts at the first sample
    skip_s = settings.release_skip_s if (angle_info or {}).get("release_detected", True) else 0.0
    early = t < skip_s
    use = ok & ~early
    if not use.any():
        _no_sample_after_the_transient(where, t[ok], n_flagged, skip_s)
    t, th = t[use], th[use]
    order = np.argsort(t, kind="stable")
    t, th = t[order], th[order]
    keep = np.concatenate([[True], np.diff(t) > 0])  # repeated time stamps: keep the first
    t, th = t[keep], th[keep]
    if t.size < 30:
        raise InputError(
            f"{where}: record too short to fit: only {t.size} usable angle samples after the release transient "
            "(at least 30 needed)"
        )
    n_extrema = swing_extrema(th).size
    if n_extrema < 2:
        raise InputError(
            f"{where}: record too short to fit: {t[-1] - t[0]:.3g} s after the release transient "
            f"with {n_extrema} swing {'extremum' if n_extrema == 1 else 'extrema'}, less than one full period "
            "(2 needed); record a longer swing"
        )
    rig = Rig.from_mapping(rig_values)
    info = angle_info or {}
    return AngleRecord(
        trial,
        rig,
        t,
        th,
        characteristic_length_m(rig_values),
        dropped={
            "flagged_or_missing": n_flagged,
            "release_transient": int((early & ok).sum()),
            "repeated_time": int((~keep).sum()),
        },
        rig_values=dict(rig_values),
        tolerances={} if tolerances is None else rig_tolerances(rig_values, tolerances),
        arm_radius_px=info.get("arm_radius_px"),
        pivot_covariance_px2=info.get("pivot_covariance_px2"),
        vertical_rad=math.radians(info.get("vertical_deg") or 0.0),
        noise_rad=math.radians(info["noise_deg"]) if info.get("noise_deg") is not None else None,
        release_skip_s=skip_s,
    )


def samples_digest(records, masks) -> str:
    """SHA-256 of the (trial, time) pairs fitted: AIC/BIC compare only fits with the same digest."""
    h = hashlib.sha256()
    for rec, mask in zip(records, masks, strict=True):
        h.update(rec.trial.encode() + b"\0")
        h.update(np.round(rec.time_s[mask], 9).tobytes())
    return h.hexdigest()[:16]


def systematic_inputs(records) -> dict:
    """What the systematic budget propagated: each rig value's 1σ and the pivot covariance per trial."""
    alike, differ = tolerances_alike([r.tolerances for r in records])
    by_trial = {"rig_tolerances_by_trial": {r.trial: dict(r.tolerances) for r in records}} if differ else {}
    return {
        "rig_tolerances": alike,  # what every trial states alike; all of each where they differ
        **by_trial,
        "pivot_covariance_px2": {r.trial: r.pivot_covariance_px2 for r in records},
        "arm_radius_px": {r.trial: r.arm_radius_px for r in records},
    }
