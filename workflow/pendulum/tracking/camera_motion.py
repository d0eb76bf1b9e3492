"""The picture's own motion, measured from the still scene: a phone held in the hand.

A track whose path is no circle (:func:`pendulum.tracking.path_shape.path_departure`) may be a pendulum
filmed by a camera that moves: each frame then shows the still scene moved and turned a little. That
motion is measured from the scene itself: each frame is aligned to the median of frames sampled over the
clip (each brought back onto their first median: the motion blurs it) by OpenCV's ECC (``findTransformECC``,
Euclidean: a shift and a turn; insensitive to brightness and contrast), with everything the pendulum sweeps
(the wedge from its pivot to its path, as wide as the body) left out by a mask, at ≤ :data:`WIDTH_PX` px
across. A tracked position p in frame k is brought to the scene's frame by the inverse of that frame's
motion, p' = Rₖᵀ (p − tₖ). A plain wall gives ECC nothing to hold: a frame that does not converge, or whose
misfit 1 − ρ is over :data:`MISFIT_RATIO` × the clip's usual, is not aligned, and where fewer than
:data:`MIN_ALIGNED` of the frames are, none is (the track is left as it was).
"""

from __future__ import annotations

import math

import cv2
import numpy as np
import pandas as pd

from pendulum.camera.video import iter_luma
from pendulum.tracking.path_shape import path_departure
from pendulum.tracking.samples import spread_frames

WIDTH_PX = 480  # frames aligned at most this wide (a 1080p frame at a quarter)
SCENE_SAMPLES = 15  # frames for the still scene's median (between this and twice it)
MIN_CORRELATION = 0.6  # ECC's correlation coefficient of an aligned frame at least ...
MISFIT_RATIO = 3.0  # ... and its misfit 1 − ρ at most this × the clip's median
MIN_ALIGNED = 0.9  # share of the frames that must align for any to be moved
MIN_STILL_SHARE = 0.2  # of the picture left to align on once the swing's wedge is masked
BLUR_PX = 5  # ECC's own Gaussian before it aligns


def _swing_mask(shape, track: pd.DataFrame, radius_px: float) -> np.ndarray | None:
    """255 where the picture is still: not the wedge from the pivot (the circle through the ok positions) to the
    path, widened by the body's size; None where too little is left."""
    ok = (track.flag == "ok").to_numpy()
    x, y = track.x_px.to_numpy(float)[ok], track.y_px.to_numpy(float)[ok]
    if x.size < 10:
        return None
    (c0, c1, _), *_ = np.linalg.lstsq(np.column_stack([x, y, np.ones_like(x)]), x**2 + y**2, rcond=None)
    pivot = (int(round(c0 / 2)), int(round(c1 / 2)))
    mask = np.full(shape, 255, np.uint8)
    width = int(round(2.5 * radius_px + 12))
    for k in np.unique(np.linspace(0, x.size - 1, min(x.size, 200)).astype(int)):
        end = (int(round(x[k])), int(round(y[k])))
        cv2.line(mask, pivot, end, 0, 2 * width)  # OpenCV clips the line to the picture
        cv2.circle(mask, end, 2 * width, 0, -1)
    return mask if np.count_nonzero(mask) >= MIN_STILL_SHARE * mask.size else None


def picture_motion(path, track: pd.DataFrame, radius_px: float) -> dict | None:
    """Per frame of ``track`` (its ``frame`` column), the picture's motion against the still scene: ``angle_rad``,
    ``shift_px`` (n × 2, full resolution) and ``correlation`` (NaN: not aligned); None where the still part of
    the picture is too small or too plain to align on (fewer than :data:`MIN_ALIGNED` of the frames)."""
    samples, _ = spread_frames(path, SCENE_SAMPLES)
    images = [image for _, image in samples]
    if not images:
        return None
    shape = images[0].shape
    mask = _swing_mask(shape, track, radius_px)
    if mask is None:
        return None
    scale = max(1, math.ceil(shape[1] / WIDTH_PX))
    size = (shape[1] // scale, shape[0] // scale)
    small = [cv2.resize(image.astype(np.float32), size, interpolation=cv2.INTER_AREA) for image in images]
    small_mask = cv2.resize(mask, size, interpolation=cv2.INTER_NEAREST)
    scene = np.median(np.stack(small), axis=0).astype(np.float32)
    # the samples' median is blurred by the motion itself: each sample brought back onto it, the median again
    back = []
    for image in small:
        found = _align(scene, image, small_mask, np.eye(2, 3, dtype=np.float32))
        if found is not None:
            back.append(cv2.warpAffine(image, found[1], size, flags=cv2.INTER_LINEAR | cv2.WARP_INVERSE_MAP))
    if len(back) >= MIN_ALIGNED * len(small):
        scene = np.median(np.stack(back), axis=0).astype(np.float32)
    rows = {int(f): k for k, f in enumerate(track.frame.to_numpy())}
    angle = np.full(len(track), np.nan)
    shift = np.full((len(track), 2), np.nan)
    correlation = np.full(len(track), np.nan)
    warp = np.eye(2, 3, dtype=np.float32)
    for index, _, image in iter_luma(path):
        k = rows.get(int(index))
        if k is None or image is None:
            continue
        aligned = _align(
            scene, cv2.resize(image.astype(np.float32), size, interpolation=cv2.INTER_AREA), small_mask, warp
        )
        if aligned is None:
            continue
        rho, found = aligned
        warp = found  # the next frame starts where this one ended
        angle[k] = math.atan2(float(found[1, 0]), float(found[0, 0]))
        # a point x of the scene is at R x + t in the frame (full resolution: t scaled, the turn about the origin)
        shift[k] = found[:, 2] * scale
        correlation[k] = rho
    # a frame aligns where ECC's misfit 1 − ρ is at most MISFIT_RATIO × the clip's usual (its own evidence: a frame
    # whose alignment caught on the wrong detail, or a hand before the scene) and ρ above MIN_CORRELATION
    if np.isfinite(correlation).any():
        usual = float(np.nanmedian(1 - correlation))
        bad = ~((correlation >= MIN_CORRELATION) & (1 - correlation <= MISFIT_RATIO * usual))
        angle[bad], shift[bad], correlation[bad] = np.nan, np.nan, np.nan
    if np.isfinite(correlation).mean() < MIN_ALIGNED:
        return None
    return {"angle_rad": angle, "shift_px": shift, "correlation": correlation}


def _align(scene: np.ndarray, frame: np.ndarray, mask: np.ndarray, warp: np.ndarray) -> tuple[float, np.ndarray] | None:
    """ECC's correlation and Euclidean warp (scene → frame) from ``warp``; None where it does not converge."""
    criteria = (cv2.TERM_CRITERIA_EPS | cv2.TERM_CRITERIA_COUNT, 30, 1e-3)
    try:
        return cv2.findTransformECC(scene, frame, warp.copy(), cv2.MOTION_EUCLIDEAN, criteria, mask, BLUR_PX)
    except cv2.error:
        return None


def steadied(track: pd.DataFrame, motion: dict) -> tuple[pd.DataFrame, dict]:
    """``track`` brought to the still scene's frame: p' = Rᵀ (p − t) per frame (:func:`picture_motion`); frames
    not aligned flagged ``jump``. Returns the track (``x_image_px``/``y_image_px``: as measured) and the motion's
    facts (``rms_px``: the picture's shift about its mean; ``max_turn_deg``; ``median_correlation``; ``unaligned``)."""
    out = track.copy()
    x, y = track.x_px.to_numpy(float), track.y_px.to_numpy(float)
    a, (tx, ty) = motion["angle_rad"], motion["shift_px"].T
    cos, sin = np.cos(a), np.sin(a)
    out["x_image_px"], out["y_image_px"] = x, y
    out["x_px"] = cos * (x - tx) + sin * (y - ty)
    out["y_px"] = -sin * (x - tx) + cos * (y - ty)
    aligned = np.isfinite(motion["correlation"])
    out.loc[~aligned & (out.flag == "ok").to_numpy(), "flag"] = "jump"
    moved = motion["shift_px"][aligned]
    facts = {
        "rms_px": round(float(np.sqrt(np.mean(np.sum((moved - moved.mean(axis=0)) ** 2, axis=1)))), 3),
        "max_turn_deg": round(float(np.degrees(np.nanmax(np.abs(a - np.nanmedian(a))))), 3),
        "median_correlation": round(float(np.nanmedian(motion["correlation"])), 4),
        "unaligned": int((~aligned).sum()),
    }
    return out, facts


def steady_camera(path, track: pd.DataFrame, document: dict) -> tuple[pd.DataFrame, dict]:
    """A track whose path is no circle (``document``: its :func:`~pendulum.tracking.path_shape.path_departure`)
    judged again with the picture's motion taken out (:func:`picture_motion`, :func:`steadied`): where that makes
    it a pendulum's, the steadied track and its path's document (``camera_motion``: the motion's facts; the verdict
    says it), the positions as measured in ``x_image_px``/``y_image_px``; else ``track`` and ``document`` as given."""
    facts = track.attrs.get("body") or track.attrs.get("marker") or {}
    motion = picture_motion(path, track, float(facts.get("radius_px") or 10.0))
    if motion is None:
        return track, document
    steady, moved = steadied(track, motion)
    again, judged = path_departure(steady.drop(columns=["x_image_px", "y_image_px"]))
    if judged.get("not_a_pendulum"):
        return track, document
    again["x_image_px"], again["y_image_px"] = steady.x_image_px, steady.y_image_px
    judged["camera_motion"] = moved
    judged["verdict"] = (
        f"the camera moved (held in the hand, or shaken): the picture's own motion, {moved['rms_px']:.2f} px RMS and "
        f"turns of up to {moved['max_turn_deg']:.2f}°, measured from the still scene (ECC, median correlation "
        f"{moved['median_correlation']:.3f}) and taken out of the positions ({moved['unaligned']} frames not aligned, "
        "flagged jump); without it the path was no circle; " + judged["verdict"]
    )
    return again, judged


def path_through_lens(track: pd.DataFrame, lens) -> tuple[pd.DataFrame, dict]:
    """:func:`path_departure` in the lens-corrected picture (``lens``: the camera setup's
    :class:`pendulum.camera.calibration.Lens`; None: in the image as filmed). A wide lens bends the swing's circle
    more where the swing reaches further out, so the first, widest swings and the later ones fit circles apart:
    in the image a GoPro-like render's path read as a knock of 4 px at the first swing's end, corrected and its
    frames flagged; in the corrected picture it is one circle. The corrections found there are taken back into
    the image (``x_px``, ``y_px``; the tracked positions in ``x_image_px``, ``y_image_px``), where the angle
    stage maps them through the same lens. Without a lens, where the marker's image changes size along its path
    (``size_change_along_path``: an uncalibrated wide lens), a correction found is said and not applied."""
    if lens is None:
        out, document = path_departure(track)
        change = (track.attrs.get("marker") or {}).get("size_change_along_path")
        if not (change and document.get("corrected")):
            return out, document
        # uncalibrated, a view that changes the marker's size along its path bends the circle too: not a move
        document["not_applied"] = document["creep"]
        rms, radius = document["circle_rms_px"], document.get("radius_px") or math.inf
        document["creep"] = {"degree": 0, "corrected": False, "rms_after_px": rms}
        document.update(unexplained_rms_px=rms, unexplained_angle_deg=round(math.degrees(rms / radius), 4))
        read = document["not_applied"]
        if knock := read.get("knock"):
            (dx, dy), when = knock["shift_px"], knock["time_s"]
            what = f"a jump of the pivot by ({dx:+.1f}, {dy:+.1f}) px at {when:.2f} s"
        else:
            what = f"a creep of the pivot by {read.get('motion_px', 0.0):.1f} px"
        document.update(
            corrected=False,
            verdict=f"the path sits {rms:.2f} px RMS off one fixed circle (noise {document['noise_px']:.3f} px); it "
            f"reads as {what}, not applied: the marker's image changes size by {100 * (change - 1):.0f} % along "
            "its path, and a wide lens that does so bends the swing's circle (calibrate the lens)",
        )
        return track.copy(), document
    x, y = track.x_px.to_numpy(float), track.y_px.to_numpy(float)
    seen = np.isfinite(x) & np.isfinite(y)
    ideal = track.copy()
    undone = lens.undistort_px(np.column_stack([x[seen], y[seen]]))
    ideal.loc[seen, "x_px"], ideal.loc[seen, "y_px"] = undone[:, 0], undone[:, 1]
    out, document = path_departure(ideal)
    if "x_image_px" in out:  # corrected there: the corrected positions taken back into the image
        back = lens.distort_px(np.column_stack([out.x_px.to_numpy(float)[seen], out.y_px.to_numpy(float)[seen]]))
        corrected_x, corrected_y = x.copy(), y.copy()
        corrected_x[seen], corrected_y[seen] = back[:, 0], back[:, 1]
        out["x_image_px"], out["y_image_px"] = x, y
        out["x_px"], out["y_px"] = corrected_x, corrected_y
    else:
        out["x_px"], out["y_px"] = x, y
    document["measured_in"] = "the lens-corrected picture"
    return out, document
