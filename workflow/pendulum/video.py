"""Video stage: container timeline, QA contact sheet and the single luma decode pass.

Everything here reads the container with PyAV. The timeline needs no decoding
(packet timestamps only); the contact sheet decodes key frames only; the
tracker gets the Y (luma) plane of every frame without colour conversion.
"""

from __future__ import annotations

import math
from collections.abc import Iterator
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import pandas as pd

VIDEO_EXTENSIONS = (".mp4", ".avi", ".mov")


class VideoError(RuntimeError):
    """A video that cannot be read; the message names the file and the problem."""


@dataclass(frozen=True)
class VideoInfo:
    path: str
    width_px: int
    height_px: int
    nominal_fps: float
    codec: str
    n_packets: int


def _open(path: Path):
    import av

    path = Path(path)
    if not path.is_file():
        raise VideoError(f"{path}: no such file")
    try:
        container = av.open(str(path))
    except Exception as exc:  # PyAV raises several error types for a bad container
        raise VideoError(f"{path}: not a readable video container ({exc})") from exc
    if not container.streams.video:
        container.close()
        raise VideoError(f"{path}: contains no video stream")
    return container


def frame_timeline(path: Path) -> tuple[VideoInfo, pd.DataFrame]:
    """Per-frame presentation times from the container (demux only, no decoding).

    Columns: ``frame``, ``pts``, ``time_s``, ``interval_s``, ``dropped_before``
    (frames missing before this one: the interval is ≥ 1.5 nominal intervals),
    ``duplicate_time`` (same timestamp as the previous frame), ``keyframe``,
    ``packet_bytes``.
    """
    container = _open(path)
    try:
        stream = container.streams.video[0]
        rate = stream.average_rate or stream.guessed_rate
        if not rate:
            raise VideoError(f"{path}: the video stream states no frame rate")
        nominal_fps = float(rate)
        tb = stream.time_base
        rows = []
        try:
            for packet in container.demux(stream):
                if packet.size == 0 or packet.pts is None:
                    continue
                rows.append((packet.pts, bool(packet.is_keyframe), packet.size))
        except Exception as exc:
            raise VideoError(f"{path}: container is corrupt after {len(rows)} packets ({exc})") from exc
        if not rows:
            raise VideoError(f"{path}: the video stream holds no frames")
        info = VideoInfo(
            str(path),
            int(stream.codec_context.width),
            int(stream.codec_context.height),
            nominal_fps,
            stream.codec_context.name,
            len(rows),
        )
    finally:
        container.close()
    table = pd.DataFrame(rows, columns=["pts", "keyframe", "packet_bytes"]).sort_values("pts", kind="stable")
    table.insert(0, "frame", np.arange(len(table)))
    start = table.pts.iloc[0]
    table.insert(2, "time_s", (table.pts - start).to_numpy(dtype=float) * float(tb))
    interval = np.diff(table.time_s.to_numpy(), prepend=np.nan)
    nominal = 1.0 / nominal_fps
    table.insert(3, "interval_s", interval)
    with np.errstate(invalid="ignore"):
        dropped = np.where(interval >= 1.5 * nominal, np.rint(interval / nominal) - 1, 0)
    table.insert(4, "dropped_before", np.nan_to_num(dropped).astype(int))
    table.insert(5, "duplicate_time", np.nan_to_num(interval, nan=1.0) <= 0)
    return info, table.reset_index(drop=True)


def luma(frame) -> np.ndarray:
    """The Y plane of a decoded frame as a (height, width) uint8 view (no colour conversion)."""
    plane = frame.planes[0]
    rows = np.frombuffer(plane, np.uint8).reshape(frame.height, plane.line_size)
    return rows[:, : frame.width]


def iter_luma(path: Path, keyframes_only: bool = False) -> Iterator[tuple[int, float, np.ndarray]]:
    """Decode the video once, yielding ``(frame_index, time_s, Y)`` in presentation order.

    Grey (``gray``) and planar YUV streams give their luma directly; other pixel
    formats are converted to grey.
    """
    container = _open(path)
    try:
        stream = container.streams.video[0]
        stream.thread_type = "AUTO"
        if keyframes_only:
            stream.codec_context.skip_frame = "NONKEY"
        tb = float(stream.time_base)
        start = None
        planar = None
        index = 0
        try:
            for frame in container.decode(stream):
                if frame.pts is None:
                    continue
                if start is None:
                    start = frame.pts
                    fmt = frame.format.name
                    planar = fmt in ("gray", "gray8") or fmt.startswith(("yuv", "yuvj", "nv12"))
                y = luma(frame) if planar else frame.to_ndarray(format="gray")
                yield index, (frame.pts - start) * tb, y
                index += 1
        except VideoError:
            raise
        except Exception as exc:
            raise VideoError(f"{path}: decoding failed after {index} frames ({exc})") from exc
        if index == 0:
            raise VideoError(f"{path}: no frame could be decoded")
    finally:
        container.close()


def contact_sheet(path: Path, n_tiles: int = 12, tile_width_px: int = 320) -> np.ndarray:
    """A grid of evenly spaced key frames (decoding key frames only), labelled with their time."""
    import cv2

    frames = [(t, y.copy()) for _, t, y in iter_luma(path, keyframes_only=True)]
    if len(frames) > n_tiles:
        pick = np.linspace(0, len(frames) - 1, n_tiles).round().astype(int)
        frames = [frames[i] for i in pick]
    h, w = frames[0][1].shape
    tile_h = int(round(tile_width_px * h / w))
    cols = min(4, len(frames))
    rows = math.ceil(len(frames) / cols)
    sheet = np.zeros((rows * tile_h, cols * tile_width_px), np.uint8)
    for k, (t, y) in enumerate(frames):
        tile = cv2.resize(y, (tile_width_px, tile_h), interpolation=cv2.INTER_AREA)
        cv2.putText(tile, f"{t:6.2f} s", (6, 20), cv2.FONT_HERSHEY_SIMPLEX, 0.6, 255, 2, cv2.LINE_AA)
        r, c = divmod(k, cols)
        sheet[r * tile_h : (r + 1) * tile_h, c * tile_width_px : (c + 1) * tile_width_px] = tile
    return sheet
