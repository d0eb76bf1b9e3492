"""The video stream a clip is measured from, and its pixels made square.

A file may hold several video streams (a camera's preview or thumbnail beside the recording, a cover image): the
recording is the stream with the most pixels as shown, a still picture (a cover) never. A stream whose pixels are not
square (a sample aspect ratio other than 1: HDV's 1440×1080 shown as 1920×1080, DV, an anamorphic export) is
resampled to square pixels, as a player shows it, before anything is measured: in its stored pixels a swing's path
is an ellipse, its horizontal offsets scaled by 1/SAR, and the pivot fitted to it and the angles about it are wrong
(a reviewer's 4:3 copy of the apple clip: its pivot 200 px off, its angles 33 % too large, and nothing said).
"""

from __future__ import annotations

from fractions import Fraction


def _disposition(stream, flag: str) -> bool:
    """Whether the stream's disposition holds ``flag`` (``attached_pic``, ``default``)."""
    import av

    return bool(int(stream.disposition) & int(getattr(av.stream.Disposition, flag)))


STILL_CODECS = ("png", "bmp", "tiff", "webp", "gif")  # a picture's codecs: a cover whose flag a muxer dropped (MKV)


def _still(stream) -> bool:
    """An attached picture, a still image's codec, or a stream of one frame: no recording."""
    return _disposition(stream, "attached_pic") or stream.codec_context.name in STILL_CODECS or stream.frames == 1


def main_stream(container):
    """The container's recording: of its video streams that are no still picture (:func:`_still`), the one with the
    most pixels as shown (its sample aspect ratio counted; on a tie the default stream, then the first)."""
    streams = [s for s in container.streams.video if not _still(s)] or list(container.streams.video)
    return max(
        streams,
        key=lambda s: (
            s.codec_context.width * s.codec_context.height * sample_aspect_ratio(s),
            _disposition(s, "default"),
            -s.index,
        ),
    )


def other_streams_sentence(path, container, stream) -> str | None:
    """A warning naming the video streams left out beside ``stream`` (None when it is the only one)."""
    others = [s for s in container.streams.video if s.index != stream.index]
    if not others:
        return None
    listed = ", ".join(
        f"stream {s.index}, {s.codec_context.width}×{s.codec_context.height}"
        + (" (a still picture)" if _still(s) else "")
        for s in others
    )
    return (
        f"{path}: holds {len(others) + 1} video streams; stream {stream.index}, "
        f"{stream.codec_context.width}×{stream.codec_context.height} px, the one with the most pixels, is measured "
        f"({listed} left out)"
    )


def sample_aspect_ratio(stream) -> Fraction:
    """The stream's pixel shape, width over height (the container's value, else the codec's; 1 when neither says)."""
    for value in (stream.sample_aspect_ratio, stream.codec_context.sample_aspect_ratio):
        if value:  # None or 0/1: not stated
            return Fraction(value)
    return Fraction(1)


def square_width(stream) -> int | None:
    """The width in pixels at which the stream's pixels are square (even, for the chroma planes); None when they
    are square already."""
    ratio = sample_aspect_ratio(stream)
    width = stream.codec_context.width
    square = 2 * round(width * ratio / 2)
    return None if ratio == 1 or square == width else int(square)


def squarer(stream):
    """A function that resamples the stream's decoded frames to square pixels (:func:`square_width`), their height
    and pixel format kept; None where they are square. One scaler, on one thread, serves every frame (a frame's own
    ``reformat`` made a scaler per frame, on as many threads as the machine has: 2.2× the decoding's time at
    1440×1080, a reviewer)."""
    width = square_width(stream)
    if width is None:
        return None
    from av.video.reformatter import VideoReformatter

    scaler = VideoReformatter()
    return lambda frame: scaler.reformat(frame, width=width, height=frame.height, threads=1)


def non_square_sentence(path, stream, width: int) -> str:
    """The warning that the frames were resampled to square pixels."""
    ratio = sample_aspect_ratio(stream)
    return (
        f"{path}: its pixels are not square (sample aspect ratio {ratio.numerator}:{ratio.denominator}, stored "
        f"{stream.codec_context.width}×{stream.codec_context.height}): its frames are resampled to {width}×"
        f"{stream.codec_context.height} square pixels, as a player shows them, before anything is measured "
        "(tracks, pivot_px and start_px are in those pixels)"
    )
