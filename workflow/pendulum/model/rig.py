"""A pendulum rig's measured (not fitted) properties: mass, arm length, frontal area, displaced volume, fluid."""

from __future__ import annotations

from dataclasses import dataclass

STANDARD_GRAVITY_M_S2 = 9.81
RIG_VALUE_UNITS = {  # every rig value a rig or sidecar may state → its unit (tables, error budgets, advice)
    "mass_kg": "kg",
    "length_m": "m",
    "frontal_area_m2": "m²",
    "displaced_volume_m3": "m³",
    "submerged_mass_kg": "kg",
    "fluid_density_kg_m3": "kg/m³",
    "gravity_m_s2": "m/s²",
    "body_inertia_kg_m2": "kg·m²",
    "characteristic_length_m": "m",
    "kinematic_viscosity_m2_s": "m²/s",
}
BUOYANCY_KEYS = ("displaced_volume_m3", "submerged_mass_kg")  # either states the buoyancy; a sidecar's replaces


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
        """A rig from its stated values; a ``submerged_mass_kg`` (the body weighed hung in the tank's fluid,
        m − ρV) stands for the displaced volume V = (m − m_sub)/ρ."""
        values = dict(values)
        submerged = values.pop("submerged_mass_kg", None)
        if submerged is not None:
            if values.get("displaced_volume_m3"):
                raise ValueError("give the displaced volume or the submerged mass, not both")
            density = values.get("fluid_density_kg_m3", cls.__dataclass_fields__["fluid_density_kg_m3"].default)
            # a body that would float (m_sub ≤ 0) is refused as any rig (no restoring torque); a stated m_sub above m
            # is refused by the config's checks, but a 1σ heavier one may pass m where the buoyancy is tiny (in air)
            values["displaced_volume_m3"] = (float(values["mass_kg"]) - float(submerged)) / float(density)
        known = {f for f in cls.__dataclass_fields__}
        return cls(**{k: v for k, v in values.items() if k in known})


def tolerances_alike(stated: list[dict]) -> tuple[dict, dict]:
    """Of the 1σ tolerances several trials state (each its :func:`pendulum.trials.trial_tolerances`, or a fit
    record's): those they all state alike, and key → the distinct values where they differ (sorted; None last: a
    trial that states none, the default)."""
    alike, differ = {}, {}
    for key in sorted({k for tolerances in stated for k in tolerances}):
        sigmas = {tolerances.get(key) for tolerances in stated}
        if len(sigmas) > 1:
            differ[key] = sorted(v for v in sigmas if v is not None) + ([None] if None in sigmas else [])
        else:
            alike[key] = sigmas.pop()
    return alike, differ
