"""The marker's arc while it is tracked: its circle about the pivot (refitted as the track grows, the
predicted position on it), and normal values of the marker along it.

The circle x² + y² = p x + q y + c is fitted by linear least squares (centre (p/2, q/2), radius
√(c + cx² + cy²)); a position is predicted at constant angular velocity on the circle, inside the
swing seen so far.
"""

from __future__ import annotations

import math

import numpy as np
from scipy.interpolate import make_smoothing_spline


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
            self.circle = self.fitted(self.points) or self.circle
        if self.circle is not None:
            a = self.angle(x, y)
            self.angles = [min(self.angles[0], a), max(self.angles[1], a)]

    def fitted(self, points) -> tuple[float, float, float] | None:
        """The circle through ``points`` (x, y), where they span 6 marker radii of arc, lie within 0.5 px of it
        (median) and its radius is at least 3 marker radii; else None."""
        pts = np.asarray(points[:: max(1, len(points) // 400)], float)
        a = np.column_stack([pts[:, 0], pts[:, 1], np.ones(len(pts))])
        (p, q, c), *_ = np.linalg.lstsq(a, (pts**2).sum(axis=1), rcond=None)
        cx, cy = p / 2, q / 2
        arm = math.sqrt(max(c + cx * cx + cy * cy, 0.0))
        resid = np.abs(np.hypot(pts[:, 0] - cx, pts[:, 1] - cy) - arm)
        span = np.ptp(np.arctan2(pts[:, 0] - cx, pts[:, 1] - cy)) * arm
        if span >= 6 * self.r and float(np.median(resid)) <= 0.5 and arm >= 3 * self.r:
            return float(cx), float(cy), float(arm)
        return None

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
    grow by a bin, the frames by a quarter, or the circle is refitted; at the end of the pass, along
    the whole path where one smooth curve explains it (:meth:`settle`).
    """

    MIN_SPAN_RADII = 4.0
    REACH_RADII = 4.0
    MAX_SLOPE_PER_RADIUS = 0.03
    MAX_SETTLED_SLOPE_PER_RADIUS = 0.08
    SETTLED_RADII = 2.0

    def __init__(self, arc: MarkerArc, radius_px: float, enabled: bool):
        self.arc, self.r, self.enabled = arc, radius_px, enabled
        self.base = math.nan
        self.points: list[tuple[float, float, float]] = []  # (x, y, value) of ok frames
        self.fit = None  # (coefficients of ρ(φ), φ_lo, φ_hi, circle)
        self.fitted_n = 0
        self.bins_seen = (math.inf, -math.inf)
        self.fitted_circle = None
        self.settled = None  # (spline of ρ in radii of arc, its ends, circle), from :meth:`settle`

    def ratio(self, x: float, y: float) -> float:
        """ρ(φ) at the marker position (x, y): its normal value / ``base``."""
        if self.settled is not None:
            spline, lo, hi, (cx, cy, arm) = self.settled
            return float(spline(min(max(math.atan2(x - cx, y - cy) * arm / self.r, lo), hi)))
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

    def span(self) -> tuple[float, float] | None:
        """The least and largest ρ along the path where the curve is fitted (None while it is not)."""
        if self.settled is not None:
            spline, lo, hi, _ = self.settled
            values = spline(np.linspace(lo, hi, 64))
        elif self.fit is not None:
            coef, lo, hi, _ = self.fit
            values = np.polyval(coef, np.linspace(lo, hi, 64))
        else:
            return None
        return float(np.min(values)), float(np.max(values))

    def covers(self, x: float, y: float) -> bool:
        """Whether ρ at (x, y) is fitted there, not carried on from the angles seen."""
        if self.fit is None:
            return False
        _, lo, hi, (cx, cy, _) = self.fit
        return lo <= math.atan2(x - cx, y - cy) <= hi

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
        pts = np.asarray(self.points)
        binned = self._bins(pts, circle)
        if binned is None or binned[0].size < 4:
            self.fit = None
            return
        keys, centre, median, counts = binned
        weight = np.sqrt(np.minimum(counts, 10)).astype(float)
        degree = 2 if keys.size >= 8 else 1
        coef = np.polyfit(centre, median, degree, w=weight)
        resid = median - np.polyval(coef, centre)
        keep = np.abs(resid) <= max(0.03, 3.0 * 1.4826 * float(np.median(np.abs(resid))))
        if keep.sum() >= degree + 3 and not keep.all():
            coef = np.polyfit(centre[keep], median[keep], degree, w=weight[keep])
        phi = np.arctan2(pts[:, 0] - circle[0], pts[:, 1] - circle[1])
        self.fit = (coef, float(phi.min()), float(phi.max()), circle)

    def settle(self, points, least_at_most: float = math.inf) -> bool:
        """At the end of the pass, ρ(φ) refitted on ``points`` (x, y, value): the ok frames and those flagged
        for their value alone, where one smooth curve explains them: a lens's magnification or vignetting along
        a swing that leaves the place of the first frames (a marker held at release near a wide lens's edge
        grows 1.3–1.4 times towards the centre, by up to 5 % per radius of arc at the edge; the ok frames alone
        never span it). The curve: a cubic smoothing spline through the bins' medians (one marker radius of arc
        per bin, weights √min(count, 10)) that follows changes over :attr:`SETTLED_RADII` radii of arc, not
        within one; fitted again without the bin farthest off it while that is off by more than max(3 %, 3 × the
        kept bins' robust spread).
        Taken where those bins hold at most a tenth of the frames, its slope stays within
        :attr:`MAX_SETTLED_SLOPE_PER_RADIUS` per radius of arc, and across bins left off the value changes as
        the kept bins beside them (6 radii on either side) trend, within that limit: a shadow's or a stripe's
        edge is a step between level stretches (the spline would smooth it over the bins left off), an
        occluder at a few places falls in the bins left off. ``least_at_most``: refused where the curve's least
        value is above it. Returns whether it was taken (ρ then held level beyond the angles given)."""
        if not self.enabled or not math.isfinite(self.base) or len(points) < 8:
            return False
        pts = np.asarray(points, float)
        pts = pts[np.isfinite(pts).all(axis=1)]
        circle = self.arc.circle or (self.arc.fitted(pts[:, :2]) if len(pts) >= 8 else None)
        binned = None if circle is None else self._bins(pts, circle)
        if binned is None or binned[0].size < 8:
            return False
        keys, centre, median, counts = binned
        along = centre * circle[2] / self.r  # radii of arc
        weight = np.sqrt(np.minimum(counts, 10)).astype(float)
        lam = float(np.mean(weight)) * self.SETTLED_RADII**4
        keep = np.ones(keys.size, bool)
        for _ in range(keys.size // 4 + 1):  # the worst bin off the curve left off, one at a time
            spline = make_smoothing_spline(along[keep], median[keep], w=weight[keep], lam=lam)
            resid = median - spline(along)
            limit = max(0.03, 3.0 * 1.4826 * float(np.median(np.abs(resid[keep]))))
            worst = int(np.argmax(np.where(keep, np.abs(resid), -1.0)))
            if abs(resid[worst]) <= limit or keep.sum() <= 8:
                break
            keep[worst] = False
        keep = np.abs(resid) <= limit
        if counts[keep].sum() < 0.9 * counts.sum() or keep.sum() < 8:
            return False
        spline = make_smoothing_spline(along[keep], median[keep], w=weight[keep], lam=lam)  # on the bins kept
        grid = np.linspace(along[0], along[-1], 8 * keys.size)
        if np.max(np.abs(spline.derivative()(grid))) > self.MAX_SETTLED_SLOPE_PER_RADIUS:
            return False
        if float(np.min(spline(grid))) > least_at_most:
            return False
        kept = np.flatnonzero(keep)
        for a, b in zip(kept[:-1], kept[1:], strict=True):
            if b == a + 1:
                continue
            # bins left off between kept bins a and b: the change across them is the trend of the kept bins
            # beside them (a lens), not a step (a shadow's edge that the spline smooths over the gap)
            before = kept[(kept <= a) & (along[kept] >= along[a] - 6)]
            after = kept[(kept >= b) & (along[kept] <= along[b] + 6)]
            slopes = [np.polyfit(along[side], median[side], 1)[0] for side in (before, after) if side.size >= 3]
            expected = float(np.mean(slopes)) * (along[b] - along[a]) if slopes else 0.0
            if abs(float(spline(along[b]) - spline(along[a])) - expected) > limit:
                return False
        self.settled = (spline, float(along[0]), float(along[-1]), circle)
        return True

    def _bins(self, pts: np.ndarray, circle):
        """The values / ``base`` binned by φ, one marker radius of arc per bin: the bins' keys, median φ, median
        ratio and frame counts, or None where they span fewer than :attr:`MIN_SPAN_RADII` radii of arc."""
        cx, cy, arm = circle
        phi = np.arctan2(pts[:, 0] - cx, pts[:, 1] - cy)
        rho = pts[:, 2] / self.base
        bins = np.floor(phi * arm / self.r).astype(int)
        keys, inverse, counts = np.unique(bins, return_inverse=True, return_counts=True)
        if keys[-1] - keys[0] + 1 < self.MIN_SPAN_RADII:
            return None
        order = np.argsort(inverse, kind="stable")
        groups = np.split(order, np.cumsum(counts)[:-1])
        centre = np.array([float(np.median(phi[g])) for g in groups])
        median = np.array([float(np.median(rho[g])) for g in groups])
        return keys, centre, median, counts


class SignalSpread:
    """The spread of the marker signal about its normal value along the arc, and the band of ratios it allows.

    Over the first :attr:`FRAMES` ok frames given (:class:`MarkerSignal` gives those after its normal value is set,
    where the curve along the arc is fitted), the ratios ρ = signal / normal value: their robust spread
    σ = 1.4826 · median|ρ − median ρ|. The band [``low``, ``high``] is the settings' flag band widened to 1 ±
    :attr:`SIGMAS` σ where that is wider, never beyond 1 ± :attr:`MAX_HALF_WIDTH`: a frame flagged for its signal
    alone within it may be the signal's own noise (a small dot in a colour view, its chroma on a grid half as fine as
    the picture's, varies by ±5 % as it moves; :class:`MarkerSignal` decides). A steady signal (σ ≤ 2.5 %; the
    demo's 0.2–0.7 %) keeps the settings' band, as does every frame before :attr:`MIN_FRAMES` are in.
    """

    FRAMES = 60
    MIN_FRAMES = 10
    SIGMAS = 4.0
    MAX_HALF_WIDTH = 0.3

    def __init__(self, low: float, high: float):
        self.settings_band = (low, high)
        self.low, self.high = low, high
        self.sigma = math.nan
        self.ratios: list[float] = []

    def add(self, ratio: float) -> None:
        """An ok frame's ρ."""
        if len(self.ratios) >= self.FRAMES:
            return
        self.ratios.append(ratio)
        if len(self.ratios) >= self.MIN_FRAMES:
            ratios = np.asarray(self.ratios)
            self.sigma = 1.4826 * float(np.median(np.abs(ratios - np.median(ratios))))
            half = min(self.SIGMAS * self.sigma, self.MAX_HALF_WIDTH)
            self.low, self.high = min(self.settings_band[0], 1.0 - half), max(self.settings_band[1], 1.0 + half)


class MarkerSignal:
    """The marker's signal judged against its normal value: the ratio ρ = signal / normal value of each frame, flagged
    outside the settings' band, and judged again at the end.

    Per measurement kind (coverage of the scene, or against its ring), the normal value is the median of the kind's
    first :attr:`FIRST_FRAMES` measured frames (their ρ is 1 until then, and set against it at the end), from
    :attr:`REFERENCE_FRAMES` of them once measured (a small dot's signal varies by ±5 % from frame to frame: five
    frames set it up to 8 % off, and the frames after "glare"), times its curve along the arc (:class:`ArcReference`,
    from the ok frames). A frame flagged for its signal alone (its position passes every other check) is judged
    again at the end, against the normal value as finally learnt: ``ok`` where ρ is then within the settings' band,
    or within the band its spread allows (:class:`SignalSpread`) while the marker's other frames at that place
    (within a marker radius; at least :attr:`PLACE_FRAMES`) read within the settings' band: the noise of one frame,
    not something at that place (an occluder's edge, a shadow across the path, a lamp's highlight where the bob
    passes it, which dim or brighten it there on every pass). Before that, the curves of the signal and of the
    width² are refitted along the whole path (:meth:`ArcReference.settle`), on the ok frames and those flagged for
    that value alone, and a frame flagged for its width² alone that is within it is judged by its signal: a
    marker held near a wide lens's edge changes both smoothly along a swing its ok frames never span.
    """

    FIRST_FRAMES = 5
    REFERENCE_FRAMES = 30
    PLACE_FRAMES = 3
    SIZE_CHANGE_SAID = 1.05  # the marker's size along its path, largest / least, said in the summary from this on

    def __init__(
        self, arc: MarkerArc, radius_px: float, along_arc: bool, low: float, high: float, width_ratio: float = 1.15
    ):
        self.curves = {kind: ArcReference(arc, radius_px, along_arc) for kind in (False, True)}
        self.width = ArcReference(arc, radius_px, along_arc)  # the marker's normal width² along the arc
        self.width_ratio = width_ratio
        self.wide: list[tuple[int, float, float, float]] = []  # (row, x, y, width²) of frames flagged for it alone
        self.wide_rows: set[int] = set()
        self.widths: list[tuple[float, float, float]] = []  # (x, y, width²) of moving frames biased by nothing else
        self.radius_px = radius_px
        self.band = SignalSpread(low, high)
        self.samples: dict[bool, list[float]] = {False: [], True: []}
        self.first: list[tuple[int, bool, float]] = []  # (row, kind, signal) before the kind's reference
        self.measured: list[tuple[int, bool, float, float, float]] = []  # (row, kind, signal, x, y) of measured frames
        self.by_signal: set[int] = set()  # rows flagged for their signal alone
        self.ok_rows: list[int] = []
        self.refitted: list[str] = []  # the values whose curve was refitted along the whole path

    def ratio(self, row: int, kind: bool, signal: float, x: float, y: float, steady: bool) -> float:
        """ρ of a measured frame; ``steady``: not a repeated frame nor one at the picture's edge (the normal value
        is then taken from it too, up to :attr:`REFERENCE_FRAMES` frames)."""
        samples, curve = self.samples[kind], self.curves[kind]
        if len(samples) < self.FIRST_FRAMES:
            samples.append(signal)
            self.first.append((row, kind, signal))
            if len(samples) == self.FIRST_FRAMES:
                curve.base = float(np.median(samples))
            return 1.0
        ratio = signal / curve.value(x, y)
        if steady and ratio >= 0.5 and len(samples) < self.REFERENCE_FRAMES:
            samples.append(signal)
            if len(samples) == self.REFERENCE_FRAMES:
                curve.base = float(np.median(samples))
        return ratio

    def judged(
        self,
        row: int,
        kind: bool,
        signal: float,
        x: float,
        y: float,
        ratio: float,
        flag: str,
        biased: bool,
        width: tuple[float, bool, bool] | None = None,
    ):
        """A measured frame's flag, given: one flagged for its signal alone (not ``biased``) is judged again at the
        end, as is one ``biased`` for its width² alone; an ok one teaches the band and the curve along the arc.
        ``width``: (width², wide, moving) where nothing else biased the frame; a moving frame's width² (across
        its motion: a marker a lens squashes reads another width at rest) enters the width² refitted at the end."""
        if flag in ("ok", "occluded", "glare"):
            self.measured.append((row, kind, signal, x, y))
        if width is not None and flag in ("ok", "occluded", "glare"):
            width2, wide, moving = width
            if moving:
                self.widths.append((x, y, width2))
            if wide and flag != "ok":
                self.wide.append((row, x, y, width2))
                self.wide_rows.add(row)
        if flag in ("occluded", "glare") and not biased:
            self.by_signal.add(row)
        elif flag == "ok":
            self.ok_rows.append(row)
            if len(self.samples[kind]) == self.REFERENCE_FRAMES and self.curves[kind].covers(x, y):
                # its spread about the normal value, where that is known
                self.band.add(ratio)
            self.curves[kind].add(x, y, signal)

    def again(self, row: int) -> bool:
        """Whether the row's flag is judged again at the end (set for its signal or its width² alone)."""
        return row in self.by_signal or row in self.wide_rows

    def finish(self, table) -> None:
        """The first frames' ratios against their kind's normal value; frames flagged for their signal alone judged
        again (``table``: the track, one row per frame, in order)."""
        for row, kind, signal in self.first:
            if len(self.samples[kind]) >= self.FIRST_FRAMES:
                table.loc[row, "signal_ratio"] = signal / self.curves[kind].base
        # a lens changes the width from place to place, and somewhere it reads as the first frames allow; more all
        # along the path (a two-tone bob beside the marker once it swings) is something else in its mask
        if self.wide and self.width.settle(self.widths, least_at_most=self.width_ratio):
            # the width² refitted along the whole path: those within it now are judged by their signal
            self.refitted.append("width")
            self.by_signal.update(row for row, x, y, w in self.wide if w <= self.width_ratio * self.width.value(x, y))
        if not self.by_signal:
            return
        rows, kinds, signals, xs, ys = (np.asarray(v) for v in zip(*self.measured, strict=True))
        unbiased = np.isin(rows, sorted(self.by_signal)) | np.isin(rows, self.ok_rows)
        for kind, curve in self.curves.items():
            on = unbiased & (kinds == kind)
            if curve.settle(np.column_stack([xs[on], ys[on], signals[on]])):
                self.refitted.append("signal")
        ratios = np.array([s / self.curves[k].value(x, y) for k, s, x, y in zip(kinds, signals, xs, ys, strict=True)])
        low, high = self.band.settings_band
        steady = (ratios >= low) & (ratios <= high)
        for k in np.flatnonzero(np.isin(rows, sorted(self.by_signal))):
            ratio = float(ratios[k])
            if not steady[k]:
                if not self.band.low <= ratio <= self.band.high:
                    continue
                place = np.hypot(xs - xs[k], ys - ys[k]) <= self.radius_px
                place[k] = False
                others = ratios[place]
                if others.size < self.PLACE_FRAMES or not low <= float(np.median(others)) <= high:
                    continue
            table.loc[int(rows[k]), ["signal_ratio", "quality", "flag"]] = [ratio, min(ratio, 1.0 / ratio), "ok"]

    def summary(self) -> dict:
        """For the tracks JSON: the ratios' spread about the normal value, and the band within which a frame flagged
        for its signal alone may be ``ok``; ``refitted_along_path``, where the curves were refitted at the end."""
        sigma = self.band.sigma
        said = {"refitted_along_path": sorted(set(self.refitted))} if self.refitted else {}
        span = self.width.span()
        if span is not None and span[0] > 0 and span[1] >= self.SIZE_CHANGE_SAID**2 * span[0]:
            said["size_change_along_path"] = round(math.sqrt(span[1] / span[0]), 3)
        return {
            "signal_spread": None if math.isnan(sigma) else round(sigma, 4),
            "signal_band": [round(self.band.low, 3), round(self.band.high, 3)],
            **said,
        }
