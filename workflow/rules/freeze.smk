import shlex

from pendulum.freeze import freeze_inputs  # noqa: E402
from pendulum.provenance import config_as_used  # noqa: E402

FREEZE_BENCHMARK = (
    f"benchmarks/jobs/freeze/{config.get('freeze_tag') or 'untagged'}.tsv"
)
FREEZE_REQUEST = {
    "tag": config.get("freeze_tag"),
    "allow_dirty": bool(config.get("freeze_allow_dirty", False)),
    "frozen_dir": "results/frozen",
    "code_root": workflow.basedir,
    "data": DATA_PATHS,  # their changes are not the code's (provenance.smk)
    # an earlier freeze of this tag whose folder is gone: refused, not taken as done (freeze.check_request)
    "record": FREEZE_BENCHMARK,
}
# hashed beside the raw folder: the truth files and each camera setup's clips
FREEZE_INPUTS = [config.get("truth_dir")] + [
    setup.get(key)
    for setup in (config.get("cameras") or {}).values()
    for key in CAMERA_CLIPS
]
# Not frozen: frame images (bulky; the contact sheets stay) and the run's all-ok flag
# (a frozen folder may hold failed trials: results/status/trials.csv says which and why).
NOT_FROZEN = ["results/status/all_trials_ok.txt"] + [
    f"results/frames/{name}/images" for name in VIDEO_TRIALS
]


localrules:
    freeze,


rule freeze:
    """Results, report, configuration as used, environment and provenance copied to
    results/frozen/<freeze_tag>/ with a SHA-256 manifest. No declared output, so Snakemake never
    deletes a frozen folder: a taken tag (or one frozen before whose folder is gone), a missing one or a
    dirty tree is refused while the DAG is
    built (nothing runs); the script writes under a temporary name and renames."""
    input:
        results=lambda wildcards: freeze_inputs(
            FREEZE_REQUEST,
            all_targets()
            + [doc for name in sorted(TRIALS) for _, doc, _ in trial_documents(name)]
            + [f"results/geometry/{rig}.json" for rig in RIGS_NEEDING_GEOMETRY]
            + [f"results/calibration/{camera}.json" for camera in used_cameras()]
            + (list(rules.report.output) if rules.has("report") else []),
            excluded=NOT_FROZEN,
        ),
        lock=os.path.relpath(Path(workflow.basedir) / "environment-lock.txt"),
        # every trial's sidecar as used, a skipped one's too: which rig, its own values, a skip and why
        sidecars=sorted(t.sidecar_path for t in FOUND.values() if t.sidecar_path),
        code=script_code("freeze.py"),
    log:
        f"logs/freeze/{FREEZE_REQUEST['tag'] or 'untagged'}.log",
    benchmark:
        FREEZE_BENCHMARK
    threads: 1
    resources:
        mem_mb=500,
        runtime=30,
    params:
        request=FREEZE_REQUEST,
        config=config_as_used(config),
        citation=config.get("citation"),
        raw_dir=config["raw_dir"],
        inputs=[path for path in FREEZE_INPUTS if path],
        command=shlex.join(["snakemake", *sys.argv[1:]]),
    script:
        "../scripts/freeze.py"
