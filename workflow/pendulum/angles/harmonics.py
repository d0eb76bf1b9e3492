"""Whether an angle record is a planar swing seen square-on: its second harmonic.

A pendulum swinging about a fixed pivot in a plane parallel to the image has odd harmonics only: the
nonlinear pendulum's θ = A cos φ + (A³/192) cos 3φ + …, and the damping laws (θ̇, θ̇|θ̇|, sgn θ̇) are odd
too. Perspective adds an even one where the body's distance from the camera changes with the swing. With
the body near the optical axis and the pivot above it, the image angle is θ_img ≈ θ (1 − Y/D), Y the body's
displacement toward the camera and D the camera's distance. For Y/D = γ cos φ (the swing plane turned against
the image plane) θ_img = A cos φ − (Aγ/2)(1 + cos 2φ); for Y/D = β sin φ (an elliptical swing, the body
coming toward the camera and going back a quarter period later) θ_img = A cos φ − (Aβ/2) sin 2φ. The body's
apparent size then changes by −Y/D with the swing. The real apple clip (2026-12-02): 0.15° in phase and
0.07° in quadrature at a 20° swing, its silhouette's area changing by −3.5 % cos φ and −1.4 % sin φ where these
figures predict −3.0 % and −1.4 %; with the harmonic removed and its frame times free at the five slips, a fit
left 0.07° where 0.23° were.

Measured over windows of one period (every half period): linear least squares of θ on 1, cos ωt, sin ωt,
t cos ωt, t sin ωt (the decay, and a frequency a little off), cos 2ωt, sin 2ωt, cos 3ωt, sin 3ωt, with ω
from the record's crossing period; the second harmonic expressed against the fundamental's phase φ
(A cos φ): its in-phase (cos 2φ) and quadrature (sin 2φ) parts. The record's figures are the medians over
the windows, their standard errors from the windows' scatter about their trend (the differences between
windows a period apart; overlapping windows counted as half).
"""

from __future__ import annotations

import math

import numpy as np

MIN_SAMPLES = 24  # usable samples a window needs
MIN_WINDOWS = 3
MIN_AMPLITUDE_DEG = 2.0  # a window whose fundamental is smaller: too little swing to tell
PRESENT_SIGMA = 5.0  # a harmonic this many standard errors from zero, ...
PRESENT_SHARE = 0.002  # ... at least this share of the swing's amplitude, ...
PRESENT_NOISE = 3.0  # ... and this many times the record's noise, is said


def _window(t: np.ndarray, theta: np.ndarray, omega: float) -> tuple[float, float, float] | None:
    """(A, in-phase, quadrature) in radians for one window's samples, or None where it cannot be fitted."""
    u = t - t.mean()
    q = omega * u
    design = np.column_stack(
        [np.ones_like(u), np.cos(q), np.sin(q), u * np.cos(q), u * np.sin(q)]
        + [f(k * q) for k in (2, 3) for f in (np.cos, np.sin)]
    )
    coef, *_ = np.linalg.lstsq(design, theta, rcond=None)
    a1, b1, a2, b2 = coef[1], coef[2], coef[5], coef[6]
    amplitude = math.hypot(a1, b1)
    if not np.isfinite(amplitude) or amplitude == 0:
        return None
    psi = math.atan2(b1, a1)  # a1 cos q + b1 sin q = A cos(q − ψ): φ = q − ψ
    in_phase = a2 * math.cos(2 * psi) + b2 * math.sin(2 * psi)
    quadrature = b2 * math.cos(2 * psi) - a2 * math.sin(2 * psi)
    return amplitude, in_phase, quadrature


def _scatter(values: np.ndarray) -> float:
    """σ of one window's figure from the differences between windows a period apart (a harmonic that grows or
    shrinks with the swing over the record is not scatter)."""
    steps = values[2:] - values[:-2] if values.size > 3 else np.diff(values)
    return float(np.sqrt(np.mean(steps**2) / 2))


def second_harmonic(time_s, theta_rad, period_s: float | None, noise_deg: float) -> dict | None:
    """The record's second harmonic (module docstring) in degrees, with what it implies; None where the record
    is too short (fewer than :data:`MIN_WINDOWS` windows of one period with a swing of 2° or more)."""
    if not period_s or not np.isfinite(period_s) or period_s <= 0:
        return None
    t = np.asarray(time_s, float)
    th = np.asarray(theta_rad, float)
    keep = np.isfinite(t) & np.isfinite(th)
    t, th = t[keep], th[keep]
    if t.size < MIN_SAMPLES:
        return None
    omega = 2 * math.pi / period_s
    rows = []
    start = t[0]
    while start + period_s <= t[-1] + 1e-9:
        inside = (t >= start) & (t < start + period_s)
        if inside.sum() >= MIN_SAMPLES:
            found = _window(t[inside], th[inside], omega)
            if found and math.degrees(found[0]) >= MIN_AMPLITUDE_DEG:
                rows.append(found)
        start += 0.5 * period_s
    if len(rows) < MIN_WINDOWS:
        return None
    amplitude, in_phase, quadrature = (np.degrees(np.array(c)) for c in zip(*rows, strict=True))
    effective = max(1.0, len(rows) / 2)  # overlapping windows
    c, s = float(np.median(in_phase)), float(np.median(quadrature))
    c_se, s_se = (_scatter(part) / math.sqrt(effective) for part in (in_phase, quadrature))
    size = math.hypot(c, s)
    size_se = math.hypot(c * c_se, s * s_se) / size if size > 0 else math.hypot(c_se, s_se)
    swing = float(np.median(amplitude))
    present = bool(size > PRESENT_SIGMA * size_se and size > PRESENT_SHARE * swing and size > PRESENT_NOISE * noise_deg)
    out = {
        "amplitude_deg": round(size, 5),
        "in_phase_deg": round(c, 5),
        "quadrature_deg": round(s, 5),
        "stderr_deg": round(size_se, 5),
        "swing_amplitude_deg": round(swing, 4),
        "windows": len(rows),
        # Y/D (module docstring): the relative change of the body's distance from the camera with the swing
        "distance_change_in_phase": round(-2 * c / swing, 5),
        "distance_change_quadrature": round(-2 * s / swing, 5),
        "present": present,
    }
    if present:
        out["verdict"] = verdict(out)
    return out


def verdict(found: dict, plane_calibrated: str | None = None) -> str:
    """One sentence: the harmonic, what makes one, what the body's distance does, what to film (``plane_calibrated``:
    the camera setup whose swing-plane board mapped the record, where calibrating the view is done already)."""
    c, s = found["in_phase_deg"], found["quadrature_deg"]
    moves = 100 * math.hypot(found["distance_change_in_phase"], found["distance_change_quadrature"])
    kinds = []
    if abs(c) >= 0.5 * abs(s):
        kinds.append("the swing plane turned against the image plane (the in-phase part)")
    if abs(s) >= 0.5 * abs(c):
        kinds.append("an elliptical swing, the body coming toward the camera and going back (the quadrature part)")
    return (
        f"the angle record carries a second harmonic of {found['amplitude_deg']:.2g}° (in phase {c:+.2g}°, in "
        f"quadrature {s:+.2g}°, ± {found['stderr_deg']:.1g}°) on a {found['swing_amplitude_deg']:.3g}° swing, "
        "which a planar swing seen square-on does not have: perspective makes one where the body's distance from "
        f"the camera changes with the swing, here by about {moves:.2g} % of that distance — "
        + " or ".join(kinds)
        + (
            "; the fits carry it (film square-on to the swing plane, from farther away, or calibrate the view: "
            "docs/footage.md)"
            if plane_calibrated is None
            else f"; the fits carry it, though the view is calibrated (camera setup {plane_calibrated}): the swing's "
            "own, or a board in the plane clip that was not in the swing plane"
        )
    )
