"""The memory of the history force: the Basset kernel 1/√s as a sum of exponentials, carried as O(1) states.

The simulator (:func:`pendulum.model.physics.simulate`) takes its RK4 stages with memory from here;
:func:`history_integral` runs the same kernel and stages for a prescribed acceleration (tests, references).
"""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field

import numpy as np
from scipy.optimize import nnls

HISTORY_MAX_RATE_PER_S = 100.0  # fastest exponential state; RK4 is stable while λ h < 2.78
HISTORY_MAX_STEP_S = 0.02  # steps of a model with memory are cut to this (λ_max h = 2)


@dataclass(frozen=True, eq=False)
class HistoryKernel:
    """1/√s ≈ c₀ δ(s) + Σ_j w_j e^{−λ_j s}: the Basset kernel as a sum of exponentials.

    With z_j(t) = ∫ e^{−λ_j (t−τ)} θ̈(τ) dτ (so z_j' = −λ_j z_j + θ̈), the history
    integral is H(t) = ∫ θ̈(τ)/√(t−τ) dτ ≈ c₀ θ̈(t) + Σ_j w_j z_j(t).

    Rates λ_j = λ_max e^{−j} (j = 0…24, λ_max = 100 s⁻¹: 1/√s = (2/√π)∫₀^∞ e^{−s y²} dy sampled every 0.5 in
    ln y) and weights w_j ≥ 0, c₀ ≥ 0 chosen by non-negative least squares so that the transfer
    function c₀ + Σ w_j/(λ_j + iω) matches √(π/(iω)) to a relative 4e-4 for 10⁻⁴ ≤ ω ≤ 30 rad/s
    (periods 0.2 s to 17 h); zero weights are dropped. Non-negative weights keep the kernel
    completely monotone, so the approximate force is dissipative like the true one. The kernel
    faster than λ_max (time scales < 10 ms) is the instantaneous c₀ δ: an inertia K_h L² c₀.
    """

    rates_per_s: np.ndarray
    weights: np.ndarray  # s^−½
    instantaneous_s05: float  # c₀, s^½
    _updates: dict = field(default_factory=dict, repr=False)  # step size → RK4 update of z (cache)

    def transfer(self, omega_rad_s):
        """c₀ + Σ w_j/(λ_j + iω), to compare with the exact √(π/(iω))."""
        omega = np.asarray(omega_rad_s, float)[..., None]
        return self.instantaneous_s05 + (self.weights / (self.rates_per_s + 1j * omega)).sum(axis=-1)

    @property
    def moment_matrix(self) -> np.ndarray:
        """Rows w λ^k (k = 0…3): the moments μ_k = Σ w_j λ_j^k z_j the RK4 stages need."""
        return np.vstack([self.weights * self.rates_per_s**k for k in range(4)])

    @property
    def sums(self) -> tuple[float, float, float]:
        """S_k = Σ w_j λ_j^k (k = 0…2)."""
        return tuple(float(np.sum(self.weights * self.rates_per_s**k)) for k in range(3))

    def initial_state(self, omega0_rad_s: float, ramp_s: float) -> np.ndarray:
        """z at the start when the fluid was at rest ``ramp_s`` earlier and θ̈ was constant since.

        z_j = (θ̇₀/T)(1 − e^{−λ_j T})/λ_j with T = ``ramp_s``; T = 0 is an impulsive start, z_j = θ̇₀.
        """
        if ramp_s <= 0:
            return np.full(self.rates_per_s.size, float(omega0_rad_s))
        return omega0_rad_s / ramp_s * -np.expm1(-self.rates_per_s * ramp_s) / self.rates_per_s

    def advance(self, z: np.ndarray, h: float, accelerations) -> np.ndarray:
        """z after one RK4 step of z' = −λ z + θ̈ with θ̈ = a₁…a₄ at the four stages (exact RK4 algebra).

        With u = λh: z ← R(u) z + (h/6)[(1 − u + u²/2 − u³/4) a₁ + (2 − u + u²/2) a₂ + (2 − u) a₃ + a₄],
        R(u) = 1 − u + u²/2 − u³/6 + u⁴/24.
        """
        h = float(h)
        update = self._updates.get(h)
        if update is None:
            u = self.rates_per_s * h
            decay = 1 - u + u * u / 2 - u**3 / 6 + u**4 / 24
            gain = h / 6 * np.vstack([1 - u + u * u / 2 - u**3 / 4, 2 - u + u * u / 2, 2 - u, np.ones_like(u)])
            update = (decay, gain)
            if len(self._updates) < 64:  # the regular step sizes; event steps are one-offs
                self._updates[h] = update
        decay, gain = update
        return decay * z + np.asarray(accelerations) @ gain

    def decay(self, z: np.ndarray, duration_s: float) -> np.ndarray:
        """z after ``duration_s`` with θ̈ = 0 (the body at rest): exact exponential decay."""
        return z * np.exp(-self.rates_per_s * duration_s)


def _fit_history_kernel() -> HistoryKernel:
    rates = HISTORY_MAX_RATE_PER_S * np.exp(-np.arange(25.0))
    omega = np.geomspace(1e-4, 30.0, 400)
    target = np.sqrt(np.pi / (1j * omega))
    design = np.column_stack([1 / (rates[None, :] + 1j * omega[:, None]), np.ones(omega.size)]) / target[:, None]
    solution, _ = nnls(
        np.vstack([design.real, design.imag]), np.concatenate([np.ones(omega.size), np.zeros(omega.size)])
    )
    keep = solution[:-1] > 0
    return HistoryKernel(rates[keep], solution[:-1][keep], float(solution[-1]))


HISTORY_KERNEL = _fit_history_kernel()


def rk4_memory_step(accel, t, theta, omega, mu, sums, h):
    """One RK4 step of θ' = ω, ω' = accel(t, θ, ω, H), z' = −λ z + ω' with H = Σ w_j z_j at each stage.

    The stage values of H follow from the moments μ_k = Σ w λ^k z at the step's start, so z itself
    is updated only once the step is accepted (:meth:`HistoryKernel.advance` with the returned θ̈s).
    θ and θ̇ combine exactly as in the plain RK4 step of :mod:`pendulum.model.physics`.
    """
    m0, m1, m2, m3 = mu
    s0, s1, s2 = sums
    k1t, k1w = omega, accel(t, theta, omega, m0)
    h2 = m0 + 0.5 * h * (k1w * s0 - m1)
    k2t, k2w = omega + 0.5 * h * k1w, accel(t + 0.5 * h, theta + 0.5 * h * k1t, omega + 0.5 * h * k1w, h2)
    h3 = m0 + 0.5 * h * (k2w * s0 - m1 - 0.5 * h * (k1w * s1 - m2))
    k3t, k3w = omega + 0.5 * h * k2w, accel(t + 0.5 * h, theta + 0.5 * h * k2t, omega + 0.5 * h * k2w, h3)
    h4 = m0 + h * (k3w * s0 - m1 - 0.5 * h * (k2w * s1 - m2 - 0.5 * h * (k1w * s2 - m3)))
    k4t, k4w = omega + h * k3w, accel(t + h, theta + h * k3t, omega + h * k3w, h4)
    return (
        theta + h / 6.0 * (k1t + 2 * k2t + 2 * k3t + k4t),
        omega + h / 6.0 * (k1w + 2 * k2w + 2 * k3w + k4w),
        (k1w, k2w, k3w, k4w),
    )


def history_integral(
    acceleration: Callable[[float], float],
    times_s: Sequence[float],
    max_step_s: float = HISTORY_MAX_STEP_S,
    kernel: HistoryKernel = HISTORY_KERNEL,
) -> np.ndarray:
    """H(t) = ∫_{t₀}^t a(τ)/√(t−τ) dτ at ``times_s`` for a prescribed a(t), through the simulator's memory.

    The fluid is at rest before t₀ = times_s[0] (a(t₀) ≠ 0 is a jump there). Same kernel, RK4
    stages and state update as :func:`simulate`; H = c₀ a(t) + Σ w_j z_j.
    """
    times = np.asarray(times_s, float)
    moments, sums = kernel.moment_matrix, kernel.sums
    z = np.zeros(kernel.rates_per_s.size)
    out = np.empty(times.size)
    out[0] = kernel.instantaneous_s05 * acceleration(times[0])

    def accel(t, theta, omega, history):
        return acceleration(t)

    for i in range(1, times.size):
        n = max(1, math.ceil((times[i] - times[i - 1]) / max_step_s - 1e-9))
        h = (times[i] - times[i - 1]) / n
        for j in range(n):
            _, _, a = rk4_memory_step(accel, times[i - 1] + j * h, 0.0, 0.0, (moments @ z).tolist(), sums, h)
            z = kernel.advance(z, h, a)
        out[i] = kernel.instantaneous_s05 * acceleration(times[i]) + kernel.weights @ z
    return out
