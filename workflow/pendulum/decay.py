"""Classical decay analysis: swing extrema, period, extinction curve.

Used for the fitter's starting values, the per-half-cycle table the report and
discovery read, and (later) the discovery's fast screen of candidate effects.
"""

from __future__ import annotations

import math

import numpy as np
import pandas as pd
from scipy.optimize import nnls

from pendulum.geometry import noise_level, oscillation_centre_rad, turning_points
from pendulum.physics import ADDED_MASS, TERMS, PendulumModel
from pendulum.records import AngleRecord


def extrema(t, theta):
    """Times and signed values of the swing extrema, refined by a parabola through 5 samples."""
    smooth = pd.Series(theta).rolling(3, center=True, min_periods=1).mean().to_numpy()
    idx = turning_points(smooth, min_separation=3)
    times, values = [], []
    for i in idx:
        if i < 2 or i > t.size - 3:
            continue
        tt, yy = t[i - 2 : i + 3] - t[i], theta[i - 2 : i + 3]
        a, b, c = np.polyfit(tt, yy, 2)
        if a == 0 or abs(-b / (2 * a)) > 2 * (tt[-1] - tt[0]):
            continue
        tv = -b / (2 * a)
        times.append(t[i] + tv)
        values.append(c - b * b / (4 * a))
    return np.array(times), np.array(values)


def decay_analysis(model: PendulumModel, record: AngleRecord) -> dict:
    """Starting values: period → inertia → added mass; extinction curve → damping coefficients.

    With A the swing amplitude, the small-damping energy balance over one half
    cycle gives the amplitude loss ΔA = 2τ_f/K + (π c / 2Iω₀) A + (4 D / 3I) A²,
    K = (mg − B)L, D = ½ρ C_dA L³. The large-amplitude period is
    T = T₀ (1 + A²/16 + 11A⁴/3072), T₀ = 2π √(I/K).
    """
    rig = model.rig
    t, th = record.time_s, record.theta_rad
    sigma = noise_level(th)
    centre = oscillation_centre_rad(th, sigma)
    if centre is None:
        centre = float(np.median(th[-max(10, th.size // 5) :]))
    x = th - centre
    K = rig.restoring_torque_nm
    ext_t, ext_v = extrema(t, x)
    big = np.abs(ext_v) > max(20 * sigma, 1e-4)
    ext_t, ext_v = ext_t[big], ext_v[big]
    alternating = np.sign(ext_v[1:]) != np.sign(ext_v[:-1])
    half_t = np.diff(ext_t)[alternating]
    amp = np.abs(ext_v)
    mean_amp = (0.5 * (amp[1:] + amp[:-1]))[alternating]
    loss = (amp[:-1] - amp[1:])[alternating]
    start = {}
    if half_t.size >= 1:
        correction = 1 + mean_amp**2 / 16 + 11 * mean_amp**4 / 3072
        period0 = float(np.median(2 * half_t / correction))
        inertia = K * (period0 / (2 * math.pi)) ** 2
    else:  # less than half a swing: assume the added mass equals the displaced mass
        inertia = rig.pivot_inertia_kg_m2 + rig.fluid_density_kg_m3 * rig.displaced_volume_m3 * rig.length_m**2
        period0 = 2 * math.pi * math.sqrt(inertia / K)
    added_mass = (inertia - rig.pivot_inertia_kg_m2) / rig.length_m**2
    start[ADDED_MASS] = added_mass
    inertia = rig.pivot_inertia_kg_m2 + start[ADDED_MASS] * rig.length_m**2
    omega0 = 2 * math.pi / period0
    columns = {
        "coulomb_friction": np.ones_like(mean_amp),
        "linear_damping": mean_amp,
        "quadratic_drag": mean_amp**2,
    }
    to_coefficient = {
        "coulomb_friction": K / 2,
        "linear_damping": 2 * inertia * omega0 / math.pi,
        "quadratic_drag": 3 * inertia / 4 / (0.5 * rig.fluid_density_kg_m3 * rig.length_m**3),
    }
    terms = list(model.terms)
    coefficients = np.zeros(len(terms))
    if loss.size >= len(terms) + 1:
        a = np.column_stack([columns[name] for name in terms])
        scale = np.abs(a).max(axis=0)
        scale[scale == 0] = 1.0
        solution, _ = nnls(a / scale, loss)
        coefficients = solution / scale
    for name, value in zip(terms, coefficients, strict=True):
        start[TERMS[name].parameter] = float(value * to_coefficient[name])
    # initial state at the first sample: local quadratic through the first samples
    n0 = min(7, t.size)
    poly = np.polyfit(t[:n0] - t[0], x[:n0], 2)
    return {
        "physical": start,
        "theta0_rad": float(poly[2]),
        "omega0_rad_s": float(poly[1]),
        "rest_offset_rad": float(centre),
        "period_s": period0,
        "n_half_cycles": int(half_t.size),
    }
