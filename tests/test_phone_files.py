"""Phone and action-camera files (issue 12, item 5): the frames stage's timeline is the frames the
decoder yields.

A trimmed clip (an edit list over packets before the first shown frame, rendered by
``synthetic_scene.Faults.trimmed_lead_frames``), a variable frame rate, display-rotation metadata and
10-bit HEVC, each against what PyAV's decoder yields and what was written.
"""

import json
import logging
import runpy
from dataclasses import replace
from fractions import Fraction
from types import SimpleNamespace

import av
import cv2
import numpy as np
import pandas as pd
import pytest

from conftest import ROOT
from pendulum.camera.video import VideoError, contact_sheet, frame_timeline, iter_luma
from pendulum.synthetic import experiment as syn
from pendulum.synthetic.specs import Camera, Faults, TrialSpec

RIG = {"mass_kg": 2.0, "length_m": 0.3, "frontal_area_m2": 0.012, "displaced_volume_m3": 0.0005}
TRUTH = {"added_mass_kg": 0.6, "drag_area_m2": 0.01, "linear_damping_nm_s": 0.02, "friction_torque_nm": 0.005}
EFFECTS = ["quadratic_drag", "linear_damping", "coulomb_friction"]


def small_spec(name, **faults):
    camera = Camera(
        width_px=320, height_px=240, fps=25.0, pivot_px=(160.3, 30.6), marker_arm_px=150.0, marker_radius_px=6.0
    )
    spec = TrialSpec(name, 30.0, RIG, TRUTH, EFFECTS, seed=4, hold_s=0.3, duration_s=3.0, camera=camera)
    return replace(spec, faults=Faults(**faults))


def run_frames_stage(video, out, monkeypatch):
    """workflow/scripts/frames.py as Snakemake runs it (its ``snakemake`` object stood in for)."""
    monkeypatch.syspath_prepend(str(ROOT / "workflow" / "scripts"))
    files = {name: str(out / name) for name in ("timeline.csv", "summary.json", "contact_sheet.png")}
    sm = SimpleNamespace(
        input=SimpleNamespace(video=str(video)),
        output=SimpleNamespace(
            timeline=files["timeline.csv"], summary=files["summary.json"], contact_sheet=files["contact_sheet.png"]
        ),
        log=[str(out / "frames.log")],
        params=SimpleNamespace(tiles=6),
        threads=1,
    )
    runpy.run_path(str(ROOT / "workflow" / "scripts" / "frames.py"), init_globals={"snakemake": sm})
    logging.getLogger("frames").handlers.clear()
    return json.loads((out / "summary.json").read_text()), (out / "frames.log").read_text()


@pytest.mark.slow
def test_trimmed_clip_timeline_is_the_decoded_frames(tmp_path, monkeypatch):
    """The issue's case: the container's packets before the first shown frame are not frames."""
    lead = 13  # the clip is cut 13 frames into a GOP: the key frame it needs is discarded
    spec = small_spec("trimmed", trimmed_lead_frames=lead)
    video = syn.generate_trial(spec, tmp_path, tmp_path, progress=None)
    decoded = [(t, y.copy()) for _, t, y in iter_luma(video)]
    info, timeline = frame_timeline(video)
    assert len(timeline) == len(decoded) == 75 and info.discarded_packets == lead
    assert np.allclose(timeline.time_s, [t for t, _ in decoded], atol=1e-9)
    assert timeline.dropped_before.sum() == 0 and not timeline.duplicate_time.any()
    assert not timeline.irregular_interval.any() and not info.variable_frame_rate
    assert any("trimmed clip: 13 packet(s)" in w for w in info.warnings)
    summary, log = run_frames_stage(video, tmp_path, monkeypatch)
    assert summary["n_frames"] == 75 and summary["duration_s"] == pytest.approx(74 / 25, abs=1e-9)
    assert summary["mean_fps"] == pytest.approx(25.0, abs=1e-6) and summary["nominal_fps"] == 25.0
    assert summary["dropped_frames"] == 0 and summary["duplicate_timestamps"] == 0
    assert summary["discarded_packets"] == lead and "dropped frame" not in log
    # the contact sheet's first tile is the first shown frame (not the discarded key frame), labelled 0.00 s
    sheet = cv2.imread(str(tmp_path / "contact_sheet.png"), cv2.IMREAD_GRAYSCALE)
    tile_h = round(320 * 240 / 320)
    below_label = slice(30, tile_h)
    expected = cv2.resize(decoded[0][1], (320, tile_h), interpolation=cv2.INTER_AREA)
    assert np.array_equal(sheet[below_label, :320], expected[below_label])
    with av.open(str(video)) as container:
        hidden = [p for p in container.demux(video=0) if p.size and p.is_discard]
    assert len(hidden) == lead and hidden[0].is_keyframe


def write_frames(
    path,
    frames,
    times_s=None,
    rate=30,
    codec="libx264",
    pix_fmt="yuv420p",
    rotation=None,
    ticks_per_s=90000,
    container_format="mp4",
):
    """``frames`` written at ``times_s`` (every 1/``rate`` s when None), stamped in ticks of 1/``ticks_per_s`` s
    (rounded to them), in a ``container_format`` container (FFmpeg's name)."""
    tick = Fraction(1, ticks_per_s)
    with av.open(str(path), mode="w", format=container_format) as container:
        stream = container.add_stream(codec, rate=rate)
        stream.width, stream.height, stream.pix_fmt = frames[0].shape[1], frames[0].shape[0], pix_fmt
        stream.codec_context.time_base = tick
        stream.time_base = tick
        if codec == "libx265":
            stream.options = {
                "crf": "20",
                "preset": "veryfast",
                "x265-params": "log-level=error:pools=1:frame-threads=1",
            }
        else:
            stream.options = {"crf": "20", "preset": "veryfast", "threads": "1"}
        if rotation is not None:
            stream.set_display_rotation(rotation)
        for i, image in enumerate(frames):
            frame = av.VideoFrame.from_ndarray(image, format="gray").reformat(format=pix_fmt)
            t = i / rate if times_s is None else times_s[i]
            frame.pts, frame.time_base = int(round(t * ticks_per_s)), tick
            for packet in stream.encode(frame):
                container.mux(packet)
        for packet in stream.encode():
            container.mux(packet)


def limited_range(grey):
    """The Y value a full-range grey level becomes in a (limited-range) yuv420p video: 16 + 219·v/255."""
    return 16 + 219 * np.asarray(grey, float) / 255


def moving_square(n, h=96, w=128):
    frames = []
    for i in range(n):
        image = np.full((h, w), 60, np.uint8)
        image[20:40, 10 + i : 30 + i] = 200
        frames.append(image)
    return frames


def test_variable_frame_rate_keeps_timestamps_and_is_no_dropped_frame_spam(tmp_path):
    """A phone's VFR clip: intervals between 1/60 and 1/24 s. One warning, no dropped frames, times kept."""
    intervals = np.random.default_rng(3).uniform(1 / 60, 1 / 24, 59)
    times = np.concatenate([[0.0], np.cumsum(intervals)])
    write_frames(tmp_path / "vfr.mp4", moving_square(60), times)
    info, timeline = frame_timeline(tmp_path / "vfr.mp4")
    assert info.variable_frame_rate and timeline.dropped_before.sum() == 0
    assert np.allclose(timeline.time_s, times, atol=2e-5)
    assert [w for w in info.warnings if "variable frame rate" in w] == list(info.warnings[:1])  # one sentence
    # a constant-rate clip with two dropped frames stays constant-rate and counts them
    keep = np.ones(60, bool)
    keep[[20, 41]] = False
    write_frames(
        tmp_path / "cfr.mp4", [f for f, k in zip(moving_square(60), keep, strict=True) if k], np.arange(60)[keep] / 30
    )
    info, timeline = frame_timeline(tmp_path / "cfr.mp4")
    assert not info.variable_frame_rate and timeline.dropped_before.sum() == 2
    assert info.frame_interval_s == pytest.approx(1 / 30, abs=1e-5) and not info.warnings


@pytest.mark.parametrize("ticks_per_s", [1000, 600])
def test_stamps_rounded_to_a_coarse_tick_are_the_regular_clock_they_round(tmp_path, ticks_per_s):
    """59.94 fps stamped in milliseconds (Matroska, some muxers) or in an iPhone's 1/600 s step by 16 and 17 ms
    (10 and 11 ticks): the frames are taken at the regular clock those stamps round, 16.683 ms, within a fifth of a
    tick (the stamps: half a tick; 0.02 ms from milliseconds, 0.25 ms from 1/600 s over 5 s), with no warning that the
    frames come every 17 ms, and a lost frame still counted (before: the median step, 17 ms, and the stamps'
    rounding in every frame's time). A variable frame rate keeps its stamps."""
    period = 1001 / 60000
    slots = np.delete(np.arange(300), 150)  # 5 s; the camera lost frame 150
    write_frames(tmp_path / "ms.mp4", moving_square(299), slots * period, rate=60, ticks_per_s=ticks_per_s)
    info, timeline = frame_timeline(tmp_path / "ms.mp4")
    assert info.rounded_stamps_tick_s == pytest.approx(1 / ticks_per_s)
    assert info.frame_interval_s == pytest.approx(period, abs=1e-5) and not info.warnings
    assert np.abs(timeline.time_s - slots * period).max() < 0.2 / ticks_per_s
    assert timeline.dropped_before.sum() == 1 and not info.variable_frame_rate
    rng = np.random.default_rng(4)
    times = np.concatenate([[0.0], np.cumsum(rng.choice([0.015, 0.0167, 0.0184], 59))])
    write_frames(tmp_path / "vfr.mp4", moving_square(60), times, rate=60, ticks_per_s=ticks_per_s)
    info, timeline = frame_timeline(tmp_path / "vfr.mp4")
    assert info.rounded_stamps_tick_s is None
    assert np.abs(timeline.time_s - times).max() <= 0.5 / ticks_per_s + 1e-9


def test_rotation_metadata_is_reported_and_frames_used_as_stored(tmp_path):
    frames = moving_square(10)
    write_frames(tmp_path / "portrait.mp4", frames, rotation=90)
    info, _ = frame_timeline(tmp_path / "portrait.mp4")
    assert abs(info.rotation_deg) == 90 and (info.width_px, info.height_px) == (128, 96)
    assert any("used as stored (128×96)" in w and "pivot_px" in w for w in info.warnings)
    _, _, first = next(iter(iter_luma(tmp_path / "portrait.mp4")))
    assert first.shape == (96, 128) and np.abs(first[20:40, 12:28] - limited_range(200)).max() < 3


def disk_scene(width, height, centre, radius, level=200):
    """A grey scene with a bright disk, in square pixels."""
    yy, xx = np.mgrid[0:height, 0:width]
    image = np.full((height, width), 60, np.uint8)
    image[(xx - centre[0]) ** 2 + (yy - centre[1]) ** 2 <= radius**2] = level
    return image


def write_streams(path, streams, n=6, rate=30, codecs=()):
    """One container with a video stream per ``(frames, sample_aspect_ratio)`` of ``streams`` (H.264, in order;
    ``codecs``: another codec per stream, e.g. ``png`` for a cover image)."""
    with av.open(str(path), mode="w") as container:
        added = []
        for k, (frames, ratio) in enumerate(streams):
            codec = codecs[k] if k < len(codecs) else "libx264"
            stream = container.add_stream(codec, rate=rate)
            pix_fmt = "yuv420p" if codec == "libx264" else "gray"
            stream.width, stream.height, stream.pix_fmt = frames[0].shape[1], frames[0].shape[0], pix_fmt
            stream.options = {"crf": "12", "preset": "veryfast", "threads": "1"} if codec == "libx264" else {}
            if ratio is not None:
                stream.codec_context.sample_aspect_ratio = ratio
            added.append(stream)
        for i in range(n):
            for stream, (frames, _) in zip(added, streams, strict=True):
                frame = av.VideoFrame.from_ndarray(frames[i % len(frames)], format="gray")
                frame = frame.reformat(format=stream.pix_fmt)
                frame.pts = i
                for packet in stream.encode(frame):
                    container.mux(packet)
        for stream in added:
            for packet in stream.encode():
                container.mux(packet)


def bright_centre(image):
    """Centre and half-extents (x, y) of the pixels above mid-grey."""
    ys, xs = np.nonzero(image > 130)
    return xs.mean(), ys.mean(), (xs.max() - xs.min() + 1) / 2, (ys.max() - ys.min() + 1) / 2


def test_non_square_pixels_are_resampled_to_square_ones_before_anything_is_measured(tmp_path):
    """A 4:3 anamorphic file (stored 96×96, shown 128×96: HDV, DV, an anamorphic export): its frames are measured as
    a player shows them. The disk at (80, 48), radius 16, in the picture is found there and round; in the stored
    pixels it was at x = 60 and 12 px wide (a reviewer's anamorphic apple: pivot fitted 200 px off, angles 33 % too
    large, nothing said). The summary states the ratio and the resampling."""
    shown = disk_scene(128, 96, (80, 48), 16)
    stored = cv2.resize(shown, (96, 96), interpolation=cv2.INTER_AREA)
    write_streams(tmp_path / "anamorphic.mp4", [([stored], Fraction(4, 3))])
    info, _ = frame_timeline(tmp_path / "anamorphic.mp4")
    assert (info.width_px, info.height_px, info.sample_aspect_ratio) == (128, 96, "4:3")
    assert any("not square (sample aspect ratio 4:3, stored 96×96)" in w and "128×96" in w for w in info.warnings)
    for _, _, image in iter_luma(tmp_path / "anamorphic.mp4"):
        assert image.shape == (96, 128)
        x, y, half_w, half_h = bright_centre(image)
        assert abs(x - 80) < 0.5 and abs(y - 48) < 0.5 and abs(half_w - half_h) <= 1.0, (x, y, half_w, half_h)
    write_streams(tmp_path / "square.mp4", [([shown], None)])
    info, _ = frame_timeline(tmp_path / "square.mp4")
    assert info.sample_aspect_ratio is None and not info.warnings


def test_the_recording_is_measured_not_a_thumbnail_stored_before_it(tmp_path):
    """A file whose first video stream is a 64×48 preview and second the 128×96 recording: the recording is decoded
    (before, the preview was tracked and nothing said), and the summary names the stream left out."""
    preview = disk_scene(64, 48, (20, 24), 6)
    recording = disk_scene(128, 96, (80, 48), 16)
    write_streams(tmp_path / "two.mp4", [([preview], None), ([recording], None)])
    info, _ = frame_timeline(tmp_path / "two.mp4")
    assert (info.width_px, info.height_px, info.n_packets) == (128, 96, 6)
    assert any(
        "holds 2 video streams; stream 1, 128×96 px" in w and "stream 0, 64×48 left out" in w for w in info.warnings
    )
    images = [image for _, _, image in iter_luma(tmp_path / "two.mp4")]
    assert len(images) == 6 and all(image.shape == (96, 128) for image in images)
    x, y, _, _ = bright_centre(images[0])
    assert abs(x - 80) < 0.5 and abs(y - 48) < 0.5
    # a cover image larger than the recording, stored first, its attached-picture flag dropped (as a reviewer.s MKV did)
    cover = disk_scene(256, 192, (40, 40), 20)
    write_streams(tmp_path / "cover.mov", [([cover], None), ([recording], None)], codecs=("png",))
    info, _ = frame_timeline(tmp_path / "cover.mov")
    assert (info.width_px, info.height_px) == (128, 96), info
    assert any("stream 0, 256×192 (a still picture) left out" in w for w in info.warnings), info.warnings
    assert next(iter(iter_luma(tmp_path / "cover.mov")))[2].shape == (96, 128)


def test_a_picture_stored_on_its_side_turns_the_vertical_given_with_it():
    """A phone held upright stores its picture on its side and says by how much players must turn it: where the
    swing hangs ±90° from the vertical given (0°, config's), the vertical is taken turned with the picture,
    whichever sign the file's rotation has; never where the given one fits the swing, or no turn does. Checked
    on the real apple clip turned on its side with a display rotation of 90° (docs/footage-notes.md): before
    2026-11-28 its angles stage refused it (the swing hangs −90°), now its record's period is 2.0779 s."""
    from pendulum.angles.record import vertical_turned_with_the_picture

    angle = np.radians(-90 + 20 * np.sin(np.linspace(0, 20, 400)))  # hangs at −90° in the image
    track = pd.DataFrame({"x_px": 300 + 500 * np.sin(angle), "y_px": 50 + 500 * np.cos(angle), "flag": "ok"})
    pivot = (300.0, 50.0)
    assert vertical_turned_with_the_picture(track, pivot, 0.0, 90.0) == pytest.approx(-90.0)
    assert vertical_turned_with_the_picture(track, pivot, 0.0, -90.0) == pytest.approx(-90.0)
    assert vertical_turned_with_the_picture(track, pivot, 0.0, 0.0) is None  # no rotation stated: refused later
    assert vertical_turned_with_the_picture(track, pivot, -88.0, 90.0) is None  # the vertical given fits
    assert vertical_turned_with_the_picture(track, pivot, 0.0, 180.0) is None  # no turn brings it near the swing


def test_ten_bit_hevc_gives_eight_bit_luma(tmp_path):
    """10-bit planes are 16-bit words: luma is their top 8 bits, the same picture as the 8-bit source."""
    frames = moving_square(12)
    write_frames(tmp_path / "hevc10.mp4", frames, codec="libx265", pix_fmt="yuv420p10le")
    info, timeline = frame_timeline(tmp_path / "hevc10.mp4")
    assert (info.codec, info.pixel_format, info.bit_depth, len(timeline)) == ("hevc", "yuv420p10le", 10, 12)
    decoded = [y.copy() for _, _, y in iter_luma(tmp_path / "hevc10.mp4")]
    assert len(decoded) == 12 and decoded[0].dtype == np.uint8 and decoded[0].shape == (96, 128)
    for source, y in zip(frames, decoded, strict=True):
        assert np.abs(y - limited_range(source)).mean() < 1  # 10 → 8 bits: the same picture
    sheet = contact_sheet(tmp_path / "hevc10.mp4", n_tiles=4, tile_width_px=128, timeline=timeline)
    assert sheet.dtype == np.uint8 and sheet.shape[0] == 96


def test_undecodable_video_data_fails_at_the_frames_stage_naming_the_file(tmp_path):
    """The container reads, its video data does not decode (random bytes over the whole 'mdat' payload)."""
    write_frames(tmp_path / "noise.mp4", moving_square(30))
    data = bytearray((tmp_path / "noise.mp4").read_bytes())
    at = data.find(b"mdat")
    size = int.from_bytes(data[at - 4 : at], "big")
    data[at + 4 : at - 4 + size] = np.random.default_rng(0).integers(0, 256, size - 8, dtype=np.uint8).tobytes()
    (tmp_path / "noise.mp4").write_bytes(bytes(data))
    with pytest.raises(VideoError, match=r"noise\.mp4: no frame of its h264 video stream could be decoded .*copy"):
        frame_timeline(tmp_path / "noise.mp4")


@pytest.mark.parametrize(
    "name, container_format, codec",
    [
        ("phone.m4v", "ipod", "libx264"),
        ("camcorder.MTS", "mpegts", "libx264"),
        ("recorder.mkv", "matroska", "libx264"),
        ("webcam.webm", "webm", "libvpx-vp9"),
        ("old_phone.3gp", "3gp", "libx264"),
    ],
)
def test_every_container_read_as_a_video_gives_its_frames_at_their_times(tmp_path, name, container_format, codec):
    """The containers a trial may come in (pendulum.camera.video.VIDEO_EXTENSIONS) beyond .mp4, .mov and .avi: each
    file's timeline is its frames, from 0 s at the rate written, and each frame's luma is the one written (a
    transport stream's clock starts 2 frames in here: the times are from its first frame)."""
    from pendulum.camera.video import VIDEO_EXTENSIONS

    assert (tmp_path / name).suffix.lower() in VIDEO_EXTENSIONS
    frames = moving_square(24)
    write_frames(tmp_path / name, frames, rate=25, codec=codec, container_format=container_format)
    info, timeline = frame_timeline(tmp_path / name)
    decoded = [(t, y.copy()) for _, t, y in iter_luma(tmp_path / name)]
    assert len(timeline) == len(decoded) == 24 and not info.variable_frame_rate
    assert np.allclose(timeline.time_s, np.arange(24) / 25, atol=1e-6)
    assert np.allclose([t for t, _ in decoded], timeline.time_s, atol=1e-9)
    for (_, image), written in zip(decoded, frames, strict=True):
        assert np.abs(image.astype(float) - limited_range(written)).max() <= 3.0
