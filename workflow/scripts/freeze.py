"""Snakemake adapter: freeze the results into results/frozen/<freeze_tag>/ (never over an existing one)."""

import sys

import _setup  # noqa: F401
from pendulum.freeze import MANIFEST, FreezeError, freeze
from pendulum.io import script_logger

sm = snakemake  # noqa: F821
log = script_logger(sm.log[0], "freeze")
request = sm.params.request
try:
    folder, manifest_sha256 = freeze(
        tag=request["tag"],
        results=list(sm.input.results),
        lock_file=sm.input.lock,
        config=sm.params.config,
        raw_dir=sm.params.raw_dir,
        code_root=request["code_root"],
        frozen_dir=request["frozen_dir"],
        allow_dirty=request["allow_dirty"],
        command=sm.params.command,
        citation=sm.params.citation,
        log=log,
        sidecars=list(sm.input.sidecars),
        data=tuple(request["data"]),
        inputs=tuple(sm.params.inputs),
    )
except FreezeError as error:
    log.error("freeze refused: %s", error)
    raise SystemExit(f"freeze refused: {error}") from None
# where a user reads it (the log has it too): the folder to cite, and how to check it
print(
    f"froze {folder}; cite it with the SHA-256 of its {MANIFEST}: {manifest_sha256} (verify: cd {folder} && "
    f"sha256sum -c {MANIFEST})",
    file=sys.stderr,
)
