"""View: the swing plane's homography, marker centres mapped onto it, and a camera setup's calibration.

A checkerboard held in the swing plane (one frame of a clip) gives the
plane-to-image homography; marker centres (undistorted) are mapped onto the
plane, in "plane pixels": metres × the image scale at the board centre, so
pixel thresholds keep their meaning. The homography also absorbs a flat port's
refraction to first order (a magnification); a lens clip filmed through the port
takes all of it (with the camera at the port it is a radial map, like a lens's
distortion). Without a plane board a swing plane
that does not face the camera squarely is only *detected*: the marker's
circular path images as an ellipse (:func:`path_tilt`).

The lens (checkerboard corners, the two lens models and their choice,
undistortion) is :mod:`pendulum.camera.calibration`.
"""

from __future__ import annotations

import math

import cv2
import numpy as np

from pendulum.camera.calibration import (
    MAX_VIEWS,
    CalibrationError,
    Lens,
    board_points_m,
    calibrate_lens,
    detect_views,
    outside_coverage_share,
    single_threaded_opencv,
)

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
    c_img, jac = _image_and_jacobian(h_img_from_board, centre_board)  # d image / d board (px per m)
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
    corner_rms_px = float(np.sqrt(np.mean(np.sum(residual**2, axis=1))))
    return {
        "homography": h.tolist(),
        "px_per_m": px_per_m,
        "corner_rms_px": corner_rms_px,
        "plane_tilt_deg": _tilt_of_homography(jac / px_per_m),
        "square_on_tilt_deg": _square_on_tilt_deg(board, px_per_m, max(corner_rms_px, 0.05)),
    }


def _square_on_tilt_deg(board_m: np.ndarray, px_per_m: float, noise_px: float, draws: int = 200) -> float:
    """The tilt (95th percentile) that a board held exactly square-on reads with corners ``noise_px`` off: a tilt
    is never below 0, so noise alone reads one (a reviewer's square-on board: 3.0°, its corners 0.1 px off)."""
    rng = np.random.default_rng(0)
    centre, tilts = board_m.mean(axis=0), []
    for _ in range(draws):
        seen = board_m * px_per_m + rng.normal(0.0, noise_px / math.sqrt(2), board_m.shape)
        h, _ = cv2.findHomography(board_m, seen, 0)
        tilts.append(_tilt_of_homography(_image_and_jacobian(h, centre)[1] / px_per_m))
    return float(np.percentile(tilts, 95))


def _image_and_jacobian(h: np.ndarray, point, eps: float = 1e-4) -> tuple[np.ndarray, np.ndarray]:
    """The image of ``point`` through the homography ``h`` and its Jacobian there (forward differences)."""
    here = _apply_h(h, np.asarray(point, float)[None])[0]
    steps = _apply_h(h, np.asarray(point, float) + np.diag([eps, eps]))
    return here, (steps - here).T / eps


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


def map_lines(lines, document: dict | None) -> list:
    """A tracks summary's rod lines (rows ``[frame, sign, x_near, y_near, x_far, y_far, body_x, body_y, rms_px]``,
    :func:`pendulum.tracking.rod.rod_lines`) as rows ``[sign, x_near, y_near, x_far, y_far, body_x, body_y]``, their
    points mapped like the marker centres (unchanged without a document)."""
    a = np.asarray(lines, float).reshape(-1, 9)
    points = a[:, 2:8].reshape(-1, 2)  # each row's three points
    x, y = ImageToPlane(document)(points[:, 0], points[:, 1]) if document else points.T
    return np.column_stack([a[:, 1], np.column_stack([x, y]).reshape(-1, 6)]).tolist()


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
    allowed for); ``significant`` only on arcs of at least 80° (swings of ±40°). On a shorter arc the ratio is
    not fitted (an apple's 44° arc gave 0.002, a plane "turned by 90°"): ``judged`` false, the arc and a ``note``.
    None when fewer than 20 points.
    """
    from scipy.optimize import least_squares

    from pendulum.angles.geometry import fit_circle

    x = np.asarray(x, float)
    y = np.asarray(y, float)
    good = np.isfinite(x) & np.isfinite(y)
    x, y = x[good], y[good]
    if x.size < 20:
        return None
    circle = fit_circle(x, y)
    if circle.arc_span_deg < PATH_TILT_MIN_ARC_DEG:
        return {
            "judged": False,
            "arc_span_deg": circle.arc_span_deg,
            "significant": False,
            "n_points": int(x.size),
            "note": f"not judged: an arc of {circle.arc_span_deg:.0f}° (under {PATH_TILT_MIN_ARC_DEG:.0f}°) does not "
            "fix the ellipse's axis ratio",
        }
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
        "judged": True,
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


@single_threaded_opencv()
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
        lens_size = doc.get("image_size_px")
        if lens_size and list(found["image_size_px"]) != list(lens_size):
            raise CalibrationError(
                f"{plane_video}: its frames are {_size(found['image_size_px'])}, the lens clip's "
                f"({calibration_video}) {_size(lens_size)}: film both in the trials' video mode, at one zoom"
            )
        corners = found["views"][plane_frame]
        ideal = corners if lens is None else lens.undistort_px(corners)
        doc.setdefault("image_size_px", list(found["image_size_px"]))
        doc["plane"] = {"video": str(plane_video), "frame": int(plane_frame)}
        doc["plane"].update(plane_homography(ideal, pattern, square_size_m))
    if lens is None and plane_video is None:
        raise CalibrationError(f"camera setup {setup}: give calibration_video and/or plane_video")
    return doc


def _size(size_px) -> str:
    return f"{int(size_px[0])}×{int(size_px[1])} px"


def frames_unlike_calibration(trial: str, frame_px, document: dict | None) -> str | None:
    """Why a trial's frames cannot be measured through its camera setup's calibration, or None: they are another
    size than the checkerboard clips' (another video mode, an upscaled or cropped copy). A lens model holds for
    the pixels it was calibrated on: a reviewer's 1280×720 copy of a 640×360 trial came out 6.7° RMS off."""
    size = (document or {}).get("image_size_px")
    if not size or not frame_px or list(frame_px) == list(size):
        return None
    return (
        f"{trial}: its frames are {_size(frame_px)}, but camera setup {document.get('camera_setup', '?')} was "
        f"calibrated on frames of {_size(size)}: a calibration holds for one video mode and zoom; film the "
        "checkerboard in the trial's mode, or give this trial a rig with a camera setup of its own"
    )


OUTSIDE_COVERAGE_WARN_SHARE = 0.1  # a track this much outside the lens clip's board coverage is warned about


def uncalibrated_size_change(marker: dict | None, document: dict | None) -> float | None:
    """The marker's size change along its path (the tracks summary's ``size_change_along_path``) where the camera
    setup has no lens model to correct what makes it (:func:`calibration_warnings`); else None."""
    change = (marker or {}).get("size_change_along_path")
    return None if not change or (document or {}).get("lens") else float(change)


def calibration_warnings(trial: str, track, frame_px, document: dict | None, marker: dict | None = None) -> list[str]:
    """What a trial measured through its camera setup's calibration should say: the calibration's own warnings,
    and where its usable centres (image pixels) lie beyond the board's coverage (the lens model extrapolated).
    Without a lens model, where the marker's image changes size along its path (``marker``: the tracks summary's,
    ``size_change_along_path``, largest / least, said from 1.05 on): a pinhole camera square to the swing plane
    sees it the same size everywhere, so a wide lens's distortion or a turned swing plane scales the angles (on
    GoPro-like renders, sizes 1.06–1.23: angles 8–17 % too large). Raises ValueError where its frames are not the
    calibration's size (:func:`frames_unlike_calibration`)."""
    change = uncalibrated_size_change(marker, document)
    if change:
        view = "a wide lens's distortion" + (
            "" if (document or {}).get("plane") else ", or a swing plane turned from the camera"
        )
        lens_said = [
            f"the marker's image is {100 * (change - 1):.0f} % larger at one place on its path than at another: "
            f"{view}, which scales the angles (a GoPro-like lens on renders: 8–17 % too large), and with them the drag "
            "and damping coefficients, unless the camera setup is calibrated with a lens clip (cameras: "
            "calibration_video, docs/configuration.md)"
        ]
    else:
        lens_said = []
    if not document:
        return lens_said
    if why := frames_unlike_calibration(trial, frame_px, document):
        raise ValueError(why)
    said = [f"calibration: {w}" for w in document.get("warnings") or []]
    ok = track[track.flag == "ok"] if "flag" in track else track
    outside = outside_coverage_share(ok.x_px.to_numpy(float), ok.y_px.to_numpy(float), document)
    if outside is not None and outside > OUTSIDE_COVERAGE_WARN_SHARE:
        said.append(
            f"calibration: {100 * outside:.0f} % of the track lies where the lens clip's board never reached "
            f"(camera setup {document.get('camera_setup', '?')}): the lens model is extrapolated there; film the "
            "board over that part of the frame too"
        )
    return said + lens_said
