"""The physics core against independent references."""

import math

import numpy as np
import pytest

from independent_eom import Pendulum, integrate
from pendulum.model.physics import PendulumModel, simulate, small_angle_period_s, stick_angle_bound_rad
from pendulum.model.rig import Rig

PAPER_RIG = Rig(mass_kg=3.53, length_m=0.76, frontal_area_m2=0.0322, displaced_volume_m3=0.0025)
TRUTH = dict(added_mass_kg=2.5, drag_area_m2=0.02576, linear_damping_nm_s=0.15, friction_torque_nm=0.02)
FIELDS = dict(
    added_mass_kg="added_mass",
    drag_area_m2="drag_area",
    linear_damping_nm_s="linear_damping",
    friction_torque_nm="friction",
)


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
    # the equation of motion typed in again, not through pendulum.model.physics (more cases: test_physics_reference.py)
    independent = Pendulum(**{FIELDS[k]: v for k, v in params.items()})
    ref, _ = integrate(independent, math.radians(release_deg), 0.0, times)
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
