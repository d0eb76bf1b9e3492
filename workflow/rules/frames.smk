rule frames:
    """Frame timeline from the container (no decoding) and a key-frame contact sheet."""
    input:
        video=raw_video,
        code=code_digest("frames.py"),
    output:
        timeline="results/frames/{trial}/timeline.csv",
        summary="results/frames/{trial}/summary.json",
        contact_sheet="results/frames/{trial}/contact_sheet.png",
    log:
        "logs/frames/{trial}.log",
    benchmark:
        "benchmarks/jobs/frames/{trial}.tsv"
    threads: 1
    resources:
        mem_mb=500,
        runtime=10,
    params:
        tiles=config["frames"]["contact_sheet_tiles"],
    script:
        "../scripts/frames.py"


rule frame_images:
    """Every decoded frame as a PNG (only when frames.keep_images is true; costly)."""
    input:
        video=raw_video,
        code=code_digest("frame_images.py"),
    output:
        images=directory("results/frames/{trial}/images"),
    log:
        "logs/frame_images/{trial}.log",
    benchmark:
        "benchmarks/jobs/frame_images/{trial}.tsv"
    threads: 1
    resources:
        mem_mb=1000,
        runtime=60,
    params:
        image_format="png",
    script:
        "../scripts/frame_images.py"
