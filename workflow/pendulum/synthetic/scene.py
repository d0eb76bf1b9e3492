"""Synthetic scene: the pendulum's grey levels, exact-coverage disks and real footage's faults drawn.

What the renderer (:func:`pendulum.synthetic.experiment.render_trial`) draws besides the background, rod
and body: grey levels of the pendulum's parts for a marker polarity; disks with exact pixel coverage (4×4
supersampled, sub-pixel centre) for the marker, a two-tone or shiny bob and a second object; the faults of
a scene (:class:`pendulum.synthetic.specs.Faults`: background stripes, letterbox borders, a second moving
object, the bob's look, a trimmed clip's discarded packets; occlusions passing in front of the marker and
their schedule) and what each covers: each pixel's fraction inside a band, the letterbox mask, the
fraction of the marker disk under a border or under another disk; each frame's own sensor noise.
"""

from __future__ import annotations

import math
from dataclasses import replace

import numpy as np

from pendulum.synthetic.specs import Bob, Camera, Letterbox, Stripes, TrialSpec


def occlusion_schedule(spec: TrialSpec, n_frames: int, first_frame: int) -> list[tuple[int, int]]:
    """Non-overlapping (start, length) occlusion events covering the requested frame fraction."""
    occ = spec.occlusions
    if occ.fraction_of_frames <= 0:
        return []
    rng = np.random.default_rng(spec.seed + 104729)
    n_events = max(1, int(round(occ.fraction_of_frames * n_frames / occ.event_frames)))
    slots = np.arange(first_frame + 5, n_frames - occ.event_frames - 1, occ.event_frames * 3)
    starts = np.sort(rng.choice(slots, size=min(n_events, len(slots)), replace=False))
    return [(int(s0), occ.event_frames) for s0 in starts]


NOISE_SHIFTS = 128  # the noise field's extra rows and columns: 128² offsets, a pair of frames alike 1 in 16,384


def sensor_noise(rng: np.random.Generator, shape: tuple[int, int], sigma: float, n_frames: int):
    """Each frame's own sensor noise, N(0, σ²) per pixel: ``noise(i)`` is frame i's (a read-only view).

    One field (``shape`` plus :data:`NOISE_SHIFTS` rows and columns) drawn once, each frame a window of it at its
    own random offset: at any pixel two frames' noise is independent unless their offsets coincide (1 pair in
    16,384), at the cost of about 1.5 frames' draw. (The frames are shifted copies of one field: a registration
    of whole noisy frames against each other could find the shift; the trackers align to medians and blurred
    images.) A bank of 4 noise images, repeated, made every 4th frame alike, and so the every-k-th frames a scene
    model takes from a clip (k a power of two) noise-free against each other, as no camera's are."""
    h, w = shape
    field = rng.standard_normal((h + NOISE_SHIFTS, w + NOISE_SHIFTS), dtype=np.float32)
    field *= np.float32(sigma)
    field.flags.writeable = False
    offsets = rng.integers(0, NOISE_SHIFTS, size=(max(n_frames, 1), 2))

    def noise(i: int) -> np.ndarray:
        y, x = offsets[i]
        return field[y : y + h, x : x + w]

    return noise


def pendulum_shades(camera: Camera) -> dict:
    if camera.polarity == "dark":
        return {"rod": 95.0, "body": 205.0, "marker": 25.0, "hub": 70.0}
    if camera.polarity == "bright":
        return {"rod": 40.0, "body": 55.0, "marker": 235.0, "hub": 30.0}
    raise ValueError(f"marker polarity must be 'bright' or 'dark', got {camera.polarity!r}")


def draw_disk(canvas, cx, cy, radius, value):
    """Exact-coverage anti-aliased disk (sub-pixel centre) blended into ``canvas``."""
    x0, x1 = int(math.floor(cx - radius - 2)), int(math.ceil(cx + radius + 2))
    y0, y1 = int(math.floor(cy - radius - 2)), int(math.ceil(cy + radius + 2))
    x0c, y0c = max(x0, 0), max(y0, 0)
    x1c, y1c = min(x1, canvas.shape[1]), min(y1, canvas.shape[0])
    if x0c >= x1c or y0c >= y1c:
        return
    # 4×4 supersampling of the pixel footprint.
    offs = (np.arange(4) + 0.5) / 4 - 0.5
    ys = (np.arange(y0c, y1c)[:, None] + offs[None, :]).reshape(-1)
    xs = (np.arange(x0c, x1c)[:, None] + offs[None, :]).reshape(-1)
    inside = ((xs[None, :] - cx) ** 2 + (ys[:, None] - cy) ** 2) <= radius**2
    cover = inside.reshape(y1c - y0c, 4, x1c - x0c, 4).mean(axis=(1, 3)).astype(np.float32)
    patch = canvas[y0c:y1c, x0c:x1c]
    patch += cover * (value - patch)


def _draw_disk_part(canvas, cx, cy, radius, value, normal=None):
    """As :func:`draw_disk`, restricted to the half (x − c)·normal ≥ 0 when ``normal`` is given."""
    x0c, x1c = max(int(math.floor(cx - radius - 2)), 0), min(int(math.ceil(cx + radius + 2)), canvas.shape[1])
    y0c, y1c = max(int(math.floor(cy - radius - 2)), 0), min(int(math.ceil(cy + radius + 2)), canvas.shape[0])
    if x0c >= x1c or y0c >= y1c:
        return
    offs = (np.arange(4) + 0.5) / 4 - 0.5
    ys = (np.arange(y0c, y1c)[:, None] + offs[None, :]).reshape(-1)[:, None] - cy
    xs = (np.arange(x0c, x1c)[:, None] + offs[None, :]).reshape(-1)[None, :] - cx
    inside = (xs**2 + ys**2) <= radius**2
    if normal is not None:
        inside &= xs * normal[0] + ys * normal[1] >= 0
    cover = inside.reshape(y1c - y0c, 4, x1c - x0c, 4).mean(axis=(1, 3)).astype(np.float32)
    patch = canvas[y0c:y1c, x0c:x1c]
    patch += cover * (value - patch)


def draw_bob(canvas, cx, cy, camera: Camera, bob: Bob, phi: float, shades: dict):
    """The marker disk with a two-tone half and/or a specular highlight (see :class:`pendulum.synthetic.specs.Bob`)."""
    r = camera.marker_radius_px
    draw_disk(canvas, cx, cy, r, shades["marker"])
    if bob.two_tone:
        other = bob.other_level
        if other is None:
            other = pendulum_shades(replace(camera, polarity="dark" if camera.polarity == "bright" else "bright"))[
                "marker"
            ]
        rod = math.atan2(math.cos(phi), math.sin(phi)) + math.radians(bob.split_deg)  # line direction in the image
        _draw_disk_part(canvas, cx, cy, r, float(other), (math.sin(rod), -math.cos(rod)))
    if bob.highlight_radius_px > 0:
        direction = math.radians(bob.highlight_direction_deg + bob.highlight_gain * math.degrees(phi))
        hx = cx + bob.highlight_offset * r * math.cos(direction)
        hy = cy + bob.highlight_offset * r * math.sin(direction)
        draw_disk(canvas, hx, hy, bob.highlight_radius_px, bob.highlight_level)


def stripe_coverage(shape: tuple[int, int], stripes: Stripes) -> np.ndarray:
    """Fraction of each pixel inside a band of ``stripes`` (4×4 supersampled; float32, shape (h, w))."""
    h, w = shape
    offs = (np.arange(4) + 0.5) / 4 - 0.5
    a = math.radians(stripes.angle_deg)
    cover = np.zeros((h, w), np.float32)
    ys = np.arange(h, dtype=np.float64)[:, None]
    xs = np.arange(w, dtype=np.float64)[None, :]
    for dy in offs:
        for dx in offs:
            u = (xs + dx) * math.cos(a) + (ys + dy) * math.sin(a) - stripes.offset_px
            if stripes.period_px > 0:
                u = np.mod(u, stripes.period_px)
            cover += ((u >= 0) & (u < stripes.width_px)).astype(np.float32)
    return cover / 16.0


def letterbox_mask(shape: tuple[int, int], letterbox: Letterbox) -> np.ndarray:
    """Boolean (h, w) mask of the letterbox borders."""
    h, w = shape
    mask = np.zeros((h, w), bool)
    mask[: letterbox.top_px, :] = True
    mask[h - letterbox.bottom_px :, :] = True
    mask[:, : letterbox.left_px] = True
    mask[:, w - letterbox.right_px :] = True
    return mask


def _disk_halfplane_fraction(radius: float, distance: float) -> float:
    """Fraction of a disk beyond a straight edge at signed ``distance`` from its centre (> 0: centre inside)."""
    d = max(-radius, min(radius, distance))
    if d >= radius:
        return 0.0
    segment = radius**2 * math.acos(d / radius) - d * math.sqrt(radius**2 - d**2)
    return segment / (math.pi * radius**2)


def letterbox_covered_fraction(camera: Camera, letterbox: Letterbox, x: float, y: float) -> float:
    """Fraction of the marker disk at (x, y) hidden under the letterbox (edges summed, capped at 1)."""
    r, w, h = camera.marker_radius_px, camera.width_px, camera.height_px
    distances = [y - letterbox.top_px, (h - letterbox.bottom_px) - y, x - letterbox.left_px]
    distances.append((w - letterbox.right_px) - x)
    widths = (letterbox.top_px, letterbox.bottom_px, letterbox.left_px, letterbox.right_px)
    return min(1.0, sum(_disk_halfplane_fraction(r, d) for d, width in zip(distances, widths, strict=True) if width))


def disk_overlap_fraction(r_marker: float, r_other: float, distance: float) -> float:
    """Fraction of a disk of radius r_marker covered by a disk of radius r_other at ``distance``."""
    r, big, d = r_marker, r_other, distance
    if d >= r + big:
        return 0.0
    if d <= abs(big - r):
        return 1.0 if big >= r else (big / r) ** 2
    a1 = r * r * math.acos((d * d + r * r - big * big) / (2 * d * r))
    a2 = big * big * math.acos((d * d + big * big - r * r) / (2 * d * big))
    a3 = 0.5 * math.sqrt((-d + r + big) * (d + r - big) * (d - r + big) * (d + r + big))
    return (a1 + a2 - a3) / (math.pi * r * r)
