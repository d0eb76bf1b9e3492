"""The reference paper's Table 1 rig and the demo set's hidden hydrodynamics, shared by the fitting tests."""

from pendulum.model.physics import PendulumModel
from pendulum.model.rig import Rig

PAPER_RIG = {
    "mass_kg": 3.53,
    "length_m": 0.76,
    "frontal_area_m2": 0.0322,
    "displaced_volume_m3": 0.0025,
    "fluid_density_kg_m3": 1000.0,
    "gravity_m_s2": 9.81,
}
VARIANTS = {
    "quadratic": ("quadratic_drag",),
    "linear": ("quadratic_drag", "linear_damping"),
    "friction": ("quadratic_drag", "linear_damping", "coulomb_friction"),
}
# The real apple's rig as a user would give it (about 0.18 kg weighed, the string's 1.04 m from the period, a
# 7.5 cm body in air), and apple-like synthetic swings in air (tests/test_residual_pattern.py)
APPLE_IN_AIR = {
    "mass_kg": 0.18,
    "length_m": 1.04,
    "frontal_area_m2": 0.0045,
    "displaced_volume_m3": 0.0002,
    "fluid_density_kg_m3": 1.2,
    "gravity_m_s2": 9.81,
    "kinematic_viscosity_m2_s": 1.5e-5,
}
TRUTH = {"added_mass_kg": 2.5, "drag_area_m2": 0.02576, "linear_damping_nm_s": 0.15, "friction_torque_nm": 0.02}


def truth_for(terms):
    """The true coefficients of the parameters a model with ``terms`` has."""
    return {k: v for k, v in TRUTH.items() if k in PendulumModel(Rig(**PAPER_RIG), terms).parameter_names}
