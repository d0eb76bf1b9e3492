"""Synthetic lens and view: checkerboard clips and trials seen through a known distorting lens and/or a tilted plane.

A trial is rendered fronto-parallel by :func:`pendulum.synthetic.experiment.render_trial`
on a canvas padded by ``pad_px``, then resampled (``cv2.remap``) through the
inverse of the camera's mapping: output pixel p → ideal pinhole pixel
u = port⁻¹(lens⁻¹(p)) → swing-plane pixel H⁻¹ u, with H the plane-to-image homography of
a swing plane turned by ``plane_tilt_deg`` about the vertical image axis through
the image centre (a pinhole of focal length ``fx``). The truth angle stays the
physical angle in the swing plane; the truth marker position is mapped forward
(H, the port, then the lens). A flat port with the camera at it refracts a
ray at θ from the axis in the water to asin(n sin θ) in the air: a radial map
about the axis, the same for every depth. Checkerboard clips are rendered exactly (3×3 supersampled
squares) through the same lens: the lens clip with the board moved and tilted
over the frame, the plane clip with the board lying in the swing plane.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, replace
from pathlib import Path

import cv2
import numpy as np

from pendulum.camera.calibration import Lens
from pendulum.synthetic.experiment import RenderedTrial, render_trial, write_video
from pendulum.synthetic.specs import TrialSpec

SUPERSAMPLE = 3


@dataclass(frozen=True)
class Optics:
    """A camera: image size, K (fx = fy, centre cx, cy), a lens model and a swing plane tilt."""

    width_px: int = 640
    height_px: int = 360
    focal_px: float = 560.0
    centre_px: tuple[float, float] | None = None  # None: image centre − (0.3, −0.2) px
    lens_model: str = "rational"  # "rational" (Brown k1, k2, p1, p2, k3, ...) or "fisheye" (Kannala–Brandt)
    distortion: tuple = (-0.3, 0.08, 0.0, 0.0, 0.0)
    plane_tilt_deg: float = 0.0  # swing plane turned about the image's vertical axis
    port_refractive_index: float = 1.0  # water behind a flat port at the camera (1: no port)

    @property
    def camera_matrix(self) -> np.ndarray:
        cx, cy = self.centre_px or (self.width_px / 2 - 0.3, self.height_px / 2 + 0.2)
        return np.array([[self.focal_px, 0, cx], [0, self.focal_px, cy], [0, 0, 1.0]])

    @property
    def lens(self) -> Lens:
        d = np.asarray(self.distortion, float)
        if self.lens_model == "fisheye":
            d = np.pad(d, (0, 4 - d.size))[:4]
        return Lens(self.lens_model if np.any(d != 0) else "none", self.camera_matrix, d)

    def _refract(self, points_px, index: float) -> np.ndarray:
        """Flat port with the camera at it: normalised radius tan θ → tan(asin(index · sin θ)) about the axis."""
        pts = np.asarray(points_px, float).reshape(-1, 2)
        if self.port_refractive_index == 1.0:
            return pts.copy()
        k = self.camera_matrix
        n = (pts - k[:2, 2]) / self.focal_px
        rho = np.hypot(n[:, 0], n[:, 1])
        sin_out = np.clip(index * np.sin(np.arctan(rho)), -0.999999, 0.999999)
        scale = np.divide(np.tan(np.arcsin(sin_out)), rho, out=np.full(rho.shape, index), where=rho > 0)
        return n * scale[:, None] * self.focal_px + k[:2, 2]

    def to_image(self, ideal_px) -> np.ndarray:
        """Ideal (water-side) pinhole pixels → image pixels: refraction at the port, then the lens."""
        return self.lens.distort_px(self._refract(ideal_px, self.port_refractive_index))

    def to_ideal(self, image_px) -> np.ndarray:
        """Image pixels → ideal (water-side) pinhole pixels: the inverse of :meth:`to_image`."""
        return self._refract(self.lens.undistort_px(image_px), 1.0 / self.port_refractive_index)

    def plane_homography(self) -> np.ndarray:
        """H: swing-plane pixels (the fronto-parallel render) → ideal image pixels; identity without tilt."""
        if self.plane_tilt_deg == 0:
            return np.eye(3)
        cx, cy = self.width_px / 2, self.height_px / 2
        tau = math.radians(self.plane_tilt_deg)
        z0, f = 1.0, self.focal_px
        s = z0 / f
        plane = np.array([[x, y] for x in (-300.0, 0.0, 300.0) for y in (-200.0, 0.0, 200.0)])
        q = np.column_stack(
            [plane[:, 0] * s * math.cos(tau), plane[:, 1] * s, z0 - plane[:, 0] * s * math.sin(tau)]
        )  # turned about the vertical (y) axis
        image = np.column_stack([f * q[:, 0] / q[:, 2] + cx, f * q[:, 1] / q[:, 2] + cy])
        h, _ = cv2.findHomography(plane + [cx, cy], image, 0)
        return h / h[2, 2]


def _apply_h(h, pts) -> np.ndarray:
    v = (h @ np.column_stack([pts, np.ones(len(pts))]).T).T
    return v[:, :2] / v[:, 2:3]


def _pixel_grid(width: int, height: int, supersample: int) -> np.ndarray:
    offs = (np.arange(supersample) + 0.5) / supersample - 0.5
    ys = (np.arange(height)[:, None] + offs[None, :]).reshape(-1)
    xs = (np.arange(width)[:, None] + offs[None, :]).reshape(-1)
    gx, gy = np.meshgrid(xs, ys)
    return np.column_stack([gx.ravel(), gy.ravel()])


def ideal_of_image(optics: Optics, supersample: int = 1) -> np.ndarray:
    """Ideal pinhole pixel of every (sub)pixel of the output image, shape (H·s, W·s, 2)."""
    grid = _pixel_grid(optics.width_px, optics.height_px, supersample)
    ideal = optics.to_ideal(grid)
    return ideal.reshape(optics.height_px * supersample, optics.width_px * supersample, 2)


def image_of_plane(optics: Optics, points_px) -> np.ndarray:
    """Swing-plane pixels → distorted image pixels (the forward camera)."""
    return optics.to_image(_apply_h(optics.plane_homography(), np.asarray(points_px, float).reshape(-1, 2)))


def _checker(board_xy, pattern, square_m, background=128.0) -> np.ndarray:
    """Grey value of board coordinates (m): squares of a (cols+1)×(rows+1) board, a white margin of one square."""
    cols, rows = pattern
    u = board_xy[..., 0] / square_m + 1.0  # square index; inner corner (0, 0) at u = v = 1
    v = board_xy[..., 1] / square_m + 1.0
    inside = (u >= 0) & (u < cols + 1) & (v >= 0) & (v < rows + 1)
    margin = (u >= -1) & (u < cols + 2) & (v >= -1) & (v < rows + 2)
    dark = (np.floor(u).astype(np.int64) + np.floor(v).astype(np.int64)) % 2 == 0
    value = np.where(margin, 235.0, background)
    return np.where(inside & dark, 25.0, value)


def _finish(image_ss: np.ndarray, supersample: int, rng, noise_sigma: float) -> np.ndarray:
    h, w = image_ss.shape[0] // supersample, image_ss.shape[1] // supersample
    image = image_ss.reshape(h, supersample, w, supersample).mean(axis=(1, 3))
    image = image + rng.normal(0, noise_sigma, image.shape)
    return np.clip(np.rint(image), 0, 255).astype(np.uint8)


def board_poses(optics: Optics, pattern, square_m: float, n_views: int, seed: int) -> list[tuple[np.ndarray, ...]]:
    """(R, t) of a board moved and tilted over the frame, every corner at least 15 px inside the image."""
    rng = np.random.default_rng(seed)
    k = optics.camera_matrix
    cols, rows = pattern
    corners = np.array([[x, y, 0.0] for y in range(rows) for x in range(cols)]) * square_m
    centre = corners.mean(axis=0)
    width_m = (cols + 1) * square_m
    poses = []
    for _ in range(200 * n_views):
        if len(poses) == n_views:
            break
        angles = np.radians([rng.uniform(-40, 40), rng.uniform(-40, 40), rng.uniform(-30, 30)])
        r = cv2.Rodrigues(angles)[0]
        span = rng.uniform(0.35, 0.65) * optics.width_px  # board width in the image
        z = optics.focal_px * width_m / span
        u = rng.uniform(0.15, 0.85) * optics.width_px
        v = rng.uniform(0.15, 0.85) * optics.height_px
        target = z * np.linalg.solve(k, [u, v, 1.0])
        t = target - r @ centre
        cam = (r @ corners.T).T + t
        if np.any(cam[:, 2] <= 0.05 * z):
            continue
        ideal = (k @ (cam / cam[:, 2:3]).T).T[:, :2]
        image = optics.to_image(ideal)
        if not np.all(np.isfinite(image)):
            continue
        margin = 15
        if (
            image[:, 0].min() < margin
            or image[:, 1].min() < margin
            or image[:, 0].max() > optics.width_px - margin
            or image[:, 1].max() > optics.height_px - margin
        ):
            continue
        back = optics.to_ideal(image)  # the camera must be invertible there
        if np.max(np.abs(back - ideal)) > 1e-3:
            continue
        poses.append((r, t))
    if len(poses) < n_views:
        raise ValueError(f"only {len(poses)} board poses fit in the image")
    return poses


def render_lens_clip(
    optics: Optics, pattern=(9, 6), square_m: float = 0.025, n_views: int = 30, seed: int = 0, noise_sigma=2.0
) -> tuple[list[np.ndarray], list]:
    """Frames of a checkerboard moved and tilted in front of the camera (one pose per frame), and the poses."""
    ideal = ideal_of_image(optics, SUPERSAMPLE)
    k_inv = np.linalg.inv(optics.camera_matrix)
    rays = (np.concatenate([ideal, np.ones(ideal.shape[:2] + (1,))], axis=2) @ k_inv.T).astype(np.float32)
    rng = np.random.default_rng(seed + 1)
    frames = []
    poses = board_poses(optics, pattern, square_m, n_views, seed)
    for r, t in poses:
        h = np.column_stack([r[:, 0], r[:, 1], t])  # board (X, Y, 1) → ray
        board = rays @ np.linalg.inv(h).T.astype(np.float32)
        with np.errstate(divide="ignore", invalid="ignore"):
            xy = board[..., :2] / board[..., 2:3]
        behind = ~(board[..., 2] > 0)  # rays that meet the board's plane behind the camera
        xy[behind] = 1e3
        frames.append(_finish(_checker(xy, pattern, square_m), SUPERSAMPLE, rng, noise_sigma))
    return frames, poses


def render_plane_clip(
    optics: Optics,
    pattern=(9, 6),
    square_px: float = 30.0,
    square_m: float = 0.025,
    centre_px=None,
    n_frames: int = 3,
    seed: int = 0,
    noise_sigma=2.0,
) -> list[np.ndarray]:
    """Frames of a checkerboard lying in the swing plane, axes along the plane's x and y, centred at ``centre_px``."""
    ideal = ideal_of_image(optics, SUPERSAMPLE).reshape(-1, 2)
    plane = _apply_h(np.linalg.inv(optics.plane_homography()), ideal)
    cols, rows = pattern
    cx, cy = centre_px or (optics.width_px / 2, optics.height_px / 2)
    origin = np.array([cx - (cols - 1) / 2 * square_px, cy - (rows - 1) / 2 * square_px])
    xy = (plane - origin) / square_px * square_m
    shape = (optics.height_px * SUPERSAMPLE, optics.width_px * SUPERSAMPLE)
    value = _checker(xy.reshape(shape + (2,)), pattern, square_m)
    rng = np.random.default_rng(seed + 2)
    return [_finish(value, SUPERSAMPLE, rng, noise_sigma) for _ in range(n_frames)]


def render_trial_through(spec: TrialSpec, optics: Optics, pad_px: int = 120) -> RenderedTrial:
    """A trial seen through ``optics``: rendered fronto-parallel on a padded canvas, then resampled.

    ``spec.camera`` gives the swing plane's pixels (pivot, arm, marker) as a
    camera facing the plane squarely would see them, at the output size. The
    truth keeps ``theta_rad``; ``marker_x_px``/``marker_y_px`` become the image
    positions of the marker centre (forward mapped), the plane positions move to
    ``plane_x_px``/``plane_y_px``.
    """
    cam = spec.camera
    if (cam.width_px, cam.height_px) != (optics.width_px, optics.height_px):
        raise ValueError("spec.camera and optics must have the same image size")
    big = replace(
        cam,
        width_px=cam.width_px + 2 * pad_px,
        height_px=cam.height_px + 2 * pad_px,
        pivot_px=(cam.pivot_px[0] + pad_px, cam.pivot_px[1] + pad_px),
    )
    rendered = render_trial(replace(spec, camera=big))
    ideal = ideal_of_image(optics).reshape(-1, 2)
    plane = _apply_h(np.linalg.inv(optics.plane_homography()), ideal) + pad_px
    map_x = plane[:, 0].reshape(optics.height_px, optics.width_px).astype(np.float32)
    map_y = plane[:, 1].reshape(optics.height_px, optics.width_px).astype(np.float32)
    frames = [
        cv2.remap(f.astype(np.float32), map_x, map_y, cv2.INTER_CUBIC, borderMode=cv2.BORDER_REFLECT).round()
        for f in rendered.frames
    ]
    frames = [np.clip(f, 0, 255).astype(np.uint8) for f in frames]
    truth = rendered.truth.copy()
    truth["plane_x_px"] = truth.marker_x_px - pad_px
    truth["plane_y_px"] = truth.marker_y_px - pad_px
    image = image_of_plane(optics, truth[["plane_x_px", "plane_y_px"]].to_numpy())
    truth["marker_x_px"], truth["marker_y_px"] = image[:, 0], image[:, 1]
    return RenderedTrial(frames, truth)


def write_clip(frames, path: Path, fps: float = 10.0, crf: int = 16) -> Path:
    """A clip as H.264 (the workflow's calibration input)."""
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    write_video(frames, path, fps, crf, "veryfast")
    return path


def generate_optics_trial(
    spec: TrialSpec,
    optics: Optics,
    video_dir: Path,
    truth_dir: Path,
    calibration_dir: Path,
    setup: str,
    pattern=(9, 6),
    square_m: float = 0.025,
) -> dict:
    """A trial seen through ``optics`` with its checkerboard clips and its truth, as the workflow takes them.

    Writes ``video_dir/<name>.mp4``, ``truth_dir/<name>.yaml|.csv`` (the truth
    record gains ``optics``) and, once per setup, ``calibration_dir/<setup>.mp4``
    (the lens clip, when the lens distorts) and ``<setup>_plane.mp4`` (when the
    plane is tilted). Returns the paths for config ``cameras.<setup>``.
    """
    import yaml

    from pendulum.synthetic.experiment import truth_record

    video_dir, truth_dir, calibration_dir = Path(video_dir), Path(truth_dir), Path(calibration_dir)
    truth_dir.mkdir(parents=True, exist_ok=True)
    rendered = render_trial_through(spec, optics)
    video_dir.mkdir(parents=True, exist_ok=True)
    write_video(rendered.frames, video_dir / f"{spec.name}.mp4", spec.camera.fps, spec.camera.crf, spec.camera.preset)
    rendered.truth.to_csv(truth_dir / f"{spec.name}.csv", index=False, float_format="%.9g")
    record = truth_record(spec)
    record["optics"] = {
        "camera_matrix": optics.camera_matrix.tolist(),
        "lens_model": optics.lens_model,
        "distortion": list(optics.distortion),
        "plane_tilt_deg": optics.plane_tilt_deg,
    }
    (truth_dir / f"{spec.name}.yaml").write_text(yaml.safe_dump(record, sort_keys=False))
    setup_doc: dict = {"square_size_m": square_m, "pattern_inner_corners": list(pattern)}
    if optics.lens.model != "none" or optics.port_refractive_index != 1.0:
        clip = calibration_dir / f"{setup}.mp4"
        if not clip.exists():
            write_clip(render_lens_clip(optics, pattern, square_m)[0], clip)
        setup_doc["calibration_video"] = str(clip)
    if optics.plane_tilt_deg:
        clip = calibration_dir / f"{setup}_plane.mp4"
        if not clip.exists():
            write_clip(render_plane_clip(optics, pattern, square_m=square_m), clip)
        setup_doc["plane_video"], setup_doc["plane_frame"] = str(clip), 0
    return setup_doc
