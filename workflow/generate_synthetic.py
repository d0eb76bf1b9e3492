"""Command: render synthetic pendulum videos with known truth from a YAML spec.

python workflow/generate_synthetic.py data/synthetic/demo.yaml [--only NAME ...]
"""

import sys
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))

from pendulum.synthetic.experiment import main  # noqa: E402

if __name__ == "__main__":
    raise SystemExit(main())
