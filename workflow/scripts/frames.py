"""Snakemake adapter: frame timeline, summary and contact sheet of one video (failed outputs if unreadable)."""

import _setup  # noqa: F401
from pendulum.camera.video import contact_sheet_with_times, frame_timeline
from pendulum.io import script_logger, write_csv, write_json, write_png
from pendulum.status import empty_table, failure_image, run_stage

sm = snakemake  # noqa: F821
log = script_logger(sm.log[0], "frames")
video = sm.input.video
TIMELINE_COLUMNS = [
    "frame",
    "pts",
    "time_s",
    "interval_s",
    "dropped_before",
    "duplicate_time",
    "irregular_interval",
    "keyframe",
    "packet_bytes",
]


def work():
    info, timeline = frame_timeline(video)
    summary = {
        "video": video,
        "status": "ok",
        "width_px": info.width_px,
        "height_px": info.height_px,
        "codec": info.codec,
        "nominal_fps": info.nominal_fps,
        "n_frames": int(len(timeline)),
        "duration_s": float(timeline.time_s.iloc[-1]),
        "mean_fps": float((len(timeline) - 1) / timeline.time_s.iloc[-1]) if len(timeline) > 1 else None,
        "frame_interval_s": info.frame_interval_s,
        "variable_frame_rate": info.variable_frame_rate,
        "rounded_stamps_tick_s": info.rounded_stamps_tick_s,
        "irregular_intervals": int(timeline.irregular_interval.sum()),
        "dropped_frames": int(timeline.dropped_before.sum()),
        "duplicate_timestamps": int(timeline.duplicate_time.sum()),
        "keyframes": int(timeline.keyframe.sum()),
        "stated_frames": info.stated_frames,
        "discarded_packets": info.discarded_packets,
        "rotation_deg": info.rotation_deg,
        "pixel_format": info.pixel_format,
        "bit_depth": info.bit_depth,
        **({"sample_aspect_ratio": info.sample_aspect_ratio} if info.sample_aspect_ratio else {}),
        "warnings": list(info.warnings),
    }
    log.info(
        "%s: %d frames of %d×%d px (%s, %s), %.3f s at %s frames/s (stated %s), %d keyframes, %d irregular intervals",
        video,
        summary["n_frames"],
        summary["width_px"],
        summary["height_px"],
        summary["codec"],
        summary["pixel_format"],
        summary["duration_s"],
        f"{summary['mean_fps']:.3f}" if summary["mean_fps"] else "–",
        summary["nominal_fps"],
        summary["keyframes"],
        summary["irregular_intervals"],
    )
    if info.rounded_stamps_tick_s:
        log.info(
            "%s: time stamps rounded to the container's %.4g ms tick, taken as the regular clock they round "
            "(%.4f ms per frame)",
            video,
            1e3 * info.rounded_stamps_tick_s,
            1e3 * info.frame_interval_s,
        )
    for warning in info.warnings:
        log.warning("%s", warning)
    if summary["dropped_frames"] or summary["duplicate_timestamps"]:
        log.warning(
            "%s: %d dropped frame(s), %d duplicate timestamp(s)",
            video,
            summary["dropped_frames"],
            summary["duplicate_timestamps"],
        )
    sheet, times = contact_sheet_with_times(video, n_tiles=sm.params.tiles, timeline=timeline)
    summary["contact_sheet_times_s"] = times  # the tiles' times: the tracks stage draws the track on them
    write_csv(timeline, sm.output.timeline)
    write_png(sheet, sm.output.contact_sheet)
    write_json(summary, sm.output.summary)


def write_failed(document):
    write_csv(empty_table(TIMELINE_COLUMNS), sm.output.timeline)
    write_png(failure_image(document["error"]), sm.output.contact_sheet)
    write_json({"video": video, **document}, sm.output.summary)


run_stage("frames", log, work, write_failed)
