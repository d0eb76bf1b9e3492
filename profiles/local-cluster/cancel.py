#!/usr/bin/env python3
"""Cancel command of the local-cluster profile: `cancel.py <job id> ...` stops each job's process group."""

import os
import signal
import sys


def main() -> int:
    for job in sys.argv[1:]:
        try:
            os.killpg(int(job), signal.SIGTERM)
        except (ProcessLookupError, ValueError):
            pass
    return 0


if __name__ == "__main__":
    sys.exit(main())
