"""Snakemake adapter: marker track of one video.

An unreadable video gives an empty track whose summary states the error, so
that the other trials of the rig still pool their geometry; the angles stage
of that trial then fails with the same message.
"""

import time

import pandas as pd

import _setup  # noqa: F401
from pendulum.io import script_logger, write_csv, write_json
from pendulum.tracking import TrackerSettings, track_video
from pendulum.video import VideoError

sm = snakemake  # noqa: F821
log = script_logger(sm.log[0], "tracks")
video = sm.input.video
settings = TrackerSettings(**{k: (tuple(v) if isinstance(v, list) else v) for k, v in sm.params.tracking.items()})
started = time.perf_counter()
try:
    track = track_video(video, settings, progress=log.info)
    status, error = "ok", None
except VideoError as exc:
    log.error("%s", exc)
    track = pd.DataFrame(columns=["frame", "time_s", "x_px", "y_px", "quality", "signal_ratio", "flag"])
    status, error = "unreadable", str(exc)
flags = track.flag.value_counts().to_dict() if len(track) else {}
write_csv(track, sm.output.track)
write_json(
    {
        "video": video,
        "status": status,
        "error": error,
        "n_frames": int(len(track)),
        "flags": {k: int(v) for k, v in sorted(flags.items())},
        "settings": settings.__dict__,
    },
    sm.output.summary,
)
log.info("%s: done in %.1f s", video, time.perf_counter() - started)
