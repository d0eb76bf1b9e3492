"""Lens: from a camera setup's checkerboard clip to a calibrated lens that undistorts marker centres.

A checkerboard clip (the board moved and tilted over the whole frame)
gives intrinsics K and distortion for two models, both calibrated with OpenCV:
the *rational* model (k1..k6, p1, p2; ``cv2.calibrateCamera`` with
``CALIB_RATIONAL_MODEL``) and the *fisheye* model (Kannala–Brandt,
θ_d = θ (1 + k1 θ² + k2 θ⁴ + k3 θ⁶ + k4 θ⁸); ``cv2.fisheye.calibrate``). The
detected views are split deterministically (every fourth held out); each model
is calibrated on the rest and judged by the RMS reprojection error of the
held-out views (their pose from ``solvePnP``, the model's intrinsics fixed).
The model with the lower held-out error (the rational one only when lower by
more than 5 %: within that the simpler model) is recalibrated on all views and used.
Only the marker centres are undistorted (to the pixels of an ideal pinhole
camera with the same K), never whole frames.

The view (plane homography, mapping of marker centres, path tilt) and the
calibration document of a camera setup are in :mod:`pendulum.camera.view`.
"""

from __future__ import annotations

import math
from contextlib import contextmanager
from dataclasses import dataclass

import cv2
import numpy as np

from pendulum.camera.streams import main_stream, squarer

HELD_OUT_EVERY = 4  # view k is held out when k % 4 == 3
MAX_VIEWS = 40  # views used for a calibration (evenly spread over the clip)
MIN_VIEWS = 8
UNDISTORT_CRITERIA = (cv2.TERM_CRITERIA_COUNT | cv2.TERM_CRITERIA_EPS, 100, 1e-12)
MODELS = ("rational", "fisheye")
RATIONAL_MARGIN = 0.05  # the rational model (8 coefficients) must beat the fisheye's (4) held-out error by 5 %
MAX_HELD_OUT_RMS_PX = 1.0  # a lens reprojecting its held-out views worse than this is refused
WARN_HELD_OUT_RMS_PX = 0.5  # ... and worse than this used with a warning (a good clip: 0.1–0.3 px)
COVERAGE_GRID = (16, 9)  # cells of the frame over which the board's coverage is counted
MIN_COVERAGE_SHARE = 0.5  # a lens clip whose boards reached less of the frame is used with a warning


class CalibrationError(ValueError):
    """A calibration clip that cannot give a camera model; the message names the file and the problem."""


@contextmanager
def single_threaded_opencv():
    """OpenCV on one thread for the block (or function, as a decorator).

    Its parallel loops (corner refinement, calibrateCamera's Jacobian sums) add in an order that
    varies between runs, so a calibration changes in its last digits from run to run; on one
    thread the results are byte-identical.
    """
    previous = cv2.getNumThreads()
    cv2.setNumThreads(1)
    try:
        yield
    finally:
        cv2.setNumThreads(previous)


def board_points_m(pattern: tuple[int, int], square_size_m: float) -> np.ndarray:
    """Inner-corner positions (columns × rows) on the board plane, Z = 0, row-major as OpenCV returns them."""
    cols, rows = pattern
    grid = np.zeros((rows * cols, 3), np.float64)
    grid[:, :2] = np.mgrid[0:cols, 0:rows].T.reshape(-1, 2) * square_size_m
    return grid


def find_board(image: np.ndarray, pattern: tuple[int, int]) -> np.ndarray | None:
    """Sub-pixel inner corners of a checkerboard in a grey image ((N, 2) float), or None.

    ``cv2.findChessboardCornersSB`` (sector-based, accurate); if it finds nothing,
    ``findChessboardCorners`` + ``cornerSubPix``.
    """
    found, corners = cv2.findChessboardCornersSB(
        image, pattern, flags=cv2.CALIB_CB_EXHAUSTIVE | cv2.CALIB_CB_ACCURACY | cv2.CALIB_CB_NORMALIZE_IMAGE
    )
    if not found:
        found, corners = cv2.findChessboardCorners(
            image, pattern, flags=cv2.CALIB_CB_ADAPTIVE_THRESH | cv2.CALIB_CB_NORMALIZE_IMAGE
        )
        if not found:
            return None
        corners = cv2.cornerSubPix(
            image, corners, (5, 5), (-1, -1), (cv2.TERM_CRITERIA_EPS | cv2.TERM_CRITERIA_COUNT, 50, 1e-3)
        )
    return corners.reshape(-1, 2).astype(np.float64)


def _grey_frames(path):
    """(index, grey image) of every decoded frame of a clip (PyAV; the clip is not a trial, no timeline needed)."""
    import av

    try:
        with av.open(str(path)) as container:
            stream = main_stream(container)  # the trials' own: the recording, in square pixels
            square = squarer(stream)
            for index, frame in enumerate(container.decode(stream)):
                yield index, (frame if square is None else square(frame)).to_ndarray(format="gray")
    except (av.error.FFmpegError, ValueError) as exc:  # ValueError: no video stream
        raise CalibrationError(f"{path}: not a readable video ({exc})") from exc


def _frame_count(path) -> int:
    import av

    try:
        container = av.open(str(path))
    except av.error.FFmpegError as exc:
        raise CalibrationError(f"{path}: not a readable video ({exc})") from exc
    with container:
        if not container.streams.video:
            raise CalibrationError(f"{path}: not a readable video (no video stream)")
        stream = main_stream(container)
        if stream.frames:
            return int(stream.frames)
        rate = float(stream.average_rate or stream.guessed_rate or 30)
        return int(float(container.duration or 0) / 1e6 * rate) or 1


def detect_views(path, pattern: tuple[int, int], max_views: int = MAX_VIEWS, frames=None) -> dict:
    """Board corners in a spread of frames of a clip: {frame index: (N, 2) corners}, and the image size.

    Every ``stride``-th frame is searched (about 3 × ``max_views`` frames over
    the clip; ``frames``: only these indices); views whose corners moved less
    than 2 % of the image diagonal from the last kept view are skipped.
    """
    n = _frame_count(path)
    stride = max(1, n // (3 * max_views))
    wanted = None if frames is None else set(int(f) for f in frames)
    views: dict[int, np.ndarray] = {}
    size = None
    last = None
    for index, image in _grey_frames(path):
        size = (int(image.shape[1]), int(image.shape[0]))
        if (wanted is not None and index not in wanted) or (wanted is None and index % stride):
            continue
        corners = find_board(image, pattern)
        if corners is None:
            continue
        if last is not None and wanted is None:
            if np.median(np.hypot(*(corners - last).T)) < 0.02 * math.hypot(*size):
                continue
        views[index] = corners
        last = corners
    if size is None:
        raise CalibrationError(f"{path}: no frame could be decoded")
    if len(views) > max_views:
        keys = sorted(views)
        pick = np.unique(np.round(np.linspace(0, len(keys) - 1, max_views)).astype(int))
        views = {keys[i]: views[keys[i]] for i in pick}
    return {"views": views, "image_size_px": size, "frames_in_clip": n, "stride": stride}


@dataclass
class Lens:
    """A calibrated lens: ``model`` ("rational", "fisheye" or "none"), K (3×3) and distortion coefficients."""

    model: str
    camera_matrix: np.ndarray
    distortion: np.ndarray

    @classmethod
    def from_dict(cls, doc: dict) -> Lens:
        return cls(doc["model"], np.asarray(doc["camera_matrix"], float), np.asarray(doc["distortion"], float))

    def to_dict(self) -> dict:
        return {
            "model": self.model,
            "camera_matrix": self.camera_matrix.tolist(),
            "distortion": self.distortion.ravel().tolist(),
        }

    def undistort_px(self, points_px) -> np.ndarray:
        """Distorted image pixels → pixels of the ideal pinhole camera with the same K (iterated to 1e-12)."""
        pts = np.asarray(points_px, np.float64).reshape(-1, 1, 2)
        if self.model == "none" or pts.size == 0:
            return pts.reshape(-1, 2).copy()
        k = self.camera_matrix
        if self.model == "fisheye":
            out = cv2.fisheye.undistortPoints(pts, k, self.distortion.reshape(4, 1), None, None, k, UNDISTORT_CRITERIA)
        else:
            out = cv2.undistortPoints(pts, k, self.distortion.ravel(), None, None, k, UNDISTORT_CRITERIA)
        return out.reshape(-1, 2)

    def distort_px(self, points_px) -> np.ndarray:
        """Ideal pinhole pixels → distorted image pixels (the forward lens model)."""
        pts = np.asarray(points_px, np.float64).reshape(-1, 2)
        if self.model == "none" or pts.size == 0:
            return pts.copy()
        k = self.camera_matrix
        normalised = (pts - k[:2, 2]) / np.diag(k)[:2]
        if self.model == "fisheye":
            return cv2.fisheye.distortPoints(normalised.reshape(-1, 1, 2), k, self.distortion.reshape(4, 1)).reshape(
                -1, 2
            )
        rays = np.column_stack([normalised, np.ones(len(pts))])
        out, _ = cv2.projectPoints(rays, np.zeros(3), np.zeros(3), k, self.distortion.ravel())
        return out.reshape(-1, 2)


def _calibrate(model: str, object_points, image_points, size, guess: np.ndarray | None = None):
    """(rms_px, K, distortion) of one model on the given views.

    The fisheye calibration starts from ``guess`` (K of the rational model; its own
    initialisation fails on some strongly distorted views) and, if that fails, from scratch.
    """
    if model == "fisheye":
        obj = [o.reshape(1, -1, 3).astype(np.float64) for o in object_points]
        img = [i.reshape(1, -1, 2).astype(np.float64) for i in image_points]
        flags = cv2.CALIB_RECOMPUTE_EXTRINSIC | cv2.CALIB_FIX_SKEW
        criteria = (cv2.TERM_CRITERIA_COUNT | cv2.TERM_CRITERIA_EPS, 200, 1e-10)
        starts = ([guess.copy()] if guess is not None else []) + [None]
        for k0 in starts:
            try:
                extra = cv2.CALIB_USE_INTRINSIC_GUESS if k0 is not None else 0
                rms, k, d, _, _ = cv2.fisheye.calibrate(
                    obj, img, size, k0, np.zeros((4, 1)), flags=flags | extra, criteria=criteria
                )
                return rms, k, d.ravel()
            except cv2.error as exc:
                error = exc
        raise error
    obj = [o.astype(np.float32) for o in object_points]
    img = [i.reshape(-1, 1, 2).astype(np.float32) for i in image_points]
    criteria = (cv2.TERM_CRITERIA_COUNT | cv2.TERM_CRITERIA_EPS, 200, 1e-12)
    rms, k, d, _, _ = cv2.calibrateCamera(obj, img, size, None, None, flags=cv2.CALIB_RATIONAL_MODEL, criteria=criteria)
    return rms, k, d.ravel()


def reprojection_rms_px(lens: Lens, object_points, image_points) -> float:
    """RMS reprojection error of views whose pose is estimated with the lens fixed (held-out views)."""
    errors = []
    for obj, img in zip(object_points, image_points, strict=True):
        ideal = lens.undistort_px(img)
        ok, rvec, tvec = cv2.solvePnP(obj, ideal, lens.camera_matrix, None, flags=cv2.SOLVEPNP_ITERATIVE)
        if not ok:
            return math.inf
        rays = (cv2.Rodrigues(rvec)[0] @ obj.T + tvec.reshape(3, 1)).T
        if np.any(rays[:, 2] <= 0):
            return math.inf
        ideal_proj = (lens.camera_matrix @ (rays / rays[:, 2:3]).T).T[:, :2]
        errors.append(lens.distort_px(ideal_proj) - img)
    e = np.concatenate(errors)
    return float(np.sqrt(np.mean(np.sum(e**2, axis=1))))


def calibrate_lens(views: dict, pattern: tuple[int, int], square_size_m: float, image_size_px, source: str) -> dict:
    """Both lens models from the detected views; the one with the lower held-out reprojection error is used.

    Returns ``lens`` (the chosen model, recalibrated on all views), per model
    ``held_out_rms_px``, ``training_rms_px`` and ``all_views_rms_px``, and the
    views used and held out.
    """
    keys = sorted(views)
    if len(keys) < MIN_VIEWS:
        raise CalibrationError(
            f"{source}: the checkerboard ({pattern[0]}×{pattern[1]} inner corners) was found in only {len(keys)} "
            f"frame(s); at least {MIN_VIEWS} views are needed: film the whole board, sharp, moved over the frame"
            + (
                "; or pattern_inner_corners is not the board's (its inner corners: the squares less one each way)"
                if not keys
                else ""
            )
        )
    obj = board_points_m(pattern, square_size_m)
    held = [k for i, k in enumerate(keys) if i % HELD_OUT_EVERY == HELD_OUT_EVERY - 1]
    train = [k for k in keys if k not in held]
    size = tuple(int(v) for v in image_size_px)
    models: dict = {}
    fits: dict = {}
    for model in MODELS:
        try:
            guess = fits["rational"][1] if model == "fisheye" and "rational" in fits else None
            fits[model] = _calibrate(model, [obj] * len(train), [views[f] for f in train], size, guess)
            lens = Lens(model, fits[model][1], fits[model][2])
            held_out = reprojection_rms_px(lens, [obj] * len(held), [views[f] for f in held])
            models[model] = {"training_rms_px": float(fits[model][0]), "held_out_rms_px": held_out}
        except cv2.error as exc:
            models[model] = {"held_out_rms_px": math.inf, "error": str(exc).strip().splitlines()[-1]}
    rational, fisheye = models["rational"]["held_out_rms_px"], models["fisheye"]["held_out_rms_px"]
    best = "rational" if rational < (1 - RATIONAL_MARGIN) * fisheye else "fisheye"
    held_out_px = models[best]["held_out_rms_px"]
    if not math.isfinite(held_out_px):
        raise CalibrationError(f"{source}: neither lens model could be calibrated ({models})")
    if held_out_px > MAX_HELD_OUT_RMS_PX:  # a reviewer's bent board (1.95 px) gave angles 0.81× too small
        raise CalibrationError(
            f"{source}: the lens model reprojects its {len(held)} held-out views {held_out_px:.2f} px RMS off the "
            f"board's corners (usable: under {MAX_HELD_OUT_RMS_PX:g} px; a good clip 0.1–0.3 px): a bent, moving or "
            f"blurred board, or a pattern_inner_corners ({pattern[0]}×{pattern[1]}) that is not the board's (its "
            "squares less one each way); the angles measured through it would be wrong, so none are"
        )
    warnings = []
    if held_out_px > WARN_HELD_OUT_RMS_PX:
        warnings.append(
            f"{source}: the lens model reprojects its held-out views {held_out_px:.2f} px RMS off the board's "
            f"corners (a good clip 0.1–0.3 px): a soft, moving or bent board? Angles measured through it may be off"
        )
    covered = board_coverage(views, size)
    if covered["share"] < MIN_COVERAGE_SHARE:
        warnings.append(
            f"{source}: the board reached only {100 * covered['share']:.0f} % of the frame over the clip's views: "
            "the lens model is extrapolated beyond it (a board kept in the middle fits well there and can be "
            "pixels off in the corners); move the board over the whole frame, corners and edges too"
        )
    try:
        rms, k, d = _calibrate(best, [obj] * len(keys), [views[f] for f in keys], size, fits[best][1])
        models[best]["all_views_rms_px"] = float(rms)
    except cv2.error:  # a held-out view breaks the fisheye initialisation: keep the training views' lens
        _, k, d = fits[best]
        models[best]["all_views_rms_px"] = None
    for entry in models.values():
        if not math.isfinite(entry["held_out_rms_px"]):
            entry["held_out_rms_px"] = None
    return {
        "lens": Lens(best, k, d).to_dict(),
        "models": models,
        "chosen_model": best,
        "chosen_by": (
            "RMS reprojection error of the held-out views; the rational model (8 coefficients) only when "
            f"more than {100 * RATIONAL_MARGIN:.0f} % below the fisheye's (4)"
        ),
        "views": keys,
        "held_out_views": held,
        "board_coverage": covered,
        "warnings": warnings,
    }


def board_coverage(views: dict, image_size_px) -> dict:
    """Where the board was in the clip's views: the cells of a :data:`COVERAGE_GRID` over the frame that some
    view's board (the hull of its corners) reaches, as rows of "#" (reached) and "." (not), and their share."""
    cols, rows = COVERAGE_GRID
    width, height = (int(v) for v in image_size_px)
    mask = np.zeros((height, width), np.uint8)
    for corners in views.values():
        hull = cv2.convexHull(np.asarray(corners, np.float32).reshape(-1, 1, 2)).astype(np.int32)
        cv2.fillConvexPoly(mask, hull, 1)
    cells = [
        "".join(
            "#"
            if mask[r * height // rows : (r + 1) * height // rows, c * width // cols : (c + 1) * width // cols].any()
            else "."
            for c in range(cols)
        )
        for r in range(rows)
    ]
    share = sum(row.count("#") for row in cells) / (cols * rows)
    return {"share": share, "grid": [cols, rows], "cells": cells}


def outside_coverage_share(x_px, y_px, document: dict) -> float | None:
    """The share of image points (a track's usable centres) in cells of the frame the lens clip's board never
    reached (:func:`board_coverage` in the calibration ``document``); None without a coverage map."""
    covered = document.get("board_coverage")
    size = document.get("image_size_px")
    x, y = np.asarray(x_px, float), np.asarray(y_px, float)
    good = np.isfinite(x) & np.isfinite(y)
    if not covered or not size or not good.any():
        return None
    (cols, rows), (width, height) = covered["grid"], size
    # the cells' pixel edges as board_coverage slices them (k · size // cells)
    c = np.clip(np.searchsorted([k * width // cols for k in range(cols + 1)], x[good], "right") - 1, 0, cols - 1)
    r = np.clip(np.searchsorted([k * height // rows for k in range(rows + 1)], y[good], "right") - 1, 0, rows - 1)
    reached = np.array([[ch == "#" for ch in row] for row in covered["cells"]])
    return float(np.mean(~reached[r, c]))
