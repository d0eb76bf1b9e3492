"""The physics core against independent references."""

import math

import numpy as np
import pytest
from scipy.integrate import solve_ivp

from pendulum.physics import PendulumModel, Rig, simulate, small_angle_period_s, stick_angle_bound_rad

PAPER_RIG = Rig(mass_kg=3.53, length_m=0.76, frontal_area_m2=0.0322, displaced_volume_m3=0.0025)
TRUTH = dict(added_mass_kg=2.5, drag_area_m2=0.02576, linear_damping_nm_s=0.15, friction_torque_nm=0.02)


def reference(model, params, theta0, times):
    """solve_ivp DOP853 at rtol 1e-10, restarted at every velocity reversal, with the stick test."""
    inertia = float(model.inertia_kg_m2(params))
    tau = model.friction_torque_nm(params)
    out = np.full(times.size, np.nan)
    t0, y0 = times[0], np.array([theta0, 0.0])
    direction = -np.sign(math.sin(theta0))
    while t0 < times[-1]:

        def rhs(t, y, d=direction):
            return [y[1], (model.smooth_torque_nm(params, y[0], y[1]) - tau * d) / inertia]

        def reversal(t, y, d=direction, start=t0):
            return y[1] * d if t > start else 1.0

        reversal.terminal, reversal.direction = True, -1
        sel = times >= t0
        sol = solve_ivp(
            rhs, (t0, times[-1]), y0, method="DOP853", rtol=1e-10, atol=1e-13, t_eval=times[sel], events=reversal
        )
        out[np.flatnonzero(sel)[: sol.y.shape[1]]] = sol.y[0]
        if sol.status != 1:
            break
        t0, y0 = sol.t_events[0][0], np.array([sol.y_events[0][0][0], 0.0])
        torque = model.smooth_torque_nm(params, y0[0], 0.0)
        if abs(torque) <= tau:
            out[times > t0] = y0[0]
            break
        direction = np.sign(torque)
    return out


@pytest.mark.parametrize(
    "terms",
    [
        ("quadratic_drag",),
        ("quadratic_drag", "linear_damping"),
        ("quadratic_drag", "linear_damping", "coulomb_friction"),
    ],
)
@pytest.mark.parametrize("release_deg", [75.0, 20.0, -5.0])
def test_simulator_matches_tight_reference(terms, release_deg):
    model = PendulumModel(PAPER_RIG, terms)
    params = {k: TRUTH[k] for k in model.parameter_names}
    times = np.arange(0, 20, 1 / 30)
    theta, _ = simulate(model, params, math.radians(release_deg), 0.0, times)
    ref = reference(model, params, math.radians(release_deg), times)
    assert np.max(np.abs(theta - ref)) < 1e-6


def friction_only_rest_angle(rig, friction_torque_nm, theta0):
    """Turning points from energy: K(cos θ_b − cos θ_a) = τ |θ_a − θ_b|; stop when K|sin θ| ≤ τ."""
    from scipy.optimize import brentq

    k, tau = rig.restoring_torque_nm, friction_torque_nm
    a = theta0
    while k * abs(math.sin(a)) > tau:
        a = brentq(lambda b, a=a: k * (math.cos(b) - math.cos(a)) - tau * abs(a - b), -a, -a * 1e-12)
    return a


def test_friction_only_comes_to_rest_where_stick_condition_says():
    model = PendulumModel(PAPER_RIG, ("coulomb_friction",))
    params = dict(added_mass_kg=2.5, friction_torque_nm=0.4)
    theta0 = math.radians(12.0)
    times = np.arange(0, 60, 1 / 30)
    theta, omega = simulate(model, params, theta0, 0.0, times)
    predicted = friction_only_rest_angle(PAPER_RIG, 0.4, theta0)
    assert omega[-1] == 0.0 and np.all(theta[-300:] == theta[-1])  # at rest, no chattering
    assert abs(theta[-1] - predicted) < 1e-7
    assert abs(theta[-1]) <= stick_angle_bound_rad(PAPER_RIG, 0.4)


def test_small_angle_period_matches_simulation():
    model = PendulumModel(PAPER_RIG, ())
    params = dict(added_mass_kg=2.5)
    times = np.arange(0, 30, 1 / 240)
    theta, _ = simulate(model, params, math.radians(0.5), 0.0, times, substeps=2)
    i = np.flatnonzero((theta[1:] > 0) & (theta[:-1] <= 0))
    crossings = times[i] - theta[i] * (times[i + 1] - times[i]) / (theta[i + 1] - theta[i])
    assert np.mean(np.diff(crossings)) == pytest.approx(small_angle_period_s(model, params), rel=1e-4)


def test_rig_rejects_unphysical_values():
    with pytest.raises(ValueError, match="mass_kg"):
        Rig(mass_kg=-1, length_m=0.76, frontal_area_m2=0.03)
    with pytest.raises(ValueError, match="buoyancy"):
        Rig(mass_kg=1.0, length_m=0.76, frontal_area_m2=0.03, displaced_volume_m3=0.01)
    with pytest.raises(ValueError, match="unknown model term"):
        PendulumModel(PAPER_RIG, ("basset_force",))
