"""Snakemake adapter: frame timeline, summary and contact sheet of one video."""

import _setup  # noqa: F401
from pendulum.io import script_logger, write_csv, write_json, write_png
from pendulum.video import contact_sheet, frame_timeline

sm = snakemake  # noqa: F821
log = script_logger(sm.log[0], "frames")
video = sm.input.video
try:
    info, timeline = frame_timeline(video)
    summary = {
        "video": video,
        "width_px": info.width_px,
        "height_px": info.height_px,
        "codec": info.codec,
        "nominal_fps": info.nominal_fps,
        "n_frames": int(len(timeline)),
        "duration_s": float(timeline.time_s.iloc[-1]),
        "dropped_frames": int(timeline.dropped_before.sum()),
        "duplicate_timestamps": int(timeline.duplicate_time.sum()),
        "keyframes": int(timeline.keyframe.sum()),
    }
    log.info("%s: %s", video, summary)
    if summary["dropped_frames"] or summary["duplicate_timestamps"]:
        log.warning(
            "%s: %d dropped frame(s), %d duplicate timestamp(s)",
            video,
            summary["dropped_frames"],
            summary["duplicate_timestamps"],
        )
    sheet = contact_sheet(video, n_tiles=sm.params.tiles)
except Exception as exc:
    log.error("%s", exc)
    raise
write_csv(timeline, sm.output.timeline)
write_json(summary, sm.output.summary)
write_png(sheet, sm.output.contact_sheet)
