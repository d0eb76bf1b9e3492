"""Shared start of every script: the job's thread budget, then the `pendulum` library on the path.

Imported first, before numpy: BLAS/OpenMP pools (OpenBLAS, OpenMP, MKL, …) and the video
decoder (``PENDULUM_DECODER_THREADS``, read by `pendulum.video`) get exactly the rule's
`threads` (``snakemake.threads``, which Snakemake lowers to the cores it was given), so a
job uses the cores the scheduler reserved for it and no more.
"""

import os
import sys
from pathlib import Path

THREAD_VARIABLES = (
    "OMP_NUM_THREADS",
    "OPENBLAS_NUM_THREADS",
    "MKL_NUM_THREADS",
    "GOTO_NUM_THREADS",
    "VECLIB_MAXIMUM_THREADS",
    "NUMEXPR_NUM_THREADS",
    "PENDULUM_DECODER_THREADS",
)


def job_threads() -> int | None:
    """The running Snakemake job's `threads` (None outside a Snakemake script)."""
    job = getattr(sys.modules.get("__main__"), "snakemake", None)
    threads = getattr(job, "threads", None)
    return max(1, int(threads)) if threads is not None else None


def set_thread_environment(threads: int | None) -> None:
    """Every thread-count variable set to ``threads`` (nothing when None)."""
    if threads is not None:
        for name in THREAD_VARIABLES:
            os.environ[name] = str(threads)


set_thread_environment(job_threads())
sys.path.insert(0, str(Path(__file__).resolve().parents[1]))
