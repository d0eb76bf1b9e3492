"""Snakemake adapter: frame timeline, summary and contact sheet of one video (failed outputs if unreadable)."""

import _setup  # noqa: F401
from pendulum.io import script_logger, write_csv, write_json, write_png
from pendulum.status import empty_table, failure_image, run_stage
from pendulum.video import contact_sheet, frame_timeline

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
        "dropped_frames": int(timeline.dropped_before.sum()),
        "duplicate_timestamps": int(timeline.duplicate_time.sum()),
        "keyframes": int(timeline.keyframe.sum()),
        "stated_frames": info.stated_frames,
        "warnings": list(info.warnings),
    }
    log.info("%s: %s", video, summary)
    for warning in info.warnings:
        log.warning("%s", warning)
    if summary["dropped_frames"] or summary["duplicate_timestamps"]:
        log.warning(
            "%s: %d dropped frame(s), %d duplicate timestamp(s)",
            video,
            summary["dropped_frames"],
            summary["duplicate_timestamps"],
        )
    sheet = contact_sheet(video, n_tiles=sm.params.tiles)
    write_csv(timeline, sm.output.timeline)
    write_png(sheet, sm.output.contact_sheet)
    write_json(summary, sm.output.summary)


def write_failed(document):
    write_csv(empty_table(TIMELINE_COLUMNS), sm.output.timeline)
    write_png(failure_image(document["error"]), sm.output.contact_sheet)
    write_json({"video": video, **document}, sm.output.summary)


run_stage("frames", log, work, write_failed)
