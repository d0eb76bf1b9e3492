"""Report: every result file in, one self-contained HTML page out: tables, figures, checks, discovery, provenance."""

# notebooks/report.ipynb calls `from pendulum import report as R; R.Report(...); R.show(...)`: its entry
# points are named here so that the notebook (and with it the report's bytes) is unchanged by the move.
from pendulum.report.notebook import Report, show  # noqa: F401
