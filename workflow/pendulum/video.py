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
    stated_frames: int | None = None  # frame count the container's index states (None: not stated)
    warnings: tuple[str, ...] = ()  # e.g. a truncated file: readable up to where it ends


ISO_BOXES = (b"ftyp", b"moov", b"mdat", b"free", b"skip", b"wide", b"pnot")  # first box of an MP4/MOV file


def _mp4_damage(path: Path, size: int) -> str:
    """What is wrong with the top-level box structure of an MP4/MOV file that no demuxer opens."""
    offset, boxes = 0, []
    with open(path, "rb") as fh:
        while offset + 8 <= size:
            fh.seek(offset)
            header = fh.read(16)
            length, kind = int.from_bytes(header[:4], "big"), header[4:8].decode("latin-1")
            if length == 1 and len(header) == 16:
                length = int.from_bytes(header[8:16], "big")
            elif length == 0:
                length = size - offset
            if length < 8 or not kind.isprintable():
                return f"unreadable data at byte {offset}"
            if offset + length > size:
                return f"it ends at byte {size} inside its {kind!r} box, which needs {offset + length} bytes"
            boxes.append(kind)
            offset += length
    if "moov" not in boxes:
        return "its index (the 'moov' box) is missing, as when a recording is not finished"
    return "its index cannot be read"


def unreadable_reason(path: Path) -> str:
    """One sentence on why a file that no demuxer opens is not a usable video."""
    path = Path(path)
    size = path.stat().st_size
    if size == 0:
        return f"{path}: empty file (0 bytes); copy the video again or remove it"
    with open(path, "rb") as fh:
        head = fh.read(8)
    if head[4:8] in ISO_BOXES:
        damage = _mp4_damage(path, size)
        kind = "truncated" if damage.startswith("it ends") else "damaged"
        return f"{path}: {kind} MP4/MOV file ({damage}); copy it again from the camera"
    return f"{path}: not a video file (no known video container format); remove it or convert it to MP4"


def _open(path: Path):
    import av

    path = Path(path)
    if not path.is_file():
        raise VideoError(f"{path}: no such file")
    try:
        container = av.open(str(path))
    except Exception as exc:  # PyAV raises several error types for a bad container
        raise VideoError(unreadable_reason(path)) from exc
    if not container.streams.video:
        container.close()
        raise VideoError(f"{path}: contains no video stream (audio only?); remove it or convert it")
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
        warnings = []
        try:
            for packet in container.demux(stream):
                if packet.size == 0 or packet.pts is None:
                    continue
                rows.append((packet.pts, bool(packet.is_keyframe), packet.size))
        except Exception:  # damaged container: readable up to here, like a truncated file
            warnings.append(f"{path}: the container is damaged after frame {len(rows)}; the rest is unreadable")
        if not rows:
            raise VideoError(f"{path}: the video stream holds no readable frames; copy the file again")
        stated = int(stream.frames) or None
        if stated and len(rows) < stated and not warnings:
            warnings.append(
                f"{path}: truncated: only {len(rows)} of the {stated} frames its index lists are in the file; "
                "the rest of the recording is missing"
            )
        info = VideoInfo(
            str(path),
            int(stream.codec_context.width),
            int(stream.codec_context.height),
            nominal_fps,
            stream.codec_context.name,
            len(rows),
            stated,
            tuple(warnings),
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


def iter_luma(
    path: Path, keyframes_only: bool = False, damaged: bool = False, report: dict | None = None
) -> Iterator[tuple[int, float, np.ndarray | None]]:
    """Decode the video once, yielding ``(frame_index, time_s, Y)`` in presentation order.

    Grey (``gray``) and planar YUV streams give their luma directly; other pixel
    formats are converted to grey. Damaged data does not end the pass: a packet
    that fails to decode is skipped, and the frames after it up to the next key
    frame (decoded from broken references) are *damaged*: left out, or with
    ``damaged=True`` yielded with ``Y = None``. A container that breaks off
    (truncated file) ends the pass there. ``report``, if given, receives
    ``failed_packets``, ``damaged_frames`` and ``stopped_early`` (a sentence or None).
    """
    container = _open(path)
    counts = {"failed_packets": 0, "damaged_frames": 0, "stopped_early": None}
    try:
        stream = container.streams.video[0]
        stream.thread_type = "AUTO"
        if keyframes_only:
            stream.codec_context.skip_frame = "NONKEY"
        tb = float(stream.time_base)
        start = None
        planar = None
        index = 0
        broken = False  # a packet failed: frames are unreliable until the next key frame
        packets = container.demux(stream)
        while True:
            try:
                packet = next(packets)
            except StopIteration:
                break
            except Exception:
                counts["stopped_early"] = (
                    f"{path}: the container is damaged after frame {index}; the rest is unreadable"
                )
                break
            try:
                frames = packet.decode()
            except Exception:
                counts["failed_packets"] += 1
                broken = True
                continue
            for frame in frames:
                if frame.pts is None:
                    continue
                if start is None:
                    start = frame.pts
                    fmt = frame.format.name
                    planar = fmt in ("gray", "gray8") or fmt.startswith(("yuv", "yuvj", "nv12"))
                if frame.key_frame and not getattr(frame, "is_corrupt", False):
                    broken = False
                if broken or getattr(frame, "is_corrupt", False):
                    counts["damaged_frames"] += 1
                    if damaged:
                        yield index, (frame.pts - start) * tb, None
                        index += 1
                    continue
                y = luma(frame) if planar else frame.to_ndarray(format="gray")
                yield index, (frame.pts - start) * tb, y
                index += 1
        if index == 0 or index == counts["damaged_frames"]:
            raise VideoError(f"{path}: no frame could be decoded (damaged video data); copy the file again")
    finally:
        container.close()
        if report is not None:
            report.update(counts)


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
