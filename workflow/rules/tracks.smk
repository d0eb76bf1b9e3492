rule tracks:
    """Sub-pixel marker (or body) centre and quality flag per frame; the track drawn over a contact sheet."""
    input:
        unpack(tracks_calibration),
        video=raw_video,
        frames_summary="results/frames/{trial}/summary.json",
        contact_sheet="results/frames/{trial}/contact_sheet.png",
        code=code_digest("tracks.py"),
    output:
        track="results/tracks/{trial}.csv",
        summary="results/tracks/{trial}.json",
        sheet="results/tracks/{trial}.sheet.png",
    log:
        "logs/tracks/{trial}.log",
    benchmark:
        "benchmarks/jobs/tracks/{trial}.tsv"
    threads: 1  # the decoder's threads (video.iter_luma); `--set-threads tracks=2` for long 1080p clips
    resources:
        mem_mb=tracks_mem_mb,  # 2 GB up to 1080p, more for larger pictures (inputs.smk)
        runtime=tracks_runtime,
    params:
        tracking=tracking_settings,
    script:
        "../scripts/tracks.py"
