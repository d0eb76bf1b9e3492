"""Snakemake adapter: marker track of one video.

A video that cannot be tracked gives an empty track whose summary states the
error (status "failed"), so that the other trials of the rig still pool their
geometry; the later stages of that trial pass the failure on.
"""

import time

import _setup  # noqa: F401
from pendulum.io import script_logger, write_csv, write_json
from pendulum.status import empty_table, run_stage
from pendulum.tracking import TrackerSettings, track_video

sm = snakemake  # noqa: F821
log = script_logger(sm.log[0], "tracks")
video = sm.input.video
settings = TrackerSettings(**{k: (tuple(v) if isinstance(v, list) else v) for k, v in sm.params.tracking.items()})
TRACK_COLUMNS = ["frame", "time_s", "x_px", "y_px", "quality", "signal_ratio", "flag"]
started = time.perf_counter()


def work():
    track = track_video(video, settings, progress=log.info)
    flags = track.flag.value_counts().to_dict()
    if track.attrs.get("video", {}).get("stopped_early"):
        log.warning("%s", track.attrs["video"]["stopped_early"])
    write_csv(track, sm.output.track)
    write_json(
        {
            "video": video,
            "status": "ok",
            "n_frames": int(len(track)),
            "flags": {k: int(v) for k, v in sorted(flags.items())},
            "exposure_fraction": track.attrs.get("exposure_fraction"),
            "marker": track.attrs.get("marker"),  # polarity, radius and start used (given or detected)
            "detection": track.attrs.get("detection"),  # what detection found (None: all given)
            "decoder": track.attrs.get("video", {}),
            "settings": settings.__dict__,
        },
        sm.output.summary,
    )


def write_failed(document):
    write_csv(empty_table(TRACK_COLUMNS), sm.output.track)
    write_json({"video": video, **document, "settings": settings.__dict__}, sm.output.summary)


run_stage("tracks", log, work, write_failed)
log.info("%s: done in %.1f s", video, time.perf_counter() - started)
