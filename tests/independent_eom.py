"""The pendulum's equation of motion written out a second time, independently of pendulum.model.physics.

Nothing here imports the workflow package: the torques are typed in again from
the paper's equation (4), generalised as in the README,

    (I_p + m_a L²) θ̈ = −(m g − ρ g V) L sin θ − ½ ρ C_dA L³ θ̇|θ̇| − c θ̇ − τ_f sgn(θ̇),

and integrated with scipy's DOP853 at tight tolerance, restarted at every
velocity reversal (where θ̇|θ̇| and sgn θ̇ are not smooth) with the Coulomb stick
test |(m g − ρ g V) L sin θ| ≤ τ_f. If pendulum.model.physics gets a term wrong, the
simulator and this reference disagree; the fitter, which simulates through
pendulum.model.physics, then also misses the truth on records made here.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
import pandas as pd
from scipy.integrate import solve_ivp


@dataclass(frozen=True)
class Pendulum:
    """Rig values and coefficients; defaults are the paper's Table 1 rig in water."""

    mass: float = 3.53  # kg
    length: float = 0.76  # m
    area: float = 0.0322  # m², frontal area (only for C_d = C_dA / A)
    volume: float = 0.0025  # m³, displaced
    rho: float = 1000.0  # kg/m³
    g: float = 9.81  # m/s²
    body_inertia: float | None = None  # kg·m² about the pivot; None: point mass m L²
    added_mass: float = 2.5  # kg
    drag_area: float = 0.0  # m², C_d A
    linear_damping: float = 0.0  # N·m·s
    friction: float = 0.0  # N·m

    @property
    def stiffness(self) -> float:
        """(m g − ρ g V) L, N·m per unit sin θ."""
        return (self.mass * self.g - self.rho * self.g * self.volume) * self.length

    @property
    def inertia(self) -> float:
        """I_p + m_a L²."""
        own = self.mass * self.length * self.length if self.body_inertia is None else self.body_inertia
        return own + self.added_mass * self.length * self.length

    @property
    def drag_factor(self) -> float:
        """½ ρ C_dA L³, N·m·s² (torque per θ̇|θ̇|)."""
        return 0.5 * self.rho * self.drag_area * self.length * self.length * self.length

    def rig_mapping(self) -> dict:
        """The rig as the workflow's config spells it."""
        rig = {
            "mass_kg": self.mass,
            "length_m": self.length,
            "frontal_area_m2": self.area,
            "displaced_volume_m3": self.volume,
            "fluid_density_kg_m3": self.rho,
            "gravity_m_s2": self.g,
        }
        if self.body_inertia is not None:
            rig["body_inertia_kg_m2"] = self.body_inertia
        return rig


def integrate(p: Pendulum, theta0: float, omega0: float, times) -> tuple[np.ndarray, np.ndarray]:
    """θ(t), θ̇(t) at ``times`` (times[0] is the start, state (theta0, omega0) there)."""
    times = np.asarray(times, dtype=float)
    K, inertia, D, c, tau = p.stiffness, p.inertia, p.drag_factor, p.linear_damping, p.friction
    theta = np.full(times.size, np.nan)
    omega = np.full(times.size, np.nan)

    def at_rest_direction(th):
        torque = -K * math.sin(th)
        if abs(torque) <= tau:
            return 0
        return 1 if torque > 0 else -1

    t0, y0 = float(times[0]), np.array([theta0, omega0], dtype=float)
    direction = (1 if omega0 > 0 else -1) if omega0 != 0 else at_rest_direction(theta0)
    while True:
        sel = times >= t0
        if direction == 0:  # stuck for good: nothing in a free decay can restart it
            theta[sel], omega[sel] = y0[0], 0.0
            break

        def rhs(t, y, d=direction):
            return [y[1], (-K * math.sin(y[0]) - D * y[1] * abs(y[1]) - c * y[1] - tau * d) / inertia]

        def reversal(t, y, d=direction, start=t0):
            return y[1] * d if t > start else 1.0

        reversal.terminal, reversal.direction = True, -1
        sol = solve_ivp(
            rhs,
            (t0, float(times[-1])),
            y0,
            method="DOP853",
            rtol=1e-12,
            atol=1e-14,
            t_eval=times[sel],
            events=reversal,
        )
        idx = np.flatnonzero(sel)[: sol.t.size]
        theta[idx], omega[idx] = sol.y[0], sol.y[1]
        if sol.status != 1:  # reached the end
            break
        t0 = float(sol.t_events[0][0])
        y0 = np.array([sol.y_events[0][0][0], 0.0])
        direction = at_rest_direction(y0[0])
    return theta, omega


def angle_table(
    p: Pendulum,
    release_deg: float,
    rng: np.random.Generator | None,
    *,
    fps: float = 30.0,
    duration_s: float = 22.0,
    white_deg: float = 0.004,
    correlated_deg: float = 0.003,
    correlation: float = 0.8,
) -> pd.DataFrame:
    """An angle table (``time_s`` since release, ``theta_rad``, ``flag``) with white + AR(1) noise."""
    times = np.arange(0, int(duration_s * fps) + 1) / fps
    theta, _ = integrate(p, math.radians(release_deg), 0.0, times)
    times, theta = times[1:], theta[1:]
    if rng is not None:
        n = times.size
        white = rng.standard_normal(n) * math.radians(white_deg)
        drive = rng.standard_normal(n) * math.radians(correlated_deg) * math.sqrt(1 - correlation**2)
        coloured = np.empty(n)
        coloured[0] = drive[0] / math.sqrt(1 - correlation**2)
        for i in range(1, n):
            coloured[i] = correlation * coloured[i - 1] + drive[i]
        theta = theta + white + coloured
    return pd.DataFrame({"time_s": times, "theta_rad": theta, "flag": "ok"})
