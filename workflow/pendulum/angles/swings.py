"""What an angle series shows: turning points, the swing's centre, the noise floor, the release, the rest."""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np


def turning_points(theta: np.ndarray, min_separation: int = 3) -> np.ndarray:
    """Indices of the local extrema of a sampled oscillation (sign changes of the difference)."""
    d = np.diff(theta)
    sign = np.sign(d)
    idx = np.flatnonzero(sign[1:] * sign[:-1] < 0) + 1
    if idx.size == 0:
        return idx
    keep = [idx[0]]
    for i in idx[1:]:
        if i - keep[-1] >= min_separation:
            keep.append(i)
    return np.array(keep)


def swing_centre_rad(theta: np.ndarray) -> tuple[float, int] | None:
    """Centre of a decaying oscillation of any amplitude, robust to sample noise: (centre, triplets used).

    The median of :func:`swing_centres`; None if there is none.
    """
    centres = swing_centres(theta)
    if not centres:
        return None
    return float(np.median([c for _, c in centres])), len(centres)


def swing_centres(theta: np.ndarray) -> list[tuple[int, float]]:
    """The oscillation's centre from each triplet of consecutive extrema: ``(sample of the middle one, centre)``.

    The extrema are the confirmed ones of :func:`swing_extrema` (hysteresis of
    10 σ, so noise makes none, at any frame rate), each refined by a parabola
    through the samples within a sixth of the way to its neighbouring extrema.
    Per triplet (p₀, q, p₁), locally geometric decay gives
    c = (p₀ p₁ − q²) / (p₀ + p₁ − 2 q); triplets whose swing is
    above 20 σ.
    """
    th = np.asarray(theta, float)
    idx = np.flatnonzero(np.isfinite(th))
    if idx.size < 20:
        return []
    v = th[idx]
    sigma = noise_level(v)
    ext = swing_extrema(v)  # positions in v (the kept samples), as idx[ext] in frames
    values = []
    for k, i in enumerate(ext):
        # in frames, not in kept samples: flagged frames (NaN) leave gaps that must not close up
        # (a passer hiding the marker near the bottom of each swing moved a vertical by 0.08°)
        spacing = [idx[i] - idx[ext[k - 1]] if k > 0 else None, idx[ext[k + 1]] - idx[i] if k + 1 < ext.size else None]
        half = max(2, min(g for g in spacing if g is not None) // 6) if any(spacing) else 2
        near = np.flatnonzero(np.abs(idx - idx[i]) <= half)
        value = v[i]
        bracketed = True
        if near.size >= 5:
            a, b, c = np.polyfit(idx[near] - idx[i], v[near], 2)
            if a != 0 and abs(b / (2 * a)) <= half:
                value = c - b * b / (4 * a)
            # the turn must lie between samples: an extremum at the edge of a run of missing frames whose
            # parabola turns beyond it (the body out of view at the end of its swing) is where the record
            # stops, not where the swing turns
            vertex = -b / (2 * a) if a != 0 else math.inf
            offsets = idx[near] - idx[i]
            bracketed = (offsets < vertex).sum() >= 2 and (offsets > vertex).sum() >= 2
        values.append(value if bracketed else math.nan)
    centres = []
    for k in range(len(values) - 2):
        p0, q, p1 = values[k : k + 3]
        if not math.isfinite(p0 + q + p1):
            continue
        swing = abs(q - 0.5 * (p0 + p1))
        if swing > 20 * sigma and np.sign(p0 - q) == np.sign(p1 - q) and p0 + p1 - 2 * q != 0:
            centres.append((int(idx[ext[k + 1]]), (p0 * p1 - q * q) / (p0 + p1 - 2 * q)))
    return centres


def swing_centre_track(time_s: np.ndarray, theta: np.ndarray, window: int = 5) -> np.ndarray | None:
    """The record's swing centre at every sample: the centres of its extrema triplets (:func:`swing_centres`),
    each averaged with the next (Coulomb friction moves the centre by ±τ_f/K with the swing's direction, which
    alternates), a running median of ``window`` of those, interpolated in time (held beyond the first and last);
    their median where there are fewer than ``window``; None where there are fewer than two triplets."""
    centres = swing_centres(theta)
    if len(centres) < 2:
        return None
    at = np.array([time_s[i] for i, _ in centres])
    values = np.array([c for _, c in centres])
    at, values = 0.5 * (at[1:] + at[:-1]), 0.5 * (values[1:] + values[:-1])
    if values.size < window:
        return np.full(time_s.size, float(np.median(values)))
    half = window // 2
    smooth = np.array([np.median(values[max(0, k - half) : k + half + 1]) for k in range(values.size)])
    return np.interp(time_s, at, smooth)


KNOCK_TURN_SIGMAS = 4.0  # a camera's turn at a knock is taken out where at least this many standard errors ...
MIN_KNOCK_TURN_DEG = 0.02  # ... and this large
MIN_SIDE_CENTRES = 3  # centre pairs on a side of the knock for its own spread ...
MIN_SIDE_PAIRS = 2  # ... and at least this many, that side's spread then the other's (a knock 4.8 s before the end at
# 30 fps: 2 pairs after it; its turn of −0.7° stayed in θ, 0.40° RMS off the clip's own record)


def turn_at_knock(time_s: np.ndarray, theta: np.ndarray, knock: dict) -> dict | None:
    """The picture's turn when the camera was knocked (``knock``: the track's, with ``from_s``/``to_s`` its shaking;
    ``path_shape`` brings the positions back for the move, which a turn about the lens's axis also makes, but a
    turn itself is no departure from the circle and stays in θ as a step): the swing's centre after ``to_s`` less
    the one before ``from_s``, each the median of that side's centres (:func:`swing_centres`, each averaged with
    the next: Coulomb friction alternates them), its standard error 1.25 × 1.4826 MAD / √(n/2) per side (pairs
    overlap). ``theta`` in radians, NaN where unusable. Returns ``turn_deg``, ``stderr_deg``, ``centre_pairs`` (per
    side) and ``taken_out`` (at least :data:`KNOCK_TURN_SIGMAS` σ and :data:`MIN_KNOCK_TURN_DEG`). A side with
    fewer than :data:`MIN_SIDE_CENTRES` pairs (at least :data:`MIN_SIDE_PAIRS`) takes the other side's spread; None
    where a side holds fewer than that, or neither holds :data:`MIN_SIDE_CENTRES`."""
    t, th = np.asarray(time_s, float), np.asarray(theta, float)
    sides = []
    for side in (t < knock["from_s"], t > knock["to_s"]):
        values = np.array([c for _, c in swing_centres(th[side])])
        pairs = 0.5 * (values[1:] + values[:-1])
        if pairs.size < MIN_SIDE_PAIRS:
            return None
        centre = float(np.median(pairs))
        sides.append((centre, 1.4826 * float(np.median(np.abs(pairs - centre))), int(pairs.size)))
    if min(n for _, _, n in sides) < MIN_SIDE_CENTRES:  # a short side: the other side's spread (the same swing's)
        if max(n for _, _, n in sides) < MIN_SIDE_CENTRES:
            return None
        spread = next(s for _, s, n in sides if n >= MIN_SIDE_CENTRES)
        sides = [(c, spread, n) for c, _, n in sides]
    sides = [(c, 1.2533 * s / math.sqrt(max(n / 2, 1.0)), n) for c, s, n in sides]
    (before, se_before, n_before), (after, se_after, n_after) = sides
    turn, stderr = math.degrees(after - before), math.degrees(math.hypot(se_before, se_after))
    return {
        "turn_deg": round(turn, 4),
        "stderr_deg": round(stderr, 4),
        "centre_pairs": [n_before, n_after],
        "taken_out": bool(abs(turn) >= max(MIN_KNOCK_TURN_DEG, KNOCK_TURN_SIGMAS * stderr)),
    }


def noise_level(theta: np.ndarray) -> float:
    """Sample noise σ from the MAD of third differences (insensitive to slow motion): for thresholds.

    A fast or wide swing's own third differences, θ0 (ωΔt)³, enter it (a 60° swing of period 1.6 s
    at 30 fps reads 0.0095° for σ = 0.005°): on the safe side for the release and rest thresholds;
    the record's noise figure is :func:`sample_noise_rad`.
    """
    return _difference_sigma(theta, 3)


def _difference_sigma(theta: np.ndarray, order: int) -> float:
    """σ of white noise from the MAD of the ``order``-th differences: var Δᵏθ = C(2k, k) σ²."""
    d = np.diff(np.asarray(theta, float)[np.isfinite(theta)], order)
    if d.size < 5:
        return 0.0
    return float(1.4826 * np.median(np.abs(d - np.median(d))) / math.sqrt(math.comb(2 * order, order)))


def noise_differences(time_s: np.ndarray, values: np.ndarray, order: int = 3) -> np.ndarray:
    """``order``-th differences over ``order`` + 1 consecutive samples, scaled to the noise: z ~ N(0, σ²) for
    white noise σ.

    z = Σ w_j x_j / √(Σ w_j²), w the divided difference's weights 1/Π_{k≠j}(t_j − t_k) (on a regular grid
    ∝ the binomial coefficients with alternating signs, so z = Δᵏx/√C(2k, k); uneven (variable-frame-rate)
    grids are handled exactly). Smooth motion adds ≈ x⁽ᵏ⁾ hᵏ/√C(2k, k), negligible at video rates.
    Consecutive: no interval longer than 1.5× the median interval; a gap (flagged or dropped frames) breaks a
    run and no difference spans it. Only finite values are returned (a garbled file's intervals can be too
    unequal for floats).
    """
    t, x = np.asarray(time_s, float), np.asarray(values, float)
    n = order + 1
    if t.size < n:
        return np.empty(0)
    dt = np.diff(t)
    regular = (dt > 0) & (dt <= 1.5 * float(np.median(dt)))
    runs = np.ones(t.size - order, bool)
    for k in range(order):
        runs &= regular[k : k + t.size - order]
    ok = np.flatnonzero(runs)
    if ok.size == 0:
        return np.empty(0)
    points = t[ok[:, None] + np.arange(n)[None, :]]
    weights = np.ones_like(points)
    samples = x[ok[:, None] + np.arange(n)[None, :]]
    with np.errstate(over="ignore", invalid="ignore"):  # intervals too unequal for floats (a garbled file): left out
        for j in range(n):
            for k in range(n):
                if k != j:
                    weights[:, j] /= points[:, j] - points[:, k]
        z = (weights * samples).sum(axis=1) / np.sqrt((weights**2).sum(axis=1))
    return z[np.isfinite(z)]


def sample_noise_rad(theta: np.ndarray, time_s: np.ndarray | None = None) -> float:
    """Sample noise σ of a record: MAD of its fifth differences / √252 (white noise: var Δ⁵θ = 252 σ²).

    The swing's own fifth differences, θ0 (ωΔt)⁵, stay far below a tracker's noise where the third
    ones do not (60°, period 1.6 s, 30 fps: 0.002° against 0.13°); unbiased within 1 % for
    σ = 0.005° at 0–75° (50 seeds, tests/test_angles.py). With ``time_s``, only over runs of consecutive
    samples (:func:`noise_differences`): no difference spans a flagged sample or a frame the camera lost
    (every 10th frame lost: 0.028° read before for a record of 0.004°).
    """
    if time_s is None:
        return _difference_sigma(theta, 5)
    return differences_sigma(time_s, theta, 5, 5)


def record_noise_floor_rad(theta: np.ndarray, time_s: np.ndarray | None = None) -> float:
    """The record's noise σ, the one figure the angles, the fits' warnings, the report and discovery all give:
    :func:`sample_noise_rad` (fifth differences), and at least the quantisation step's uniform σ, step/√12, for a
    record its tracker quantised (integer-pixel clicks: at least a quarter of its third differences exactly zero;
    the step the median gap between its distinct values). A record of continuous values has no such step: the gap
    between its distinct values is only how densely the samples fill the swing (a 60° swing of 600 samples: 0.2°,
    whose /√12 is four times a tracker's 0.005°)."""
    sigma = sample_noise_rad(theta, time_s)
    values = np.asarray(theta, float)
    values = values[np.isfinite(values)]
    d3 = np.diff(values, 3)
    if d3.size == 0 or np.mean(np.abs(d3) < 1e-12) < 0.25:
        return sigma
    steps = np.diff(np.unique(np.round(values, 12)))
    quantum = float(np.median(steps)) if steps.size else 0.0
    return max(sigma, quantum / math.sqrt(12))


def differences_sigma(time_s: np.ndarray, values: np.ndarray, order: int, least: int) -> float:
    """Robust (MAD) σ of :func:`noise_differences` of ``order`` (finite); 0 with fewer than ``least``."""
    z = noise_differences(time_s, values, order)
    if z.size < least:
        return 0.0
    return float(1.4826 * np.median(np.abs(z - np.median(z))))


SWINGING_LIMITS = 10  # |θ − θ_h| beyond this many departure thresholds: swinging for certain
HOLD_JITTER_SIGMAS = 5.0  # the hold's band: this many robust σ of its own samples (a trembling hold), at least
MIN_HELD_FRAMES = 3  # held frames before the first free one: a release by hand in view
HAND_RELEASE_FIT_S = 0.25  # of the free swing's start, fitted to find where a hand let it go
MAX_CROSSING_GAP = 0.2  # a crossing is timed across flagged samples spanning up to this share of the half swing


def first_swing_rate(time_s: np.ndarray, theta: np.ndarray) -> tuple[float, float] | None:
    """The record's fastest swing as measured: (the largest |θ̇| of its first cycle, in rad/s; that cycle's period T).

    T runs from the record's first crossing of θ = 0 to its third (linear interpolation), else is twice the first
    to the second; θ̇ at the samples up to there (every few, then each about the fastest of those) is the slope of a
    quintic through the samples within T/6 of it (at least 9: θ = A sin ωt to O((ωt)⁷) there, 0.03 % on a sine; so
    wide that the largest of the slopes is not the noise's). The largest is not where it crosses the vertical: drag
    slows a wide release's swing well before the bottom (a 75° one by 40 %). None with fewer than two crossings (4
    samples apart at least: noise flickering about one is one).
    """
    t, x = np.asarray(time_s, float), np.asarray(theta, float)
    good = np.isfinite(t) & np.isfinite(x)
    t, x = t[good], x[good]
    at = []
    for i in np.flatnonzero(np.signbit(x[1:]) != np.signbit(x[:-1]))[:12]:
        if not at or i - at[-1] >= 4:  # noise flickering about one crossing: taken once
            at.append(i)
    at = np.array(at[:3], int)
    if at.size < 2 or t.size < 9:
        return None
    a, b = x[at], x[at + 1]
    crossings = t[at] + (t[at + 1] - t[at]) * a / (a - b)
    period = float(crossings[2] - crossings[0]) if at.size >= 3 else 2 * float(crossings[1] - crossings[0])
    if not period > 0:
        return None

    def rate(i: int) -> float:
        near = np.flatnonzero(np.abs(t - t[i]) <= period / 6)
        if near.size < 9:  # a few samples a cycle: the 9 nearest
            near = np.sort(np.argsort(np.abs(t - t[i]), kind="stable")[:9])
        return abs(np.polynomial.polynomial.polyfit(t[near] - t[i], x[near], 5)[1])

    cycle = min(int(at[-1]) + 2, t.size)
    step = max(1, cycle // 40)  # every step-th sample, then every one about the fastest of those
    coarse = max(range(0, cycle, step), key=rate)
    return float(max(rate(i) for i in range(max(0, coarse - step), min(cycle, coarse + step + 1)))), period


@dataclass
class Release:
    detected: bool
    time_s: float  # release instant in the record's own time
    hold_angle_rad: float | None
    first_sample: int  # first sample after the release


def detect_release(
    time_s: np.ndarray, theta: np.ndarray, threshold_sigmas: float = 8.0, min_threshold_rad: float = math.radians(0.05)
) -> Release:
    """Release instant from a held start: the first departure from the hold angle, back-extrapolated.

    While held, θ = θ_h; after release θ_h − θ ≈ ½ a (t − t_r)², so √|θ − θ_h| is
    linear in t and its zero is t_r. A record that starts already moving has no hold:
    the release is its first sample. A hold that trembles (a hand, a swaying rig: a helper's render, ±0.3 px at
    2 Hz, gave a release 1.05 s early), one that leaves the threshold and comes back before it departs by
    :data:`SWINGING_LIMITS` thresholds, counts from where the record last leaves the hold's own band, 5 robust σ
    of its samples to its last return; a still hold as before.
    """
    t = np.asarray(time_s, float)
    th = np.asarray(theta, float)
    valid = np.flatnonzero(np.isfinite(th))
    if valid.size < 10:
        raise ValueError(f"only {valid.size} valid angle samples (at least 10 needed)")
    sigma = noise_level(th)
    hold = float(np.median(th[valid[:5]]))
    limit = max(threshold_sigmas * sigma, min_threshold_rad)
    departed = valid[np.abs(th[valid] - hold) > limit]
    if departed.size == 0:
        raise ValueError(
            f"the angle never moves more than {math.degrees(limit):.2g}° from its start: no swing, no release found"
        )
    first_departure = int(departed[0])
    moving = valid[np.abs(th[valid] - hold) > SWINGING_LIMITS * limit]
    between = valid[(valid > first_departure) & (valid < moving[0])] if moving.size else valid[:0]
    back_inside = between[np.abs(th[between] - hold) <= limit]
    if back_inside.size and np.searchsorted(valid, first_departure) >= 5:
        # a hold that trembles (a hand, a rig that sways) leaves its band and comes back before it swings: the
        # release is where the record last left the hold's own band (its samples to its last return) before that
        before = valid[valid < moving[0]]
        held_part = th[valid[valid <= back_inside[-1]]]
        hold = float(np.median(held_part))
        jitter = 1.4826 * float(np.median(np.abs(held_part - hold)))
        limit = max(limit, HOLD_JITTER_SIGMAS * jitter)
        inside = before[np.abs(th[before] - hold) <= limit]
        first_departure = int(valid[np.searchsorted(valid, inside[-1]) + 1]) if inside.size else int(before[0])
    if np.searchsorted(valid, first_departure) < 5:
        return Release(False, float(t[valid[0]]), None, int(valid[0]))
    held = valid[valid < first_departure]
    hold = float(np.median(th[held[: max(5, held.size - 5)]]))  # the last held frames may already move
    window = valid[(valid >= first_departure - 5) & (valid < first_departure + 6)]
    dev = np.abs(th[window] - hold)
    # Well above the noise and above a fifth of the departure threshold: compressed video
    # (B-frames) blends the first moving frames into the last held ones, a jitter that the
    # white-noise σ of a precise track does not cover.
    keep = dev > max(3 * sigma, 0.2 * limit, 1e-6)
    t_release = float(t[held[-1]])
    if keep.sum() >= 3 and np.ptp(t[window][keep]) > 0:  # repeated time stamps alone give no line
        slope, intercept = np.polyfit(t[window][keep], np.sqrt(dev[keep]), 1)
        if slope > 0:
            candidate = -intercept / slope
            if t[max(held[0], first_departure - 10)] <= candidate <= t[first_departure]:
                t_release = float(candidate)
    first = int(np.searchsorted(t, t_release, side="right"))
    return Release(True, t_release, hold, first)


def release_by_hand(time_s, theta: np.ndarray, held: np.ndarray, first_free: int) -> Release | None:
    """A release in view whose hold a hand hides: the tracker's ``held`` frames (the body with the hand) before
    the record's first free sample ``first_free``. The free swing's start tells where and when it was let go:

        θ(t) = c + A cos(ω (t − t_r))

    (ω from the record's own period, c the middle of its swing) fitted to its first
    :data:`HAND_RELEASE_FIT_S` of usable samples (at least six, within a quarter period); the release t_r is the
    turning point at or before the first
    free sample, the hold angle θ(t_r). Where that cannot be measured (no period, too few samples, a turning
    point before the held frames or after the first free one), the release is the last held frame and the
    hold angle unknown (None). None when fewer than :data:`MIN_HELD_FRAMES` frames are held there."""
    t = np.asarray(time_s, float)
    th = np.asarray(theta, float)
    run = np.flatnonzero(np.asarray(held, bool)[:first_free])
    if run.size < MIN_HELD_FRAMES:
        return None
    fallback = Release(True, float(t[run[-1]]), None, int(run[-1]) + 1)
    period = crossing_period(t, th)
    extrema = swing_extrema(th)
    if period is None or extrema.size < 2:
        return fallback
    after = np.flatnonzero(np.isfinite(th) & (t >= t[first_free]) & (t <= t[first_free] + period[0] / 4))
    window = after[(t[after] <= t[first_free] + HAND_RELEASE_FIT_S) | (np.arange(after.size) < 6)]  # ≥ 6 samples
    if window.size < 6:
        return fallback
    omega = 2 * math.pi / period[0]
    middle = 0.5 * (float(np.median(th[extrema[0::2]])) + float(np.median(th[extrema[1::2]])))
    design = np.column_stack([np.cos(omega * t[window]), np.sin(omega * t[window])])
    (p, q), *_ = np.linalg.lstsq(design, th[window] - middle, rcond=None)
    phase = math.atan2(q, p)  # turning points where ω t = phase + k π
    k = math.floor((omega * t[first_free] - phase) / math.pi)
    t_release = (phase + k * math.pi) / omega
    if not t[run[0]] <= t_release <= t[first_free]:
        return fallback
    hold = middle + p * math.cos(omega * t_release) + q * math.sin(omega * t_release)
    return Release(True, t_release, hold, int(np.searchsorted(t, t_release, side="right")))


def swing_extrema(theta: np.ndarray) -> np.ndarray:
    """Indices of the confirmed swing extrema of a record (not its first sample).

    An extremum counts once the angle has come back from it by more than
    max(10 σ, 1e-4 rad) (σ the sample noise), so noise makes none; the last one
    needs that much record after it. A record from a release holds its first
    two extrema after about one period.
    """
    th = np.asarray(theta, float)
    idx = np.flatnonzero(np.isfinite(th))
    if idx.size < 3:
        return np.array([], int)
    v = th[idx]
    h = max(10 * noise_level(v), 1e-4)
    found, state, cand = [], 0, 0
    for k in range(1, v.size):
        x = v[k]
        if state == 0:
            if abs(x - v[0]) > h:
                state, cand = (1 if x > v[0] else -1), k
        elif state * (x - v[cand]) >= 0:
            cand = k
        elif abs(v[cand] - x) > h:
            found.append(cand)
            state, cand = -state, k
    return idx[np.array(found, int)]


def rest_start_index(theta: np.ndarray, sigmas: float = 5.0) -> int | None:
    """First sample of a final period at rest (|θ − θ_final| within noise to the end), or None."""
    th = np.asarray(theta, float)
    sigma = max(noise_level(th), 1e-6)
    finite = np.isfinite(th)
    tail = th[finite][-15:]
    if tail.size < 15:
        return None
    final = float(np.median(tail))
    moving = np.flatnonzero(finite & (np.abs(th - final) > sigmas * sigma))
    if moving.size == 0:
        return 0
    start = int(moving[-1]) + 1
    return start if start < th.size - 1 else None


def missing_period(time_s: np.ndarray, theta: np.ndarray) -> str:
    """Why :func:`crossing_period` gives no period for this record, for its angles document and the status table."""
    t = np.asarray(time_s, float)
    finite = np.isfinite(np.asarray(theta, float))
    span = float(t[finite][-1] - t[finite][0]) if finite.sum() > 1 else 0.0
    turning = int(swing_extrema(np.asarray(theta, float)).size)
    return (
        f"no period measured: it is timed from three crossings of the swing's middle each way (two whole periods "
        f"in each direction), and this record has {turning} turning point(s) over {span:.1f} s, too few; a "
        "record of three periods or more, with its swings' middles in view, gives it"
    )


def crossing_period(time_s: np.ndarray, theta: np.ndarray) -> tuple[float, float, int] | None:
    """The record's mean period from the times it crosses its middle level: ``(period_s, stderr_s, n_cycles)``.

    The middle is halfway between the median maximum and minimum of the confirmed swing extrema
    (:func:`swing_extrema`: noise makes none, nor does the record's rest at its end); one crossing per
    half swing between two of them (linear interpolation between neighbouring usable samples, also across
    flagged ones where they span up to :data:`MAX_CROSSING_GAP` of the half swing; the median time where noise
    crosses more than once). The upward and downward crossings are each numbered
    by whole periods from the first and fitted with a line t = t₀ + P·n; P is the mean of the two
    directions' slopes (an off-centre swing makes its half periods alternate, not its periods), its
    standard error from the lines' residuals. None with fewer than two periods in either direction.
    """
    t = np.asarray(time_s, float)
    th = np.asarray(theta, float)
    extrema = swing_extrema(th)
    if extrema.size < 4:
        return None
    high = th[extrema][th[extrema] > np.median(th[extrema])]
    low = th[extrema][th[extrema] <= np.median(th[extrema])]
    if high.size < 2 or low.size < 2:
        return None
    centred = th - 0.5 * (float(np.median(high)) + float(np.median(low)))
    usable = np.flatnonzero(np.isfinite(centred))
    crossings = {1: [], -1: []}
    for a, b in zip(extrema[:-1], extrema[1:], strict=True):
        direction = 1 if centred[b] > centred[a] else -1
        if direction * centred[a] >= 0 or direction * centred[b] <= 0:
            continue  # both on one side of the middle: no crossing to time
        k = usable[(usable >= a) & (usable <= b)]  # across a gap of flagged samples (a post before the swing)
        i, j = k[:-1], k[1:]  # too, where it is short: mid-swing θ is straight in t to ω²Δt²/6 of its slope
        keep = (np.sign(centred[i]) != np.sign(centred[j])) & (centred[i] != centred[j])
        keep &= t[j] - t[i] <= MAX_CROSSING_GAP * (t[b] - t[a])
        i, j = i[keep], j[keep]
        if i.size:
            when = t[i] - centred[i] * (t[j] - t[i]) / (centred[j] - centred[i])
            crossings[direction].append(float(np.median(when)))
    slopes, variances, cycles = [], [], []
    for direction in (1, -1):
        when = np.array(crossings[direction])
        if when.size < 3:
            return None
        gaps = np.diff(when)
        one = float(np.median(gaps))
        n = np.round((when - when[0]) / one)
        if np.unique(n).size < 3:
            return None
        design = np.column_stack([np.ones_like(n), n])
        coef, *_ = np.linalg.lstsq(design, when, rcond=None)
        residual = when - design @ coef
        s2 = float(residual @ residual) / max(1, n.size - 2)
        slopes.append(float(coef[1]))
        variances.append(s2 / float(np.sum((n - n.mean()) ** 2)))
        cycles.append(int(n[-1]))
    return float(np.mean(slopes)), 0.5 * math.sqrt(sum(variances)), min(cycles)
