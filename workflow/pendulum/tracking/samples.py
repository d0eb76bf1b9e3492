"""Frames spread over a clip, decoded once and shared by the searches that need them.

Marker detection (:func:`pendulum.tracking.spots.sample_frames`) and the body's static scene
(:func:`pendulum.tracking.body_scene.sample_clip`, also when the scene is taken again from the swing's
ends) each take every k-th decoded frame, k doubling whenever 2n frames are held, so that n to 2n frames
spread over the clip remain, frame 0 first. With k a power of two, a smaller set (larger k) is a subset of a
larger one. The last clip's set is kept (one clip at a time, its frames read-only, until :func:`release`): a
body tracked after a marker search (of a clip within the search's first ``max_frames``, 30 s at 60 fps), or
tracked again with a scene from its swing's ends, does not decode the clip again for them.
"""

from __future__ import annotations

import os
from pathlib import Path

import numpy as np

from pendulum.camera.video import VideoError, iter_luma

_held: dict = {}  # the last clip's spread frames: key, n, frames, frames decoded, whether to the clip's end


def spread_indices(n_frames: int, n: int) -> list[int]:
    """The indices of the frames that every-k-th sampling keeps of ``n_frames`` (k doubling when 2n are held)."""
    kept, stride = [], 1
    for index in range(n_frames):
        if index % stride == 0:
            kept.append(index)
            if len(kept) >= 2 * n:
                kept, stride = kept[::2], stride * 2
    return kept


def _key(path) -> tuple | None:
    try:
        stat = os.stat(path)
    except OSError:  # not cached: the decoder says what is wrong with the path
        return None
    return str(Path(path).resolve()), stat.st_ino, stat.st_size, stat.st_mtime_ns, stat.st_ctime_ns


def spread_frames(path, n: int, max_frames: int | None = None, view=None) -> tuple[list[tuple[int, np.ndarray]], int]:
    """Every k-th decoded frame of the clip's first ``max_frames`` (all when None): ``n`` to ``2n − 1`` of them
    (all of a clip shorter than ``n`` frames) as ``(index, image)`` (read-only), and how many frames were decoded.
    ``view``: the image taken of each frame (its luma when None; see :func:`~pendulum.camera.video.iter_luma`),
    with a ``key`` attribute that tells views apart. Raises :class:`~pendulum.camera.video.VideoError` when no
    frame decodes."""
    key = _key(path)
    if key is not None and view is not None:
        key = (*key, view.key)
    held = _held.get("clip")
    if key is not None and held is not None and held["key"] == key and held["n"] >= n:  # fewer samples: a subset
        complete, decoded = held["complete"], held["decoded"]
        if (complete and (max_frames is None or decoded <= max_frames)) or held["max_frames"] == max_frames:
            wanted = set(spread_indices(decoded, n))
            return [(i, image) for i, image in held["frames"] if i in wanted], decoded
    kept, stride, decoded, report = [], 1, 0, {}
    deferred = None if view is None else _deferred(view)  # a view made of the frames kept alone
    for index, _t, image in iter_luma(path, report=report, view=deferred):
        if max_frames is not None and index >= max_frames:
            break
        decoded = index + 1
        if index % stride == 0:
            image = (image if view is None else image()).copy()
            image.flags.writeable = False
            kept.append((index, image))
            if len(kept) >= 2 * n:
                kept, stride = kept[::2], stride * 2
    if not kept:
        raise VideoError(f"{path}: no frame could be decoded")
    complete = max_frames is None or decoded < max_frames
    # its frame count is the clip's where every frame decoded (a damaged one is left out of the samples' count)
    whole = complete and not report.get("damaged_frames") and not report.get("stopped_early")
    _held["clip"] = {"key": key, "n": n, "frames": kept, "decoded": decoded, "complete": complete, "whole": whole}
    _held["clip"]["max_frames"] = max_frames
    return list(kept), decoded


def _deferred(view):
    """``view`` as a frame → a call that makes its image (a colour view of a 1080p frame costs more than decoding
    it; of every frame decoded, one in k is kept)."""

    def later(frame):
        return lambda: view(frame)

    return later


def frame_count(path) -> int | None:
    """The clip's number of frames, where its held samples were taken to its end and every frame decoded (else
    None)."""
    held = _held.get("clip")
    key = _key(path)
    if key is None or held is None or held["key"] != key or not held["whole"]:
        return None
    return held["decoded"]


def held_spread(path, n: int) -> list[tuple[int, np.ndarray]] | None:
    """The clip's held luma samples (:func:`spread_frames`'s, of its first frames or all of them), n to 2n − 1 of
    them, without decoding; None where the frames held are another clip's, another view's or fewer."""
    held = _held.get("clip")
    key = _key(path)
    if key is None or held is None or held["key"] != key or held["n"] < n:
        return None
    wanted = set(spread_indices(held["decoded"], n))
    return [(i, image) for i, image in held["frames"] if i in wanted]


def release() -> None:
    """Let the last clip's frames go (a trial's tracking is done)."""
    _held.clear()
