rule tracks:
    """Sub-pixel marker centre and quality flag per frame (one decode pass)."""
    input:
        video=raw_video,
        code=script_code("tracks.py"),
    output:
        track="results/tracks/{trial}.csv",
        summary="results/tracks/{trial}.json",
    log:
        "logs/tracks/{trial}.log",
    threads: 1
    resources:
        mem_mb=1000,
        runtime=60,
    params:
        tracking=tracking_settings,
    script:
        "../scripts/tracks.py"
