"""Equation of motion of a submerged free-decay pendulum: one source of truth.

The rotational equation of motion (generalising equation (4) of the reference
paper, with the drag opposing the velocity)::

    (I_p + m_a L²) θ̈ = −(m g − B) L sin θ − ½ ρ C_d A L³ θ̇|θ̇| − c θ̇ − τ_f sgn(θ̇)

``I_p`` is the body's own moment of inertia about the pivot (``m L²`` for the
paper's point mass), ``m_a`` the added mass, ``B = ρ g V`` the buoyancy, ``C_d A``
the drag area, ``c`` a linear damping coefficient and ``τ_f`` a Coulomb (bearing)
friction torque. Every term after the restoring torque is optional: a model
variant is a list of term names from :data:`TERMS`. The synthetic-experiment
generator and the fitter both build their right-hand side from this module.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field

import numpy as np
from scipy.optimize import brentq

STANDARD_GRAVITY_M_S2 = 9.81


@dataclass(frozen=True)
class Rig:
    """Measured (not fitted) properties of one pendulum rig."""

    mass_kg: float
    length_m: float
    frontal_area_m2: float
    displaced_volume_m3: float = 0.0
    fluid_density_kg_m3: float = 1000.0
    gravity_m_s2: float = STANDARD_GRAVITY_M_S2
    body_inertia_kg_m2: float | None = None  # None: point mass, I_p = m L²

    def __post_init__(self):
        for name in ("mass_kg", "length_m", "frontal_area_m2"):
            if not getattr(self, name) > 0:
                raise ValueError(f"rig value {name} must be positive, got {getattr(self, name)!r}")
        if self.restoring_torque_nm <= 0:
            raise ValueError(
                f"rig is not a pendulum: weight {self.mass_kg * self.gravity_m_s2:.3g} N does not "
                f"exceed buoyancy {self.buoyancy_n:.3g} N"
            )

    @property
    def buoyancy_n(self) -> float:
        """B = ρ g V."""
        return self.fluid_density_kg_m3 * self.gravity_m_s2 * self.displaced_volume_m3

    @property
    def restoring_torque_nm(self) -> float:
        """(m g − B) L: the restoring torque per unit sin θ."""
        return (self.mass_kg * self.gravity_m_s2 - self.buoyancy_n) * self.length_m

    @property
    def pivot_inertia_kg_m2(self) -> float:
        """I_p, the body's moment of inertia about the pivot (m L² by default)."""
        if self.body_inertia_kg_m2 is not None:
            return self.body_inertia_kg_m2
        return self.mass_kg * self.length_m**2

    @classmethod
    def from_mapping(cls, values: dict) -> Rig:
        known = {f for f in cls.__dataclass_fields__}
        return cls(**{k: v for k, v in values.items() if k in known})


@dataclass(frozen=True)
class Term:
    """One damping or friction torque term, linear in its coefficient.

    ``shape(rig, theta, omega)`` returns the torque per unit coefficient, so the
    term's torque is ``coefficient * shape``. ``coulomb`` marks the
    discontinuous sgn(θ̇) term that the exact simulator treats with stick–slip.
    """

    name: str
    parameter: str
    unit: str
    shape: Callable
    coulomb: bool = False
    description: str = ""


def _quadratic_drag_shape(rig: Rig, theta, omega):
    return -0.5 * rig.fluid_density_kg_m3 * rig.length_m**3 * omega * abs(omega)


def _linear_damping_shape(rig: Rig, theta, omega):
    return -omega


def _coulomb_shape(rig: Rig, theta, omega):
    return -np.sign(omega)


TERMS: dict[str, Term] = {
    t.name: t
    for t in (
        Term(
            "quadratic_drag",
            "drag_area_m2",
            "m²",
            _quadratic_drag_shape,
            description="−½ ρ C_d A L³ θ̇|θ̇|",
        ),
        Term(
            "linear_damping",
            "linear_damping_nm_s",
            "N·m·s",
            _linear_damping_shape,
            description="−c θ̇",
        ),
        Term(
            "coulomb_friction",
            "friction_torque_nm",
            "N·m",
            _coulomb_shape,
            coulomb=True,
            description="−τ_f sgn(θ̇)",
        ),
    )
}

ADDED_MASS = "added_mass_kg"


@dataclass(frozen=True)
class PendulumModel:
    """A rig plus a list of torque terms; the added mass is always a parameter."""

    rig: Rig
    terms: tuple[str, ...] = field(default=("quadratic_drag",))

    def __post_init__(self):
        unknown = [t for t in self.terms if t not in TERMS]
        if unknown:
            raise ValueError(f"unknown model term(s) {unknown}; known terms: {sorted(TERMS)}")
        object.__setattr__(self, "terms", tuple(self.terms))

    @property
    def parameter_names(self) -> tuple[str, ...]:
        return (ADDED_MASS,) + tuple(TERMS[t].parameter for t in self.terms)

    def inertia_kg_m2(self, params: dict):
        """I = I_p + m_a L²."""
        return self.rig.pivot_inertia_kg_m2 + params[ADDED_MASS] * self.rig.length_m**2

    def smooth_torque_nm(self, params: dict, theta, omega):
        """Restoring torque plus every term except Coulomb friction."""
        torque = -self.rig.restoring_torque_nm * np.sin(theta)
        for name in self.terms:
            term = TERMS[name]
            if not term.coulomb:
                torque = torque + params[term.parameter] * term.shape(self.rig, theta, omega)
        return torque

    def friction_torque_nm(self, params: dict) -> float:
        """τ_f, the magnitude of the Coulomb term (0 if the model has none)."""
        return sum(float(params[TERMS[t].parameter]) for t in self.terms if TERMS[t].coulomb)

    def angular_acceleration(self, params: dict, theta, omega, friction_smoothing_rad_s=None):
        """θ̈ with sgn(θ̇) replaced by tanh(θ̇/ε) for a smooth fitter (ε given) or exact sgn."""
        torque = self.smooth_torque_nm(params, theta, omega)
        tau_f = self.friction_torque_nm(params)
        if tau_f:
            if friction_smoothing_rad_s:
                torque = torque - tau_f * np.tanh(omega / friction_smoothing_rad_s)
            else:
                torque = torque - tau_f * np.sign(omega)
        return torque / self.inertia_kg_m2(params)

    def with_terms(self, terms: Sequence[str]) -> PendulumModel:
        return PendulumModel(self.rig, tuple(terms))


def _rk4_step(accel, theta, omega, h):
    """One classical Runge–Kutta step of θ' = ω, ω' = accel(θ, ω)."""
    k1t, k1w = omega, accel(theta, omega)
    k2t, k2w = omega + 0.5 * h * k1w, accel(theta + 0.5 * h * k1t, omega + 0.5 * h * k1w)
    k3t, k3w = omega + 0.5 * h * k2w, accel(theta + 0.5 * h * k2t, omega + 0.5 * h * k2w)
    k4t, k4w = omega + h * k3w, accel(theta + h * k3t, omega + h * k3w)
    return (
        theta + h / 6.0 * (k1t + 2 * k2t + 2 * k3t + k4t),
        omega + h / 6.0 * (k1w + 2 * k2w + 2 * k3w + k4w),
    )


def simulate(
    model: PendulumModel,
    params: dict,
    theta0_rad: float,
    omega0_rad_s: float,
    times_s: Sequence[float],
    substeps: int = 8,
    max_step_s: float | None = None,
) -> tuple[np.ndarray, np.ndarray]:
    """Exact-physics trajectory θ(t), θ̇(t) sampled at ``times_s`` (t[0] is the start).

    Fixed-step RK4 between samples (``substeps`` steps per sample interval, or
    as many as keep each step under ``max_step_s``), with every velocity
    reversal located as an event so that each integrated segment is smooth
    (θ̇|θ̇| and sgn θ̇ are not). At a reversal the Coulomb stick condition is
    checked: if the remaining torque |−(mg−B)L sin θ| ≤ τ_f the pendulum stays
    at rest for good (no chattering; nothing else can set it moving in a free
    decay). Because the steps are fixed and the events exact, θ(t) is a smooth
    function of the parameters and the initial state: finite-difference
    Jacobians of a fit through it are honest.
    """
    times = np.asarray(times_s, dtype=float)
    if times.ndim != 1 or times.size < 1 or np.any(np.diff(times) <= 0):
        raise ValueError("times_s must be a strictly increasing 1-D sequence")
    inertia = float(model.inertia_kg_m2(params))
    tau_f = model.friction_torque_nm(params)
    rig = model.rig
    restoring = rig.restoring_torque_nm
    smooth_terms = [(float(params[TERMS[t].parameter]), TERMS[t].shape) for t in model.terms if not TERMS[t].coulomb]
    sin = math.sin

    def smooth_torque(theta, omega):  # scalar twin of PendulumModel.smooth_torque_nm
        torque = -restoring * sin(theta)
        for coefficient, shape in smooth_terms:
            torque = torque + coefficient * shape(rig, theta, omega)
        return torque

    def accel_for(direction):
        friction = tau_f * direction

        def accel(theta, omega):
            return (smooth_torque(theta, omega) - friction) / inertia

        return accel

    accelerations = {d: accel_for(d) for d in (-1, 1)}

    def direction_at_rest(theta):
        torque = smooth_torque(theta, 0.0)
        if abs(torque) <= tau_f:
            return 0
        return 1 if torque > 0 else -1

    theta, omega = float(theta0_rad), float(omega0_rad_s)
    direction = (1 if omega > 0 else -1) if omega != 0 else direction_at_rest(theta)
    out_theta = np.empty_like(times)
    out_omega = np.empty_like(times)
    out_theta[0], out_omega[0] = theta, omega
    intervals = np.diff(times)
    if max_step_s is not None:
        counts = np.maximum(1, np.ceil(intervals / max_step_s - 1e-9)).astype(int)
    else:
        counts = np.full(intervals.size, int(substeps))
    for i in range(1, times.size):
        n_steps = int(counts[i - 1])
        h = float(intervals[i - 1]) / n_steps
        for _ in range(n_steps):
            if direction == 0:
                break
            remaining = h
            while remaining > 0 and direction != 0:
                accel = accelerations[direction]
                new_theta, new_omega = _rk4_step(accel, theta, omega, remaining)
                if new_omega * direction > 0:
                    theta, omega = new_theta, new_omega
                    break

                # Velocity reaches zero inside this step: locate the reversal.
                def velocity_after(step, accel=accel, theta=theta, omega=omega, direction=direction):
                    return _rk4_step(accel, theta, omega, step)[1] * direction

                if velocity_after(0.0) <= 0:
                    if omega == 0.0:  # cannot happen for a consistent direction; never spin
                        raise RuntimeError(f"simulator stalled at theta={theta!r}")
                    h_event = 0.0
                else:
                    h_event = brentq(velocity_after, 0.0, remaining, xtol=1e-15, rtol=1e-15)
                theta = _rk4_step(accel, theta, omega, h_event)[0]
                omega = 0.0
                remaining -= h_event
                direction = direction_at_rest(theta)
        out_theta[i], out_omega[i] = theta, omega
    return out_theta, out_omega


def stick_angle_bound_rad(rig: Rig, friction_torque_nm: float) -> float:
    """Largest |θ| at which Coulomb friction holds the pendulum: (mg−B)L |sin θ| ≤ τ_f."""
    ratio = friction_torque_nm / rig.restoring_torque_nm
    return math.asin(min(ratio, 1.0))


def keulegan_carpenter_number(peak_speed_m_s: float, period_s: float, length_scale_m: float) -> float:
    """KC = U_max T / D."""
    return peak_speed_m_s * period_s / length_scale_m


def small_angle_period_s(model: PendulumModel, params: dict) -> float:
    """T₀ = 2π √(I / ((mg − B) L))."""
    return 2 * math.pi * math.sqrt(float(model.inertia_kg_m2(params)) / model.rig.restoring_torque_nm)
