"""The tracker's settings and the flags a tracked frame can carry: what every module of the stage takes."""

from __future__ import annotations

import math
from dataclasses import dataclass

FLAGS = ("ok", "occluded", "glare", "jump", "duplicate", "edge", "held", "lost")


@dataclass(frozen=True)
class TrackerSettings:
    # None: found by :func:`pendulum.tracking.detection.detect_marker` (so is "auto" polarity); given values win.
    marker_radius_px: float | None = 10.0
    polarity: str = "bright"  # "bright" marker on a darker scene, "dark" on a brighter one, or "auto"
    start_px: tuple[float, float] | None = None  # a hint where the marker is in the first frame
    # marker signal below this fraction of normal: "occluded"; above the other: "glare" (a frame so flagged is ok in
    # the end where, within 1 ± 4 × the signal's own spread, the marker's other frames at its place read normal:
    # marker_arc.MarkerSignal)
    min_signal_ratio: float = 0.9
    max_signal_ratio: float = 1.12
    jump_floor_px: float = 1.0  # smallest leave-one-out residual that counts as a jump
    jump_sigmas: float = 6.0
    reacquire_after_frames: int = 10
    max_centroid_disagreement_px: float = 0.4  # linear vs thresholded centroid; more: "occluded"
    # the linear centroid moves more than this when its mask shrinks from r + 2.5 to r + 1 px: something of
    # the marker's grey in the margin (which the thresholded centroid does not tell): "occluded"
    max_margin_shift_px: float = 0.25
    max_width_ratio: float = 1.15  # spot wider across the motion than this × normal (width²): "occluded"
    min_acquire_score: float = 0.75  # disk-template correlation a spot needs to be taken for the marker
    min_usable_fraction: float = 0.3  # fewer "ok" frames than this: the video cannot give a record
    centroid: str = "linear"  # "linear": Σ (I − b) x in a soft streak mask; "threshold": Σ max(I − T, 0) x
    # Shutter-open time / frame interval, for the exposure-centre correction; None: measured
    # from the streaks (needs ≥ 10 frames moving more than half a marker radius, else 0.5),
    # 0: no correction.
    exposure_fraction: float | None = None

    max_unresolved: float = 0.03  # share of the marker over scene of its own grey, unmeasurable: "occluded"
    max_lost_step_radii: float = 2.0  # search window growth per lost frame, in marker radii (bounded, see below)
    # The normal signal and width² as smooth functions of the marker's angle on its arc (lens
    # magnification, vignetting, lighting falloff), fitted to the ok frames (see ArcReference);
    # False: the first frames' values everywhere.
    reference_along_arc: bool = True
    # "marker": a marker disk; "body": the swinging object's silhouette (pendulum.tracking.body); "auto": the marker
    # where a good one is found, else the body (pendulum.tracking.method)
    method: str = "auto"
    # the camera's frame rate where the file plays at another (a phone's slow-motion clip: filmed at 240 fps,
    # stored at 30): the record's times are put at it (pendulum.tracking.timing.at_capture_rate); None: the file's
    capture_fps: float | None = None

    def __post_init__(self):
        if self.method not in ("auto", "marker", "body"):
            raise ValueError(f"tracking method must be 'auto', 'marker' or 'body', got {self.method!r}")
        if self.polarity not in ("bright", "dark", "auto"):
            raise ValueError(f"marker polarity must be 'bright', 'dark' or 'auto', got {self.polarity!r}")
        if self.centroid not in ("linear", "threshold"):
            raise ValueError(f"centroid must be 'linear' or 'threshold', got {self.centroid!r}")
        if self.marker_radius_px is not None and not self.marker_radius_px > 0:
            raise ValueError("marker_radius_px must be positive")
        if self.capture_fps is not None and not self.capture_fps > 0:
            raise ValueError("capture_fps must be positive")
        if not 0 < self.min_acquire_score < 1:
            raise ValueError("min_acquire_score must be between 0 and 1")

    @classmethod
    def from_config(cls, values: dict) -> TrackerSettings:
        """Settings from config.yaml's ``tracking`` block (or a trial's merged settings): lists become tuples."""
        return cls(**{k: (tuple(v) if isinstance(v, list) else v) for k, v in values.items()})

    @property
    def needs_detection(self) -> bool:
        return self.polarity == "auto" or self.marker_radius_px is None


# The tracks job's memory and time grow with the picture: the frames sampled over the clip (60–119, held for the
# searches and the body's scene) are full size. Peaks measured on 2026-11-29 (one decoder thread): 0.35 GB at
# 720p, 0.5–0.8 GB at 1080p, 2.2 GB for a 4K clip holding 75 samples (up to 119: ~2.9 GB); 0.13 s per 4K frame
# (the marker tried, then the body), 6 ms per 720p frame (a marker).
JOB_MEM_MB, JOB_MEM_MB_PER_MPX, JOB_MIN_MEM_MB = 400, 350, 2000
JOB_MIN_RUNTIME_MIN, JOB_S_PER_FRAME_MPX = 60, 0.1  # ~6× the seconds measured per 4K frame and megapixel


def job_resources(width_px: int, height_px: int, n_frames: int) -> tuple[int, int]:
    """Memory (MB) and runtime (min) a tracks job declares for a clip: M = max(2000, 400 + 350 P) MB and
    t = max(60, 0.1 s × P × N) min, P its megapixels, N its frames (rounded up to 100 MB, 10 min)."""
    megapixels = width_px * height_px / 1e6
    mem_mb = max(JOB_MIN_MEM_MB, math.ceil((JOB_MEM_MB + JOB_MEM_MB_PER_MPX * megapixels) / 100) * 100)
    minutes = megapixels * n_frames * JOB_S_PER_FRAME_MPX / 60
    return mem_mb, max(JOB_MIN_RUNTIME_MIN, math.ceil(minutes / 10) * 10)
