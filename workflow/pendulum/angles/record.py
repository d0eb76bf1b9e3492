"""A marker track or a Tracker table → the angle record: θ(t) about the pivot, release found, rest trimmed.

θ = atan2(x − x_p, y − y_p) − φ, with image y pointing down, the pivot at (x_p, y_p) and φ the image
angle of the true vertical (camera roll); θ > 0 swings to +x. Bad input raises :class:`InputError`,
which names the file and what to do.
"""

from __future__ import annotations

import hashlib
import io
import math
from dataclasses import asdict, dataclass, field
from pathlib import Path

import numpy as np
import pandas as pd

from pendulum.angles.geometry import circular_mean_rad, image_angle_rad, wrapped_rad
from pendulum.angles.harmonics import second_harmonic
from pendulum.angles.swings import (
    crossing_period,
    detect_release,
    noise_level,
    record_noise_floor_rad,
    release_by_hand,
    rest_start_index,
    swing_extrema,
    turn_at_knock,
)

MAX_HANG_DEG = 60.0  # a swing centred further from the vertical it is measured from: the vertical is not the camera's


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
    noise_deg: float  # the record's noise σ (swings.record_noise_floor_rad), the one every stage and the report say
    # frames the tracker found held (the body with a hand) before the first free one: a release by hand in view,
    # its instant and hold angle from the free swing's start (swings.release_by_hand)
    held_frames: int = 0
    arm_radius_px: float | None = None  # pivot to marker, median over the tracked samples
    pivot_covariance_px2: list | None = None  # of an estimated pivot (None: given, taken as exact)
    # the record's mean period from the crossings of its middle level (swings.crossing_period), its standard error
    # and the whole periods it spans; None where the record holds fewer than two
    period_s: float | None = None
    period_stderr_s: float | None = None
    period_cycles: int | None = None
    # θ at the record's first turning point (its first sample where it starts just past one): the swing's
    # amplitude and side, as a release angle, where no release is in view
    first_extremum_deg: float | None = None
    # the record's second harmonic, which a planar swing seen square-on does not have (harmonics.second_harmonic)
    second_harmonic: dict | None = None
    # a knocked camera's turn (swings.turn_at_knock): measured from the swing's centre on either side of the knock,
    # taken out of θ after it where it is clear of its error; None without a knock
    camera_turn: dict | None = None
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
    theta = wrapped_rad(theta)  # in [−π, π) whatever the vertical
    if not np.isfinite(t).all() or np.any(np.diff(t) < 0):
        raise InputError(f"{source}: times are missing or not in order; cannot make an angle record")
    usable = (flag == "ok") & np.isfinite(theta)
    held = flag == "held"  # the body with the hand that holds it (the tracker's flag)
    theta = np.where(usable, theta, np.nan)
    try:
        release = detect_release(t, theta)
    except ValueError as exc:
        raise InputError(f"{source}: {exc}") from exc
    # held by hand before the first usable sample: its first frames, slow near the turning point, are no hold
    first_free = int(np.flatnonzero(np.isfinite(theta))[0])
    by_hand = release_by_hand(t, theta, held, first_free)
    release = by_hand or release
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
        held_frames=int((held[:first_free] & (t[:first_free] < release.time_s)).sum()) if by_hand else 0,
        noise_deg=math.degrees(record_noise_floor_rad(theta, t)),
        arm_radius_px=arm_radius_px,
        pivot_covariance_px2=pivot_covariance_px2,
    )
    if by_hand:
        where = "" if release.hold_angle_rad is None else f" at {math.degrees(release.hold_angle_rad):+.2f}°"
        letting_go = int(held[:first_free].sum()) - info.held_frames  # the hand still over it as it draws back
        info.notes.append(
            f"released by hand in view: {info.held_frames} frame(s) held (the body with the hand) before it was let "
            f"go{where} at {release.time_s:.3f} s (video time, from the free swing's start)"
            + (f", {letting_go} more with the hand still over it as it drew back" if letting_go else "")
        )
    period = crossing_period(table.time_s.to_numpy(float), table.theta_rad.to_numpy(float))
    if period is not None:
        info.period_s, info.period_stderr_s, info.period_cycles = period
        usable = (table.flag == "ok").to_numpy()
        info.second_harmonic = second_harmonic(
            table.time_s.to_numpy(float)[usable], table.theta_rad.to_numpy(float)[usable], period[0], info.noise_deg
        )
    extrema = swing_extrema(table.theta_rad.to_numpy(float))
    if extrema.size:
        first = float(table.theta_deg.iloc[int(extrema[0])])
        start = table.theta_deg.dropna()
        start = float(start.iloc[0]) if len(start) else first
        # a record that starts just past a turning point on the other side (the apple clip: −22.06°, then +22.07°)
        # starts at that turning point, as a release would; one that starts on its way back from a turning point
        # out of view (a fresh-eyes user's clip cropped at one end: −18.5°, moving at 40 % of the swing's speed)
        # takes the first turning point it reaches
        at_rest = _starts_slowly(table, first, info.period_s)
        info.first_extremum_deg = start if start * first < 0 and abs(start) > 0.5 * abs(first) and at_rest else first
    return table, info


START_SPEED_SHARE = 0.25  # of the swing's top speed ω|θ_max|: a record starting slower starts at a turning point


def _starts_slowly(table: pd.DataFrame, first_deg: float, period_s: float | None) -> bool:
    """Whether the record's first samples move at under :data:`START_SPEED_SHARE` of the swing's top speed
    (2π/T)|θ₁|, θ₁ its first turning point: the slope at the first sample of a parabola through the samples of the
    first twelfth of a period (at least three). True where the period is not known (no speed to compare)."""
    if period_s is None or not math.isfinite(period_s) or period_s <= 0:
        return True
    seen = table.dropna(subset=["theta_deg"])
    t, theta = seen.time_s.to_numpy(float), seen.theta_deg.to_numpy(float)
    if t.size < 3:
        return True
    n = max(3, int(np.searchsorted(t, t[0] + period_s / 12, side="right")))
    slope = np.polyfit(t[:n] - t[0], theta[:n], 2)[-2]  # dθ/dt at the first sample (through 3 samples: exact)
    return abs(slope) < START_SPEED_SHARE * 2 * math.pi / period_s * abs(first_deg)


def record_digest(table: pd.DataFrame) -> str:
    """SHA-256 of a record's times and angles as written (``%.10g``): two trials with the same digest are one
    recording under two names (a video copied, or exported twice, and tracked alike), not two measurements."""
    text = table[["time_s", "theta_rad"]].to_csv(index=False, float_format="%.10g", lineterminator="\n")
    return hashlib.sha256(text.encode()).hexdigest()


def vertical_turned_with_the_picture(track: pd.DataFrame, pivot_px, vertical_deg: float, rotation_deg: float):
    """The vertical given, turned by the file's display rotation (a phone held upright stores its picture on its
    side and asks players to turn it): ``vertical_deg ± rotation_deg`` whichever the swing hangs within
    MAX_HANG_DEG of, where it hangs further than that from the vertical given; else None (the vertical given
    fits the swing, or neither turn does: :func:`angles_from_track` then says where it hangs)."""
    if not rotation_deg or len(pivot_px) != 2:
        return None
    ok = (track.flag == "ok").to_numpy()
    x, y = (pd.to_numeric(track[c], errors="coerce").to_numpy(float)[ok] for c in ("x_px", "y_px"))
    theta = image_angle_rad(x, y, pivot_px)
    theta = theta[np.isfinite(theta)]
    if theta.size == 0:
        return None
    hang = circular_mean_rad(theta)
    if abs(math.degrees(wrapped_rad(hang - math.radians(vertical_deg)))) <= MAX_HANG_DEG:
        return None
    for turned in (vertical_deg + rotation_deg, vertical_deg - rotation_deg):
        if abs(math.degrees(wrapped_rad(hang - math.radians(turned)))) <= MAX_HANG_DEG:
            return math.degrees(wrapped_rad(math.radians(turned)))
    return None


def angles_from_track(
    track: pd.DataFrame,
    *,
    pivot_px,
    vertical_deg: float,
    length_m: float,
    source: str,
    pivot_covariance_px2=None,
    knock: dict | None = None,
):
    """Angle record of a marker track (see :func:`angle_record`); a malformed track raises :class:`InputError`.

    ``knock``: the camera knocked (the track's path document, ``creep.knock``): the picture's turn then
    (:func:`~pendulum.angles.swings.turn_at_knock`) is taken out of θ from the knock on, where it is clear of its
    error, and said in ``info.camera_turn`` and its notes."""
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
    if ok.any():  # where the swing hangs against the vertical it is measured from: a camera on its side or upside down
        hangs_deg = math.degrees(circular_mean_rad(theta_img[ok] - math.radians(vertical_deg)))
        if abs(hangs_deg) > MAX_HANG_DEG:
            raise InputError(
                f"{source}: the swing hangs {hangs_deg:+.0f}° from the vertical it is measured from "
                f"({vertical_deg:g}° in the image): the camera is on its side or upside down, or vertical_deg is "
                "wrong; set vertical_deg: null in its rig's entry in config.yaml (rigs: <rig>: vertical_deg: null) to "
                "have it estimated from the swing (a sidecar's vertical_deg is a number within ±45°)"
            )
    turn = None
    if knock and ok.any():  # measured about the swing's own middle: no wrap at ±180° (a camera upside down)
        middle = circular_mean_rad(theta_img[ok])
        turn = turn_at_knock(columns["time_s"], np.where(ok, wrapped_rad(theta_img - middle), np.nan), knock)
        if turn and turn["taken_out"]:
            theta_img = np.where(
                columns["time_s"] >= knock["from_s"], theta_img - math.radians(turn["turn_deg"]), theta_img
            )
    table, info = angle_record(
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
    if turn is not None:
        info.camera_turn = {"time_s": knock["time_s"], **turn}
        if turn["taken_out"]:
            info.notes.append(knock_turn_sentence(info.camera_turn))
    return table, info


def knock_turn_sentence(turn: dict) -> str:
    """What was done about a knocked camera's turn (:attr:`AngleRecordInfo.camera_turn`, taken out)."""
    return (
        f"the camera turned by {turn['turn_deg']:+.3f}° (± {turn['stderr_deg']:.3f}°) when it was knocked at "
        f"{turn['time_s']:.2f} s (the swing's centre moved by that much): taken out of θ from then on"
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


SECOND_RECORD_ROWS = 10  # rows on each side of a step back in time, at the same times: a second record
JAGGED_RATIO = 3.0  # ... whose angles, sorted in with the first's, make a record this much noisier than either


def _second_record(t: np.ndarray, deg: np.ndarray) -> tuple[int, int] | None:
    """(row, rows on the fewer side) of a step back in time where the rows before and after it, each in time order
    but for a few, cover the same times in at least :data:`SECOND_RECORD_ROWS` rows each, with other angles, and
    sorted together make a jagged record (:data:`JAGGED_RATIO`: two records one after the other in one file); None
    where sorting by time makes one record (rows out of order, a block of rows repeated or tracked again, a record's
    even rows then its odd ones)."""
    steps = np.diff(t)
    if (steps < 0).sum() > 3:  # shuffled rows, not two records
        return None
    k = int(np.argmin(steps)) + 1
    before, after = t[:k], t[k:]
    low, high = max(before.min(), after.min()), min(before.max(), after.max())
    inside = (after >= low) & (after <= high)
    fewer = min(int(((before >= low) & (before <= high)).sum()), int(inside.sum()))
    copies = set(zip(before.tolist(), deg[:k].tolist(), strict=True))
    copied = sum((x, y) in copies for x, y in zip(after[inside].tolist(), deg[k:][inside].tolist(), strict=True))
    if not (high > low and fewer >= SECOND_RECORD_ROWS and copied < fewer / 2):
        return None
    # two records interleave when sorted, another angle at each time: jagged; two parts of one record merge smoothly
    merged = noise_level(deg[np.argsort(t, kind="stable")])
    return (k, fewer) if merged > JAGGED_RATIO * max(noise_level(deg[:k]), noise_level(deg[k:]), 1e-9) else None


def angles_from_tracker_csv(table: pd.DataFrame, *, vertical_deg: float, length_m: float, source: str):
    """Angle record of an angle export (columns ``t_s``, ``theta_deg``, as Tracker writes).

    Imperfect rows are dealt with and listed in ``info.notes``: rows without a
    time are dropped; missing or infinite angles are flagged ``lost``; rows out
    of time order are sorted; exact repeats are dropped; a later row at a time
    already used is flagged ``duplicate``. Raises :class:`InputError` (naming
    ``source``) for missing columns, text in a number column, angles beyond
    ±180°, times repeated in more than 10 % of the rows, two records one after the
    other (:func:`_second_record`), or no swing.
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
        if (restart := _second_record(t, deg)) is not None:
            k, overlap = restart
            raise InputError(
                f"{source}: t_s goes back at data row {k + 1} (from {t[k - 1]:g} s to {t[k]:g} s), and {overlap} rows "
                "before it and after it cover the same times: two records in one file (a logger restarted)? Keep one "
                "record per file"
            )
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
