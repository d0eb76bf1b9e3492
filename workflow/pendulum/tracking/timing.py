"""Frames the camera dropped or repeated under even time stamps, found from the motion and put right.

A phone that films at a constant frame rate still loses a frame now and then, or repeats one, while the
file's time stamps stay evenly spaced (the real apple clip: one frame lost at 4.6, 7.7 and 21.5 s, one
repeated at 6.8 s). Every later frame is then shown one frame period earlier or later than it was
taken: the record's phase steps by ω·Δt (0.5–1° at mid-swing there), which a fit cannot absorb and
discovery would blame on physics. The container cannot tell (its stamps are even); the motion can.

Between consecutive usable frames i | j, one polynomial of degree :data:`DEGREE` in time is fitted to the
:data:`HALF_WINDOW` positions on each side, with the frames from j on taken ``s`` frame periods later
(−1 ≤ s ≤ 2.5; x and y together). Where the motion is smooth a slip of s frames leaves a misfit of about
the step per frame (about 10 px at mid-swing on the apple clip, against 0.03 px of noise); the
boundary is a slip when shifting by s brings the misfit down to the clip's usual level (≤ 4× the median
over the moving boundaries) and lowers it by at least 5× that level, both halves of the window moving,
and it is the largest such boundary within its window. A window spans at most three frame periods more
than its twelve frames (flagged or lost frames inside it): a polynomial through a wider one cannot
follow the swing, and a shift would be found where only the curve is missed.
A slip whose turning points moved across it (both sides, along the motion, by half the distance it implies
and three times their usual move) is the picture moving, not the clock (a knock, a stabiliser): it is not applied
and ``picture_steps`` says so; nor is one where the body's measured size steps across it (a print turning onto a
ball's limb moves its centroid: ``look_steps``, :func:`_size_step`), nor are :data:`PLACE_SLIPS` or more at one
place of the path (the body passing it both ways: something behind it there pulls its track), which
``scene_places`` lists. A repeated frame (no motion from
the frame before where the motion is fast) is taken out first and flagged ``duplicate``. Near the turning points,
where the pendulum hardly moves during one frame period, a slip cannot be seen: the figures say how much of the
record was checked.

Implemented: ``time_s`` of frame k becomes t_k + Δ·m_k (m_k: the frames lost minus the frames repeated
before k, Δ the stamps' regular step (:func:`frame_period`)); the stamps are those of the frames summary.
"""

from __future__ import annotations

import numpy as np
import pandas as pd

from pendulum.camera.stamps import regular_times

HALF_WINDOW = 6  # usable frames on each side of a boundary
DEGREE = 4  # of the polynomial through a window (x and y)
MAX_SHIFT = 2.5  # frame periods a slip may be late (lost frames) ...
MOST_MISSING = 3  # frame periods a window may span beyond its own frames (flagged or lost frames in it)
MOST_EARLY = 1.0  # ... or early (a frame shown twice: time does not run backwards)
SMALLEST_SLIP = 0.15  # frame periods: smaller shifts are not reported or applied
MOVING = 20.0  # a window's half moves by at least this × the position noise (a slip shows only in motion)
CLEAN_FACTOR = 4.0  # a shifted fit at most this × the usual misfit
SLIP_FACTOR = 5.0  # the shift lowers the misfit by at least this × the usual (about 70 σ² of noise)
STILL_FRACTION = 0.05  # a repeated frame: a step under this share of the steps around it
MAX_ROUNDS = 3
UNEXPLAINED = 100.0  # a break this × the usual misfit that no shift mends: said (the apple's rough spots: 5–12×)
PICTURE_SHARE = 0.5  # turning points that move across a slip by this share of what it implies: the picture moved
ROUNDING_SHARE = 0.05  # of a frame period: corrected stamps may run back by this much (stamps rounded to ticks)
PICTURE_USUAL = 3.0  # ... and by this many times their usual movement from one swing to the next
PLACE_SLIPS = 3  # slips at least this many at one place of the path (both ways through it) are the scene's ...
PLACE_SHARE, PLACE_MIN_PX = 0.05, 3.0  # ... within this share of the path's spread (SD), at least this, of each other,
PLACE_PASSES = 0.5  # ... at this share of the body's passes through that place or more
LOOK_STEP_FACTOR = 5.0  # a slip across which the body's size steps by this × its usual step a frame period ...
LOOK_STEP_FLOOR = 1e-3  # ... (that step at least this share of its size): its look changed, not the clock


def _window_misfits(tau: np.ndarray, x: np.ndarray, y: np.ndarray, b: np.ndarray, shift) -> np.ndarray:
    """Residual sum of squares of one polynomial through each boundary's window: boundary ``b`` lies after
    usable frame b, its window is usable frames b−W+1 … b+W (``tau`` in frame periods; x and y together),
    the frames after the boundary taken ``shift`` periods later (a number, or one per boundary)."""
    w = HALF_WINDOW
    idx = b[:, None] + np.arange(-w + 1, w + 1)[None, :]
    t = tau[idx] - 0.5 * (tau[b] + tau[b + 1])[:, None]
    values = np.stack([x[idx], y[idx]], axis=-1)  # (B, 2W, 2)
    values = values - values.mean(axis=1, keepdims=True)
    right = (np.arange(2 * w) >= w)[None, :]
    u = (t + np.reshape(shift, (-1, 1)) * right) / w
    q, _ = np.linalg.qr(u[..., None] ** np.arange(DEGREE + 1))
    fitted = q @ (np.swapaxes(q, 1, 2) @ values)
    return ((values - fitted) ** 2).sum(axis=(1, 2))


def _boundaries(tau: np.ndarray) -> np.ndarray:
    """Boundaries whose windows hold nearly consecutive frames: at most MOST_MISSING frame periods more than
    consecutive frames would span (frames flagged, or lost at the boundary)."""
    w = HALF_WINDOW
    b = np.arange(w - 1, tau.size - w)
    gaps = np.diff(tau)
    idx = b[:, None] + np.arange(-w + 1, w)[None, :]  # the window's 2W − 1 gaps
    span = gaps[idx].sum(axis=1)
    return b[span < 2 * w - 1 + MOST_MISSING + 0.5]


def _moving(x: np.ndarray, y: np.ndarray, b: np.ndarray, noise_px: float) -> np.ndarray:
    """Boundaries whose window halves both move by MOVING × the noise or more (not a still hang, not a release)."""
    w = HALF_WINDOW
    before = np.hypot(x[b] - x[b - w + 1], y[b] - y[b - w + 1])
    after = np.hypot(x[b + w] - x[b + 1], y[b + w] - y[b + 1])
    return np.minimum(before, after) >= MOVING * max(noise_px, 1e-3)


def _best_shifts(tau, x, y, b) -> np.ndarray:
    """Per boundary: the shift (periods, within ±MAX_SHIFT) that fits best and its misfit, as two columns."""
    grid = np.arange(-MOST_EARLY, MAX_SHIFT + 1e-9, 0.25)
    misfits = np.stack([_window_misfits(tau, x, y, b, s) for s in grid], axis=1)
    best = grid[np.argmin(misfits, axis=1)]
    best_misfit = misfits.min(axis=1)
    step = 0.125
    for _ in range(5):  # halving around the best grid point
        for trial in (best - step, best + step):
            misfit = _window_misfits(tau, x, y, b, trial)
            better = misfit < best_misfit
            better &= trial >= -MOST_EARLY
            best = np.where(better, trial, best)
            best_misfit = np.where(better, misfit, best_misfit)
        step /= 2
    return np.column_stack([best, best_misfit])


def _repeated(tau: np.ndarray, x: np.ndarray, y: np.ndarray, noise_px: float) -> np.ndarray:
    """Usable frames that repeat the one before: a step under STILL_FRACTION of the steps before and after it,
    which point the same way (not a turning point) and are over 20× the position noise; the four frames
    consecutive."""
    d = np.column_stack([np.diff(x), np.diff(y)])  # d[k]: from frame k to k+1
    step = np.hypot(d[:, 0], d[:, 1])
    repeated = np.zeros(x.size, bool)
    if step.size < 3:
        return repeated
    before, after = step[:-2], step[2:]
    around = np.minimum(before, after)
    same_way = (d[:-2] * d[2:]).sum(axis=1) > 0.5 * before * after
    consecutive = np.abs(np.diff(tau) - 1.0) < 0.5
    consecutive = consecutive[:-2] & consecutive[1:-1] & consecutive[2:]
    small = np.maximum(STILL_FRACTION * around, 4.0 * noise_px)  # a repeat's step is the noise's alone
    still = (step[1:-1] < small) & same_way & (around > MOVING * noise_px) & consecutive
    repeated[2:-1][still] = True
    return repeated


def frame_period(stamp_s: np.ndarray) -> float:
    """The frame period of even stamps: the mean of the steps within half a period of their median (stamps
    rounded to milliseconds step by 16 and 17 ms at 60 fps: 16.667 ms, not their median's 17; a gap in the stamps
    left out). 0 where fewer than two stamps are finite."""
    steps = np.diff(stamp_s[np.isfinite(stamp_s)])
    if steps.size == 0:
        return 0.0
    typical = float(np.median(steps))
    regular = steps[np.abs(steps - typical) <= 0.5 * abs(typical)]
    return float(regular.mean()) if regular.size else typical


def path_turning_points(tau: np.ndarray, x: np.ndarray, y: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The swing's turning points: per completed half swing (a run of one sign of the position along the swing's
    main axis less its median) the time of its extreme, the side (+1, −1) and the (x, y) there, each to a fraction
    of a frame by the parabola through the extreme sample and its neighbours."""
    centred = np.column_stack([x - x.mean(), y - y.mean()])
    _, vectors = np.linalg.eigh(np.cov(centred.T))
    along = centred @ vectors[:, -1]
    side = np.sign(along - np.median(along))
    edges = np.flatnonzero(np.diff(side) != 0) + 1
    times, sides, points = [], [], []
    for a, e in zip(edges[:-1], edges[1:], strict=True):
        if e - a < 3:
            continue
        k = a + int(np.argmax(along[a:e] * side[a]))
        lo, mid, hi = along[k - 1], along[k], along[k + 1]
        curvature = lo - 2.0 * mid + hi
        d = float(np.clip(0.5 * (lo - hi) / curvature, -0.5, 0.5)) if curvature != 0 else 0.0
        at = [v[k] + 0.5 * d * (v[k + 1] - v[k - 1]) + 0.5 * d * d * (v[k + 1] - 2 * v[k] + v[k - 1]) for v in (x, y)]
        times.append(tau[k] + d * 0.5 * (tau[k + 1] - tau[k - 1]))
        sides.append(side[a])
        points.append(at)
    return np.array(times), np.array(sides), np.reshape(np.array(points, float), (-1, 2))


def _picture_step(turning, at_tau: float) -> tuple[np.ndarray | None, float]:
    """How far the swing's turning points moved across the moment ``at_tau`` beyond their usual move from one swing
    to the next, and the usual size of that excess. Per side of the swing: the move from its last turning point
    before the moment to its first after, less the median of its other moves (a shrinking swing, the rise of its
    ends, a creeping camera); the two sides' excesses averaged. None where a side has no turning point before or
    after the moment, or fewer than three other moves in all."""
    times, sides, points = turning
    across, excess = [], []
    for one in (1.0, -1.0):
        mine = sides == one
        t, moves = times[mine], np.diff(points[mine], axis=0)
        spans = (t[:-1] < at_tau) & (t[1:] > at_tau)
        if not spans.any() or not (~spans).any():
            return None, 0.0
        typical = np.median(moves[~spans], axis=0)
        across.append(moves[spans][0] - typical)
        excess.append(np.hypot(*(moves[~spans] - typical).T))
    excess = np.concatenate(excess)
    if excess.size < 3:  # too few swings to know how the turning points move
        return None, 0.0
    return np.mean(across, axis=0), float(np.median(excess))


def _moved_picture(tau, x, y, j: int, periods: float, turning, at_tau: float) -> np.ndarray | None:
    """The picture's step (px) where a slip of ``periods`` found after usable frame ``j`` is the picture moving
    instead, else None. A clock slip moves no turning point (the pendulum goes where it went, only later than its
    stamp says); a picture that moved along the motion there looks, over a few frames, like one: its turning points
    moved across the boundary along the motion by at least :data:`PICTURE_SHARE` of the distance the slip implies
    (the speed there × the shift), by :data:`PICTURE_USUAL` × their usual move, and more than across it."""
    step, usual = _picture_step(turning, at_tau)
    w = min(2, j, tau.size - j - 2)
    if step is None or w < 1:
        return None
    around = [i for i in range(j - w, j + w + 1) if i != j]
    velocity = np.mean(
        [[x[i + 1] - x[i], y[i + 1] - y[i]] / np.float64(max(tau[i + 1] - tau[i], 1e-9)) for i in around], axis=0
    )
    speed = float(np.hypot(*velocity))
    if speed <= 0:
        return None
    along = abs(float(step @ velocity)) / speed
    across = abs(float(step[0] * velocity[1] - step[1] * velocity[0])) / speed
    implied = abs(periods) * speed
    moved = along >= PICTURE_SHARE * implied and along >= PICTURE_USUAL * usual and along > across
    return step if moved else None


def _largest_in_window(misfit: np.ndarray, b: np.ndarray, chosen: np.ndarray) -> list[int]:
    """The chosen boundaries whose misfit is the largest of the chosen ones within a window's half of them (one
    event shows at every boundary whose window holds it: the middle one is taken)."""
    return [
        int(k) for k in np.flatnonzero(chosen) if misfit[k] >= misfit[chosen & (np.abs(b - b[k]) < HALF_WINDOW)].max()
    ]


def find_slips(
    frame: np.ndarray, stamp_s: np.ndarray, x: np.ndarray, y: np.ndarray, usable: np.ndarray, size=None
) -> dict:
    """Lost and repeated frames of one track (module docstring). ``size``: the body's measured size per frame (the
    track's ``quality``), where a step of it across a slip's boundary says the measured point moved on the body
    (``look_steps``), not the clock.

    Returns ``period_s`` (Δ), ``slips`` (``[frame, periods]``: from that frame on, every frame was taken
    that many periods later than its stamp says, on top of earlier slips; 1 a lost frame, −1 one shown
    twice; fractions where the phone's clock slipped by part of a period), ``repeated`` (frames that
    repeat the one before), ``shift_periods`` (m_k per frame) and ``checked_fraction`` (share of the
    usable frame pairs where a slip of one period would have stood out)."""
    stamp_s = np.asarray(stamp_s, float)
    period = frame_period(stamp_s)
    shift = np.zeros(stamp_s.size)
    result = {
        "period_s": period,
        "slips": [],
        "repeated": [],
        "picture_steps": [],
        "look_steps": [],
        "unexplained": [],
        "scene_places": [],
        "checked_fraction": 0.0,
        "shift_periods": shift,
    }
    usable = usable & np.isfinite(stamp_s)
    if not period > 0 or usable.sum() < 4 * HALF_WINDOW:
        return result
    idx = np.flatnonzero(usable)
    tau0 = stamp_s[idx] / period
    b = _boundaries(tau0)
    if b.size < 2 * HALF_WINDOW:
        return result
    unshifted = _window_misfits(tau0, x[idx], y[idx], b, 0.0)
    noise_px = float(np.sqrt(np.median(unshifted) / (2 * (2 * HALF_WINDOW - DEGREE - 1))))
    repeated_mask = _repeated(tau0, x[idx], y[idx], noise_px)
    # a repeated frame shows the moment of the one before, and the frames after it a period later than their
    # stamps (unless a frame is lost after it too: the search below finds that)
    result["repeated"] = [int(frame[i]) for i in idx[repeated_mask]]
    for i in idx[repeated_mask]:
        shift[i:] -= 1
    idx = idx[~repeated_mask]
    turning = path_turning_points(stamp_s[idx] / period, x[idx], y[idx])
    sizes = None if size is None else np.nan_to_num(np.asarray(size, float)[idx])
    refused: set[int] = set()  # boundaries (usable frame after them) where the picture moved, not the clock
    applied_at: list[tuple[int, float]] = []  # (usable frame after the boundary, periods) of each slip applied
    for round_ in range(MAX_ROUNDS):
        tau = stamp_s[idx] / period + shift[idx]
        b = _boundaries(tau)
        unshifted = _window_misfits(tau, x[idx], y[idx], b, 0.0)
        moving = _moving(x[idx], y[idx], b, noise_px)
        if not moving.any():
            break
        usual = max(float(np.median(unshifted[moving])), 1e-9)  # a still hang's windows are noise alone
        if round_ == 0:  # where a slip of one period would have stood out, of every pair of usable frames
            one = np.minimum(*(_window_misfits(tau, x[idx], y[idx], b, s) for s in (-1.0, 1.0)))
            standing_out = moving & (np.maximum(one, unshifted) >= SLIP_FACTOR * usual)
            result["checked_fraction"] = float(standing_out.sum() / max(idx.size - 1, 1))
        suspect = np.flatnonzero(moving & (unshifted >= SLIP_FACTOR * usual) & ~np.isin(idx[b + 1], list(refused)))
        if suspect.size == 0:
            break
        best = _best_shifts(tau, x[idx], y[idx], b[suspect])
        slip = (
            (best[:, 1] <= CLEAN_FACTOR * usual)
            & (unshifted[suspect] - best[:, 1] >= SLIP_FACTOR * usual)
            & (np.abs(best[:, 0]) >= SMALLEST_SLIP)
        )
        found = _largest_in_window(unshifted[suspect], b[suspect], slip)
        applied = 0
        for k in found:
            j = b[suspect[k]]
            periods = round(float(best[k, 0]), 2)
            look = _size_step(tau, sizes, j, periods)
            if look > LOOK_STEP_FACTOR:  # the body's look changed there (a turning print): not the clock
                refused.add(int(idx[j + 1]))
                result["look_steps"].append([int(frame[idx[j + 1]]), periods, round(look, 1)])
                continue
            moved = _moved_picture(tau, x[idx], y[idx], j, periods, turning, stamp_s[idx[j]] / period)
            if moved is not None:  # the picture jumped (a knock, a stabiliser): not the clock
                refused.add(int(idx[j + 1]))
                result["picture_steps"].append([int(frame[idx[j + 1]]), [round(float(v), 2) for v in moved]])
                continue
            shift[idx[j + 1] :] += periods
            applied_at.append((int(idx[j + 1]), periods))
            applied += 1
        if not applied:
            break
    for i, periods, place in _at_one_place(applied_at, x, y, idx):  # the scene there biases the track: no slip
        shift[i:] -= periods
        refused.add(i)
        result["scene_places"].append([int(frame[i]), place])
    # breaks in the motion that no shift explains (two slips within a window, more frames lost than MAX_SHIFT):
    # the frames after them may be off by a period or more; said, not mended
    tau = stamp_s[idx] / period + shift[idx]
    b = _boundaries(tau)
    if b.size:
        unshifted = _window_misfits(tau, x[idx], y[idx], b, 0.0)
        moving = _moving(x[idx], y[idx], b, noise_px)
        usual = max(float(np.median(unshifted[moving])), 1e-9) if moving.any() else 1e-9
        broken = moving & (unshifted >= UNEXPLAINED * usual) & ~np.isin(idx[b + 1], list(refused))
        result["unexplained"] = [int(frame[idx[b[k] + 1]]) for k in _largest_in_window(unshifted, b, broken)]
    # a frame taken at the moment of the one before: a repeat the first look did not see (the motion slower there)
    result["repeated"] = sorted(set(result["repeated"]) | {int(frame[i]) for i in idx[1:][np.diff(tau) < 0.15]})
    steps = np.diff(np.concatenate([[0.0], shift]))
    repeated = set(result["repeated"])
    result["slips"] = []
    for i in np.flatnonzero(np.abs(steps) > 1e-9):
        periods = float(steps[i]) + (1.0 if int(frame[i]) in repeated else 0.0)  # a repeat's own −1 said as such
        if abs(periods) >= SMALLEST_SLIP:
            result["slips"].append([int(frame[i]), round(periods, 2)])
    result["shift_periods"] = shift
    return result


def _size_step(tau: np.ndarray, sizes, j: int, periods: float) -> float:
    """The body's measured size (``sizes`` per usable frame; None where the track is not a silhouette's) across
    boundary ``j``: its step per frame period the boundary spans with the frames after it ``periods`` later (a lost
    frame: two), over its median step between consecutive frames (at least :data:`LOOK_STEP_FLOOR`); 0 where no size
    is given. A slip of the clock leaves the body's picture as it was; a print turning onto a two-tone ball's limb
    steps its colour silhouette's size and moves its centroid (a helper's 1080p render: 0.27 and 0.38 of a frame
    taken for slips, its size stepping 9.3 and 5.3 times its usual rate; one frame deleted at 30 fast moments of
    each of ten body tracks, the real apple's among them: 1.1–3.3 times)."""
    if sizes is None:
        return 0.0
    consecutive = np.abs(np.diff(tau)) < 1.5
    steps = np.abs(np.diff(sizes))[consecutive]
    usual = max(float(np.median(steps)) if steps.size else 0.0, LOOK_STEP_FLOOR)
    spanned = max(float(tau[j + 1] - tau[j]) + periods, 1.0)
    return float(abs(sizes[j + 1] - sizes[j]) / spanned / usual)


def _at_one_place(applied: list[tuple[int, float]], x: np.ndarray, y: np.ndarray, idx: np.ndarray) -> list:
    """Of the slips ``applied`` (frame index after each, periods), those at one place of the path: at least
    :data:`PLACE_SLIPS` within max(:data:`PLACE_SHARE` × the path's spread, two frames' step there,
    :data:`PLACE_MIN_PX`) of each other, found at :data:`PLACE_PASSES` or more of the body's passes through that
    place. A phone's lost frames fall anywhere in the fast part of the swing, at a few of its passes; breaks in the
    motion at most passes through one place, both ways (its track pulled there by an edge or a reflection behind
    it, a clock's case), are the scene's.
    Returns ``(index, periods, [x, y])`` of each."""
    if len(applied) < PLACE_SLIPS:
        return []
    at = np.array([[x[i], y[i]] for i, _ in applied])
    path = np.column_stack([x[idx], y[idx]])
    centred = path - path.mean(axis=0)
    axis = np.linalg.svd(centred, full_matrices=False)[2][0]  # the path's main direction
    # a slip is seen at the frame after the break, up to a frame's motion beyond the place that causes it, either way
    moves = np.array([[x[i] - x[i - 1], y[i] - y[i - 1]] if i > 0 else [0.0, 0.0] for i, _ in applied])
    reach = max(
        PLACE_SHARE * float(np.hypot(*centred.std(axis=0))), 2 * float(np.median(np.hypot(*moves.T))), PLACE_MIN_PX
    )
    near = np.hypot(*(at[:, None, :] - at[None, :, :]).transpose(2, 0, 1)) <= reach
    direction = moves @ axis  # the way each passes the place
    chosen = np.zeros(len(applied), bool)
    for k in np.flatnonzero(near.sum(axis=1) >= PLACE_SLIPS):
        members = near[k] & ~chosen
        along = centred @ axis - float((at[k] - path.mean(axis=0)) @ axis)
        passes = int(np.count_nonzero(np.diff(np.sign(along[along != 0])) != 0))
        ways = {int(np.sign(direction[m])) for m in np.flatnonzero(members)}  # passing the place both ways
        if members.sum() >= PLACE_SLIPS and members.sum() >= PLACE_PASSES * passes and ways >= {-1, 1}:
            chosen |= members
    return [(i, p, [round(float(v), 1) for v in at[k]]) for k, (i, p) in enumerate(applied) if chosen[k]]


def correct_slips(track: pd.DataFrame) -> pd.DataFrame:
    """``track`` with ``time_s`` put right for lost and repeated frames (:func:`find_slips` on its ``ok`` and
    ``jump`` frames, with a body silhouette's size, its ``quality``; stamps rounded to a coarse tick first taken as
    the regular clock they round: :func:`pendulum.camera.stamps.regular_times`), repeated frames flagged
    ``duplicate``, and ``jump`` frames beside a slip that fit the corrected motion made ``ok``; ``attrs["timing"]``
    says what was found."""
    if track.empty:
        return track
    # a frame the marker tracker saw repeat the one before (the same picture) is flagged duplicate already: its
    # position is the one before's, and the frames after it may be a period late
    usable = track.flag.isin(("ok", "jump", "duplicate")).to_numpy()
    x = track.x_px.to_numpy(float)
    y = track.y_px.to_numpy(float)
    stamp = track.time_s.to_numpy(float)
    rounded = regular_times(stamp)  # stamps rounded to a coarse tick: the regular clock they round (camera.stamps)
    if rounded is not None:
        stamp = rounded[0]
    body = track.attrs.get("body") or {}
    silhouette = bool(body) and body.get("by") != "look" and not track.attrs.get("marker")
    size = track.quality.to_numpy(float) if silhouette and "quality" in track else None  # a silhouette's area
    found = find_slips(track.frame.to_numpy(), stamp, x, y, usable & np.isfinite(x) & np.isfinite(y), size)
    out = track.copy()
    out.attrs = dict(track.attrs)
    period = found["period_s"]
    shift = found.pop("shift_periods")
    corrected = stamp + period * shift
    # never (a safeguard), but for stamps rounded to a coarse tick (a repeat's moment a rounding before the frame's
    # before it: max.accumulate below takes that): a step back of a twentieth of a period is no rounding
    if np.any(np.diff(corrected[np.isfinite(corrected)]) < -ROUNDING_SHARE * max(period, 1e-9)):
        shift[:] = 0.0
        corrected = stamp.copy()
        found.update(slips=[], repeated=[], note="slips found made time run backwards: none applied")
    finite = np.isfinite(corrected)  # a repeat's moment is the frame's before it, not a rounding error earlier
    corrected[finite] = np.maximum.accumulate(corrected[finite])
    out["stamp_s"] = stamp  # the file's time stamp (the contact sheet's times)
    out["time_s"] = corrected
    repeated = out.frame.isin(found["repeated"]).to_numpy()
    out.loc[repeated, "flag"] = "duplicate"
    cleared = _clear_jumps(out, found)
    out.attrs["timing"] = {
        **found,
        "jumps_cleared": cleared,
        "checked_fraction": round(found["checked_fraction"], 4),
        "rounded_stamps_tick_s": None if rounded is None else rounded[1],
        "max_shift_s": round(float(np.abs(period * shift).max()), 6) if shift.size else 0.0,
    }
    return out


def at_capture_rate(track: pd.DataFrame, capture_fps: float | None) -> pd.DataFrame:
    """``track`` with its times at the rate the camera filmed, where the file plays at another rate: a phone's
    slow-motion clip (filmed at 240 fps, stored to play at 30) stamps its frames 8 times too far apart, and every
    period and decay of its record comes out 8 times too slow. ``time_s`` × 1 / (capture_fps · Δ), Δ the stamps'
    regular step (:func:`frame_period`); ``stamp_s`` keeps the file's stamps (the contact sheet's times, and those
    of ``attrs["timing"]``); ``attrs["time_base"]`` says what was done. ``capture_fps`` None: ``track`` as it is."""
    if capture_fps is None or track.empty:
        return track
    stamp = (track["stamp_s"] if "stamp_s" in track else track.time_s).to_numpy(float)
    step = frame_period(stamp)
    if not step > 0:  # one frame: no time to scale
        return track
    scale = 1.0 / (capture_fps * step)
    out = track.copy()
    out.attrs = dict(track.attrs)
    out["stamp_s"] = stamp
    out["time_s"] = track.time_s.to_numpy(float) * scale
    out.attrs["time_base"] = {"capture_fps": float(capture_fps), "file_fps": round(1.0 / step, 4), "scale": scale}
    return out


def _clear_jumps(out: pd.DataFrame, found: dict) -> list[int]:
    """``jump`` frames within two frames of a slip or a repeat whose position now lies on the local polynomial
    (fitted to the ok frames around them in corrected time; residual under 4× theirs): made ``ok``."""
    marks = [f for f, _ in found["slips"]] + list(found["repeated"])
    if not marks:
        return []
    frames = out.frame.to_numpy()
    flags = out.flag.to_numpy()
    t = out.time_s.to_numpy(float) / found["period_s"]
    x = out.x_px.to_numpy(float)
    y = out.y_px.to_numpy(float)
    cleared = []
    for i in np.flatnonzero(flags == "jump"):
        if min(abs(int(frames[i]) - m) for m in marks) > 2:
            continue
        near = np.flatnonzero((flags == "ok") & (np.abs(np.arange(frames.size) - i) <= HALF_WINDOW + 2))
        if near.size < 2 * HALF_WINDOW - 2:
            continue
        u = (t[near] - t[i]) / HALF_WINDOW
        design = u[:, None] ** np.arange(DEGREE + 1)
        coef, *_ = np.linalg.lstsq(design, np.stack([x[near], y[near]], axis=1), rcond=None)
        residual = np.stack([x[near], y[near]], axis=1) - design @ coef
        spread = float(np.sqrt((residual**2).sum() / max(1, 2 * (near.size - DEGREE - 1))))
        miss = float(np.hypot(x[i] - coef[0, 0], y[i] - coef[0, 1]))
        if miss <= max(4.0 * spread, 0.05):
            flags[i] = "ok"
            cleared.append(int(frames[i]))
    out["flag"] = flags
    return cleared
