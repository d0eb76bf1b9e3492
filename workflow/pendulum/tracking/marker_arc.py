"""The marker's arc while it is tracked: its circle about the pivot (refitted as the track grows, the
predicted position on it), and normal values of the marker along it.

The circle x² + y² = p x + q y + c is fitted by linear least squares (centre (p/2, q/2), radius
√(c + cx² + cy²)); a position is predicted at constant angular velocity on the circle, inside the
swing seen so far.
"""

from __future__ import annotations

import math

import numpy as np


class MarkerArc:
    """The marker's circle (centre, radius): from detection, refitted on the track as it grows."""

    def __init__(self, detection, radius_px: float):
        self.r = radius_px
        self.circle = None if detection is None else (*detection.pivot_px, detection.arm_px)
        self.angles = [math.inf, -math.inf]  # range of the marker's angle seen so far
        self.points: list[tuple[float, float]] = []
        self.next_fit = 60

    def angle(self, x, y) -> float:
        return math.atan2(x - self.circle[0], y - self.circle[1])

    def add(self, x: float, y: float) -> None:
        self.points.append((x, y))
        if len(self.points) >= self.next_fit:
            self.next_fit = int(len(self.points) * 1.5)
            pts = np.array(self.points[:: max(1, len(self.points) // 400)])
            a = np.column_stack([pts[:, 0], pts[:, 1], np.ones(len(pts))])
            (p, q, c), *_ = np.linalg.lstsq(a, (pts**2).sum(axis=1), rcond=None)
            cx, cy = p / 2, q / 2
            arm = math.sqrt(max(c + cx * cx + cy * cy, 0.0))
            resid = np.abs(np.hypot(pts[:, 0] - cx, pts[:, 1] - cy) - arm)
            span = np.ptp(np.arctan2(pts[:, 0] - cx, pts[:, 1] - cy)) * arm
            if span >= 6 * self.r and float(np.median(resid)) <= 0.5 and arm >= 3 * self.r:
                self.circle = (float(cx), float(cy), float(arm))
        if self.circle is not None:
            a = self.angle(x, y)
            self.angles = [min(self.angles[0], a), max(self.angles[1], a)]

    def near(self, x: float, y: float) -> bool:
        """On the arc (within a few marker radii) and inside the swing seen (when seen)."""
        if self.circle is None:
            return True
        cx, cy, arm = self.circle
        if abs(math.hypot(x - cx, y - cy) - arm) > max(3 * self.r, 0.05 * arm):
            return False
        return True

    def off(self, x: float, y: float, tolerance_px: float) -> bool:
        """Farther than ``tolerance_px`` from the circle (False while it is unknown)."""
        if self.circle is None:
            return False
        cx, cy, arm = self.circle
        return abs(math.hypot(x - cx, y - cy) - arm) > tolerance_px

    def predict(self, x1, y1, x0, y0, gap: int):
        """Position ``gap`` frames after (x1, y1) at the angular velocity from (x0, y0), on the arc,
        kept inside the swing seen so far (a pendulum's swing does not grow)."""
        cx, cy, arm = self.circle
        a1, a0 = self.angle(x1, y1), self.angle(x0, y0)
        a = a1 + (a1 - a0) * gap
        if self.angles[0] <= self.angles[1]:
            margin = 2 * self.r / arm
            a = min(max(a, self.angles[0] - margin), self.angles[1] + margin)
        return cx + arm * math.sin(a), cy + arm * math.cos(a)


class ArcReference:
    """A normal value of the marker (its signal, or width²) as a smooth function of its arc angle φ.

    The value changes smoothly and repeatably with the marker's place in the picture (lens
    magnification, vignetting, lighting falloff), so it is referred to ``base`` (the first
    frames' value) by a curve ρ(φ), φ = atan2(x − x_p, y − y_p) about the arc's pivot: the ok
    frames' values / ``base`` are binned by φ (one marker radius of arc per bin) and a polynomial
    (degree 1, or 2 from 8 bins on) is fitted to the bins' medians, weights √min(count, 10), once
    more without the bins off it by more than max(3 %, 3 × their robust spread): the few biased
    frames inside the flag band do not bend it, and flagged frames never enter. Outside the
    angles seen, ρ goes on along its end tangent for at most :attr:`REACH_RADII` radii of arc, its
    slope there at most :attr:`MAX_SLOPE_PER_RADIUS` per radius of arc (a smooth change; a stripe
    or an occluder changes the signal by as much over one marker diameter), then stays level.
    ρ = 1 (the first frames' value) while the circle is unknown, the ok frames span fewer than
    :attr:`MIN_SPAN_RADII` radii of arc, or ``enabled`` is False. Refitted when the angles seen
    grow by a bin, the frames by a quarter, or the circle is refitted.
    """

    MIN_SPAN_RADII = 4.0
    REACH_RADII = 4.0
    MAX_SLOPE_PER_RADIUS = 0.03

    def __init__(self, arc: MarkerArc, radius_px: float, enabled: bool):
        self.arc, self.r, self.enabled = arc, radius_px, enabled
        self.base = math.nan
        self.points: list[tuple[float, float, float]] = []  # (x, y, value) of ok frames
        self.fit = None  # (coefficients of ρ(φ), φ_lo, φ_hi, circle)
        self.fitted_n = 0
        self.bins_seen = (math.inf, -math.inf)
        self.fitted_circle = None

    def ratio(self, x: float, y: float) -> float:
        """ρ(φ) at the marker position (x, y): its normal value / ``base``."""
        if self.fit is None:
            return 1.0
        coef, lo, hi, (cx, cy, arm) = self.fit
        phi = math.atan2(x - cx, y - cy)
        if lo <= phi <= hi:
            return float(np.polyval(coef, phi))
        end = lo if phi < lo else hi
        cap = self.MAX_SLOPE_PER_RADIUS * arm / self.r  # per radian
        slope = min(max(float(np.polyval(np.polyder(coef), end)), -cap), cap)
        reach = self.REACH_RADII * self.r / arm
        return float(np.polyval(coef, end)) + slope * min(max(phi - end, -reach), reach)

    def value(self, x: float, y: float) -> float:
        """The normal value at (x, y): ``base`` × ρ(φ), ρ kept within [0.5, 2]."""
        return self.base * min(max(self.ratio(x, y), 0.5), 2.0)

    def add(self, x: float, y: float, value: float) -> None:
        """An ok frame's value at (x, y); refits ρ when due."""
        if not self.enabled or not math.isfinite(self.base) or not math.isfinite(value):
            return
        self.points.append((x, y, value))
        circle = self.arc.circle
        if circle is None:
            return
        b = math.floor(self.arc.angle(x, y) * circle[2] / self.r)
        lo, hi = self.bins_seen
        grown = b < lo or b > hi
        self.bins_seen = (min(lo, b), max(hi, b))
        if grown or len(self.points) >= 1.25 * self.fitted_n or circle is not self.fitted_circle:
            self._refit(circle)

    def _refit(self, circle) -> None:
        self.fitted_n, self.fitted_circle = len(self.points), circle
        cx, cy, arm = circle
        pts = np.asarray(self.points)
        phi = np.arctan2(pts[:, 0] - cx, pts[:, 1] - cy)
        rho = pts[:, 2] / self.base
        bins = np.floor(phi * arm / self.r).astype(int)
        keys, inverse, counts = np.unique(bins, return_inverse=True, return_counts=True)
        if keys.size < 4 or keys[-1] - keys[0] + 1 < self.MIN_SPAN_RADII:
            self.fit = None
            return
        order = np.argsort(inverse, kind="stable")
        groups = np.split(order, np.cumsum(counts)[:-1])
        centre = np.array([float(np.median(phi[g])) for g in groups])
        median = np.array([float(np.median(rho[g])) for g in groups])
        weight = np.sqrt(np.minimum(counts, 10)).astype(float)
        degree = 2 if keys.size >= 8 else 1
        coef = np.polyfit(centre, median, degree, w=weight)
        resid = median - np.polyval(coef, centre)
        keep = np.abs(resid) <= max(0.03, 3.0 * 1.4826 * float(np.median(np.abs(resid))))
        if keep.sum() >= degree + 3 and not keep.all():
            coef = np.polyfit(centre[keep], median[keep], degree, w=weight[keep])
        self.fit = (coef, float(phi.min()), float(phi.max()), circle)
