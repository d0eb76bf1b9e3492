"""Snakemake adapter: execute notebooks/report.ipynb with papermill, write it and its HTML."""

import os
from pathlib import Path

import _setup  # noqa: F401
from pendulum.io import script_logger
from pendulum.report.notebook import build_report

sm = snakemake  # noqa: F821
log = script_logger(sm.log[0], "report")
declared = set(sm.input.results)


def paths(node):
    return [p for key in sorted(node) for p in paths(node[key])] if isinstance(node, dict) else [node]


undeclared = sorted(set(paths(sm.params.files)) - declared)
if undeclared:
    raise ValueError(f"the report would read files that are not inputs of rule report: {undeclared}")
# the folder holding the pendulum package, as declared in the code input (relative: same bytes anywhere)
init = next(p for p in sm.input.code if Path(p).parts[-2:] == ("pendulum", "__init__.py"))
parameters = {
    "library": str(Path(init).parent.parent),
    "files": sm.params.files,
    "trials": sm.params.trials,
    "rigs": sm.params.rigs,
    "variants": sm.params.variants,
    "fitting": sm.params.fitting,
    "provenance": sm.params.provenance,
}
log.info("executing %s: %d trial(s), %d variant(s)", sm.input.notebook, len(sm.params.trials), len(sm.params.variants))
build_report(sm.input.notebook, sm.output.html, sm.output.notebook, parameters, cwd=os.getcwd(), log=log)
log.info("wrote %s and %s", sm.output.html, sm.output.notebook)
