"""The results report: the :class:`Report` the notebook calls and the deterministic notebook → HTML conversion.

``notebooks/report.ipynb`` calls :class:`Report` section by section; the
Snakemake rule ``report`` runs it with papermill (:func:`build_report`) and
converts it to one self-contained HTML file. Everything here only *reads* what
the rules wrote (fit documents, curve and half-cycle tables, joint fits, the
summary and status tables, tracking summaries, truth files of synthetic
trials): nothing is fitted. Identical inputs give identical bytes: figures are
PNG without a software stamp, the executed notebook carries no timestamps and
fixed cell ids.

The sections live in groups, one module each: ``tables`` (Tables 1–3),
``figures``, ``comparison`` (summary box, model comparison),
``discovery`` (the physics the baseline misses, per group) and
``checks`` (header, truth, tracking, failures, provenance), over
``data`` (the results, read once) and ``format`` (names, numbers,
HTML pieces). This module puts them together and runs the notebook.
"""

from __future__ import annotations

import re

from pendulum.report.budget import BudgetSections
from pendulum.report.checks import CheckSections
from pendulum.report.comparison import ComparisonSections
from pendulum.report.design import DesignSections
from pendulum.report.discovery import DiscoverySections
from pendulum.report.figures import FigureSections
from pendulum.report.format import esc
from pendulum.report.status import StatusSections
from pendulum.report.tables import TableSections
from pendulum.report.truth import TruthSections

# ---------------------------------------------------------------------------
# The report


class Report(
    ComparisonSections,
    TableSections,
    BudgetSections,
    FigureSections,
    DiscoverySections,
    DesignSections,
    CheckSections,
    TruthSections,
    StatusSections,
):
    """The report's sections as HTML, one method per notebook cell; its fields and look-ups: ``ReportData``."""


def show(html_text: str) -> None:
    """Display an HTML fragment as the cell's output (in the notebook)."""
    from IPython.display import HTML, display

    display(HTML(html_text))


# ---------------------------------------------------------------------------
# Executing the notebook and writing the HTML

PAGE_CSS = """
:root { --ink: #1b1b1b; --muted: #5a5a5a; --rule: #c9c9c9; --band: #f4f6f8; --warn: #a33a00; }
html { font-size: 15px; }
body { margin: 0; color: var(--ink); background: #fff;
  font-family: "Source Sans Pro", "Segoe UI", "Helvetica Neue", Arial, "DejaVu Sans", sans-serif; line-height: 1.45; }
main { max-width: 1400px; margin: 0 auto; padding: 24px 28px 60px; }
h1 { font-size: 1.7rem; margin: 0.2em 0 0.3em; }
h2 { font-size: 1.3rem; margin: 1.8em 0 0.5em; padding-bottom: 0.2em; border-bottom: 2px solid var(--ink); }
h3 { font-size: 1.05rem; margin: 0.4em 0 0.5em; }
p { margin: 0.45em 0; }
.subtitle { color: var(--muted); margin: 0.2em 0; }
nav.contents { font-size: 0.9rem; margin: 0.6em 0 0; color: var(--muted); }
a.anchor-link { display: none; }
code { font-size: 0.9em; }
.warn { color: var(--warn); font-weight: 600; }
.summary-box { border: 2px solid #0072B2; border-radius: 6px; padding: 10px 16px 12px; margin: 12px 0 18px;
  background: #f3f8fc; }
.summary-box table { width: auto; }
.summary-box ul.warnings { margin: 0.2em 0 0.2em 1.2em; padding: 0; }
.table-block { margin: 14px 0 20px; }
.table-wrap { overflow-x: auto; }
p.caption { font-size: 0.9rem; margin: 0 0 6px; max-width: 1060px; }
table { border-collapse: collapse; font-size: 0.86rem; font-variant-numeric: tabular-nums; }
th { text-align: left; vertical-align: bottom; padding: 4px 8px; font-weight: 600;
  border-bottom: 1.5px solid var(--ink); border-top: 1.5px solid var(--ink); }
th.group { text-align: center; border-bottom: 1px solid var(--rule); }
th.sub { border-top: none; text-align: right; font-weight: 500; }
td { padding: 3px 8px; vertical-align: top; border-bottom: 1px solid #eee; }
td.num { text-align: right; white-space: nowrap; }
td.num .v { display: block; }
td.num .q { display: block; color: var(--muted); font-size: 0.8rem; }
td.flagged .v, td.flagged .q { color: var(--warn); }
td.na { color: #9a9a9a; }
td.fail { color: var(--warn); white-space: normal; }
td.truth, tr.truth td { color: #333; font-style: italic; background: #fbfbf3; }
tr.joint td { background: var(--band); }
tr.group-end td { border-bottom: 1px solid var(--rule); }
td.warncell { color: var(--warn); font-size: 0.8rem; min-width: 8em; max-width: 12em; }
.table-note { font-size: 0.85rem; color: var(--muted); max-width: 1060px; }
figure { margin: 16px 0 22px; break-inside: avoid; }
figure.fig img { width: 100%; max-width: 1100px; height: auto; display: block; }
figcaption, p.figcaption { font-size: 0.88rem; max-width: 1060px; margin-top: 4px; }
.sheets { display: grid; grid-template-columns: repeat(2, minmax(0, 1fr)); gap: 10px 16px; }
figure.sheet { margin: 0; }
figure.sheet img { width: 100%; height: auto; display: block; border: 1px solid var(--rule); }
figure.sheet figcaption { text-align: center; }
details.fit-warnings { font-size: 0.82rem; color: var(--muted); margin: -8px 0 16px; }
div.design-next { margin-bottom: 14px; }
div.design-next ol { margin: 4px 0 2px 0; }
p.discovery-verdict, div.discovery-verdict {
  border-left: 4px solid #0072B2; background: #f3f8fc; padding: 6px 12px; max-width: 1060px;
}
p.discovery-ending { border-left: 4px solid var(--warn); padding: 4px 12px; max-width: 1060px; }
details.fit-warnings li { margin: 2px 0; }
@media print {
  html { font-size: 10pt; }
  main { max-width: none; padding: 0; }
  h2 { break-after: avoid; }
  .table-wrap { overflow: visible; }
  figure, .summary-box, .table-block { break-inside: avoid; }
  .sheets { grid-template-columns: repeat(3, minmax(0, 1fr)); }
  details.fit-warnings { display: none; }
  @page { size: A4; margin: 14mm 12mm; }
}
"""


def page_html(body: str, title: str) -> str:
    """One self-contained HTML page: the notebook's outputs, the report's CSS, no scripts, no external files."""
    return (
        '<!DOCTYPE html>\n<html lang="en">\n<head>\n<meta charset="utf-8">\n'
        '<meta name="viewport" content="width=device-width, initial-scale=1">\n'
        f"<title>{esc(title)}</title>\n<style>{PAGE_CSS}</style>\n</head>\n<body>\n<main>\n{body}\n</main>\n</body>\n</html>\n"
    )


def normalise_notebook(nb) -> list[str]:
    """Make an executed notebook depend on its inputs only; returns the stderr texts it removed.

    Drops papermill's and nbclient's timing metadata (start and end times,
    durations, input and output paths), numbers the cells (``cell-00``, …) and
    moves text written to stderr out of the notebook (the rule logs it).
    """
    nb.metadata.pop("papermill", None)
    stderr = []
    for i, cell in enumerate(nb.cells):
        cell["id"] = f"cell-{i:02d}"
        for key in ("papermill", "execution", "collapsed", "scrolled"):
            cell.metadata.pop(key, None)
        if cell.cell_type == "code":
            kept = []
            for output in cell.get("outputs", []):
                if output.get("output_type") == "stream" and output.get("name") == "stderr":
                    stderr.append(output.get("text", ""))
                else:
                    kept.append(output)
            cell["outputs"] = kept
    return stderr


def with_contents(body: str) -> str:
    """The page body with a line of links to its sections (every ``<h2 id=…>``) after its header."""
    sections = [
        (anchor, re.sub(r"<[^>]+>|¶", "", title).strip())
        for anchor, title in re.findall(r'<h2 id="([^"]+)"[^>]*>(.*?)</h2>', body, flags=re.S)
    ]
    if not sections:
        return body
    links = " · ".join(f'<a href="#{anchor}">{title}</a>' for anchor, title in sections)
    nav = f'<nav class="contents">Contents: {links}</nav>'
    return body.replace("</header>", "</header>\n" + nav, 1) if "</header>" in body else nav + "\n" + body


def notebook_body(nb) -> str:
    """The notebook's outputs and markdown as HTML (code hidden), via nbconvert's basic template."""
    from nbconvert import HTMLExporter

    exporter = HTMLExporter(
        template_name="basic", exclude_input=True, exclude_input_prompt=True, exclude_output_prompt=True
    )
    body, _ = exporter.from_notebook_node(nb)
    return body


def build_report(notebook, html_path, executed_path, parameters: dict, cwd=".", log=None) -> None:
    """Execute the report notebook with papermill (same interpreter), write it normalised and as HTML."""
    import matplotlib.font_manager  # noqa: F401  (builds the font cache here, not in the notebook's output)
    import nbformat
    import papermill
    import zmq
    from traitlets.config import Config

    from pendulum.io import write_text

    # The kernel talks to papermill over local TCP; CurveZMQ keys provisioned by the kernel
    # manager (when the kernel declares support, as ipykernel does) encrypt that traffic and
    # spare every build the kernel's "running over TCP without encryption" warning. A libzmq
    # built without CurveZMQ would refuse the setting, so there the default (plain TCP) stays.
    encryption = "auto" if zmq.has("curve") else "disabled"
    kernel_config = Config({"KernelManager": {"transport_encryption": encryption}})
    nb = papermill.execute_notebook(
        str(notebook),
        None,
        parameters=parameters,
        kernel_name="python3",
        cwd=str(cwd),
        progress_bar=False,
        log_output=False,
        request_save_on_cell_execute=False,
        config=kernel_config,
    )
    for text in normalise_notebook(nb):
        if log:
            log.warning("notebook stderr: %s", text.strip())
    write_text(nbformat.writes(nb) + "\n", executed_path)
    title = "Free-decay pendulum: added mass and drag coefficient"
    write_text(page_html(with_contents(notebook_body(nb)), title), html_path)
