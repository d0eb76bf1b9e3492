"""Lens and view: from a camera setup's checkerboard clips to a map of marker centres onto the swing plane.

Lens. A checkerboard clip (the board moved and tilted over the whole frame)
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

View. A checkerboard held in the swing plane (one frame of a clip) gives the
plane-to-image homography; marker centres (undistorted) are mapped onto the
plane, in "plane pixels": metres × the image scale at the board centre, so
pixel thresholds keep their meaning. The homography also absorbs a flat port's
refraction to first order (a magnification); a lens clip filmed through the port
takes all of it (with the camera at the port it is a radial map, like a lens's
distortion). Without a plane board a swing plane
that does not face the camera squarely is only *detected*: the marker's
circular path images as an ellipse (:func:`path_tilt`).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import cv2
import numpy as np

HELD_OUT_EVERY = 4  # view k is held out when k % 4 == 3
MAX_VIEWS = 40  # views used for a calibration (evenly spread over the clip)
MIN_VIEWS = 8
UNDISTORT_CRITERIA = (cv2.TERM_CRITERIA_COUNT | cv2.TERM_CRITERIA_EPS, 100, 1e-12)
MODELS = ("rational", "fisheye")
RATIONAL_MARGIN = 0.05  # the rational model (8 coefficients) must beat the fisheye's (4) held-out error by 5 %


class CalibrationError(ValueError):
    """A calibration clip that cannot give a camera model; the message names the file and the problem."""


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
            for index, frame in enumerate(container.decode(container.streams.video[0])):
                yield index, frame.to_ndarray(format="gray")
    except (av.error.FFmpegError, IndexError) as exc:
        raise CalibrationError(f"{path}: not a readable video ({exc})") from exc


def _frame_count(path) -> int:
    import av

    try:
        container = av.open(str(path))
    except av.error.FFmpegError as exc:
        raise CalibrationError(f"{path}: not a readable video ({exc})") from exc
    with container:
        stream = container.streams.video[0]
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
    if not math.isfinite(models[best]["held_out_rms_px"]):
        raise CalibrationError(f"{source}: neither lens model could be calibrated ({models})")
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
    }


# The view: a plane-to-image homography and the plane frame.

_PLANE_AXES = [np.array(m, float) for m in ([[1, 0], [0, 1]], [[0, -1], [1, 0]], [[-1, 0], [0, -1]], [[0, 1], [-1, 0]])]


def plane_homography(corners_ideal_px, pattern: tuple[int, int], square_size_m: float) -> dict:
    """Homography from ideal (undistorted) image pixels to the swing plane, in plane pixels.

    Plane coordinates are board metres rotated by a multiple of 90° so that the
    plane's x and y point as the image's right and down (the detector's corner
    order is ambiguous), shifted to the board centre's image position and scaled
    by ``px_per_m`` = √|det J| of the image-from-plane Jacobian at the board centre:
    near the board, plane pixels are image pixels of a camera facing the plane.
    """
    board = board_points_m(pattern, square_size_m)[:, :2]
    img = np.asarray(corners_ideal_px, float).reshape(-1, 2)
    h_img_from_board, _ = cv2.findHomography(board, img, 0)
    centre_board = board.mean(axis=0)

    def image_of(p):
        v = h_img_from_board @ np.array([p[0], p[1], 1.0])
        return v[:2] / v[2]

    eps = 1e-4
    c_img = image_of(centre_board)
    jac = np.column_stack(
        [(image_of(centre_board + [eps, 0]) - c_img) / eps, (image_of(centre_board + [0, eps]) - c_img) / eps]
    )  # d image / d board (px per m)
    px_per_m = math.sqrt(abs(np.linalg.det(jac)))
    mirrored = np.linalg.det(jac) < 0
    flip = np.diag([1.0, -1.0]) if mirrored else np.eye(2)
    # Plane axes: board axes (mirrored if seen from behind) turned by the multiple of 90° that best matches the image.
    best = min(_PLANE_AXES, key=lambda r: np.linalg.norm(jac @ np.linalg.inv(r @ flip) / px_per_m - np.eye(2)))
    axes = best @ flip  # plane = axes · (board − centre) · px_per_m + image centre
    to_plane = np.eye(3)
    to_plane[:2, :2] = axes * px_per_m
    to_plane[:2, 2] = c_img - axes @ centre_board * px_per_m
    h = to_plane @ np.linalg.inv(h_img_from_board)
    h /= h[2, 2]
    residual = _apply_h(h_img_from_board, board) - img  # the board's corners as the homography images them
    image_tilt_deg = _tilt_of_homography(jac / px_per_m)
    return {
        "homography": h.tolist(),
        "px_per_m": px_per_m,
        "corner_rms_px": float(np.sqrt(np.mean(np.sum(residual**2, axis=1)))),
        "plane_tilt_deg": image_tilt_deg,
    }


def _tilt_of_homography(jac_normalised: np.ndarray) -> float:
    """Tilt of the plane against the image (orthographic approximation): acos of the singular-value ratio."""
    s = np.linalg.svd(jac_normalised, compute_uv=False)
    return float(math.degrees(math.acos(min(1.0, s[1] / s[0]))))


def _apply_h(h, points) -> np.ndarray:
    """Points (N, 2) through the homography h."""
    pts = np.asarray(points, float).reshape(-1, 2)
    v = (h @ np.column_stack([pts, np.ones(len(pts))]).T).T
    return v[:, :2] / v[:, 2:3]


class ImageToPlane:
    """Marker centre in the image → swing-plane position: undistortion (if a lens), then homography (if a plane)."""

    def __init__(self, document: dict):
        self.lens = Lens.from_dict(document["lens"]) if document.get("lens") else None
        plane = document.get("plane")
        self.homography = np.asarray(plane["homography"], float) if plane else None
        self.setup = document.get("camera_setup", "?")

    def __call__(self, x, y) -> tuple[np.ndarray, np.ndarray]:
        x = np.asarray(x, float)
        y = np.asarray(y, float)
        out_x = np.full(x.shape, np.nan)
        out_y = np.full(y.shape, np.nan)
        good = np.isfinite(x) & np.isfinite(y)
        pts = np.column_stack([x[good], y[good]])
        if self.lens is not None:
            pts = self.lens.undistort_px(pts)
        if self.homography is not None and len(pts):
            pts = _apply_h(self.homography, pts)
        out_x[good], out_y[good] = pts[:, 0], pts[:, 1]
        return out_x, out_y

    def describe(self) -> str:
        parts = []
        if self.lens is not None:
            parts.append(f"{self.lens.model} lens undistorted")
        if self.homography is not None:
            parts.append("mapped onto the swing plane by its homography")
        return f"marker centres {' and '.join(parts) or 'unchanged'} (camera setup {self.setup})"


def map_track(track, document: dict | None):
    """A copy of a marker track with ``x_px``, ``y_px`` mapped to the swing plane (unchanged without a document)."""
    if not document:
        return track
    mapping = ImageToPlane(document)
    out = track.copy()
    out["x_px"], out["y_px"] = mapping(track.x_px.to_numpy(float), track.y_px.to_numpy(float))
    return out


def map_point(point, document: dict | None):
    """One image point (e.g. a pivot_px given in image pixels) mapped like the marker centres."""
    if point is None or not document:
        return point
    x, y = ImageToPlane(document)(np.array([point[0]], float), np.array([point[1]], float))
    return [float(x[0]), float(y[0])]


# The view without a plane board: the ellipse of the marker's circular path.

PATH_TILT_MIN_DEG = 3.0  # a path tilt below this is not reported (orthographic ellipse, noise)
PATH_TILT_SIGMAS = 4.0  # ... nor one within this many standard errors of 0
PATH_TILT_MIN_ARC_DEG = 80.0  # on a shorter arc the ratio is biased by the track's noise: not judged


def path_tilt(x, y) -> dict | None:
    """Tilt of the swing plane from the ellipse the marker's circular path makes (orthographic).

    Assumes the tilt axis is the image's vertical or horizontal (a camera turned
    or pitched against the swing plane): the path is the axis-aligned ellipse
    ((x − c_x)/a)² + ((y − c_y)/b)² = 1, fitted by least squares of
    R (√(…) − 1) (≈ the geometric distance in px). The horizontal-to-vertical
    semi-axis ratio a/b < 1 is a plane turned about the vertical by acos(a/b),
    > 1 a plane pitched by acos(b/a). The ratio is fixed only by the fourth-order
    shape of the arc, so a short arc leaves it uncertain and biased by noise:
    ``axis_ratio_stderr`` from the fit's covariance (residual autocorrelation
    allowed for); ``significant`` only on arcs of at least 80° (swings of ±40°).
    None when fewer than 20 points.
    """
    from scipy.optimize import least_squares

    from pendulum.geometry import fit_circle

    x = np.asarray(x, float)
    y = np.asarray(y, float)
    good = np.isfinite(x) & np.isfinite(y)
    x, y = x[good], y[good]
    if x.size < 20:
        return None
    circle = fit_circle(x, y)
    r0 = circle.radius_px

    def residual(p):
        cx, cy, a, b = p
        return r0 * (np.sqrt(((x - cx) / a) ** 2 + ((y - cy) / b) ** 2) - 1)

    sol = least_squares(residual, [circle.pivot_x_px, circle.pivot_y_px, r0, r0], x_scale="jac")
    res = sol.fun
    sigma2 = float(res @ res) / max(x.size - 4, 1)
    rho = float(np.clip(np.corrcoef(res[1:], res[:-1])[0, 1], 0.0, 0.99)) if res.size > 3 else 0.0
    cov = np.linalg.pinv(sol.jac.T @ sol.jac) * sigma2 * (1 + rho) / (1 - rho)
    a, b = sol.x[2], sol.x[3]
    ratio = a / b
    grad = np.array([1 / b, -a / b**2])
    ratio_se = float(math.sqrt(max(grad @ cov[2:, 2:] @ grad, 0.0)))
    shrink = min(ratio, 1 / ratio)
    tilt = math.degrees(math.acos(min(shrink, 1.0)))
    return {
        "axis_ratio": float(ratio),
        "axis_ratio_stderr": ratio_se,
        "tilt_deg": tilt,
        "tilt_axis": "vertical" if ratio < 1 else "horizontal",
        "arc_span_deg": circle.arc_span_deg,
        "significant": bool(
            circle.arc_span_deg >= PATH_TILT_MIN_ARC_DEG
            and tilt > PATH_TILT_MIN_DEG
            and abs(1 - ratio) > PATH_TILT_SIGMAS * ratio_se
        ),
        "n_points": int(x.size),
    }


def calibrate_camera_setup(
    setup: str,
    pattern: tuple[int, int],
    square_size_m: float,
    calibration_video=None,
    plane_video=None,
    plane_frame: int = 0,
    max_views: int = MAX_VIEWS,
) -> dict:
    """The calibration document of one camera setup (``results/calibration/<setup>.json``).

    ``calibration_video``: the lens clip (None: an ideal lens, no undistortion);
    ``plane_video``/``plane_frame``: the board held in the swing plane (None: no
    homography; the swing plane is taken as facing the camera and only a tilt
    seen in the marker path is warned about).
    """
    doc: dict = {"camera_setup": setup, "pattern_inner_corners": list(pattern), "square_size_m": square_size_m}
    lens = None
    if calibration_video is not None:
        found = detect_views(calibration_video, pattern, max_views)
        doc.update(
            calibrate_lens(found["views"], pattern, square_size_m, found["image_size_px"], str(calibration_video))
        )
        doc["image_size_px"] = list(found["image_size_px"])
        doc["frames_in_clip"] = found["frames_in_clip"]
        lens = Lens.from_dict(doc["lens"])
        k = lens.camera_matrix
        doc["focal_length_px"] = [float(k[0, 0]), float(k[1, 1])]
        doc["principal_point_px"] = [float(k[0, 2]), float(k[1, 2])]
    if plane_video is not None:
        found = detect_views(plane_video, pattern, frames=[plane_frame])
        if plane_frame not in found["views"]:
            raise CalibrationError(
                f"{plane_video}: no {pattern[0]}×{pattern[1]} checkerboard found in frame {plane_frame}; "
                "choose a frame where the whole board is sharp and held in the swing plane (plane_frame)"
            )
        corners = found["views"][plane_frame]
        ideal = corners if lens is None else lens.undistort_px(corners)
        doc["plane"] = {"video": str(plane_video), "frame": int(plane_frame)}
        doc["plane"].update(plane_homography(ideal, pattern, square_size_m))
    if lens is None and plane_video is None:
        raise CalibrationError(f"camera setup {setup}: give calibration_video and/or plane_video")
    return doc
