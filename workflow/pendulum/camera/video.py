"""Video stage: container timeline, QA contact sheet and the single luma decode pass.

Everything here reads the container with PyAV. The timeline needs no decoding
(packet timestamps only); the contact sheet decodes key frames only; the
tracker gets the Y (luma) plane of every frame without colour conversion.
"""

from __future__ import annotations

import math
import os
import queue
import threading
from collections.abc import Iterator
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import pandas as pd

from pendulum.camera import streams as pixels  # the stream measured, its pixels made square
from pendulum.camera.stamps import read_clock, regular_times

# the containers a lab's cameras write: phones (.mov, .mp4, .m4v, .3gp), action cameras (.mp4), camcorders (.mts),
# screen and webcam recorders (.mkv, .webm), older cameras (.avi); any of them decoded by FFmpeg (PyAV)
VIDEO_EXTENSIONS = (".mp4", ".mov", ".m4v", ".avi", ".mkv", ".webm", ".mts", ".3gp")


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
    discarded_packets: int = 0  # packets before the first shown frame (a trimmed clip's edit list)
    frame_interval_s: float | None = None  # median interval between shown frames
    variable_frame_rate: bool = False
    rounded_stamps_tick_s: float | None = None  # stamps rounded to this tick, taken as the regular clock they round
    rotation_deg: float = 0.0  # display rotation the file states (frames are used as stored)
    pixel_format: str = ""
    bit_depth: int = 8
    sample_aspect_ratio: str | None = None  # "4:3": pixels not square, frames resampled to square ones (streams)


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


# Decoder threads: the workflow's script set-up (workflow/scripts/_setup.py) puts the rule's
# `threads` into PENDULUM_DECODER_THREADS, so a job decodes with exactly what it asked the
# scheduler for; unset (library use), FFmpeg picks its own count.
DECODER_THREADS: int | None = int(os.environ.get("PENDULUM_DECODER_THREADS", "0")) or None
DECODE_AHEAD_FRAMES = 4  # frames decoded ahead of the consumer (memory: this many frames, not the video)


def set_decoder_threads(threads: int | None) -> None:
    """Threads every later :func:`iter_luma` call gives the decoder (None: FFmpeg's own choice)."""
    global DECODER_THREADS
    if threads is not None and int(threads) < 1:
        raise ValueError(f"decoder threads must be at least 1, not {threads}")
    DECODER_THREADS = None if threads is None else int(threads)


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


def _first_decoded_frame(packet, state: dict) -> None:
    """Feed ``packet`` to the decoder until it yields its first frame; keep that frame in ``state``."""
    if state.get("frame") is not None:
        return
    try:
        for frame in packet.decode():
            if frame.pts is not None:
                state["frame"] = frame
                return
    except Exception as exc:  # damaged or undecodable data: try the next packet
        state["error"] = str(exc)


def _frame_facts(frame) -> dict:
    """Pixel format, bit depth and display rotation of a decoded frame."""
    if frame is None:
        return {"pixel_format": "", "bit_depth": 8, "rotation_deg": 0.0}
    fmt = frame.format
    bits = max((int(c.bits) for c in fmt.components), default=8)
    rotation = float(getattr(frame, "rotation", 0) or 0)
    return {"pixel_format": fmt.name, "bit_depth": bits, "rotation_deg": rotation}


def frame_timeline(path: Path) -> tuple[VideoInfo, pd.DataFrame]:
    """Per-frame presentation times of the frames the decoder yields (demux; only the first frame decoded).

    A trimmed clip's container holds packets before its first shown frame (its edit list starts
    later; FFmpeg marks them *discard* and the decoder drops their frames): they are no frames
    here (``VideoInfo.discarded_packets``), nor are packets before the first frame the decoder
    yields. Time 0 is that first shown frame, as in :func:`iter_luma`.

    Columns: ``frame``, ``pts``, ``time_s``, ``interval_s``, ``dropped_before``
    (frames missing before this one: the interval is ≥ 1.5 frame intervals; constant frame
    rate only), ``duplicate_time`` (same timestamp as the previous frame), ``irregular_interval``
    (more than 10 % off a whole number of frame intervals), ``keyframe``, ``packet_bytes``. The
    frame interval is the median interval (a warning when none of the container's stated rates,
    average or base, is within 1 % of it). More than 2 % irregular intervals (and at least 3) is a
    *variable frame rate*: every frame keeps its timestamp and no frames are called dropped.
    The first decoded frame gives the pixel format, bit depth and display rotation (reported;
    frames are used as stored).
    """
    container = _open(path)
    try:
        stream = pixels.main_stream(container)
        rate = stream.average_rate or stream.guessed_rate
        if not rate:
            raise VideoError(f"{path}: the video stream states no frame rate")
        stated_fps = float(rate)
        stated_rates = [float(r) for r in (rate, stream.base_rate, stream.guessed_rate) if r]
        tb = stream.time_base
        rows, discarded = [], 0
        warnings = []
        first: dict = {}
        try:
            for packet in container.demux(stream):
                if packet.size == 0 or packet.pts is None:
                    continue
                if packet.is_discard:
                    discarded += 1
                else:
                    rows.append((packet.pts, bool(packet.is_keyframe), packet.size))
                _first_decoded_frame(packet, first)
        except Exception:  # damaged container: readable up to here, like a truncated file
            warnings.append(f"{path}: the container is damaged after frame {len(rows)}; the rest is unreadable")
        if not rows:
            raise VideoError(f"{path}: the video stream holds no readable frames; copy the file again")
        codec = stream.codec_context.name
        if first.get("frame") is None:
            advice = "copy the file again" if codec == "h264" else "copy the file again or convert it to H.264 MP4"
            raise VideoError(
                f"{path}: no frame of its {codec} video stream could be decoded ({first.get('error', 'no output')}); "
                f"{advice}"
            )
        facts = _frame_facts(first["frame"])
        stated = int(stream.frames) or None
        if stated and len(rows) + discarded < stated and not warnings:
            warnings.append(
                f"{path}: truncated: only {len(rows) + discarded} of the {stated} frames its index lists are in the "
                "file; the rest of the recording is missing"
            )
        width, height = int(stream.codec_context.width), int(stream.codec_context.height)
        warnings += [w for w in (pixels.other_streams_sentence(path, container, stream),) if w]
        if (square := pixels.square_width(stream)) is not None:  # resampled: said, and its ratio reported
            warnings.append(pixels.non_square_sentence(path, stream, square))
            width, ratio = square, pixels.sample_aspect_ratio(stream)
    finally:
        container.close()
    table = pd.DataFrame(rows, columns=["pts", "keyframe", "packet_bytes"]).sort_values("pts", kind="stable")
    shown_from = first["frame"].pts
    before = int((table.pts < shown_from).sum())
    table = table[table.pts >= shown_from]
    discarded += before
    if discarded:
        warnings.append(
            f"{path}: trimmed clip: {discarded} packet(s) before the first shown frame (an edit list) are not frames "
            "the decoder yields; the timeline starts at the first shown frame"
        )
    table.insert(0, "frame", np.arange(len(table)))
    stamps = (table.pts - shown_from).to_numpy(dtype=float) * float(tb)
    rounded = regular_times(stamps)  # the tracks stage reads its stamps the same way (tracking.timing)
    table.insert(2, "time_s", stamps if rounded is None else rounded[0])
    clock, clock_warnings = read_clock(table.time_s.to_numpy(), stated_rates, path)
    warnings.extend(clock_warnings)
    if facts["rotation_deg"]:
        warnings.append(
            f"{path}: the file asks players to rotate the picture by {facts['rotation_deg']:g}°; its frames are used "
            f"as stored ({width}×{height}{' once made square' if square else ''}): tracks and pivot_px are in stored "
            "pixel coordinates (give pivot_px as measured in the stored frames, not in the rotated picture a player "
            "shows; a vertical_deg the swing "
            "shows to be the shown picture's is turned with it)"
        )
    table.insert(3, "interval_s", clock["interval"])
    table.insert(4, "dropped_before", clock["dropped"])
    table.insert(5, "duplicate_time", np.nan_to_num(clock["interval"], nan=1.0) <= 0)
    table.insert(6, "irregular_interval", clock["irregular"])
    info = VideoInfo(
        str(path),
        width,
        height,
        stated_fps,
        codec,
        len(table),
        stated,
        tuple(warnings),
        discarded_packets=discarded,
        frame_interval_s=clock["frame_interval"],
        variable_frame_rate=clock["variable"],
        rounded_stamps_tick_s=None if rounded is None else rounded[1],
        rotation_deg=facts["rotation_deg"],
        pixel_format=facts["pixel_format"],
        bit_depth=facts["bit_depth"],
        sample_aspect_ratio=None if square is None else f"{ratio.numerator}:{ratio.denominator}",
    )
    return info, table.reset_index(drop=True)


def luma(frame) -> np.ndarray:
    """The Y plane of a decoded frame as a (height, width) uint8 view (no colour conversion).

    A 9–16-bit plane (10-bit HEVC, ``yuv420p10le``: 16-bit words) is reduced to its top 8 bits (a copy).
    """
    return plane_8bit(frame, 0)


def plane_8bit(frame, index: int) -> np.ndarray:
    """Plane ``index`` of a planar frame as a (plane height, plane width) uint8 view; a 9–16-bit plane reduced to
    its top 8 bits (a copy)."""
    plane = frame.planes[index]
    bits = int(frame.format.components[index].bits)
    if bits > 8:
        dtype = ">u2" if frame.format.name.endswith("be") else "<u2"
        rows = np.frombuffer(plane, dtype).reshape(plane.height, plane.line_size // 2)
        return (rows[:, : plane.width] >> (bits - 8)).astype(np.uint8)
    rows = np.frombuffer(plane, np.uint8).reshape(plane.height, plane.line_size)
    return rows[:, : plane.width]


def _decoder_threads(threads: int | None) -> int | None:
    threads = DECODER_THREADS if threads is None else threads
    if threads is not None and int(threads) < 1:
        raise ValueError(f"decoder threads must be at least 1, not {threads}")
    return None if threads is None else int(threads)


def _decoded_frames(path, container, stream, counts: dict, stop: threading.Event) -> Iterator:
    """``(frame, damaged)`` in presentation order, in square pixels (:mod:`pendulum.camera.streams`); failed packets
    counted and skipped (see :func:`iter_luma`)."""
    square = pixels.squarer(stream)
    broken = False  # a packet failed: frames are unreliable until the next key frame
    packets = container.demux(stream)
    n_frames = 0
    while not stop.is_set():
        try:
            packet = next(packets)
        except StopIteration:
            break
        except Exception:
            counts["stopped_early"] = f"{path}: the container is damaged after frame {n_frames}; the rest is unreadable"
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
            corrupt = getattr(frame, "is_corrupt", False)
            if frame.key_frame and not corrupt:
                broken = False
            n_frames += 1
            yield (frame if square is None else square(frame)), broken or corrupt


def _decode_ahead(frames: Iterator, stop: threading.Event, ahead: int) -> Iterator:
    """The items of ``frames``, produced by a background thread up to ``ahead`` items in advance.

    PyAV releases the GIL while FFmpeg demuxes and decodes, so decoding the next frames
    overlaps with the consumer's work on this one. The consumer must set ``stop`` and
    exhaust or drop this generator (its ``finally`` joins the thread) before the
    container is closed.
    """
    done = object()
    items: queue.Queue = queue.Queue(maxsize=ahead)

    def put(item) -> bool:
        while not stop.is_set():
            try:
                items.put(item, timeout=0.1)
                return True
            except queue.Full:
                continue
        return False

    def produce():
        try:
            for item in frames:
                if not put(item):
                    return
            put(done)
        except BaseException as exc:  # handed to the consumer, raised there
            put(exc)

    worker = threading.Thread(target=produce, name="pendulum-decoder", daemon=True)
    worker.start()
    try:
        while True:
            item = items.get()
            if item is done:
                return
            if isinstance(item, BaseException):
                raise item
            yield item
    finally:
        stop.set()
        worker.join()


def iter_luma(
    path: Path,
    keyframes_only: bool = False,
    damaged: bool = False,
    report: dict | None = None,
    threads: int | None = None,
    view=None,
) -> Iterator[tuple[int, float, np.ndarray | None]]:
    """Decode the video once, yielding ``(frame_index, time_s, Y)`` in presentation order.

    Grey (``gray``) and planar YUV streams give their luma directly; other pixel
    formats are converted to grey. Damaged data does not end the pass: a packet
    that fails to decode is skipped, and the frames after it up to the next key
    frame (decoded from broken references) are *damaged*: left out, or with
    ``damaged=True`` yielded with ``Y = None``. A container that breaks off
    (truncated file) ends the pass there. ``report``, if given, receives
    ``failed_packets``, ``damaged_frames`` and ``stopped_early`` (a sentence or None).

    ``threads``: the decoder's thread count (default :data:`DECODER_THREADS`, set from
    the rule's ``threads`` in a workflow job; None: FFmpeg's own choice). Decoding runs
    in a background thread at most :data:`DECODE_AHEAD_FRAMES` frames ahead of the
    consumer, so memory stays a few frames whatever the video's length. ``Y`` is a view
    of the decoded frame, valid as long as the caller holds it (copy it to keep it).
    ``view``: a function of the decoded frame whose result is yielded instead of ``Y`` (e.g. its colour,
    :mod:`pendulum.tracking.colour`; or something that makes it later: a window of it, a call).
    """
    threads = _decoder_threads(threads)
    container = _open(path)
    counts = {"failed_packets": 0, "damaged_frames": 0, "stopped_early": None}
    stop = threading.Event()
    decoded = None
    try:
        stream = pixels.main_stream(container)
        stream.thread_type = "AUTO"  # frame and slice threads
        if threads is not None:
            stream.codec_context.thread_count = threads
        if keyframes_only:
            stream.codec_context.skip_frame = "NONKEY"
        tb = float(stream.time_base)
        start = None
        planar = None
        index = 0
        decoded = _decode_ahead(_decoded_frames(path, container, stream, counts, stop), stop, DECODE_AHEAD_FRAMES)
        for frame, is_damaged in decoded:
            if start is None:
                start = frame.pts
                fmt = frame.format.name
                planar = fmt in ("gray", "gray8") or fmt.startswith(("yuv", "yuvj", "nv12"))
            if is_damaged:
                counts["damaged_frames"] += 1
                if damaged:
                    yield index, (frame.pts - start) * tb, None
                    index += 1
                continue
            if view is not None:
                y = view(frame)
            else:
                y = luma(frame) if planar else frame.to_ndarray(format="gray")
            yield index, (frame.pts - start) * tb, y
            index += 1
        if index == 0 or index == counts["damaged_frames"]:
            raise VideoError(f"{path}: no frame could be decoded (damaged video data); copy the file again")
    finally:
        stop.set()
        if decoded is not None:
            decoded.close()  # joins the decoding thread before the container goes
        container.close()
        if report is not None:
            report.update(counts)


def _keyframe_lumas(path: Path, wanted_pts: set, origin_pts: int) -> list[tuple[float, np.ndarray]]:
    """``(time_s, Y copy)`` of the key frames whose pts is in ``wanted_pts`` (decoding key frames only)."""
    container = _open(path)
    found = []
    try:
        stream = pixels.main_stream(container)
        stream.codec_context.skip_frame = "NONKEY"
        tb = float(stream.time_base)
        square = pixels.squarer(stream)
        for packet in container.demux(stream):
            try:
                frames = packet.decode()
            except Exception:  # damaged data: that tile is left out
                continue
            for frame in frames:
                if frame.pts in wanted_pts:
                    frame = frame if square is None else square(frame)
                    fmt = frame.format.name
                    planar = fmt in ("gray", "gray8") or fmt.startswith(("yuv", "yuvj", "nv12"))
                    y = luma(frame) if planar else frame.to_ndarray(format="gray")
                    found.append(((frame.pts - origin_pts) * tb, np.array(y, np.uint8)))
    except Exception:  # a container that breaks off: the tiles found so far
        pass
    finally:
        container.close()
    return found


def contact_sheet(path: Path, n_tiles: int = 12, tile_width_px: int = 320, timeline=None) -> np.ndarray:
    """A grid of evenly spaced tiles labelled with their time: the first shown frame, then key frames.

    ``timeline`` (from :func:`frame_timeline`; computed when None) says which frames are shown and
    where the key frames are; only the first frame and the picked key frames are kept in memory.
    """
    return contact_sheet_with_times(path, n_tiles, tile_width_px, timeline)[0]


def contact_sheet_with_times(
    path: Path, n_tiles: int = 12, tile_width_px: int = 320, timeline=None
) -> tuple[np.ndarray, list[float]]:
    """:func:`contact_sheet` and its tiles' times (s), in tile order."""
    import cv2

    frames = _sheet_frames(path, n_tiles, timeline)
    h, w = frames[0][1].shape
    tile_h = int(round(tile_width_px * h / w))
    cols = min(4, len(frames))
    rows = math.ceil(len(frames) / cols)
    sheet = np.full((rows * tile_h, cols * tile_width_px), 255, np.uint8)  # a short last row: white, as the page
    for k, (t, y) in enumerate(frames):
        tile = cv2.resize(y, (tile_width_px, tile_h), interpolation=cv2.INTER_AREA)
        cv2.putText(tile, f"{t:6.2f} s", (6, 20), cv2.FONT_HERSHEY_SIMPLEX, 0.6, 255, 2, cv2.LINE_AA)
        r, c = divmod(k, cols)
        sheet[r * tile_h : (r + 1) * tile_h, c * tile_width_px : (c + 1) * tile_width_px] = tile
    return sheet, [float(t) for t, _ in frames]


def _sheet_frames(path: Path, n_tiles: int, timeline) -> list[tuple[float, np.ndarray]]:
    if timeline is None:
        _, timeline = frame_timeline(path)
    decoded = iter_luma(path)
    try:
        _, t0, y0 = next(decoded)
        first = (t0, np.array(y0, np.uint8))  # the first shown frame, key frame or not
    finally:
        decoded.close()
    keys = timeline[timeline.keyframe & (timeline.frame > 0)]
    pick = np.linspace(0, len(keys), min(n_tiles, len(keys) + 1)).round().astype(int)[1:] - 1
    wanted = {int(p) for p in keys.pts.iloc[np.unique(pick)]} if len(keys) else set()
    return [first, *_keyframe_lumas(path, wanted, int(timeline.pts.iloc[0]))]


def track_over_sheet(
    sheet: np.ndarray, times_s: list[float], frame_width_px: int, track: pd.DataFrame, tile_width_px: int = 320
) -> np.ndarray:
    """The contact sheet (grey, from :func:`contact_sheet`) in colour with the track drawn in every tile.

    Per tile: the tracked path (grey) and the position tracked at the tile's time (a green ring where
    ``ok``, red where flagged, a red cross where lost): the visual check that the track sits on the
    pendulum. No frame is decoded again.
    """
    import cv2

    out = cv2.cvtColor(sheet, cv2.COLOR_GRAY2BGR)
    cols = min(4, len(times_s))
    tile_h = sheet.shape[0] // max(1, math.ceil(len(times_s) / cols))
    for k, t in enumerate(times_s):
        r, c = divmod(k, cols)
        tile = out[r * tile_h : (r + 1) * tile_h, c * tile_width_px : (c + 1) * tile_width_px]
        _draw_track(tile, track, t, tile_width_px / frame_width_px)
    return out


def _draw_track(tile: np.ndarray, track: pd.DataFrame, time_s: float, scale: float) -> None:
    """The tracked path (grey) and the position at ``time_s`` (green ring: ok; red: flagged; red cross: lost)."""
    import cv2

    ok = (track.flag == "ok").to_numpy() & track.x_px.notna().to_numpy()
    points = np.round(track.loc[ok, ["x_px", "y_px"]].to_numpy(float) * scale * 4).astype(np.int32)
    if len(points) > 1:
        cv2.polylines(tile, [points.reshape(-1, 1, 2)], False, (160, 160, 160), 1, cv2.LINE_AA, shift=2)
    if track.empty:
        return
    row = track.iloc[int(np.argmin(np.abs(track.time_s.to_numpy(float) - time_s)))]
    if not (np.isfinite(row.x_px) and np.isfinite(row.y_px)):
        cv2.drawMarker(tile, (12, tile.shape[0] - 12), (0, 0, 255), cv2.MARKER_TILTED_CROSS, 14, 2)
        return
    centre = (int(round(row.x_px * scale * 4)), int(round(row.y_px * scale * 4)))
    good = row.flag == "ok"
    cv2.circle(tile, centre, 4 * 7, (0, 200, 0) if good else (0, 0, 255), 1 if good else 2, cv2.LINE_AA, shift=2)
