"""The pivot where a rod's lines meet, and how it joins the pivot of the swing's arc.

Each line the tracks stage drew along a rod or thread (:func:`pendulum.tracking.rod.rod_lines`) passes through the
pivot. The point nearest all of them in the least-squares sense, p = (Σ nᵢnᵢᵀ)⁻¹ Σ nᵢnᵢᵀ qᵢ (nᵢ a line's unit
normal, qᵢ a point on it), is the rod's pivot; its covariance σ² (Σ nᵢnᵢᵀ)⁻¹ from the lines' scatter about it, with
a floor of :data:`ROD_SCALE_FLOOR` of the arm along it (a rod not quite straight, a thread that sags; or the turn's
slope's distance from 1, below, where more) and :data:`ROD_FLOOR_PX` in every direction. It is the rod's only where
the lines pass within :data:`MAX_MEET_RMS_PX` of it (RMS) and turn with the body, the line's angle against the
body's about that point at a slope within :data:`MAX_TURN_MISMATCH` of one (a fixed edge's lines do not turn; a
rod's shadow cast along the arm meets it elsewhere: its slope is off 1 by as much, and of two signs' lines the one
nearer 1 is taken, :func:`best_rod`). Where the arc leaves the angles' scale uncertain by more than
:data:`ROD_WORTH_PCT` and the two pivots agree (their difference within the 99.9 % ellipse of their summed
covariances), they are joined, weighted by their inverse covariances (:func:`joined_pivot`); where they disagree the
arc's stands, and the geometry says why.
"""

from __future__ import annotations

import math

import numpy as np

ROD_SCALE_FLOOR = 0.005  # of the arm: the rod's pivot along the arm at best to this (1σ)
# ... and to this in every direction, as the arc's (ARC_FLOOR_PX): two pivots each known across its own arm to a
# tenth of a pixel, their arms 1.7° apart, were joined 27 px along the arm from both (a helper's render)
ROD_FLOOR_PX = 1.0
# The lines' turn against the body's about where they meet: a slope of 1 ± this. A slope s off 1 puts that point
# (1 − s) of the arm off the body's pivot along it, the angles' scale as far off: a light rod's dark shadow, cast
# downwards, 0.960 and 0.969 in a helper's renders (its lines meet 20 px along a 640 px arm from the pivot); their
# rods 0.9992–1.0007, another helper's clocks' 0.9975–1.0053
MAX_TURN_MISMATCH = 0.01  # or three of the slope's standard errors where more (a swing of ±1°: 0.007 each), up to
MAX_TURN_MISMATCH_NOISY = 0.02  # this (a light rod's shadow whose lines scatter: 0.960 ± 0.016)
MAX_MEET_RMS_PX = 1.0  # the lines' RMS distance from where they meet: one straight rod's (a helper's clocks: 0.04–0.3)
MIN_TURN_DEG = 0.5  # the body's angles about the rod's pivot spread over this at least (their SD)
# A line of the other sign alongside the rod's (its shadow on a wall close behind): the rod's place is pulled by it,
# by an amount that changes with the angle as the two part (a light rod 4.6 px from its shadow in a render: its
# pivot 1.9 % of the arm off along it, the turn's slope 1.003), so its pivot is known along the arm to this at best
BESIDE_PX, BESIDE_SCALE = 10.0, 0.015
ROD_WORTH_PCT = 0.5  # the arc's angle-scale σ above which the rod's pivot is joined to it
AGREE_CHI2 = 13.82  # χ² with 2 degrees of freedom at 99.9 %
# The arc's pivot, joined with a rod's, at best to this every way: its own covariance put a helper's clocks (4–5°
# swings) 0.03 px across the arm, where they were 0.4–0.5 px off, and its x–y correlation would carry that into y
ARC_FLOOR_PX = 1.0


def rod_pivot(lines) -> dict:
    """The rod's pivot from ``lines`` (rows ``[x_near, y_near, x_far, y_far, body_x, body_y]`` in the geometry's
    coordinates): ``pivot_px``, ``pivot_covariance_px2``, ``lines``, ``rms_px`` (the lines' RMS distance from it)
    and ``turn_slope``; with ``reason`` where they do not make a rod's pivot (module docstring)."""
    a = np.asarray(lines, float).reshape(-1, 6)
    a = a[np.isfinite(a).all(axis=1)]
    near, far, body = a[:, 0:2], a[:, 2:4], a[:, 4:6]
    d = far - near
    d /= np.hypot(d[:, 0], d[:, 1])[:, None]
    normals = np.column_stack([d[:, 1], -d[:, 0]])
    m = np.einsum("ni,nj->ij", normals, normals)
    if a.shape[0] < 3 or np.linalg.cond(m) > 1e12:
        return {"lines": int(a.shape[0]), "reason": "the lines are parallel: they meet nowhere"}
    v = np.einsum("ni,nj,nj->i", normals, normals, near)
    pivot = np.linalg.solve(m, v)
    residual = np.einsum("ni,ni->n", normals, pivot - near)
    sigma2 = float(np.sum(residual**2) / max(a.shape[0] - 2, 1))
    covariance = sigma2 * np.linalg.inv(m)
    arm = body - pivot
    arm_px = float(np.median(np.hypot(arm[:, 0], arm[:, 1])))
    along = np.median(arm, axis=0)
    along /= np.hypot(*along)
    covariance += ROD_FLOOR_PX**2 * np.eye(2)
    middle = math.atan2(along[0], along[1])  # angles about the arm's middle direction (a camera upside down: ±π)
    body_rad = (np.arctan2(arm[:, 0], arm[:, 1]) - middle + math.pi) % (2 * math.pi) - math.pi
    line_rad = np.arctan2(-d[:, 0], -d[:, 1]) - middle  # the line from its far end (the pivot's side) to the body
    line_rad = body_rad + (line_rad - body_rad + math.pi) % (2 * math.pi) - math.pi
    result = {
        "pivot_px": [float(pivot[0]), float(pivot[1])],
        "pivot_covariance_px2": covariance.tolist(),
        "pivot_body_direction": along.round(6).tolist(),  # along the arm, from the pivot to the body
        "lines": int(a.shape[0]),
        "rms_px": round(float(np.sqrt(np.mean(residual**2))), 4),
        "arm_px": round(arm_px, 2),
        "turn_slope": None,
    }
    if result["rms_px"] > MAX_MEET_RMS_PX:  # the real apple's thread: 3.4 px, its pivot 84 px from the arc's
        return {
            **result,
            "reason": f"the lines pass {result['rms_px']:.1f} px RMS from where they meet: no one straight rod",
        }
    spread_deg = math.degrees(float(np.std(body_rad)))
    if spread_deg < MIN_TURN_DEG:
        return {**result, "reason": f"the body turns by only {spread_deg:.2f}° (SD) about where the lines meet"}
    (slope, _), cov = np.polyfit(body_rad, line_rad, 1, cov="unscaled")
    residual_turn = line_rad - np.polyval([slope, _], body_rad)
    slope_se = math.sqrt(float(cov[0, 0]) * float(np.sum(residual_turn**2)) / max(a.shape[0] - 2, 1))
    result.update(turn_slope=round(float(slope), 4), turn_slope_se=round(slope_se, 4))
    if abs(slope - 1.0) > min(max(MAX_TURN_MISMATCH, 3.0 * slope_se), MAX_TURN_MISMATCH_NOISY):
        return {**result, "reason": f"the lines turn {slope:.3f} times as far as the body: not the body's rod"}
    along_px = max(ROD_SCALE_FLOOR, abs(slope - 1.0), slope_se) * arm_px  # the floor, or the scale the slope doubts
    result["pivot_covariance_px2"] = (covariance + along_px**2 * np.outer(along, along)).tolist()
    return result


def best_rod(lines) -> dict:
    """Of the lines of each sign (rows ``[sign, x_near, y_near, x_far, y_far, body_x, body_y]``), the rod's pivot
    (:func:`rod_pivot`) whose lines turn with the body most nearly (a light rod beside its dark shadow: both draw
    lines, the shadow's often more), with its ``polarity``; where neither is a rod's, the sign with more lines and
    its reason."""
    a = np.asarray(lines, float).reshape(-1, 7)
    found = []
    for sign, polarity in ((1.0, "bright"), (-1.0, "dark")):
        mine = a[a[:, 0] == sign, 1:]
        if len(mine):
            found.append({**rod_pivot(mine), "polarity": polarity})
    rods = [r for r in found if "reason" not in r]
    if not rods:
        return max(found, key=lambda r: r["lines"]) if found else {"lines": 0, "reason": "no lines"}
    rod = min(rods, key=lambda r: abs(r["turn_slope"] - 1.0))
    beside = _beside_px(a, 1.0 if rod["polarity"] == "bright" else -1.0)
    if beside is not None and beside <= BESIDE_PX:
        rod["beside_px"] = round(beside, 2)
        along = np.asarray(rod["pivot_body_direction"])
        covariance = np.asarray(rod["pivot_covariance_px2"])
        short = (BESIDE_SCALE * rod["arm_px"]) ** 2 - float(along @ covariance @ along)
        rod["pivot_covariance_px2"] = (covariance + max(short, 0.0) * np.outer(along, along)).tolist()
    return rod


def _beside_px(a: np.ndarray, sign: float) -> float | None:
    """The median distance of the other sign's lines from this sign's, in the frames both drew one (matched by the
    body's place), at the lines' ends; None where they share no frame."""
    other = {(row[5], row[6]): row for row in a[a[:, 0] == -sign]}
    distances = []
    for row in a[a[:, 0] == sign]:
        match = other.get((row[5], row[6]))
        if match is None:
            continue
        near, far = row[1:3], row[3:5]
        u = (far - near) / np.hypot(*(far - near))
        normal = np.array([u[1], -u[0]])
        distances += [abs(float(normal @ (match[1:3] - near))), abs(float(normal @ (match[3:5] - near)))]
    return float(np.median(distances)) if distances else None


def joined_pivot(arc_px, arc_covariance, rod: dict) -> tuple[np.ndarray, np.ndarray, float]:
    """The arc's pivot and the rod's joined by their inverse covariances (the arc's with :data:`ARC_FLOOR_PX` in
    every direction), with the squared Mahalanobis distance between them (over their summed covariances)."""
    p_arc, c_arc = np.asarray(arc_px, float), np.asarray(arc_covariance, float) + ARC_FLOOR_PX**2 * np.eye(2)
    p_rod, c_rod = np.asarray(rod["pivot_px"], float), np.asarray(rod["pivot_covariance_px2"], float)
    difference = p_arc - p_rod
    distance2 = float(difference @ np.linalg.solve(c_arc + c_rod, difference))
    w_arc, w_rod = np.linalg.inv(c_arc), np.linalg.inv(c_rod)
    covariance = np.linalg.inv(w_arc + w_rod)
    return covariance @ (w_arc @ p_arc + w_rod @ p_rod), covariance, distance2


def join_rod(geometry: dict, rod_lines) -> bool:
    """The rig's ``geometry`` (:func:`pendulum.angles.geometry.estimate_rig_geometry`'s, its arc's pivot and covariance
    in it) with the rod's pivot from ``rod_lines`` (:func:`best_rod`) joined (:func:`joined_pivot`) where the arc
    leaves the angles' scale uncertain by over :data:`ROD_WORTH_PCT` and the two agree; ``geometry["rod"]`` says
    what the rod's lines gave and whether, or why not, they were used. True where they were."""
    if not len(rod_lines):
        return False
    rod = best_rod(rod_lines)
    facts = {k: v for k, v in rod.items() if k != "pivot_covariance_px2"}
    facts["pivot_stderr_px"] = [round(math.sqrt(v), 3) for v in np.diag(rod.get("pivot_covariance_px2", []))]
    geometry["rod"] = facts
    arc_pct = geometry.get("angle_scale_stderr_pct", 0.0)
    if "reason" in rod:
        facts["used"] = False
        return False
    if arc_pct <= ROD_WORTH_PCT:
        facts.update(used=False, reason=f"the arc places the pivot well enough (the angles' scale ± {arc_pct:.2f} %)")
        return False
    pivot, covariance, distance2 = joined_pivot(geometry["pivot_px"], geometry["pivot_covariance_px2"], rod)
    facts["sigmas_from_arc"] = round(math.sqrt(distance2), 2)
    if distance2 > AGREE_CHI2:
        facts.update(used=False, reason=f"its pivot is {math.sqrt(distance2):.1f} σ from the arc's")
        geometry["warnings"].append(
            f"the rod's lines in {rod['lines']} frames meet at ({rod['pivot_px'][0]:.1f}, {rod['pivot_px'][1]:.1f}) "
            f"px, {math.sqrt(distance2):.1f} σ from the arc's pivot: not used (a bent rod, its shadow taken for it, "
            "or a tracking bias across the arc); give pivot_px if the pivot can be seen"
        )
        return False
    facts["used"] = True
    geometry["arc_pivot_px"] = geometry["pivot_px"]
    geometry["pivot_px"] = [float(pivot[0]), float(pivot[1])]
    geometry["pivot_covariance_px2"] = covariance.tolist()
    geometry["pivot_source"] += f"; joined with where a rod's lines meet in {rod['lines']} frames"
    return True
