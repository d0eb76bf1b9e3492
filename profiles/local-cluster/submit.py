#!/usr/bin/env python3
"""Submit command of the local-cluster profile: run a Snakemake job script as its own detached local process.

Called by snakemake-executor-plugin-cluster-generic as `submit.py <jobscript>`;
prints the job id (the process id). The exit code is written to
.snakemake/local-cluster/<id>.rc when the job ends, for status.py.
"""

import subprocess
import sys
from pathlib import Path

STATE = Path(".snakemake/local-cluster")


def main() -> int:
    jobscript = sys.argv[-1]
    STATE.mkdir(parents=True, exist_ok=True)
    wrapper = f'bash "{jobscript}"; echo $? > "{STATE}/$$.rc.part" && mv "{STATE}/$$.rc.part" "{STATE}/$$.rc"'
    log = open(STATE / "jobs.log", "a")  # noqa: SIM115 - handed to the child
    proc = subprocess.Popen(
        ["bash", "-c", wrapper], stdout=log, stderr=subprocess.STDOUT, stdin=subprocess.DEVNULL, start_new_session=True
    )
    # $$ in the wrapper is the bash process's id, the one printed here
    print(proc.pid)
    return 0


if __name__ == "__main__":
    sys.exit(main())
