"""Snakemake adapter: lens model and swing-plane homography of one camera setup from its checkerboard clips."""

import _setup  # noqa: F401
from pendulum.camera.calibration import CalibrationError
from pendulum.camera.view import calibrate_camera_setup
from pendulum.io import script_logger, write_json
from pendulum.status import run_stage

sm = snakemake  # noqa: F821
log = script_logger(sm.log[0], "calibrate_camera")
camera = sm.wildcards.camera
setup = sm.params.setup


def work():
    for key, clip in setup["clips"].items():
        if key not in sm.input.keys():  # named in config, not there (inputs.smk leaves it out of the inputs)
            raise CalibrationError(f"{clip}: no such file (cameras/{camera}/{key} in the configuration)")
    document = calibrate_camera_setup(
        camera,
        tuple(setup["pattern_inner_corners"]),
        setup["square_size_m"],
        calibration_video=sm.input.get("calibration_video"),
        plane_video=sm.input.get("plane_video"),
        plane_frame=setup["plane_frame"],
    )
    for model, entry in document.get("models", {}).items():
        log.info("%s: %s model: %s", camera, model, entry)
    log.info("%s: lens %s, plane %s", camera, document.get("chosen_model", "none"), document.get("plane"))
    write_json({"status": "ok", **document}, sm.output.calibration)


run_stage(
    "calibration",
    log,
    work,
    lambda document: write_json({"camera_setup": camera, **document, "log": sm.log[0]}, sm.output.calibration),
)
