rule rig_geometry:
    """Pivot and vertical of one rig, estimated from its trials' pooled marker paths."""
    input:
        unpack(geometry_inputs),
        code=script_code("rig_geometry.py"),
    output:
        geometry="results/geometry/{rig}.json",
    log:
        "logs/geometry/{rig}.log",
    benchmark:
        "benchmarks/jobs/geometry/{rig}.tsv"
    threads: 1
    resources:
        mem_mb=1000,
        runtime=10,
    params:
        pivot_px=lambda wc: config["rigs"][wc.rig].get("pivot_px"),
        vertical_deg=lambda wc: config["rigs"][wc.rig].get("vertical_deg"),
    script:
        "../scripts/rig_geometry.py"


rule angles:
    """θ(t) about the pivot, arc displacement s = Lθ, trimmed from release to rest."""
    input:
        unpack(angles_inputs),
        code=code_digest("angles.py"),
    output:
        angles="results/angles/{trial}.csv",
        summary="results/angles/{trial}.json",
    log:
        "logs/angles/{trial}.log",
    benchmark:
        "benchmarks/jobs/angles/{trial}.tsv"
    threads: 1
    resources:
        mem_mb=500,
        runtime=5,
    params:
        settings=angles_settings,
        keep_rest_s=config["angles"]["keep_rest_s"],
    script:
        "../scripts/angles.py"
