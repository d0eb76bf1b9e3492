# The code input of the per-trial rules: one digest of the library modules a stage's script imports
# (see code_digest in provenance.smk).


rule code_digest:
    """The digest of the library modules a per-trial stage's script imports (its one code input)."""
    input:
        lambda wc: script_code(f"{wc.script}.py"),
    output:
        digest="results/code/{script}.sha256",
    log:
        "logs/code/{script}.log",
    benchmark:
        "benchmarks/jobs/code/{script}.tsv"
    wildcard_constraints:
        script="[a-z_]+",
    threads: 1
    resources:
        mem_mb=100,
        runtime=1,
    run:
        write_text(code_digest_text(input), output.digest)
        Path(log[0]).write_text(f"{len(input)} files\n")
