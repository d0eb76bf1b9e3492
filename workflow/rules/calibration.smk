rule calibrate_camera:
    """Lens (rational or fisheye model, chosen by held-out reprojection error) and swing-plane homography of a camera setup."""
    input:
        unpack(calibration_inputs),
        code=script_code("calibrate_camera.py"),
    output:
        calibration="results/calibration/{camera}.json",
    log:
        "logs/calibration/{camera}.log",
    benchmark:
        "benchmarks/jobs/calibration/{camera}.tsv"
    wildcard_constraints:
        camera=r"[A-Za-z0-9_.+-]+",
    threads: 1
    resources:
        mem_mb=2000,
        runtime=30,
    params:
        setup=camera_setup,
    script:
        "../scripts/calibrate_camera.py"
