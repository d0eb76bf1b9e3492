"""Angles stage: marker track → θ(t) about the pivot, release detection, trimming.

θ = atan2(x − x_p, y − y_p) − φ, with image y pointing down, the pivot at
(x_p, y_p) and φ the image angle of the true vertical (camera roll); θ > 0
swings to +x. The arc displacement is s = L θ. The pivot, when not given, is
the centre of a circle fitted to the marker path (pooled over a rig's trials);
the vertical, when not given, is the centre of the oscillation.
"""

from __future__ import annotations

import io
import math
from dataclasses import asdict, dataclass, field
from pathlib import Path

import numpy as np
import pandas as pd
from scipy.optimize import least_squares


@dataclass
class CircleFit:
    pivot_x_px: float
    pivot_y_px: float
    radius_px: float
    rms_px: float
    n_points: int
    arc_span_deg: float
    pivot_covariance_px2: list | None = None  # 2×2 covariance of (x_p, y_p), for the error budget
    effective_points: float | None = None  # n corrected for the residuals' autocorrelation


def fit_circle(x, y, weights=None) -> CircleFit:
    """Geometric least-squares circle (algebraic Kåsa fit as the start), minimising Σ w (|p − c| − R)².

    ``weights`` w per point (None: all 1). The pivot covariance is σ² (JᵀWJ)⁻¹
    with σ² = Σ w r² / (n − 3), inflated for the residuals' lag-1 correlation.
    """
    x = np.asarray(x, float)
    y = np.asarray(y, float)
    good = np.isfinite(x) & np.isfinite(y)
    x, y = x[good], y[good]
    root_w = None if weights is None else np.sqrt(np.asarray(weights, float)[good])
    if x.size < 10:
        raise ValueError(f"a circle fit needs at least 10 tracked points, got {x.size}")
    a = np.column_stack([x, y, np.ones_like(x)])
    b = x**2 + y**2
    (c0, c1, c2), *_ = np.linalg.lstsq(a, b, rcond=None)
    cx, cy = c0 / 2, c1 / 2
    r0 = math.sqrt(max(c2 + cx**2 + cy**2, 1e-9))

    def residual(p):
        return np.hypot(x - p[0], y - p[1]) - p[2]

    if root_w is None:
        sol = least_squares(residual, [cx, cy, r0], x_scale="jac")
    else:
        sol = least_squares(lambda p: root_w * residual(p), [cx, cy, r0], x_scale="jac")
    cx, cy, r = sol.x
    ang = np.degrees(np.arctan2(x - cx, y - cy))
    # Covariance σ² (JᵀJ)⁻¹, with n replaced by an effective count n (1 − ρ)/(1 + ρ):
    # neighbouring track points share their errors (texture, blur), ρ is the lag-1 correlation.
    res = sol.fun
    rho = float(np.clip(np.corrcoef(res[1:], res[:-1])[0, 1], 0.0, 0.99)) if res.size > 3 else 0.0
    n_eff = max(x.size * (1 - rho) / (1 + rho), 4.0)
    sigma2 = float(res @ res) / max(x.size - 3, 1)
    cov = np.linalg.pinv(sol.jac.T @ sol.jac) * sigma2 * x.size / n_eff
    return CircleFit(
        float(cx),
        float(cy),
        float(r),
        float(np.sqrt(np.mean(res**2))) if root_w is None else float(np.sqrt(np.mean(residual(sol.x) ** 2))),
        int(x.size),
        float(np.ptp(ang)),
        cov[:2, :2].tolist(),
        float(n_eff),
    )


def image_angle_rad(x, y, pivot_px) -> np.ndarray:
    """atan2(x − x_p, y − y_p): the marker's angle from the image's downward vertical."""
    return np.arctan2(np.asarray(x, float) - pivot_px[0], np.asarray(y, float) - pivot_px[1])


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

    The extrema are the confirmed ones of :func:`swing_extrema` (hysteresis of
    10 σ, so noise makes none, at any frame rate), each refined by a parabola
    through the samples within a sixth of the way to its neighbouring extrema.
    Per triplet (p₀, q, p₁), locally geometric decay gives
    c = (p₀ p₁ − q²) / (p₀ + p₁ − 2 q); the median over triplets whose swing is
    above 20 σ. None if no such triplet.
    """
    th = np.asarray(theta, float)
    idx = np.flatnonzero(np.isfinite(th))
    if idx.size < 20:
        return None
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
        if near.size >= 5:
            a, b, c = np.polyfit(idx[near] - idx[i], v[near], 2)
            if a != 0 and abs(b / (2 * a)) <= half:
                value = c - b * b / (4 * a)
        values.append(value)
    centres = []
    for k in range(len(values) - 2):
        p0, q, p1 = values[k : k + 3]
        swing = abs(q - 0.5 * (p0 + p1))
        if swing > 20 * sigma and np.sign(p0 - q) == np.sign(p1 - q) and p0 + p1 - 2 * q != 0:
            centres.append((p0 * p1 - q * q) / (p0 + p1 - 2 * q))
    if not centres:
        return None
    return float(np.median(centres)), len(centres)


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


def sample_noise_rad(theta: np.ndarray) -> float:
    """Sample noise σ of a record: MAD of its fifth differences / √252 (white noise: var Δ⁵θ = 252 σ²).

    The swing's own fifth differences, θ0 (ωΔt)⁵, stay far below a tracker's noise where the third
    ones do not (60°, period 1.6 s, 30 fps: 0.002° against 0.13°); unbiased within 1 % for
    σ = 0.005° at 0–75° (50 seeds, tests/test_angles.py).
    """
    return _difference_sigma(theta, 5)


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
    the release is its first sample.
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


@dataclass
class AngleRecordInfo:
    source: str
    pivot_px: list | None
    vertical_deg: float
    length_m: float
    release_detected: bool
    release_time_s: float
    hold_angle_deg: float | None
    first_frame: int | None
    n_samples: int
    n_flagged: int
    rest_from_s: float | None
    noise_deg: float
    arm_radius_px: float | None = None  # pivot to marker, median over the tracked samples
    pivot_covariance_px2: list | None = None  # of an estimated pivot (None: given, taken as exact)
    notes: list = field(default_factory=list)  # what was done about imperfect input (sorted, dropped rows, …)

    def to_dict(self):
        return asdict(self)


def angle_record(
    time_s,
    theta_image_rad,
    quality,
    flag,
    *,
    vertical_deg: float,
    length_m: float,
    source: str,
    pivot_px=None,
    frame=None,
    keep_rest_s: float = 2.0,
    arm_radius_px: float | None = None,
    pivot_covariance_px2=None,
) -> tuple[pd.DataFrame, AngleRecordInfo]:
    """θ relative to the vertical, trimmed to the free decay (release → shortly after coming to rest).

    Output columns: ``time_s`` (since release), ``video_time_s``, ``frame``,
    ``theta_rad``, ``theta_deg``, ``s_m`` (= L θ), ``quality``, ``flag``.
    Flagged samples keep θ = NaN (never interpolated). Times must be finite and
    in order; a record without a swing raises :class:`InputError` naming ``source``.
    """
    t = np.asarray(time_s, float)
    flag = np.asarray(flag, dtype=object)
    theta = np.asarray(theta_image_rad, float) - math.radians(vertical_deg)
    theta = np.mod(theta + math.pi, 2 * math.pi) - math.pi  # in [−π, π) whatever the vertical
    if not np.isfinite(t).all() or np.any(np.diff(t) < 0):
        raise InputError(f"{source}: times are missing or not in order; cannot make an angle record")
    usable = (flag == "ok") & np.isfinite(theta)
    theta = np.where(usable, theta, np.nan)
    try:
        release = detect_release(t, theta)
    except ValueError as exc:
        raise InputError(f"{source}: {exc}") from exc
    end = t.size
    rest = rest_start_index(theta)
    rest_from = None
    if rest is not None and rest > release.first_sample:
        rest_from = float(t[rest])
        end = int(np.searchsorted(t, t[rest] + keep_rest_s, side="right"))
    sl = slice(release.first_sample, end)
    table = pd.DataFrame(
        {
            "time_s": t[sl] - release.time_s,
            "video_time_s": t[sl],
            "frame": (np.arange(t.size) if frame is None else np.asarray(frame))[sl],
            "theta_rad": theta[sl],
            "theta_deg": np.degrees(theta[sl]),
            "s_m": length_m * theta[sl],
            "quality": np.asarray(quality, float)[sl],
            "flag": flag[sl],
        }
    )
    info = AngleRecordInfo(
        source=source,
        pivot_px=None if pivot_px is None else [float(pivot_px[0]), float(pivot_px[1])],
        vertical_deg=float(vertical_deg),
        length_m=float(length_m),
        release_detected=release.detected,
        release_time_s=release.time_s,
        hold_angle_deg=None if release.hold_angle_rad is None else math.degrees(release.hold_angle_rad),
        first_frame=int(table.frame.iloc[0]) if len(table) else None,
        n_samples=int(len(table)),
        n_flagged=int((table.flag != "ok").sum()),
        rest_from_s=rest_from,
        noise_deg=math.degrees(sample_noise_rad(theta)),
        arm_radius_px=arm_radius_px,
        pivot_covariance_px2=pivot_covariance_px2,
    )
    return table, info


def angles_from_track(
    track: pd.DataFrame, *, pivot_px, vertical_deg: float, length_m: float, source: str, pivot_covariance_px2=None
):
    """Angle record of a marker track (see :func:`angle_record`); a malformed track raises :class:`InputError`."""
    missing = {"frame", "time_s", "x_px", "y_px", "quality", "flag"} - set(track.columns)
    if missing:
        raise InputError(f"{source}: the track lacks column(s) {sorted(missing)}")
    if len(pivot_px) != 2 or not np.isfinite(np.asarray(pivot_px, float)).all():
        raise InputError(f"{source}: the pivot {pivot_px!r} is not a finite pixel position (x, y)")
    columns = {c: pd.to_numeric(track[c], errors="coerce").to_numpy(float) for c in ("time_s", "x_px", "y_px")}
    x, y = columns["x_px"], columns["y_px"]
    with np.errstate(over="ignore", invalid="ignore"):
        theta_img = image_angle_rad(x, y, pivot_px)
        radius = np.hypot(x - pivot_px[0], y - pivot_px[1])
    # a position on the pivot (or not finite) has no angle
    ok = (track.flag == "ok").to_numpy() & np.isfinite(theta_img) & np.isfinite(radius) & (radius >= 1.0)
    flag = np.where(ok | (track.flag != "ok").to_numpy(), track.flag.to_numpy(object), "lost")
    return angle_record(
        columns["time_s"],
        theta_img,
        pd.to_numeric(track.quality, errors="coerce").to_numpy(float),
        flag,
        vertical_deg=vertical_deg,
        length_m=length_m,
        source=source,
        pivot_px=pivot_px,
        frame=track.frame,
        arm_radius_px=float(np.median(radius[ok])) if ok.any() else None,
        pivot_covariance_px2=pivot_covariance_px2,
    )


class InputError(ValueError):
    """A bad angle table or track: the message names the file and the problem."""


ANGLE_TABLE_COLUMNS = ("t_s", "theta_deg")
MAX_REPEATED_TIME_FRACTION = 0.1  # more rows at an already used time than this: the time column is broken


def read_tracker_csv(path) -> pd.DataFrame:
    """Read an angle table (``t_s``, ``theta_deg``) as exported by Tracker or a spreadsheet.

    Comma-, semicolon- (with decimal commas) and tab-separated files are read;
    an empty or unparsable file raises :class:`InputError` naming it.
    """
    path = Path(path)
    try:
        text = path.read_text(encoding="utf-8-sig", errors="replace")
    except OSError as exc:
        raise InputError(f"{path}: cannot be read ({exc.strerror or exc})") from exc
    if not text.strip():
        raise InputError(f"{path}: empty file; export the angle table again (columns t_s, theta_deg)")
    header = text.lstrip().splitlines()[0]
    sep = max((",", ";", "\t"), key=header.count)
    try:
        return pd.read_csv(io.StringIO(text), sep=sep, decimal="," if sep == ";" else ".")
    except (pd.errors.ParserError, pd.errors.EmptyDataError, ValueError) as exc:
        reason = str(exc).strip().splitlines()[0] if str(exc).strip() else type(exc).__name__
        raise InputError(f"{path}: not a readable CSV table ({reason}); export it again") from exc


def _numeric(table: pd.DataFrame, column: str, source: str) -> np.ndarray:
    """A column as floats; text that is not a number raises :class:`InputError` (blank cells are NaN)."""
    raw = table[column]
    values = pd.to_numeric(raw, errors="coerce")
    text = raw.astype(str).str.strip()
    bad = values.isna() & raw.notna() & (text != "") & ~text.str.lower().isin(("nan", "na", "n/a", "null", "none"))
    if bad.any():
        rows = np.flatnonzero(bad.to_numpy())
        more = f" and {rows.size - 1} more" if rows.size > 1 else ""
        raise InputError(
            f"{source}: column {column} holds text that is not a number ({text.iloc[rows[0]]!r} on line "
            f"{rows[0] + 2}{more}); fix those cells or export again"
        )
    return values.to_numpy(float)


def angles_from_tracker_csv(table: pd.DataFrame, *, vertical_deg: float, length_m: float, source: str):
    """Angle record of an angle export (columns ``t_s``, ``theta_deg``, as Tracker writes).

    Imperfect rows are dealt with and listed in ``info.notes``: rows without a
    time are dropped; missing or infinite angles are flagged ``lost``; rows out
    of time order are sorted; exact repeats are dropped; a later row at a time
    already used is flagged ``duplicate``. Raises :class:`InputError` (naming
    ``source``) for missing columns, text in a number column, angles beyond
    ±180°, times repeated in more than 10 % of the rows, or no swing.
    """
    missing = set(ANGLE_TABLE_COLUMNS) - set(table.columns)
    if missing:
        names = [str(c) for c in table.columns]
        found = f"found {names[:6]}" if all(n.isprintable() for n in names) else "no readable header: not a text CSV?"
        raise InputError(
            f"{source}: angle table lacks column(s) {sorted(missing)}; expected t_s and theta_deg ({found})"
        )
    t = _numeric(table, "t_s", source)
    deg = _numeric(table, "theta_deg", source)
    notes = []
    timed = np.isfinite(t)
    if not timed.all():
        notes.append(f"{int((~timed).sum())} row(s) without a time dropped")
        t, deg = t[timed], deg[timed]
    with np.errstate(invalid="ignore"):
        beyond = np.abs(deg) > 180
    if beyond.any():
        raise InputError(
            f"{source}: theta_deg reaches {deg[beyond][0]:g}°, beyond ±180°; is the column an angle in degrees?"
        )
    if np.any(np.diff(t) < 0):
        notes.append("rows were not in time order; sorted by t_s")
        order = np.argsort(t, kind="stable")
        t, deg = t[order], deg[order]
    same_row = np.concatenate([[False], (np.diff(t) == 0) & ((deg[1:] == deg[:-1]) | ~np.isfinite(deg[1:]))])
    if same_row.any():
        notes.append(f"{int(same_row.sum())} repeated row(s) dropped")
        t, deg = t[~same_row], deg[~same_row]
    repeated = np.concatenate([[False], np.diff(t) == 0])
    if repeated.sum() > MAX_REPEATED_TIME_FRACTION * max(t.size, 1):
        raise InputError(
            f"{source}: {int(repeated.sum())} of {t.size} rows repeat an earlier time with another angle; "
            "export t_s with more decimals"
        )
    finite = np.isfinite(deg)
    flag = np.where(repeated, "duplicate", np.where(finite, "ok", "lost"))
    if repeated.any():
        notes.append(f"{int(repeated.sum())} row(s) at an already used time flagged duplicate")
    if (~finite).any():
        notes.append(f"{int((~finite).sum())} missing angle(s) flagged lost")
    table_out, info = angle_record(
        t,
        np.radians(np.where(finite, deg, np.nan)),
        finite.astype(float),
        flag,
        vertical_deg=vertical_deg,
        length_m=length_m,
        source=source,
    )
    info.notes = notes
    return table_out, info


OUTLIER_TRACK_FACTOR = 8.0  # a track this many times the others' circle RMS off their circle is left out
OUTLIER_TRACK_FLOOR_PX = 1.0  # ... and at least this far (px RMS)


def _radial_rms_px(track: pd.DataFrame, circle: CircleFit) -> float:
    ok = track.flag == "ok"
    d = np.hypot(track.x_px[ok] - circle.pivot_x_px, track.y_px[ok] - circle.pivot_y_px) - circle.radius_px
    return float(np.sqrt(np.mean(d.to_numpy(float) ** 2))) if ok.any() else math.inf


NOISY_TRACK_FACTOR = 2.0  # a track more than this × the median track's RMS off the circle is down-weighted
STILL_TOLERANCE_PX = 0.5  # a run of ok frames all this close to their running mean ...
STILL_MIN_FRAMES = 10  # ... and at least this long is the marker held still: one point of the path


def path_points(track: pd.DataFrame) -> tuple[np.ndarray, np.ndarray]:
    """The ok positions of a track, each run of ≥ 10 frames within 0.5 px of its running mean (the hold
    before the release, the rest after it) replaced by its median: one position measured many times.

    Its frames share one error (the same sub-pixel phase, a video codec's persistent blocks: a new
    user's 1.5 s hold was 0.11 px off in all 42 frames while the swing's frames were within 0.035 px);
    counted 42 times, that error moved the pooled pivot by 2.3 px on a 27° arc.
    """
    ok = (track.flag == "ok").to_numpy()
    x, y = track.x_px.to_numpy(float)[ok], track.y_px.to_numpy(float)[ok]
    keep_x, keep_y = [], []
    i = 0
    while i < x.size:
        j, sx, sy = i + 1, x[i], y[i]
        while j < x.size and math.hypot(x[j] - sx / (j - i), y[j] - sy / (j - i)) <= STILL_TOLERANCE_PX:
            sx, sy, j = sx + x[j], sy + y[j], j + 1
        if j - i >= STILL_MIN_FRAMES:
            keep_x.append(float(np.median(x[i:j])))
            keep_y.append(float(np.median(y[i:j])))
            i = j
        else:
            keep_x.append(float(x[i]))
            keep_y.append(float(y[i]))
            i += 1
    return np.array(keep_x), np.array(keep_y)


def _pooled_circle(tracks: dict[str, pd.DataFrame]) -> CircleFit:
    """Circle through the pooled paths (:func:`path_points`), each track weighted min(1, (2 σ_median / σ_k)²).

    σ_k is track k's RMS distance from the unweighted pooled circle: a track
    noisier than twice the median counts by its inverse variance. When no track
    is that noisy every weight is 1 and the unweighted fit is the answer.
    """
    names = list(tracks)  # the callers' order: the pooled sums are the same numbers every time
    points = {n: path_points(tracks[n]) for n in names}
    xs = np.concatenate([points[n][0] for n in names])
    ys = np.concatenate([points[n][1] for n in names])
    circle = fit_circle(xs, ys)
    if len(tracks) < 2:
        return circle
    spread = {n: _radial_rms_px(tracks[n], circle) for n in names}
    median = float(np.median([v for v in spread.values() if math.isfinite(v)] or [0.0]))
    weight = {n: min(1.0, (NOISY_TRACK_FACTOR * median / spread[n]) ** 2) if spread[n] > 0 else 1.0 for n in names}
    if all(w == 1.0 for w in weight.values()):
        return circle
    w = np.concatenate([np.full(points[n][0].size, weight[n]) for n in names])
    return fit_circle(xs, ys, weights=w)


def pooled_pivot(tracks: dict[str, pd.DataFrame]) -> tuple[CircleFit, dict[str, str]]:
    """Circle through the pooled marker paths, leaving out tracks that are not on it.

    With three or more tracks, the track farthest off the pooled circle (RMS
    radial distance) is compared with the circle fitted to the others: more than
    OUTLIER_TRACK_FACTOR × their RMS and more than OUTLIER_TRACK_FLOOR_PX off, it
    is left out (a moved camera, a tracked reflection) and the test repeated.
    Returns the circle and {trial: reason} of the tracks left out.
    """
    kept = dict(tracks)
    rejected: dict[str, str] = {}
    circle = _pooled_circle(kept)
    while len(kept) >= 3:
        worst = max(sorted(kept), key=lambda name: _radial_rms_px(kept[name], circle))
        others = {k: v for k, v in kept.items() if k != worst}
        reference = _pooled_circle(others)
        off = _radial_rms_px(kept[worst], reference)
        limit = max(OUTLIER_TRACK_FACTOR * reference.rms_px, OUTLIER_TRACK_FLOOR_PX)
        if not off > limit:
            break
        rejected[worst] = (
            f"its marker path is {off:.2f} px RMS off the circle through the other {len(others)} trials' paths "
            f"(limit {limit:.2f} px): camera moved or wrong object tracked? Give its pivot_px in a sidecar"
        )
        kept, circle = others, reference
    return circle, rejected


def off_rig_circle(track: pd.DataFrame, geometry: dict) -> str | None:
    """Why a track cannot use its rig's pooled pivot (its path is off the rig's circle), or None."""
    circle = geometry.get("circle")
    if not circle:
        return None
    off = _radial_rms_px(track, CircleFit(**circle))
    limit = max(OUTLIER_TRACK_FACTOR * circle["rms_px"], OUTLIER_TRACK_FLOOR_PX)
    if off > limit:
        return (
            f"the marker path is {off:.2f} px RMS off the rig's pivot circle (limit {limit:.2f} px): "
            "camera moved or wrong object tracked? Give this trial's pivot_px in a sidecar"
        )
    return None


def pivot_uncertainty(pivot_covariance_px2, radius_px: float, vertical_deg: float) -> dict:
    """Standard errors of an estimated pivot and the angle offset they cause.

    A pivot error δp moves every angle by the component of δp across the arm at
    rest, divided by the arm: σ_θ = √(eᵀ C e) / R with e = (cos φ, −sin φ), φ the
    vertical's image angle (a constant offset, absorbed by the fits' rest offset).
    """
    cov = np.asarray(pivot_covariance_px2, float)
    phi = math.radians(vertical_deg)
    e = np.array([math.cos(phi), -math.sin(phi)])
    return {
        "pivot_stderr_px": [float(math.sqrt(max(cov[0, 0], 0.0))), float(math.sqrt(max(cov[1, 1], 0.0)))],
        "angle_offset_stderr_deg": float(math.degrees(math.sqrt(max(e @ cov @ e, 0.0)) / radius_px)),
    }


def estimate_rig_geometry(tracks: dict[str, pd.DataFrame], pivot_px=None, vertical_deg=None) -> dict:
    """Pivot (circle through the pooled marker paths, outlying tracks left out) and vertical.

    The vertical is the median oscillation centre (:func:`swing_centre_rad`, any
    amplitude) of the tracks used; when no track has a clean swing it is the
    image vertical (0°) with a warning under ``warnings`` (the fits' rest offset
    absorbs a camera roll). Values given are kept; only the missing ones are
    estimated. An estimated pivot comes with ``pivot_stderr_px`` and
    ``angle_offset_stderr_deg``.
    """
    result: dict = {"trials": sorted(tracks), "rejected_trials": {}, "warnings": []}
    if pivot_px is None:
        if not tracks:
            raise ValueError("no trial has a usable track to estimate the pivot from; give pivot_px")
        circle, rejected = pooled_pivot(tracks)
        tracks = {k: v for k, v in tracks.items() if k not in rejected}
        pivot_px = [circle.pivot_x_px, circle.pivot_y_px]
        result["rejected_trials"] = rejected
        result["pivot_source"] = f"estimated: circle fitted to the pooled marker paths of {len(tracks)} trial(s)"
        result["circle"] = asdict(circle)
        result["pivot_covariance_px2"] = circle.pivot_covariance_px2
    else:
        result["pivot_source"] = "given"
    result["pivot_px"] = [float(pivot_px[0]), float(pivot_px[1])]
    if vertical_deg is None:
        centres = []
        for track in tracks.values():
            th = image_angle_rad(track.x_px.where(track.flag == "ok"), track.y_px.where(track.flag == "ok"), pivot_px)
            found = swing_centre_rad(th)
            if found is not None:
                centres.append(found[0])
        if centres:
            vertical_deg = math.degrees(float(np.median(centres)))
            result["vertical_source"] = f"estimated: median oscillation centre of {len(centres)} trial(s)"
        else:
            vertical_deg = 0.0
            why = "no usable track" if not tracks else "no trial has a clean swing (three extrema above the noise)"
            result["vertical_source"] = "image vertical (not estimated)"
            result["warnings"].append(
                f"cannot estimate the vertical ({why}); the image vertical (0°) is used: the fits' rest offset "
                "absorbs a camera roll, give vertical_deg to state it"
            )
    else:
        result["vertical_source"] = "given"
    result["vertical_deg"] = float(vertical_deg)
    if result.get("circle") and result["pivot_covariance_px2"] is not None:
        result.update(pivot_uncertainty(result["pivot_covariance_px2"], result["circle"]["radius_px"], vertical_deg))
    return result
