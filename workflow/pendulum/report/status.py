"""The trials' outcomes in the report: failed ones (stage, what stands, reason, log), those skipped by their
sidecars, those that succeeded but that no model variant fits, and files renamed to their trials' names."""

from __future__ import annotations

from pendulum.outcomes import misfit_trials
from pendulum.report.data import ReportData
from pendulum.report.format import as_number, esc, fmt, table_html, td


class StatusSections(ReportData):
    """The section *Failed trials* (results/status/trials.csv as a reader needs it)."""

    def failures_section(self) -> str:
        """Failed trials with the stage, what stands, the reason and the log to read; then the trials skipped by their
        sidecars, those no variant fits, and renamed files."""
        failed = self.failed_trials()
        n = len(self.trials)
        if failed.empty:
            return (
                f"<p>All {n} trial(s) succeeded at every stage (<code>results/status/trials.csv</code>).</p>"
                + self.skipped_note()
                + self.misfit_note()
                + self.renamed_note()
            )
        measured = {"ok_frames_pct", "period_s"} <= set(failed.columns)
        rows = []
        for r in failed.itertuples():
            cells = [td(esc(str(r.trial))), td(esc(str(r.stage)))]
            if measured:  # the track and angle record of a trial that failed later (its fit) stand
                cells += [
                    td(esc(fmt(as_number(r.ok_frames_pct), 4)), "num"),
                    td(esc(fmt(as_number(r.period_s), 6)), "num"),
                ]
            rows.append(cells + [td(esc(str(r.reason))), td(f"<code>{esc(str(r.log))}</code>")])
        caption = self.table_caption(
            f"{len(failed)} of {n} trial(s) failed and are left out of the fits (Tables 2 and 3 mark them failed) and "
            "the joint fits above: "
            "the stage where each failed, "
            + (
                "the share of its frames usable and its period as swung where its angle record was made, "
                if measured
                else ""
            )
            + "the reason and the log to read."
        )
        header = ["trial", "stage"] + (["usable frames (%)", "period (s)"] if measured else []) + ["reason", "log"]
        return (
            table_html(header, rows, caption=caption, table_id="failed-table")
            + self.skipped_note()
            + self.misfit_note()
            + self.renamed_note()
        )

    def skipped_note(self) -> str:
        """The trials whose sidecars say ``skip: <why>``: no job ran for them."""
        if self.status is None or self.status.empty or "status" not in self.status.columns:
            return ""
        skipped = self.status[self.status.status == "skipped"].astype(object).fillna("")
        if skipped.empty:
            return ""
        items = "".join(
            f"<li><code>{esc(str(r.trial))}</code>: {esc(str(r.reason))}</li>" for r in skipped.itertuples()
        )
        return f"<p>Skipped by their sidecars (<code>skip:</code>; nothing was run for them):</p><ul>{items}</ul>"

    def misfit_note(self) -> str:
        """The trials that succeeded but whose every variant misses the record: their coefficients may be biased."""
        wrong = misfit_trials(self.status) if self.status is not None else []
        if not wrong:
            return ""
        return (
            f"<p>{', '.join(f'<code>{esc(t)}</code>' for t in wrong)}: succeeded, but every model variant misses "
            "the record far beyond its noise (the <code>warnings</code> in <code>results/status/trials.csv</code>): "
            "what the models miss may bias the coefficients, and their intervals do not cover it. Table 2 gives "
            "each residual against the record's noise; discovery names what is missing where it can.</p>"
        )

    def renamed_note(self) -> str:
        """The files whose names are not their trials' names (spaces, brackets, accents made ``_``)."""
        renamed = []
        for trial, info in sorted(self.trials.items()):
            source = str((info or {}).get("source") or "")
            stem = source.rsplit("/", 1)[-1].rsplit(".", 1)[0]
            if source and stem != trial:
                renamed.append(f"<code>{esc(source.rsplit('/', 1)[-1])}</code> → <code>{esc(trial)}</code>")
        if not renamed:
            return ""
        return (
            "<p>Trials named after files whose names hold spaces, brackets or other signs (each run of them is "
            "<code>_</code> in a trial's name and its results' file names): " + "; ".join(renamed) + ".</p>"
        )
