"""Snakemake adapter: angle record of one trial, from its track or from an angle table."""

import json
from pathlib import Path

import pandas as pd

import _setup  # noqa: F401
from pendulum.angles.geometry import estimate_rig_geometry, trial_geometry
from pendulum.angles.harmonics import verdict
from pendulum.angles.record import (
    angles_from_track,
    angles_from_tracker_csv,
    read_tracker_csv,
    record_digest,
    vertical_turned_with_the_picture,
)
from pendulum.angles.swings import missing_period
from pendulum.camera.view import (
    ImageToPlane,
    calibration_warnings,
    map_lines,
    map_point,
    map_track,
    uncalibrated_size_change,
)
from pendulum.io import script_logger, write_csv, write_json
from pendulum.status import empty_table, require_ok, run_stage

sm = snakemake  # noqa: F821
log = script_logger(sm.log[0], "angles")
trial = sm.wildcards.trial
settings = sm.params.settings
length_m = settings["length_m"]
ANGLE_COLUMNS = ["time_s", "video_time_s", "frame", "theta_rad", "theta_deg", "s_m", "quality", "flag"]


def read_json(path):
    return json.loads(Path(path).read_text())


def work():
    track_summary, path, plane_calibrated, size_change, rod = None, None, None, None, None
    warnings = []  # about the angle measurement (shown in the report's tracking-quality notes)
    if "table" in sm.input.keys():
        source = sm.input.table
        vertical = settings["vertical_deg"] if settings["vertical_deg"] is not None else 0.0
        table, info = angles_from_tracker_csv(
            read_tracker_csv(source), vertical_deg=vertical, length_m=length_m, source=source
        )
    else:
        track_summary = require_ok(read_json(sm.input.track_summary), "tracks")
        path = track_summary.get("path") or {}
        if path.get("corrected") or path.get("departs"):
            warnings.append(f"path: {path['verdict']}")
        source = sm.input.track
        calibration = None
        if "calibration" in sm.input.keys():
            calibration = require_ok(read_json(sm.input.calibration), "calibration")
        in_image = pd.read_csv(source)
        warnings += calibration_warnings(
            trial, in_image, track_summary.get("frame_px"), calibration, track_summary.get("marker")
        )
        size_change = uncalibrated_size_change(track_summary.get("marker"), calibration)
        plane_calibrated = calibration.get("camera_setup") if calibration and calibration.get("plane") else None
        track = map_track(in_image, calibration)
        pivot, vertical = map_point(settings["pivot_px"], calibration), settings["vertical_deg"]
        pivot_cov = None
        notes = [ImageToPlane(calibration).describe()] if calibration else []
        if "geometry" in sm.input.keys():
            geometry = require_ok(read_json(sm.input.geometry), "geometry")
            warnings += [f"rig geometry: {w}" for w in geometry.get("warnings", [])]
            if pivot is None:
                lines = (track_summary.get("rod") or {}).get("lines")  # its own rod's, for a pivot of its own
                used, own = trial_geometry(
                    track, geometry, vertical, trial, map_lines(lines, calibration) if lines else None
                )
                pivot, pivot_cov, vertical = used["pivot_px"], used["pivot_covariance_px2"], used["vertical_deg"]
                joined = used if own else geometry  # the pivot used: the trial's own, or the rig's
                if (joined.get("rod") or {}).get("used"):  # joined with where a rod's lines meet
                    rod = joined["rod"]
                    notes.append(f"pivot: {joined['pivot_source']}" + ("" if own else " (results/geometry)"))
                for warning in [own, *used["warnings"]] if own else []:
                    log.warning("trial %s: %s", trial, warning)
                    notes.append(warning)
                    warnings.append(warning)
                if not own and trial in (geometry.get("rejected_trials") or {}):  # the pooling's stricter test
                    notes.append(
                        "left out of the rig's pooled pivot (results/geometry: "
                        f"{geometry['rejected_trials'][trial].split(':')[0]}), yet close enough to the rig's circle "
                        "for its angles to be measured about the rig's pivot"
                    )
            vertical = vertical if vertical is not None else geometry["vertical_deg"]
        if vertical is None:  # the trial's own pivot (sidecar), no vertical: from its own swings
            own = estimate_rig_geometry({trial: track}, pivot_px=pivot)
            vertical = own["vertical_deg"]
            notes.append(f"vertical {vertical:.4g}°: {own['vertical_source']}")
            for warning in own["warnings"]:
                log.warning("trial %s: %s", trial, warning)
                notes.append(warning)
                warnings.append(warning)
        turned = vertical_turned_with_the_picture(track, pivot, vertical, track_summary.get("rotation_deg") or 0.0)
        if turned is not None:  # a phone held upright: its picture stored turned, and the file says so
            warning = (
                f"the swing hangs near {turned:+.0f}° in the stored frames, not at the vertical given "
                f"({vertical:g}°): the file asks players to turn its picture by {track_summary['rotation_deg']:g}°, "
                f"so the vertical given is taken as turned with it, {turned:g}° in the stored frames"
            )
            log.warning("trial %s: %s", trial, warning)
            notes.append(warning)
            warnings.append(warning)
            vertical = turned
        table, info = angles_from_track(
            track,
            pivot_px=pivot,
            vertical_deg=vertical,
            length_m=length_m,
            source=source,
            pivot_covariance_px2=pivot_cov,
            knock=(path.get("creep") or {}).get("knock"),
        )
        if (info.camera_turn or {}).get("taken_out"):  # a knocked camera's turn, taken out of θ
            log.warning("trial %s: %s", trial, info.notes[-1])
            warnings.append(info.notes[-1])
        info.notes = notes + info.notes
    if info.period_s is None:  # said where the period would be read (trials.csv, the report), not a blank
        warning = missing_period(table.time_s.to_numpy(float), table.theta_rad.to_numpy(float))
        log.warning("trial %s: %s", trial, warning)
        warnings.append(warning)
    if (info.second_harmonic or {}).get("present"):
        if plane_calibrated:  # the view is calibrated already: the verdict does not ask for it
            info.second_harmonic["verdict"] = verdict(info.second_harmonic, plane_calibrated)
        warning = info.second_harmonic["verdict"]
        log.warning("trial %s: %s", trial, warning)
        warnings.append(warning)
    log.info("trial %s: %s", trial, info)
    write_csv(table, sm.output.angles)
    document = {"trial": trial, "rig": settings["rig_name"], "status": "ok", **info.to_dict()}
    document["record_sha256"] = record_digest(table)  # the same recording under two names is counted once
    if track_summary is not None:
        document["method"] = (track_summary.get("method") or {}).get("used", "marker")
        document["path"] = path
        if rod:  # the pivot joined with where the rod's lines meet (the report's Table 1 says so)
            document["pivot_rod_lines"] = rod["lines"]
        if size_change:  # an uncalibrated view that scales the angles (the report's summary says so)
            document["uncalibrated_size_change"] = size_change
    write_json({**document, "warnings": warnings}, sm.output.summary)


def write_failed(document):
    write_csv(empty_table(ANGLE_COLUMNS), sm.output.angles)
    write_json({"trial": trial, "rig": settings["rig_name"], **document}, sm.output.summary)


run_stage("angles", log, work, write_failed)
