"""What a synthetic trial is: the camera, the scene's faults, disturbances outside the model, the trial itself.

Plain specifications (dataclasses read from data/synthetic/*.yaml); :mod:`pendulum.synthetic.experiment`
renders them and :mod:`pendulum.synthetic.scene` draws the faults.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np


@dataclass
class Camera:
    """How the synthetic camera sees the rig."""

    width_px: int = 1280
    height_px: int = 720
    fps: float = 30.0
    pivot_px: tuple[float, float] = (640.3, 70.6)
    marker_arm_px: float = 560.0  # pivot to marker centre
    marker_radius_px: float = 10.0
    polarity: str = "bright"  # bright marker on darker scene, or "dark" on bright
    roll_deg: float = 0.0  # camera roll: image vertical minus true vertical
    exposure_fraction: float = 0.5  # shutter open time / frame interval
    exposure_subsamples: int = 8
    noise_sigma: float = 3.0  # grey levels, before compression
    crf: int = 22  # x264 constant rate factor (lossy compression)
    preset: str = "veryfast"
    # Largest marker step between sub-exposures: a long exposure gets more sub-exposures (never fewer
    # than ``exposure_subsamples``) so its streak is smooth. In the truth record only when changed.
    blur_step_px: float = 1.5


@dataclass
class Occlusions:
    """Opaque objects (a hand, a bubble cloud) passing in front of the marker."""

    fraction_of_frames: float = 0.0
    event_frames: int = 6


@dataclass
class Stripes:
    """Flat bands across the background with hard edges the marker crosses (a striped wall, tile joints).

    A pixel is in a band when u − offset_px, with u = x cos a + y sin a (a = ``angle_deg``; 0: vertical
    bands, u = x), lies in [0, width_px) modulo ``period_px`` (0: one band). Bands are drawn with exact
    pixel coverage at grey ``level`` (below the scene for dark bands, above for bright).
    """

    width_px: float = 0.0  # 0: no stripes
    period_px: float = 0.0
    offset_px: float = 0.0
    level: float = 30.0
    angle_deg: float = 0.0

    @property
    def active(self) -> bool:
        return self.width_px > 0


@dataclass
class Letterbox:
    """Black borders (a phone's letterbox/pillarbox) of the given widths, drawn over everything, noise-free."""

    top_px: int = 0
    bottom_px: int = 0
    left_px: int = 0
    right_px: int = 0
    level: float = 0.0

    @property
    def active(self) -> bool:
        return any((self.top_px, self.bottom_px, self.left_px, self.right_px))


@dataclass
class SecondObject:
    """Another disk in the scene (a bubble, a swaying float) on a non-circular path; ``path: none`` is off.

    ``linear``: back and forth on the segment start→end, p = start + (end − start)(1 − cos 2πt/T)/2.
    ``bubble``: rises from start to end in T, then again from start (one bubble at a time), with a
    sideways wobble w sin(2πt/T_w) across the segment. t is video time; T = ``period_s``. Radius and
    grey level default to the marker's (same size and polarity). Drawn behind the pendulum unless
    ``in_front``; exposure-blurred like the marker.
    """

    path: str = "none"
    start_px: tuple[float, float] = (0.0, 0.0)
    end_px: tuple[float, float] = (0.0, 0.0)
    period_s: float = 2.0
    radius_px: float | None = None
    level: float | None = None
    wobble_px: float = 0.0
    wobble_period_s: float = 0.5
    in_front: bool = False

    @property
    def active(self) -> bool:
        if self.path not in ("none", "linear", "bubble"):
            raise ValueError(f"second_object.path must be 'none', 'linear' or 'bubble', got {self.path!r}")
        return self.path != "none"

    def position_px(self, times_s) -> tuple[np.ndarray, np.ndarray]:
        """Centre at video times ``times_s`` (arrays allowed)."""
        t = np.asarray(times_s, float)
        (x0, y0), (x1, y1) = self.start_px, self.end_px
        if self.path == "linear":
            u = 0.5 * (1 - np.cos(2 * np.pi * t / self.period_s))
            return x0 + u * (x1 - x0), y0 + u * (y1 - y0)
        u = np.mod(t / self.period_s, 1.0)
        length = math.hypot(x1 - x0, y1 - y0) or 1.0
        nx, ny = -(y1 - y0) / length, (x1 - x0) / length  # across the path
        w = self.wobble_px * np.sin(2 * np.pi * t / self.wobble_period_s)
        return x0 + u * (x1 - x0) + w * nx, y0 + u * (y1 - y0) + w * ny


@dataclass
class Bob:
    """The marker's look: plain (default), two-tone and/or shiny.

    ``two_tone``: the half on the +x side of a line through the centre (at ``split_deg`` from the rod,
    turning with the bob) has grey ``other_level`` (None: the opposite polarity's marker grey).
    ``highlight_radius_px`` > 0: a specular spot of grey ``highlight_level`` at
    ``highlight_offset`` marker radii from the centre, in image direction
    ``highlight_direction_deg + highlight_gain·θ`` (degrees from +x toward +y; gain 0: a sphere under a fixed
    lamp, the spot stays put while the bob turns under it; gain 1: it turns with the bob).
    The truth's marker centre is always the disk's geometric centre.
    """

    two_tone: bool = False
    other_level: float | None = None
    split_deg: float = 0.0
    highlight_radius_px: float = 0.0
    highlight_level: float = 255.0
    highlight_offset: float = 0.5
    highlight_direction_deg: float = -135.0
    highlight_gain: float = 0.0

    @property
    def active(self) -> bool:
        return self.two_tone or self.highlight_radius_px > 0


@dataclass
class Faults:
    """Real-world faults for the tracker and the frames stage; all off by default (renders unchanged).

    ``trimmed_lead_frames``: the video file holds this many extra frames before its first shown
    frame, as packets an MP4 edit list tells the decoder to discard (a phone's trimmed clip); the
    truth describes the shown frames only (frame 0 at time 0).
    """

    stripes: Stripes = field(default_factory=Stripes)
    letterbox: Letterbox = field(default_factory=Letterbox)
    second_object: SecondObject = field(default_factory=SecondObject)
    bob: Bob = field(default_factory=Bob)
    trimmed_lead_frames: int = 0

    @property
    def active(self) -> bool:
        parts = (self.stripes, self.letterbox, self.second_object, self.bob)
        return any(p.active for p in parts) or self.trimmed_lead_frames > 0

    @classmethod
    def from_mapping(cls, values: dict | None) -> Faults:
        values = dict(values or {})
        second = dict(values.get("second_object") or {})
        for key in ("start_px", "end_px"):
            if key in second:
                second[key] = tuple(second[key])
        return cls(
            stripes=Stripes(**(values.get("stripes") or {})),
            letterbox=Letterbox(**(values.get("letterbox") or {})),
            second_object=SecondObject(**second),
            bob=Bob(**(values.get("bob") or {})),
            trimmed_lead_frames=int(values.get("trimmed_lead_frames", 0)),
        )


@dataclass(frozen=True)
class PeriodicTorque:
    """A disturbance torque outside the library: τ(t) = A sin(2π t / T + φ), t in the simulation's time base."""

    amplitude_nm: float
    period_s: float
    phase_rad: float = 0.0

    def __call__(self, t: float) -> float:
        return self.amplitude_nm * math.sin(2 * math.pi * t / self.period_s + self.phase_rad)


@dataclass
class Disturbances:
    """Effects outside the model library, for tests of the discovery; all off by default.

    ``pivot_drift_px``: the rendered pivot (and with it the whole pendulum) moves
    linearly from ``camera.pivot_px`` at t = 0 to ``pivot_px + pivot_drift_px`` at
    the end of the video. ``torque_*``: a periodic torque A sin(2π t/T + φ) acting
    on the pendulum (t: video time), e.g. a pump or vortex shedding off the tank.
    """

    pivot_drift_px: tuple[float, float] = (0.0, 0.0)
    torque_amplitude_nm: float = 0.0
    torque_period_s: float = 1.0
    torque_phase_rad: float = 0.0

    @property
    def torque(self) -> PeriodicTorque | None:
        if self.torque_amplitude_nm == 0:
            return None
        return PeriodicTorque(self.torque_amplitude_nm, self.torque_period_s, self.torque_phase_rad)

    @property
    def drifting(self) -> bool:
        return any(v != 0 for v in self.pivot_drift_px)

    @property
    def active(self) -> bool:
        return self.drifting or self.torque is not None


@dataclass
class TrialSpec:
    name: str
    release_deg: float
    rig: dict
    truth: dict  # physical coefficients, e.g. added_mass_kg, drag_area_m2, ...
    effects: list[str]  # terms of the true physics (names in pendulum.model.effects.TERMS)
    seed: int = 0
    hold_s: float = 1.0  # pendulum held at the release angle before release
    duration_s: float = 25.0
    camera: Camera = field(default_factory=Camera)
    occlusions: Occlusions = field(default_factory=Occlusions)
    disturbances: Disturbances = field(default_factory=Disturbances)
    faults: Faults = field(default_factory=Faults)

    @classmethod
    def from_mapping(cls, values: dict) -> TrialSpec:
        values = dict(values)
        camera = dict(values.get("camera", {}))
        if "pivot_px" in camera:
            camera["pivot_px"] = tuple(camera["pivot_px"])
        values["camera"] = Camera(**camera)
        values["occlusions"] = Occlusions(**values.get("occlusions", {}))
        disturbances = dict(values.get("disturbances") or {})
        if "pivot_drift_px" in disturbances:
            disturbances["pivot_drift_px"] = tuple(disturbances["pivot_drift_px"])
        values["disturbances"] = Disturbances(**disturbances)
        values["faults"] = Faults.from_mapping(values.get("faults"))
        return cls(**values)
