"""Snakemake adapter: marker (or body) track of one video, its path's departure from one circle measured.

A video that cannot be tracked gives an empty track whose summary states the
error (status "failed"), so that the other trials of the rig still pool their
geometry; the later stages of that trial pass the failure on.
"""

import json
import time
from pathlib import Path

import cv2
import numpy as np

import _setup  # noqa: F401
from pendulum.camera.calibration import Lens
from pendulum.camera.video import VideoError, track_over_sheet
from pendulum.io import script_logger, write_csv, write_json, write_png
from pendulum.status import empty_table, failure_image, require_ok, run_stage
from pendulum.tracking import samples
from pendulum.tracking.camera_motion import path_through_lens, steady_camera
from pendulum.tracking.method import track_trial, usable_fraction
from pendulum.tracking.rod import rod_lines, worth_measuring
from pendulum.tracking.settings import TrackerSettings
from pendulum.tracking.timing_notes import break_sentence, slip_sentence

sm = snakemake  # noqa: F821
log = script_logger(sm.log[0], "tracks")
video = sm.input.video
settings = TrackerSettings.from_config(sm.params.tracking)
TRACK_COLUMNS = ["frame", "time_s", "x_px", "y_px", "quality", "signal_ratio", "flag"]
started = time.perf_counter()
measured = {}  # facts of a track that was then refused, for the failed document
refused_sheet = {}  # ... and that track drawn over the key frames: the user sees what was followed


def drawn_sheet(track, frames: dict):
    """The track over the frames stage's contact sheet (no frame decoded again; ``frames``: that stage's summary),
    in image coordinates and at the file's time stamps (the sheet's); the sheet as it is without its times, None
    without a sheet."""
    in_image = track.assign(
        x_px=track.get("x_image_px", track.x_px),
        y_px=track.get("y_image_px", track.y_px),
        time_s=track.get("stamp_s", track.time_s),
    )
    sheet = cv2.imread(sm.input.contact_sheet, cv2.IMREAD_GRAYSCALE)
    times = frames.get("contact_sheet_times_s") or []
    if sheet is not None and times and frames.get("width_px"):
        return track_over_sheet(sheet, times, frames["width_px"], in_image)
    return sheet


def calibrated_lens():
    """The camera setup's lens, where its calibration has one (a failed calibration fails the trial's angles)."""
    if "calibration" not in sm.input.keys():
        return None
    document = json.loads(Path(sm.input.calibration).read_text())
    return Lens.from_dict(document["lens"]) if document.get("status") == "ok" and document.get("lens") else None


def work():
    # a video the frames stage could not read is not tracked again: its failure is said once, by that stage
    frames = require_ok(json.loads(Path(sm.input.frames_summary).read_text()), "frames")
    track = track_trial(video, settings, progress=log.info, keep_samples=True)  # for a rod's lines (below)
    method = track.attrs.get("method", {})
    log.info("%s: tracked the %s (%s)", video, method.get("used"), method.get("reason"))
    measured_track = track
    track, path = path_through_lens(measured_track, calibrated_lens())
    if path.get("not_a_pendulum"):  # a camera in the hand? its motion from the still scene, taken out
        track, path = steady_camera(video, measured_track, path)
    log.info("%s: %s", video, path["verdict"])
    if path.get("not_a_pendulum"):
        measured.update(method=method, path=path, body=track.attrs.get("body"), marker=track.attrs.get("marker"))
        try:
            refused_sheet["image"] = drawn_sheet(track, frames)
        except (OSError, ValueError, KeyError, cv2.error) as error:  # the refusal is said all the same
            log.warning("%s: the refused track could not be drawn over the contact sheet (%s)", video, error)
        raise VideoError(f"{video}: {path['verdict']}; no angle record is made from it")
    flags = track.flag.value_counts().to_dict()
    n_ok = int(flags.get("ok", 0))  # after the timing check (repeats flagged), unlike the method's share
    held = int(flags.get("held", 0))  # a hand holds the body before the release (or after a catch)
    log.info(
        "%s: %d of %d frames usable (%.1f %%)%s",
        video,
        n_ok,
        len(track) - held,
        100 * usable_fraction(track),
        f"; {held} more held by hand before the release or after a catch" if held else "",
    )
    if base := track.attrs.get("time_base"):
        log.info(
            "%s: times put at the camera's %g fps (the file plays at %g fps: each stamp × %.6g)",
            video,
            base["capture_fps"],
            base["file_fps"],
            base["scale"],
        )
    warnings = []  # what may be wrong in the track (trials.csv and the report list them)
    if track.attrs.get("video", {}).get("stopped_early"):
        log.warning("%s", track.attrs["video"]["stopped_early"])
        warnings.append(track.attrs["video"]["stopped_early"])
    timing = track.attrs.get("timing") or {}
    if said := slip_sentence(timing):
        log.warning("%s: %s", video, said)
    if said := break_sentence(timing):  # found and not put right
        warnings.append(f"{said}, which biases a fit; not corrected")
    for aside in (track.attrs.get("body") or {}).get("set_aside") or []:  # a tank's water surface, moving in place
        log.info("%s: set aside as no body, moving in place in most samples: %s", video, aside)
    if (track.attrs.get("body") or {}).get("warning"):
        log.warning("%s: %s", video, track.attrs["body"]["warning"])
    rod = None  # a rod's (or thread's) lines, for the pivot where the arc bends too little to place it
    if worth_measuring(path):
        try:
            rod = rod_lines(video, track)  # in the frames the tracker sampled, where it did
        except (ValueError, cv2.error, np.linalg.LinAlgError, VideoError) as error:  # the track stands without it
            rod = {"lines": [], "reason": f"not measured: {error}"}
            log.warning("%s: a rod's lines could not be measured: %s", video, error)
        found = f"in {len(rod['lines'])} of {rod['frames_tried']} frames" if rod["lines"] else rod.get("reason")
        log.info("%s: the arc bends too little to place its pivot well: a rod's line looked for: %s", video, found)
    write_csv(track, sm.output.track)
    drawn = drawn_sheet(track, frames)
    write_png(drawn if drawn is not None else failure_image("no contact sheet"), sm.output.sheet)
    write_json(
        {
            "video": video,
            "status": "ok",
            "n_frames": int(len(track)),
            "flags": {k: int(v) for k, v in sorted(flags.items())},
            "rotation_deg": float(frames.get("rotation_deg") or 0.0),  # the file's display rotation (frames as stored)
            "frame_px": [frames["width_px"], frames["height_px"]] if frames.get("width_px") else None,  # as stored
            "method": method,  # marker or body, why, and what each tried gave
            "path": path,  # departure from one circle, a creeping pivot (corrected), what is left
            "timing": track.attrs.get("timing"),  # frames lost or repeated under even stamps, found from the motion
            "time_base": track.attrs.get("time_base"),  # capture_fps: the camera's rate where the file plays slower
            "exposure_fraction": track.attrs.get("exposure_fraction"),
            "marker": track.attrs.get("marker"),  # polarity, radius and start used (given or detected)
            "detection": track.attrs.get("detection"),  # what detection found (None: all given)
            "body": track.attrs.get("body"),  # the body tracker's scene facts (None: a marker was tracked)
            "rod": rod,  # its lines where the arc bends too little (pendulum.tracking.rod; None: not looked for)
            "decoder": track.attrs.get("video", {}),
            "settings": settings.__dict__,
            "warnings": warnings,
        },
        sm.output.summary,
    )


def write_failed(document):
    write_csv(empty_table(TRACK_COLUMNS), sm.output.track)
    sheet = refused_sheet.get("image")
    if sheet is None:
        write_png(failure_image(document["error"]), sm.output.sheet)
    else:  # a refused track: the reason above the track it was measured from (drawn in colour)
        banner = failure_image(document["error"], sheet.shape[1], header="REFUSED:")
        if sheet.ndim == 3:
            banner = cv2.cvtColor(banner, cv2.COLOR_GRAY2BGR)
        write_png(np.vstack([banner, sheet]), sm.output.sheet)
    # what was measured before the refusal (a path that is not a pendulum's): the user can see why
    write_json({"video": video, **document, **measured, "settings": settings.__dict__}, sm.output.summary)


run_stage("tracks", log, work, write_failed)
samples.release()  # the frames track_trial kept for the rod's lines
log.info("%s: done in %.1f s", video, time.perf_counter() - started)
