"""The equation of motion's inner loops, compiled with numba (about 30–60× the same loops in Python).

:func:`pendulum.model.physics.simulate` prepares the numbers and calls these; they implement

    I θ̈ = F_s sin θ + F_q θ̇|θ̇| + F_l θ̇ − τ_f sgn θ̇ − K_h L² H,   H = c₀ θ̈ + Σ_j w_j z_j,  z_j' = −λ_j z_j + θ̈,

(F_b: :func:`pendulum.model.physics.basis_factors`; the memory states z_j of
:class:`pendulum.model.history.HistoryKernel`, c₀ folded into the effective inertia I + K_h L² c₀)
with classical RK4 steps, every velocity reversal located by Brent's method as
:func:`scipy.optimize.brentq` does it (xtol = rtol = 1e-15, 100 iterations), and Coulomb stick:
at rest while |torque at rest| ≤ τ_f. The compiled code is cached in ``__pycache__`` after a
process's first call. A state that leaves the finite numbers ends the integration with the rest
of the output NaN (the caller raises :class:`pendulum.model.physics.SimulationDiverged`).
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

XTOL = RTOL = 1e-15  # scipy.optimize.brentq's tolerances, as the Python simulator used them
MAX_ITERATIONS = 100


@njit(cache=True)
def brent_start(xa, fa, xb, fb):
    """The state of a Brent search for a zero of f in [xa, xb] (f(xa) = fa, f(xb) = fb), for :func:`brent_next`.

    Brent's method as scipy's brentq.c, driven by the caller (a compiled function taking another
    as an argument could not be cached): ``x = brent_next(s)`` until ``s[9]`` (done), setting
    ``s[4] = f(x)`` after each; the zero is then ``x``.
    """
    # xpre, xcur, xblk, fpre, fcur, fblk, spre, scur, iterations, done
    return np.array([xa, xb, 0.0, fa, fb, 0.0, 0.0, 0.0, 0.0, 0.0])


@njit(cache=True)
def brent_next(s):
    """The next point at which the caller evaluates f (``s[4] = f(x)``), or the zero once ``s[9]`` is set."""
    xpre, xcur, xblk, fpre, fcur, fblk, spre, scur = s[0], s[1], s[2], s[3], s[4], s[5], s[6], s[7]
    if s[8] == 0.0 and (fpre == 0.0 or fcur == 0.0):
        s[9] = 1.0
        return xpre if fpre == 0.0 else xcur
    if s[8] >= MAX_ITERATIONS:
        s[9] = 1.0
        return xcur
    s[8] += 1.0
    if fpre != 0.0 and fcur != 0.0 and (fpre < 0.0) != (fcur < 0.0):
        xblk, fblk = xpre, fpre
        spre = scur = xcur - xpre
    if abs(fblk) < abs(fcur):
        xpre, xcur, xblk = xcur, xblk, xcur
        fpre, fcur, fblk = fcur, fblk, fcur
    delta = (XTOL + RTOL * abs(xcur)) / 2
    sbis = (xblk - xcur) / 2
    if fcur == 0.0 or abs(sbis) < delta:
        s[9] = 1.0
        return xcur
    if abs(spre) > delta and abs(fcur) < abs(fpre):
        if xpre == xblk:  # secant
            stry = -fcur * (xcur - xpre) / (fcur - fpre)
        else:  # inverse quadratic interpolation
            dpre = (fpre - fcur) / (xpre - xcur)
            dblk = (fblk - fcur) / (xblk - xcur)
            stry = -fcur * (fblk * dblk - fpre * dpre) / (dblk * dpre * (fblk - fpre))
        if 2 * abs(stry) < min(abs(spre), 3 * abs(sbis) - delta):
            spre, scur = scur, stry
        else:
            spre = scur = sbis
    else:
        spre = scur = sbis
    xpre, fpre = xcur, fcur
    xcur += scur if abs(scur) > delta else (delta if sbis > 0 else -delta)
    s[0], s[1], s[2], s[3], s[5], s[6], s[7] = xpre, xcur, xblk, fpre, fblk, spre, scur
    return xcur


@njit(cache=True)
def rk4_step(theta, omega, h, a_sin, a_quad, a_lin, a_const):
    """One classical Runge–Kutta step of θ̈ = a_s sin θ + a_q θ̇|θ̇| + a_l θ̇ + a_const."""
    k1 = a_sin * math.sin(theta) + a_quad * omega * abs(omega) + a_lin * omega + a_const
    w2 = omega + 0.5 * h * k1
    k2 = a_sin * math.sin(theta + 0.5 * h * omega) + a_quad * w2 * abs(w2) + a_lin * w2 + a_const
    w3 = omega + 0.5 * h * k2
    k3 = a_sin * math.sin(theta + 0.5 * h * w2) + a_quad * w3 * abs(w3) + a_lin * w3 + a_const
    w4 = omega + h * k3
    k4 = a_sin * math.sin(theta + h * w3) + a_quad * w4 * abs(w4) + a_lin * w4 + a_const
    return theta + h / 6.0 * (omega + 2 * w2 + 2 * w3 + w4), omega + h / 6.0 * (k1 + 2 * k2 + 2 * k3 + k4)


@njit(cache=True)
def _velocity_after(dt, args):
    """θ̇ · direction after one step of ``dt`` (positive until the reversal)."""
    theta, omega, a_sin, a_quad, a_lin, a_const, direction = args
    return rk4_step(theta, omega, dt, a_sin, a_quad, a_lin, a_const)[1] * direction


@njit(cache=True)
def _direction_at_rest(torque, tau_f):
    """Sign of the torque at rest, 0 when Coulomb friction τ_f holds the body."""
    if abs(torque) <= tau_f:
        return 0
    return 1 if torque > 0 else -1


@njit(cache=True)
def integrate_memoryless(theta0, omega0, times, counts, force_sin, force_quad, force_lin, tau_f, inertia):
    """θ, θ̇ at ``times`` without the history force: ``counts[i]`` RK4 steps per interval."""
    a_sin, a_quad, a_lin = force_sin / inertia, force_quad / inertia, force_lin / inertia
    out_theta = np.full(times.size, np.nan)
    out_omega = np.full(times.size, np.nan)
    theta, omega = theta0, omega0
    direction = (1 if omega > 0 else -1) if omega != 0 else _direction_at_rest(force_sin * math.sin(theta), tau_f)
    out_theta[0], out_omega[0] = theta, omega
    for i in range(1, times.size):
        h = (times[i] - times[i - 1]) / counts[i - 1]
        for _ in range(counts[i - 1]):
            if direction == 0:
                break
            remaining = h
            while remaining > 0 and direction != 0:
                a_const = -tau_f * direction / inertia
                new_theta, new_omega = rk4_step(theta, omega, remaining, a_sin, a_quad, a_lin, a_const)
                if not (math.isfinite(new_theta) and math.isfinite(new_omega)):
                    return out_theta, out_omega  # diverged (RK4 unstable): the rest stays NaN
                if new_omega * direction > 0:
                    theta, omega = new_theta, new_omega
                    break
                # θ̇ reaches zero inside this step: locate the reversal
                args = (theta, omega, a_sin, a_quad, a_lin, a_const, float(direction))
                if _velocity_after(0.0, args) <= 0:
                    if omega == 0.0:  # cannot happen for a consistent direction; never spin
                        raise RuntimeError("simulator stalled")
                    h_event = 0.0
                else:
                    search = brent_start(0.0, _velocity_after(0.0, args), remaining, _velocity_after(remaining, args))
                    h_event = brent_next(search)
                    while search[9] == 0.0:
                        search[4] = _velocity_after(h_event, args)
                        h_event = brent_next(search)
                theta = rk4_step(theta, omega, h_event, a_sin, a_quad, a_lin, a_const)[0]
                omega = 0.0
                remaining -= h_event
                direction = _direction_at_rest(force_sin * math.sin(theta), tau_f)
        out_theta[i], out_omega[i] = theta, omega
    return out_theta, out_omega


# ---------------------------------------------------------------------------
# With the history force's memory


@njit(cache=True)
def rk4_memory_step(theta, omega, h, mu, sums, a_sin, a_quad, a_lin, a_const, a_history):
    """One RK4 step of θ' = ω, ω' = a_s sin θ + a_q ω|ω| + a_l ω + a_const − a_H H, z' = −λ z + ω',
    H = Σ w_j z_j at each stage from the moments μ_k = Σ w λ^k z at the step's start (``mu``) and
    S_k = Σ w λ^k (``sums``): :func:`pendulum.model.history.rk4_memory_step`'s algebra. Returns θ, θ̇
    and the four stage accelerations (for :func:`advance_memory`)."""
    m0, m1, m2, m3 = mu[0], mu[1], mu[2], mu[3]
    s0, s1, s2 = sums[0], sums[1], sums[2]
    k1 = a_sin * math.sin(theta) + a_quad * omega * abs(omega) + a_lin * omega + a_const - a_history * m0
    h2 = m0 + 0.5 * h * (k1 * s0 - m1)
    w2 = omega + 0.5 * h * k1
    k2 = a_sin * math.sin(theta + 0.5 * h * omega) + a_quad * w2 * abs(w2) + a_lin * w2 + a_const - a_history * h2
    h3 = m0 + 0.5 * h * (k2 * s0 - m1 - 0.5 * h * (k1 * s1 - m2))
    w3 = omega + 0.5 * h * k2
    k3 = a_sin * math.sin(theta + 0.5 * h * w2) + a_quad * w3 * abs(w3) + a_lin * w3 + a_const - a_history * h3
    h4 = m0 + h * (k3 * s0 - m1 - 0.5 * h * (k2 * s1 - m2 - 0.5 * h * (k1 * s2 - m3)))
    w4 = omega + h * k3
    k4 = a_sin * math.sin(theta + h * w3) + a_quad * w4 * abs(w4) + a_lin * w4 + a_const - a_history * h4
    return (
        theta + h / 6.0 * (omega + 2 * w2 + 2 * w3 + w4),
        omega + h / 6.0 * (k1 + 2 * k2 + 2 * k3 + k4),
        k1,
        k2,
        k3,
        k4,
    )


@njit(cache=True)
def advance_memory(z, rates, h, k1, k2, k3, k4):
    """z after one RK4 step of z' = −λ z + θ̈ (θ̈ = k1…k4 at the stages); with u = λh:
    z ← R(u) z + (h/6)[(1 − u + u²/2 − u³/4) k1 + (2 − u + u²/2) k2 + (2 − u) k3 + k4],
    R(u) = 1 − u + u²/2 − u³/6 + u⁴/24."""
    out = np.empty_like(z)
    for j in range(z.size):
        u = rates[j] * h
        decay = 1 - u + u * u / 2 - u * u * u / 6 + u * u * u * u / 24
        gain = (1 - u + u * u / 2 - u * u * u / 4) * k1 + (2 - u + u * u / 2) * k2 + (2 - u) * k3 + k4
        out[j] = decay * z[j] + h / 6 * gain
    return out


@njit(cache=True)
def _moments(z, rates, weights):
    """μ_k = Σ_j w_j λ_j^k z_j, k = 0…3."""
    mu = np.zeros(4)
    for j in range(z.size):
        term = weights[j] * z[j]
        for k in range(4):
            mu[k] += term
            term *= rates[j]
    return mu


@njit(cache=True)
def _torque_at_rest(theta, z, rates, weights, force_sin, history_torque, step):
    """F_s sin θ − K_h L² Σ w_j z_j e^{−λ_j step}: the torque at rest after the memory decayed ``step``."""
    memory = 0.0
    for j in range(z.size):
        memory += weights[j] * z[j] * math.exp(-rates[j] * step)
    return force_sin * math.sin(theta) - history_torque * memory


@njit(cache=True)
def _excess(step, args):
    theta, z, rates, weights, force_sin, history_torque, tau_f = args
    return abs(_torque_at_rest(theta, z, rates, weights, force_sin, history_torque, step)) - tau_f


@njit(cache=True)
def _memory_velocity_after(dt, args):
    theta, omega, mu, sums, a_sin, a_quad, a_lin, a_const, a_history, direction = args
    return rk4_memory_step(theta, omega, dt, mu, sums, a_sin, a_quad, a_lin, a_const, a_history)[1] * direction


@njit(cache=True)
def integrate_with_memory(
    theta0, omega0, z0, times, counts, force_sin, force_quad, force_lin, tau_f, inertia, history_torque, rates, weights
):
    """θ, θ̇ at ``times`` with the history force's memory (states ``z0`` at the start); ``inertia``
    is the effective one, I + K_h L² c₀. At rest the memory decays and its torque can set the body
    moving again once it exceeds τ_f; a pendulum whose torque at rest can never again exceed τ_f
    (|F_s sin θ| + |K_h L²| Σ w_j |z_j| ≤ τ_f: the bound only falls) stays at rest for good."""
    a_sin, a_quad, a_lin = force_sin / inertia, force_quad / inertia, force_lin / inertia
    a_history = history_torque / inertia
    sums = np.zeros(3)
    for j in range(rates.size):
        sums[0] += weights[j]
        sums[1] += weights[j] * rates[j]
        sums[2] += weights[j] * rates[j] * rates[j]
    out_theta = np.full(times.size, np.nan)
    out_omega = np.full(times.size, np.nan)
    theta, omega, z = theta0, omega0, z0.copy()
    if omega != 0:
        direction = 1 if omega > 0 else -1
    else:
        direction = _direction_at_rest(_torque_at_rest(theta, z, rates, weights, force_sin, history_torque, 0.0), tau_f)
    out_theta[0], out_omega[0] = theta, omega
    restarted = stuck_for_good = False
    for i in range(1, times.size):
        h = (times[i] - times[i - 1]) / counts[i - 1]
        for _ in range(counts[i - 1]):
            if stuck_for_good:
                break
            remaining = h
            while remaining > 0:
                if direction == 0:
                    bound = 0.0
                    for j in range(z.size):
                        bound += weights[j] * abs(z[j])
                    if abs(force_sin * math.sin(theta)) + abs(history_torque) * bound <= tau_f:
                        stuck_for_good = True
                        break
                    rest = _torque_at_rest(theta, z, rates, weights, force_sin, history_torque, remaining)
                    if abs(rest) <= tau_f:
                        z = z * np.exp(-rates * remaining)
                        break
                    args = (theta, z, rates, weights, force_sin, history_torque, tau_f)
                    search = brent_start(0.0, _excess(0.0, args), remaining, _excess(remaining, args))
                    h_start = brent_next(search)
                    while search[9] == 0.0:
                        search[4] = _excess(h_start, args)
                        h_start = brent_next(search)
                    z = z * np.exp(-rates * h_start)
                    remaining -= h_start
                    rest = _torque_at_rest(theta, z, rates, weights, force_sin, history_torque, 0.0)
                    direction = 1 if rest > 0 else -1
                    restarted = True
                    continue
                a_const = -tau_f * direction / inertia
                mu = _moments(z, rates, weights)
                new_theta, new_omega, k1, k2, k3, k4 = rk4_memory_step(
                    theta, omega, remaining, mu, sums, a_sin, a_quad, a_lin, a_const, a_history
                )
                if not (math.isfinite(new_theta) and math.isfinite(new_omega)):
                    return out_theta, out_omega  # diverged (RK4 unstable): the rest stays NaN
                if new_omega * direction > 0:
                    theta, omega = new_theta, new_omega
                    z = advance_memory(z, rates, remaining, k1, k2, k3, k4)
                    restarted = False
                    break
                # θ̇ reaches zero inside this step: locate the reversal
                args = (theta, omega, mu, sums, a_sin, a_quad, a_lin, a_const, a_history, float(direction))
                if _memory_velocity_after(0.0, args) <= 0:
                    if omega == 0.0:
                        if restarted:  # freed at the threshold, held again at once: at rest for this step
                            direction = 0
                            z = z * np.exp(-rates * remaining)
                            break
                        raise RuntimeError("simulator stalled")
                    h_event = 0.0
                else:
                    search = brent_start(
                        0.0, _memory_velocity_after(0.0, args), remaining, _memory_velocity_after(remaining, args)
                    )
                    h_event = brent_next(search)
                    while search[9] == 0.0:
                        search[4] = _memory_velocity_after(h_event, args)
                        h_event = brent_next(search)
                theta, _, k1, k2, k3, k4 = rk4_memory_step(
                    theta, omega, h_event, mu, sums, a_sin, a_quad, a_lin, a_const, a_history
                )
                z = advance_memory(z, rates, h_event, k1, k2, k3, k4)
                omega = 0.0
                remaining -= h_event
                direction = _direction_at_rest(
                    _torque_at_rest(theta, z, rates, weights, force_sin, history_torque, 0.0), tau_f
                )
                restarted = False
        out_theta[i], out_omega[i] = theta, omega
    return out_theta, out_omega
