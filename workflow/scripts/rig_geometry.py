"""Snakemake adapter: pivot and vertical of one rig from its trials' pooled tracks (failed tracks left out)."""

import json
from pathlib import Path

import numpy as np
import pandas as pd

import _setup  # noqa: F401
from pendulum.angles.geometry import (
    ELSEWHERE,
    MAX_ANGLE_SCALE_STDERR_PCT,
    estimate_rig_geometry,
    unlike_picture,
)
from pendulum.camera.view import (
    ImageToPlane,
    frames_unlike_calibration,
    map_lines,
    map_point,
    map_track,
    path_tilt,
    uncalibrated_size_change,
)
from pendulum.io import script_logger, write_json
from pendulum.status import is_failed, require_ok, run_stage

sm = snakemake  # noqa: F821
log = script_logger(sm.log[0], "rig_geometry")
rig = sm.wildcards.rig
PIVOT_STDERR_WARN_FRACTION = 0.05  # pivot standard error above this fraction of the arm: poorly determined


def read_json(path):
    return json.loads(Path(path).read_text())


def tilt_warning(tracks: dict, lens_change: float | None = None) -> tuple[dict | None, str | None]:
    """The ellipse test of the pooled marker paths: a swing plane not facing the camera, detected, not corrected;
    ``lens_change``: the largest size change of a marker along its path that no lens calibration corrects (a wide
    lens makes the ellipse too, and the angles too large, not compressed)."""
    ok = [t[t.flag == "ok"] for t in tracks.values()]
    if not ok:
        return None, None
    tilt = path_tilt(
        np.concatenate([t.x_px.to_numpy(float) for t in ok]), np.concatenate([t.y_px.to_numpy(float) for t in ok])
    )
    if not tilt or not tilt["significant"]:
        return tilt, None
    if lens_change:
        return tilt, (
            f"the marker path is an ellipse (axis ratio {tilt['axis_ratio']:.3f} ± {tilt['axis_ratio_stderr']:.3f}) "
            f"and the marker's image changes size by {100 * (lens_change - 1):.0f} % along it: most likely a wide "
            "lens's distortion, uncalibrated (the angles too large), else a swing plane turned against the camera; "
            "calibrate the lens first (cameras: calibration_video, docs/configuration.md)"
        )
    return tilt, (
        f"the marker path is an ellipse (axis ratio {tilt['axis_ratio']:.3f} ± {tilt['axis_ratio_stderr']:.3f}): "
        f"the swing plane seems turned about the image's {tilt['tilt_axis']} by about {tilt['tilt_deg']:.0f}° "
        "against the camera, which compresses the angles (not corrected); film a checkerboard held in the swing "
        "plane (cameras: plane_video) or face the plane squarely"
    )


def work():
    calibration = None
    if "calibration" in sm.input.keys():
        calibration = require_ok(read_json(sm.input.calibration), "calibration")
        log.info("rig %s: %s", rig, ImageToPlane(calibration).describe())
    tracks, failed, pictures, refused, lens_change, rod_lines = {}, {}, {}, {}, {}, {}
    for path, summary_path in zip(sm.input.tracks, sm.input.summaries, strict=True):
        summary = read_json(summary_path)
        name = Path(path).stem
        if summary.get("frame_px"):
            pictures[name] = (*summary["frame_px"], summary.get("rotation_deg") or 0.0)
        if is_failed(summary):
            failed[name] = summary["error"]
            log.warning("%s: left out of the pooled geometry (tracking failed: %s)", name, summary["error"])
        elif unlike := frames_unlike_calibration(name, summary.get("frame_px"), calibration):
            refused[name] = unlike  # its angles stage refuses it with the same words
            log.warning("left out of the pooled geometry: %s", unlike)
        else:
            tracks[name] = map_track(pd.read_csv(path), calibration)
            lens_change[name] = uncalibrated_size_change(summary.get("marker"), calibration)
            if (summary.get("rod") or {}).get("lines"):
                rod_lines[name] = map_lines(summary["rod"]["lines"], calibration)
    pivot = map_point(sm.params.pivot_px, calibration)
    if not tracks and pivot is None:
        if failed or refused:  # nothing to measure on this rig: the trials' own errors say why (trials.csv)
            why = [f"the tracks of {', '.join(sorted(failed))} failed"] if failed else []
            why += [f"{', '.join(sorted(refused))}: frames not of the camera setup's size"] if refused else []
            raise ValueError(
                f"rig {rig}: no usable track to estimate the pivot from: {'; '.join(why)} (their errors are in "
                "results/status/trials.csv and the report)"
            )
        raise ValueError(
            f"rig {rig}: no usable track to estimate the pivot from (no trial of the rig is pooled); give pivot_px "
            "(and vertical_deg) in config or in the trials' sidecars"
        )
    geometry = estimate_rig_geometry(tracks, pivot_px=pivot, vertical_deg=sm.params.vertical_deg, rod_lines=rod_lines)
    kept = [k for k in tracks if k not in geometry["rejected_trials"]]
    geometry["unlike_picture"] = {}  # a trial's angles say it in place of a moved camera (off_rig_circle)
    for name in sorted(geometry["rejected_trials"]):
        if note := unlike_picture(name, pictures, kept):  # told for what it is, not as a camera that moved
            geometry["rejected_trials"][name] = geometry["rejected_trials"][name].replace(ELSEWHERE, note)
            geometry["unlike_picture"][name] = note
    for name, reason in geometry["rejected_trials"].items():
        log.warning("%s: left out of the pooled geometry: %s", name, reason)
    circle = geometry.get("circle")
    shared = geometry.get("shared", True)  # False: the pooled circle is no pivot (each trial's own is used)
    if (
        circle
        and shared
        and max(geometry.get("pivot_stderr_px", [0, 0])) > PIVOT_STDERR_WARN_FRACTION * circle["radius_px"]
        and geometry.get("angle_scale_stderr_pct", 0.0) <= MAX_ANGLE_SCALE_STDERR_PCT  # else said with its scale
    ):
        geometry["warnings"].append(
            f"the pivot is poorly determined by the marker paths (standard error {max(geometry['pivot_stderr_px']):.3g}"
            f" px on an arm of {circle['radius_px']:.0f} px over an arc of {circle['arc_span_deg']:.0f}°); "
            "give pivot_px or film larger swings"
        )
    if not (calibration and calibration.get("plane")):
        kept = {k: v for k, v in tracks.items() if k not in geometry["rejected_trials"]}
        if shared:
            geometry["path_tilt"], warning = tilt_warning(kept, max(filter(None, lens_change.values()), default=None))
            if warning:
                geometry["warnings"].append(warning)
        else:  # paths about different pivots are no one ellipse: each is tested alone
            geometry["path_tilt"] = {}
            for name in sorted(kept):
                geometry["path_tilt"][name], warning = tilt_warning({name: kept[name]}, lens_change.get(name))
                if warning:
                    geometry["warnings"].append(f"{name}: {warning}")
    if calibration:
        geometry["coordinates"] = ImageToPlane(calibration).describe()
    for warning in geometry["warnings"]:
        log.warning("rig %s: %s", rig, warning)
    log.info("rig %s: %s", rig, geometry)
    inputs = sorted(Path(p).stem for p in sm.input.tracks)
    write_json(
        {"rig": rig, "status": "ok", "input_trials": inputs, **geometry, "failed_trials": {**failed, **refused}},
        sm.output.geometry,
    )


run_stage("geometry", log, work, lambda document: write_json({"rig": rig, **document}, sm.output.geometry))
