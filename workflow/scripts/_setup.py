"""Shared start of every script: the job's thread budget, then the `pendulum` library on the path.

Imported first, before numpy: BLAS/OpenMP pools (OpenBLAS, OpenMP, MKL, …) and the video
decoder (``PENDULUM_DECODER_THREADS``, read by `pendulum.camera.video`) get exactly the rule's
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
    "OPENCV_FOR_THREADS_NUM",  # OpenCV's parallel loops (blurs, morphology, resizing): all cores unless told
    "PENDULUM_DECODER_THREADS",
)


def _job():
    """The running Snakemake job's ``snakemake`` object (None outside a Snakemake script)."""
    return getattr(sys.modules.get("__main__"), "snakemake", None)


def job_threads() -> int | None:
    """The running Snakemake job's `threads` (None outside a Snakemake script)."""
    threads = getattr(_job(), "threads", None)
    return max(1, int(threads)) if threads is not None else None


def set_thread_environment(threads: int | None) -> None:
    """Every thread-count variable set to ``threads`` (nothing when None)."""
    if threads is not None:
        for name in THREAD_VARIABLES:
            os.environ[name] = str(threads)


def job_log() -> str | None:
    """The running Snakemake job's first log file (None outside a Snakemake script)."""
    logs = list(getattr(_job(), "log", None) or [])
    return str(logs[0]) if logs else None


def _written_failure(exc: BaseException):
    """The :class:`pendulum.io.WriteFailure` behind an exception (its cause or context, or an error of the
    report's notebook kernel), else None."""
    import re

    from pendulum.io import write_failure

    seen = set()
    while exc is not None and id(exc) not in seen:
        seen.add(id(exc))
        failure = write_failure(exc)
        if failure is None and getattr(exc, "ename", None):  # papermill: the kernel's error by name and text
            text = str(getattr(exc, "evalue", ""))
            if exc.ename == "WriteFailure":
                return text
            code = re.search(r"\[Errno (\d+)\] ([^:]+)", text)
            failure = write_failure(OSError(int(code.group(1)), code.group(2))) if code else None
        if failure is not None:
            return str(failure)
        exc = exc.__cause__ or exc.__context__
    return None


def report_write_failures(kind, exc, tb) -> None:
    """``sys.excepthook``: a write that failed for want of room or rights (disk full, read-only folder, quota)
    is one sentence on the screen, naming the file and how to resume; its traceback goes to the job's log.
    Any other error is shown as Python shows it."""
    try:
        sentence = _written_failure(exc)
    except Exception:  # noqa: BLE001 - never hide the original error behind one of this hook
        sentence = None
    if sentence is None:
        sys.__excepthook__(kind, exc, tb)
        return
    log = job_log()
    if log:
        try:
            import traceback

            with open(log, "a", encoding="utf-8") as fh:
                traceback.print_exception(kind, exc, tb, file=fh)
        except OSError:
            pass  # the log is on the same full disk
    sys.stderr.write(f"error: {sentence}\n")


set_thread_environment(job_threads())
sys.path.insert(0, str(Path(__file__).resolve().parents[1]))
sys.excepthook = report_write_failures
