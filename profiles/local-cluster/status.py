#!/usr/bin/env python3
"""Status command of the local-cluster profile: `status.py <job id>` prints running, success or failed."""

import os
import sys
from pathlib import Path

STATE = Path(".snakemake/local-cluster")


def main() -> int:
    job = sys.argv[-1]
    rc_file = STATE / f"{job}.rc"
    if rc_file.is_file():
        print("success" if rc_file.read_text().strip() == "0" else "failed")
        return 0
    try:
        os.kill(int(job), 0)  # the job's process still exists
        print("running")
    except ProcessLookupError:
        # ended without writing its exit code (killed)
        print("success" if rc_file.is_file() and rc_file.read_text().strip() == "0" else "failed")
    return 0


if __name__ == "__main__":
    sys.exit(main())
