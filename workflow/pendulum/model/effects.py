"""The library of candidate effects: one entry per torque term a model variant may add.

Each :class:`Term` says how the effect enters the equation of motion of
:mod:`pendulum.model.physics`,

    (I_p + m_a L²) θ̈ = −(m g − B) L sin θ + Σ_terms p · shape(θ, θ̇) − K_h L² ∫₀ᵗ θ̈(τ)/√(t−τ) dτ,

with p its one coefficient (the model is linear in it), what the coefficient
is called and measured in, its bounds, and how it shows in a free decay: the
amplitude lost per half cycle as a power of the amplitude (the extinction
curve ΔA(A)) and what it does to the period. ``explanation`` is the paragraph
a report prints. The history force has no ``basis``: it acts through the
memory that :func:`pendulum.model.physics.simulate` carries.

Small-damping energy balance over a half cycle of amplitude A (K = (m g − B)L,
I = I_p + m_a L², ω₀ = √(K/I)): ΔA = ``extinction_per_unit`` · p · A^``extinction_power``.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from pendulum.model.rig import Rig


@dataclass(frozen=True)
class Term:
    """One candidate effect, linear in its coefficient.

    The torque per unit coefficient is ``scale(rig) · b(θ, θ̇)`` with ``basis`` naming b in
    :data:`BASES` (:meth:`shape`), so the term's torque is ``coefficient * shape``; the
    history force has neither (its torque depends on the past). Terms of one basis add up
    to one factor, which is how :func:`pendulum.model.physics.simulate` evaluates a model
    in its inner loop. ``coulomb`` marks the discontinuous sgn(θ̇) term that the exact
    simulator treats with stick–slip.
    """

    name: str
    parameter: str
    unit: str
    basis: str | None
    scale: Callable[[Rig], float] | None = None
    coulomb: bool = False
    description: str = ""  # the torque, as an equation
    memory: bool = False  # the Basset–Boussinesq history force: simulate() carries its memory
    lower_bound: float = 0.0  # the fitter's bound (coefficients of dissipative effects are ≥ 0)
    label: str = ""  # plain name for a report: "bearing friction"
    symbol: str = ""  # the coefficient's symbol: "τ_f"
    extinction_power: int | None = None  # ΔA per half cycle ∝ A^power; None: no loss (conservative)
    extinction_per_unit: Callable | None = None  # (rig, inertia, omega0) → ΔA / (p · A^power)
    period_signature: str = ""
    explanation: str = ""
    typical_scale: Callable | None = None  # rig → a magnitude of the coefficient (finite-difference steps only)

    def shape(self, rig: Rig, theta, omega):
        """Torque per unit coefficient, ``scale(rig) · b(θ, θ̇)`` (scalars or arrays)."""
        return self.scale(rig) * BASES[self.basis](theta, omega)

    def half_cycle_loss_rad(self, rig: Rig, inertia_kg_m2: float, omega0_rad_s: float, value: float, amplitude_rad):
        """ΔA, the amplitude this effect alone removes over a half cycle starting near ``amplitude_rad``."""
        amplitude = np.asarray(amplitude_rad, float)
        if self.extinction_power is None:
            return np.zeros_like(amplitude)
        return value * self.extinction_per_unit(rig, inertia_kg_m2, omega0_rad_s) * amplitude**self.extinction_power

    def coefficient_from_loss(self, rig: Rig, inertia_kg_m2: float, omega0_rad_s: float, loss_coefficient: float):
        """p from the fitted extinction-curve coefficient a of ΔA = a · A^power (the fast screen's inverse)."""
        if self.extinction_power is None:
            raise ValueError(f"{self.name} removes no energy: it has no extinction-curve signature")
        return loss_coefficient / self.extinction_per_unit(rig, inertia_kg_m2, omega0_rad_s)


# ---------------------------------------------------------------------------
# Torque bases: a term's torque per unit coefficient is scale(rig) · b(θ, θ̇)

BASES: dict[str, Callable] = {
    "sin_theta": lambda theta, omega: np.sin(theta),
    "omega_abs_omega": lambda theta, omega: omega * abs(omega),
    "omega": lambda theta, omega: omega,
    "sign_omega": lambda theta, omega: np.sign(omega),
}


def _quadratic_drag_scale(rig: Rig) -> float:
    """−½ ρ L³ (the torque −½ ρ C_dA L³ θ̇|θ̇| per unit C_dA)."""
    return -0.5 * rig.fluid_density_kg_m3 * rig.length_m**3


def _pivot_omega(rig: Rig) -> float:
    return math.sqrt(rig.restoring_torque_nm / rig.pivot_inertia_kg_m2)


# ---------------------------------------------------------------------------
# The history force at one frequency


def history_equivalent(rig: Rig, coefficient_kg_per_sqrt_s: float, omega_rad_s: float) -> dict:
    """What the history force looks like in a steady oscillation at ω: added mass plus linear damping.

    For θ ∝ e^{iωt}, ∫_{−∞}^t θ̈(τ)/√(t−τ) dτ = √(π/(iω)) θ̈ = √(π/2ω) θ̈ + √(πω/2) θ̇, so the torque
    −K_h L² ∫ θ̈/√(t−τ) dτ equals an added mass K_h √(π/(2ω)) (∝ ω^−½, kg) and a linear damping
    K_h L² √(πω/2) (∝ ω^½, N·m·s). One swing frequency cannot separate these from m_a and c.
    """
    return {
        "added_mass_kg": coefficient_kg_per_sqrt_s * math.sqrt(math.pi / (2 * omega_rad_s)),
        "linear_damping_nm_s": coefficient_kg_per_sqrt_s * rig.length_m**2 * math.sqrt(math.pi * omega_rad_s / 2),
    }


def _history_loss_per_unit(rig: Rig, inertia, omega0):
    # ΔA = π c_eq A / (2 I ω₀) with c_eq the equivalent linear damping of a unit coefficient
    return math.pi * history_equivalent(rig, 1.0, omega0)["linear_damping_nm_s"] / (2 * inertia * omega0)


def _history_scale(rig: Rig) -> float:
    # the coefficient whose equivalent damping is 1e-3 I_p ω (as linear_damping's scale)
    omega = _pivot_omega(rig)
    return 1e-3 * rig.pivot_inertia_kg_m2 * omega / history_equivalent(rig, 1.0, omega)["linear_damping_nm_s"]


TERMS: dict[str, Term] = {
    t.name: t
    for t in (
        Term(
            "quadratic_drag",
            "drag_area_m2",
            "m²",
            "omega_abs_omega",
            _quadratic_drag_scale,
            description="−½ ρ C_d A L³ θ̇|θ̇|",
            label="quadratic (form) drag",
            symbol="C_dA",
            extinction_power=2,
            extinction_per_unit=lambda rig, inertia, omega0: (
                4 * 0.5 * rig.fluid_density_kg_m3 * rig.length_m**3 / (3 * inertia)
            ),
            period_signature="none to first order in the damping",
            explanation=(
                "Quadratic (form) drag, torque −½ρ C_dA L³ θ̇|θ̇|: the pressure drag of the separated flow behind "
                "a bluff body at high Reynolds number, the only damping of the reference paper's model. Its loss per "
                "half cycle grows as the square of the amplitude, ΔA = (4D/3I)A² with D = ½ρ C_dA L³, so it "
                "dominates large swings and fades at small ones: on the extinction curve (ΔA against A) it is a "
                "parabola through the origin, and the amplitude decays hyperbolically (1/A grows linearly in time). "
                "It leaves the period unchanged to first order."
            ),
            typical_scale=lambda rig: 0.01 * rig.frontal_area_m2,
        ),
        Term(
            "linear_damping",
            "linear_damping_nm_s",
            "N·m·s",
            "omega",
            lambda rig: -1.0,
            description="−c θ̇",
            label="linear (viscous) damping",
            symbol="c",
            extinction_power=1,
            extinction_per_unit=lambda rig, inertia, omega0: math.pi / (2 * inertia * omega0),
            period_signature="ω_d = ω₀ √(1 − ζ²): second order in the damping",
            explanation=(
                "Linear (viscous) damping, torque −c θ̇: skin friction of an attached, laminar boundary layer, the "
                "viscous part of the oscillating flow, a wetted bearing with an oil film, losses in a flexible arm "
                "or cable. Each half cycle removes the same fraction of the amplitude, ΔA = (πc/2Iω₀)A: a straight "
                "line through the origin on the extinction curve and an exponential decay in time. The period "
                "changes only at second order in the damping."
            ),
            typical_scale=lambda rig: 1e-3 * rig.pivot_inertia_kg_m2 * _pivot_omega(rig),
        ),
        Term(
            "coulomb_friction",
            "friction_torque_nm",
            "N·m",
            "sign_omega",
            lambda rig: -1.0,
            coulomb=True,
            description="−τ_f sgn(θ̇)",
            label="bearing (Coulomb) friction",
            symbol="τ_f",
            extinction_power=0,
            extinction_per_unit=lambda rig, inertia, omega0: 2 / rig.restoring_torque_nm,
            period_signature="none; the centre of each half cycle shifts by ±τ_f/K",
            explanation=(
                "Bearing (Coulomb) friction, torque −τ_f sgn θ̇: dry friction in the pivot bearing, a seal or a "
                "cable guide, independent of speed. Every half cycle loses the same amplitude, ΔA = 2τ_f/K whatever "
                "the amplitude: a constant offset on the extinction curve and an amplitude falling linearly in time. "
                "Each half cycle oscillates about a centre shifted by ±τ_f/K against the motion, the period is "
                "unchanged, and the pendulum stops for good within ±arcsin(τ_f/K) of the vertical."
            ),
            typical_scale=lambda rig: 1e-4 * rig.restoring_torque_nm,
        ),
        Term(
            "restoring_correction",
            "restoring_torque_correction",
            "1",
            "sin_theta",
            lambda rig: -rig.restoring_torque_nm,
            description="−ε (m g − B) L sin θ",
            lower_bound=-0.5,
            label="restoring-torque correction",
            symbol="ε",
            extinction_power=None,
            period_signature="T ∝ (1 + ε)^−½ at every amplitude, as a change of inertia",
            explanation=(
                "A relative correction ε of the restoring torque, −ε(mg − B)L sin θ on top of the rig values' "
                "−(mg − B)L sin θ: the stated mass, displaced volume (buoyancy) or arm length is wrong, or the centre "
                "of mass is not where the rig values put it. It is conservative (no loss on the extinction curve) "
                "and scales the stiffness, so the period changes as (1 + ε)^−½ at every amplitude. On a single rig "
                "it cannot be told from added mass: a free decay fixes only ratios to the inertia, and ε with m_a "
                "and every damping coefficient rescaled together gives the same motion. It becomes measurable when "
                "rigs of different arms or payloads share one body's hydrodynamic coefficients, or the added mass "
                "is known. Dimensionless and signed (bound ε ≥ −0.5: a larger error is no correction)."
            ),
            typical_scale=lambda rig: 1e-3,
        ),
        Term(
            "history_force",
            "history_coefficient_kg_per_sqrt_s",
            "kg/√s",
            None,
            description="−K_h L² ∫₀ᵗ θ̈(τ)/√(t−τ) dτ",
            memory=True,
            label="Basset–Boussinesq history force",
            symbol="K_h",
            extinction_power=1,
            extinction_per_unit=_history_loss_per_unit,
            period_signature="lengthened as by an added mass K_h √(π/2ω) (∝ ω^−½)",
            explanation=(
                "The Basset–Boussinesq history force, F = −K_h ∫₀ᵗ u̇(τ)/√(t−τ) dτ on the body moving at u = Lθ̇ "
                "(torque −K_h L² ∫ θ̈/√(t−τ) dτ): the boundary layer diffuses vorticity away at a finite rate, so "
                "the drag depends on the past accelerations, with a memory fading as 1/√age. For a sphere of "
                "radius a, K_h = 6a²√(πρμ) (kg/√s); for another body a is an equivalent radius. In a steady swing "
                "at ω it is an added mass K_h√(π/2ω) plus a linear damping K_h L²√(πω/2): the extinction curve "
                "grows ∝ A as for linear damping and the period lengthens as if the added mass were larger. At a "
                "single swing frequency it is therefore indistinguishable from added mass plus linear damping; "
                "rigs of two arm lengths (two frequencies) separate them, since the equivalent added mass falls "
                "and the damping rises with ω. It matters when the oscillatory boundary layer √(2ν/ω) is not "
                "negligible against the body's size."
            ),
            typical_scale=_history_scale,
        ),
    )
}

ADDED_MASS = "added_mass_kg"


def term_for_parameter(parameter: str) -> Term | None:
    """The library entry whose coefficient is ``parameter`` (None for the added mass or an unknown name)."""
    return next((t for t in TERMS.values() if t.parameter == parameter), None)


def unit_of(parameter: str) -> str:
    """A coefficient's unit ("kg" for the added mass; "" for an unknown name)."""
    term = term_for_parameter(parameter)
    return "kg" if parameter == ADDED_MASS else term.unit if term is not None else ""


def lower_bound(parameter: str) -> float:
    """The fitter's lower bound of a coefficient (0 for the added mass: the fitter overrides it)."""
    term = term_for_parameter(parameter)
    return term.lower_bound if term is not None else 0.0


def effects_for(truth: dict) -> tuple[str, ...]:
    """The effect names whose coefficients appear in ``truth`` (a parameter mapping), in library order."""
    return tuple(t.name for t in TERMS.values() if t.parameter in truth)
