"""Is a fitted angle record a clean swing, and do the rig values and the record agree? Warnings, not errors.

Garbage in (:func:`record_checks`): too few usable samples, a rest angle far from a known vertical,
residuals that jump far beyond the record's noise. A wrong model (:func:`misfit_warning`): smooth
residuals far above the noise. Rig values that cannot match the measured period (:func:`rig_checks`).
"""

from __future__ import annotations

import math

import numpy as np

from pendulum.angles.swings import noise_differences
from pendulum.fit.records import AngleRecord, record_noise_rad
from pendulum.fit.uncertainty import lag1_autocorrelation
from pendulum.model.rig import Rig

# Garbage in (issue 12): thresholds of :func:`record_checks`.
MIN_USABLE_FRACTION = 0.5  # of the samples after the release transient: less, and pieces of the swing are fitted
MAX_REST_OFFSET_DEG = 2.0  # with the vertical given or estimated from the swings the rest angle is ≈ 0
MAX_ROUGHNESS_RATIO = 5.0  # RMS over robust σ of the residual's third differences; Gaussian noise: ≈ 1
MIN_NOISE_TRIPLES = 20  # fewer runs of four consecutive samples: the noise cannot be told from jumps


def record_checks(record: AngleRecord, mask: np.ndarray, residual: np.ndarray, rest_offset_rad: float) -> dict:
    """Signs that a fitted record is not a clean swing of the marker, each against a stated threshold.

    * ``usable_fraction``: fitted samples over the record's samples after the release transient
      (flagged, missing, repeated and outlier samples are unusable); below
      :data:`MIN_USABLE_FRACTION` the fit rests on pieces of the swing, typically those where the
      tracker followed something else.
    * ``rest_offset_deg`` (checked when the vertical is known: a record tracked from video, whose
      vertical was given or estimated from the swings): beyond :data:`MAX_REST_OFFSET_DEG` the
      angles are not about the pendulum's vertical (wrong pivot or wrong object).
    * ``roughness_ratio``: RMS over robust σ of the residual's third differences on consecutive
      samples (:func:`noise_differences`). A pendulum moves smoothly and a wrong model leaves
      smooth residuals, so with noise alone the ratio is ≈ 1; above :data:`MAX_ROUGHNESS_RATIO` the
      record jumps by far more than its noise (the track hopping between objects). With fewer than
      :data:`MIN_NOISE_TRIPLES` runs of consecutive samples the noise, and so the residual against
      it, cannot be judged.

    ``problems``: one sentence per failed check (empty: nothing found).
    """
    after_transient = record.n_samples + record.dropped.get("flagged_or_missing", 0)
    after_transient += record.dropped.get("repeated_time", 0)
    fraction = residual.size / max(after_transient, 1)
    d3 = noise_differences(record.time_s[mask], residual)
    robust = float(1.4826 * np.median(np.abs(d3 - np.median(d3)))) if d3.size else 0.0
    rough = float(np.sqrt(np.mean(d3**2))) / robust if robust > 0 and d3.size >= MIN_NOISE_TRIPLES else None
    vertical_known = record.arm_radius_px is not None
    offset_deg = math.degrees(rest_offset_rad)
    rms = float(np.sqrt(np.mean(residual**2))) if residual.size else 0.0
    noise = robust
    problems = []
    name = f"trial {record.trial}"
    if fraction < MIN_USABLE_FRACTION:
        problems.append(
            f"{name}: only {fraction:.0%} of the samples after the release are usable ({residual.size} of "
            f"{after_transient}; at least {MIN_USABLE_FRACTION:.0%} needed): the fit rests on pieces of the swing, "
            "often where the tracker followed something else; check the track and its flags"
        )
    if vertical_known and abs(offset_deg) > MAX_REST_OFFSET_DEG:
        problems.append(
            f"{name}: fitted rest angle {offset_deg:+.1f}° from the vertical (more than {MAX_REST_OFFSET_DEG:g}°): "
            "the angles are not about the pendulum's vertical (wrong object tracked, wrong pivot_px or vertical_deg)"
        )
    if d3.size < MIN_NOISE_TRIPLES:
        problems.append(
            f"{name}: only {d3.size} runs of four consecutive samples (at least {MIN_NOISE_TRIPLES} needed): the "
            "record's noise cannot be estimated, so its residual RMS cannot be judged against it"
        )
    elif rough is not None and rough > MAX_ROUGHNESS_RATIO:
        problems.append(
            f"{name}: the residuals jump: their sample-to-sample changes have {rough:.0f}× the RMS their own noise "
            f"({math.degrees(noise):.2g}°, from their third differences' median) gives (more than "
            f"{MAX_ROUGHNESS_RATIO:g}×; residual RMS {math.degrees(rms):.3g}°): the track hops between objects or "
            "mis-tracks; check the track"
        )
    return {
        "usable_fraction": fraction,
        "rest_offset_deg": offset_deg,
        "vertical_known": vertical_known,
        # the residual's own sample-to-sample noise (its third differences), which its jumps are judged against: not
        # the record's noise (the angles stage's noise_deg, Table 2's), and named apart from it
        "residual_noise_deg": math.degrees(noise) if d3.size >= MIN_NOISE_TRIPLES else None,
        "rms_over_residual_noise": rms / noise if noise > 0 and d3.size >= MIN_NOISE_TRIPLES else None,
        "roughness_ratio": rough,
        "thresholds": {
            "min_usable_fraction": MIN_USABLE_FRACTION,
            "max_rest_offset_deg": MAX_REST_OFFSET_DEG,
            "max_roughness_ratio": MAX_ROUGHNESS_RATIO,
        },
        "problems": problems,
    }


def rig_checks(rig: Rig, added_mass: dict, starts: list[dict], rigs: list[Rig] | None = None) -> list[str]:
    """Warnings when the measured period and the rig values cannot both be right, or the added mass that reconciles
    them is more than any body of the frontal area of ``rigs`` (a joint fit's trials'; default ``[rig]``) takes
    (:func:`added_mass_scale_warning`)."""
    bare = 2 * math.pi * math.sqrt(rig.pivot_inertia_kg_m2 / rig.restoring_torque_nm)
    measured = float(np.median([s["period_s"] for s in starts]))
    out = []
    if added_mass["at_bound"]:
        lower = float(added_mass.get("lower_bound") or 0.0)
        least = 2 * math.pi * math.sqrt((rig.pivot_inertia_kg_m2 + lower * rig.length_m**2) / rig.restoring_torque_nm)
        with_least = "with no added mass" if lower == 0 else f"with the least added mass ({lower:g} kg)"
        out.append(
            f"measured small-amplitude period {measured:.4g} s is shorter than the rig values allow {with_least} "
            f"({least:.4g} s): length_m or body_inertia_kg_m2 overstate the pendulum's own inertia"
            if measured < least
            else f"the added mass is held at its lower bound ({lower:g} kg) although the measured small-amplitude "
            f"period {measured:.4g} s is at least the rig values' {with_least} ({least:.4g} s): the fit's other "
            "terms pull it there, and the bound is no measurement of it"
        )
    elif added_mass["value"] > 5 * rig.mass_kg:
        out.append(
            f"fitted added mass is {added_mass['value'] / rig.mass_kg:.0f}× the body mass (period {measured:.4g} s "
            f"against {bare:.4g} s for the rig alone): check length_m, mass_kg and the record's time base (a "
            "slow-motion clip plays slower than it was filmed: give the rate the camera filmed at in the trial's "
            "sidecar, data/raw/<trial>.yaml, e.g. capture_fps: 240)"
        )
    else:
        out += [w for w in [added_mass_scale_warning(rigs or [rig], added_mass)] if w]
    return out


def added_mass_scale_warning(rigs: list[Rig], added_mass: dict) -> str | None:
    """The warning when the added mass's whole 95 % interval lies over :data:`ADDED_MASS_SCALE_LIMIT` × ρA^1.5,
    A the frontal area (of the trials' ``rigs``: the largest ρA^1.5 where sidecars state different ones)."""
    rig = max(rigs, key=lambda r: r.fluid_density_kg_m3 * r.frontal_area_m2**1.5)
    scale = rig.fluid_density_kg_m3 * rig.frontal_area_m2**1.5  # a body's added mass is ~0.4–0.8 of this
    least = float((added_mass.get("ci95") or [0.0])[0] or 0.0)  # the 95 % interval's lower end
    if added_mass["at_bound"] or scale <= 0 or least <= ADDED_MASS_SCALE_LIMIT * scale:
        return None
    value = added_mass["value"]
    return (
        f"fitted added mass {value:.3g} kg is {value / scale:.0f}× ρA^1.5 ({scale:.2g} kg), its whole 95 % "
        f"interval over {ADDED_MASS_SCALE_LIMIT:g}×: more than a solid body of this frontal area takes (a sphere's "
        "is 0.38×, a flat plate's broadside 0.48×): check length_m, the distance from the pivot to the body's "
        "centre (for a point mass, 1 % off moves the added mass by 1 % of mass and added mass together, "
        f"{0.01 * (rig.mass_kg + value):.2g} kg here), body_inertia_kg_m2 (not given, the body's own inertia "
        "about its centre, I_c / L², is counted as added mass), mass_kg, frontal_area_m2 and "
        "fluid_density_kg_m3; water inside a free-flooding body counts as added mass too"
    )


# the added mass of a body of frontal area A, in units of ρ A^1.5: a sphere ½ ρ V = 0.38, a disk broadside
# (8/3) ρ r³ = 0.48, a cylinder broadside (π/4) √(d/ℓ) ≤ 0.79; a fitted one whose whole 95 % interval lies above
# this many (history forces at most double a body's) is a rig value's error
ADDED_MASS_SCALE_LIMIT = 3.0


DRAG_COEFFICIENT_RANGE = (0.05, 10.0)  # any body's C_d, streamlined to a flat plate and its rod: outside, a rig value


def drag_checks(rig: Rig, drag_coefficient: dict) -> list[str]:
    """A warning when a measured C_d lies far outside any body's (:data:`DRAG_COEFFICIENT_RANGE`): the drag torque
    ½ ρ C_d A L³ θ̇|θ̇| gives C_d only through ρ and A, and the decay it makes through the swing's inertia
    I = m L² + …, so a fluid density, frontal area or mass that is not the rig's shows here first (a pendulum in
    air with water's default density: C_d ≈ 0.0018 for an apple's 1.5; its mass in grams, 180 for 0.18 kg,
    which leaves an air pendulum's period as it is: C_d ≈ 1460)."""
    value = drag_coefficient.get("value")
    if value is None or drag_coefficient.get("at_bound") or drag_coefficient.get("identifiable") is False:
        return []
    low, high = DRAG_COEFFICIENT_RANGE
    if low <= value <= high:
        return []
    return [
        f"fitted drag coefficient C_d = {value:.3g} is far {'below' if value < low else 'above'} any body's "
        f"({low:g}–{high:g}): check the rig values it comes through: fluid_density_kg_m3 "
        f"({rig.fluid_density_kg_m3:g} kg/m³ here; water's 1000 is the default, air is 1.2), frontal_area_m2 "
        f"({rig.frontal_area_m2:g} m² here) and mass_kg ({rig.mass_kg:g} kg here: the swing's inertia sets how "
        "much drag a decay means; a mass in grams leaves an air pendulum's period as it is), and the record's time "
        "base (a slow-motion clip: capture_fps)"
    ]


def smooth_swing(record: AngleRecord) -> bool:
    """Whether the record itself moves smoothly: RMS over robust σ of its own third differences
    (:func:`noise_differences`) within :data:`MAX_ROUGHNESS_RATIO`, from at least :data:`MIN_NOISE_TRIPLES` runs.
    Its period can then be trusted before any fit; a record that hops between objects has none."""
    d3 = noise_differences(record.time_s, record.theta_rad)
    if d3.size < MIN_NOISE_TRIPLES:
        return False
    robust = float(1.4826 * np.median(np.abs(d3 - np.median(d3))))
    return robust > 0 and float(np.sqrt(np.mean(d3**2))) <= MAX_ROUGHNESS_RATIO * robust


def fastest_period_s(record: AngleRecord, added_mass_lower_kg: float) -> float:
    """The shortest small-amplitude period the record's rig values allow: T_min = 2π √((I_p + m_a,min L²) / τ_g)."""
    rig = record.rig
    inertia = rig.pivot_inertia_kg_m2 + added_mass_lower_kg * rig.length_m**2
    return 2 * math.pi * math.sqrt(max(inertia, 1e-12) / rig.restoring_torque_nm)


def rig_period_problem(
    record: AngleRecord, period_s: float, added_mass_lower_kg: float, swing_period_s: float | None = None
) -> str | None:
    """A sentence when the record's small-amplitude period lies outside what the rig values allow, else None.

    With the added mass at its lower bound the rig swings fastest: T_min = 2π √((I_p + m_a,min L²) / τ_g),
    τ_g = (m g − ρ V g) L; a shorter measured period, or no restoring torque at all, means the rig values
    (length, mass, volume, fluid) are not this pendulum's. ``swing_period_s``, the period as swung (what a
    stopwatch gives; longer than the small-amplitude one by T₀ A²/16), leads the sentence where given: a reader
    checks the record against it.
    """
    fastest = fastest_period_s(record, added_mass_lower_kg)
    if not math.isfinite(period_s) or period_s >= 0.98 * fastest:
        return None
    measured = f"small-amplitude period {period_s:.4g} s"
    if swing_period_s is not None and math.isfinite(swing_period_s):
        measured = f"period {swing_period_s:.4g} s as swung ({period_s:.4g} s at small amplitude)"
    rig = record.rig
    simple = rig.gravity_m_s2 * period_s**2 / (4 * math.pi**2)  # a simple pendulum of this period: L = g T₀²/4π²
    weighed = record.rig_values.get("submerged_mass_kg")  # the buoyancy as stated: weighed, or the volume
    buoyancy = f"submerged_mass_kg {weighed:.4g}" if weighed else f"displaced_volume_m3 {rig.displaced_volume_m3:.4g}"
    return (
        f"trial {record.trial}: its {measured} is shorter than its rig values allow "
        f"({fastest:.4g} s at small amplitude with the least added mass): its values (length_m {rig.length_m:.4g}, "
        f"mass_kg {rig.mass_kg:.4g}, {buoyancy}, fluid_density_kg_m3 "
        f"{rig.fluid_density_kg_m3:.4g}) are not this pendulum's (a simple pendulum of this period is "
        f"{simple:.3g} m long){_length_unit_hint(rig.length_m, simple)}; give the trial's rig in config or its sidecar"
    )


def _length_unit_hint(length_m: float, simple_m: float) -> str:
    """'; length_m … is 100 times that: in centimetres?' where the stated length is a unit's factor (100: cm, 1000:
    mm) times the simple pendulum's, within 25 % (a body's size and added mass lengthen the period); else ''."""
    for factor, unit in ((100.0, "centimetres"), (1000.0, "millimetres")):
        if simple_m > 0 and abs(math.log(length_m / (factor * simple_m))) <= math.log(1.25):
            return f"; length_m {length_m:.4g} is about {factor:.0f} times that: in {unit}? (length_m is in metres)"
    return ""


MISFIT_RATIO = 5.0  # residual RMS over the record's sample-to-sample noise above which the model is called wrong


def misfit_warning(record: AngleRecord, residual: np.ndarray) -> list[str]:
    """A model that misses physics leaves smooth residuals far above the record's noise: the angles stage's (Table
    2's record noise; for a record that did not come from there, the same figure of its samples,
    :func:`~pendulum.angles.swings.record_noise_floor_rad`).

    Its coefficients then absorb the missing effect and no interval covers that; say so. On tracked
    video with the right model the ratio is 1–3.
    """
    floor = record_noise_rad(record)
    rms = float(np.sqrt(np.mean(residual**2)))
    if floor <= 0 or rms <= MISFIT_RATIO * floor:
        return []
    return [
        f"trial {record.trial}: residual RMS {math.degrees(rms):.3g}° is {rms / floor:.0f}× the record's noise "
        f"({math.degrees(floor):.2g}°) and smooth (lag-1 {lag1_autocorrelation(residual):.2f}): the model misses "
        "a systematic effect; its coefficients absorb it and their intervals do not cover that error"
    ]
