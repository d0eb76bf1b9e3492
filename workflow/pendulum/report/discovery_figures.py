"""The discovery section's figures: residuals per model on the path, the extinction curve, the autocorrelation.

Drawn from the rule ``discovery``'s tables (``<group>.residuals.csv``: ``model``, ``trial``,
``time_s``, ``residual_rad``; ``<group>.extinction.csv``: ``model`` (``measured`` or a model),
``trial``, ``amplitude_rad``, ``mean_amplitude_rad``, ``amplitude_loss_rad``) in the report's figure
style; a model is its terms joined by ``+``.
"""

from __future__ import annotations

import math

import numpy as np
import pandas as pd

from pendulum.model.effects import TERMS
from pendulum.report.figures import EXTINCTION_LABELS, MPL_STYLE, figure_png, log_axes, new_figure, trials_collapsed
from pendulum.report.format import MARKERS, PALETTE, esc, figure_html, fmt

TRIAL_COLOURS = tuple(c for c in PALETTE if c != "#F0E442")  # yellow lines vanish on white


def model_key(terms) -> str:
    return "+".join(terms)


def trial_legend(fig, handles: list, labels: list[str], n_trials: int, fontsize: float | None = None) -> None:
    """The trials' legend above the figure, in as many columns as fit its width; with more trials than colours
    (their lines repeat the colours) a line saying so instead of a legend that cannot tell them apart."""
    if n_trials > len(TRIAL_COLOURS):  # one entry for them all, then what follows the trials (a noise band)
        from matplotlib.lines import Line2D

        every = Line2D([], [], color="0.45", lw=0.8)
        handles = [every, *handles[n_trials:]]
        labels = [f"one line per trial ({n_trials} trials; the colours repeat)", *labels[n_trials:]]
    width_pt = fig.get_figwidth() * 72
    entry_pt = 30 + 5.5 * max(len(label) for label in labels)  # handle, gap and the label at the legend's size
    ncol = max(1, min(len(labels), int(width_pt // entry_pt), 8))
    fig.legend(handles, labels, loc="outside upper center", ncol=ncol, frameon=False, fontsize=fontsize)


def model_label(document: dict, key: str) -> str:
    """A model of the residual and extinction tables in words: ``baseline: …``, or ``baseline + …`` (final)."""
    base = document["baseline"]["terms"]
    added = [TERMS[t].label if t in TERMS else t for t in key.split("+") if t and t not in base]
    if not added:
        return "baseline: " + (", ".join(TERMS[t].label for t in base) or "added mass only")
    final = " (final)" if key == model_key(document["final_terms"]) else ""
    return "baseline + " + " + ".join(added) + final


def residual_figure(document: dict, residuals: pd.DataFrame) -> bytes | None:
    """One panel per model on the path (baseline, after each step, final): residual against time, per trial."""
    import matplotlib

    if residuals.empty:
        return None
    models, trials = list(pd.unique(residuals.model)), list(pd.unique(residuals.trial))
    steps = {s["model_after"]: (k, s["effect"]) for k, s in enumerate(document["steps"], 1) if "model_after" in s}
    with matplotlib.rc_context(MPL_STYLE):
        fig = new_figure(10, 0.5 + 1.6 * len(models))
        axes = fig.subplots(len(models), 1, sharex=True, squeeze=False)[:, 0]
        for ax, model in zip(axes, models, strict=True):
            rows = residuals[residuals.model == model]
            for i, trial in enumerate(trials):
                r = rows[rows.trial == trial]
                colour = TRIAL_COLOURS[i % len(TRIAL_COLOURS)]
                ax.plot(r.time_s, np.degrees(r.residual_rad), "-", lw=0.7, color=colour, label=trial)
            ax.axhline(0, color="0.3", lw=0.6)
            rms = math.degrees(float(np.sqrt(np.mean(rows.residual_rad.to_numpy(float) ** 2))))
            k, effect = steps.get(model, (None, None))
            title = f"after step {k}: + {TERMS[effect].label}" if k else model_label(document, model)
            ax.set_title(f"{title} — RMS {fmt(rms, 2)}°", loc="left")
            ax.set_ylabel("residual (°)")
        axes[-1].set_xlabel("time since release (s)")
        trial_legend(fig, *axes[0].get_legend_handles_labels(), len(trials))
        return figure_png(fig)


def _off_axes(extinction: pd.DataFrame) -> str:
    """The caption's note of the measured half cycles a log axis cannot show (no loss within noise), or ''."""
    if extinction.empty or "model" not in extinction:
        return ""
    measured = extinction[extinction.model == "measured"]
    off = int((measured.amplitude_loss_rad <= 0).sum())
    if not off:
        return ""
    return f" {off} of {len(measured)} measured half cycles lost no amplitude, within noise: off the log axes."


OVERLAP = 0.05  # two models' predicted losses within this share of each other: their lines overlap on log axes


def _overlapping(document: dict, extinction: pd.DataFrame) -> str:
    """The caption's note of models whose predicted losses lie within :data:`OVERLAP` of each other in every half
    cycle of every trial (one line hides the other), or ''."""
    if extinction.empty or "model" not in extinction:
        return ""
    table = extinction[(extinction.model != "measured") & (extinction.amplitude_loss_rad > 0)]
    curves = {
        model: rows.sort_values(["trial", "amplitude_rad"]).reset_index(drop=True)
        for model, rows in table.groupby("model", sort=False)
    }
    models = list(curves)
    pairs = []
    for i, a in enumerate(models):
        for b in models[i + 1 :]:
            ca, cb = curves[a], curves[b]
            if len(ca) != len(cb) or not ca.trial.equals(cb.trial) or ca.empty:
                continue
            apart = float(np.max(np.abs(np.log(ca.amplitude_loss_rad / cb.amplitude_loss_rad))))
            if apart <= math.log1p(OVERLAP):
                label_a, label_b = esc(model_label(document, a)), esc(model_label(document, b))
                pct = 100 * math.expm1(apart)  # under 0.05 %: not "at most 0.0 % apart" (a new user's report)
                within = f"at most {pct:.1f} % apart" if pct >= 0.05 else "under 0.05 % apart"
                pairs.append(f"{label_a} and {label_b} ({within})")
    if not pairs:
        return ""
    return (
        f" Lines that lie over each other (predictions within {100 * OVERLAP:.0f} % in every half cycle): "
        + "; ".join(pairs)
        + "."
    )


def extinction_figure(document: dict, extinction: pd.DataFrame, markers: dict | None = None) -> bytes | None:
    """Amplitude loss per half cycle against amplitude: measured points (``markers``: trial → shape), and each
    model's prediction."""
    import matplotlib

    if extinction.empty:
        return None
    table = extinction[(extinction.amplitude_rad > 0) & (extinction.amplitude_loss_rad > 0)]
    if table.empty:
        return None
    final = model_key(document["final_terms"])
    with matplotlib.rc_context(MPL_STYLE):
        fig = new_figure(10, 4.4)
        ax = fig.subplots()
        measured = table[table.model == "measured"]
        for i, trial in enumerate(pd.unique(measured.trial)):
            m = measured[measured.trial == trial]
            ax.plot(
                np.degrees(m.amplitude_rad),
                np.degrees(m.amplitude_loss_rad),
                (markers or {}).get(trial, MARKERS[i % len(MARKERS)]),
                ms=4.5,
                mfc="none",
                mec="0.35",
                label=f"{trial} (measured)",
            )
        models = [m for m in pd.unique(table.model) if m != "measured"]
        colours = iter(TRIAL_COLOURS)
        for model in models:
            style = {"color": "black", "lw": 1.8} if model == final else {"color": next(colours, "0.5"), "lw": 1.0}
            for j, (_, c) in enumerate(table[table.model == model].groupby("trial", sort=False)):
                c = c.sort_values("amplitude_rad")
                ax.plot(
                    np.degrees(c.amplitude_rad),
                    np.degrees(c.amplitude_loss_rad),
                    "-",
                    alpha=0.85,
                    label=model_label(document, model) if j == 0 else None,
                    **style,
                )
        log_axes(ax, *EXTINCTION_LABELS)
        n_measured = measured.trial.nunique()
        ax.legend(
            *trials_collapsed(*ax.get_legend_handles_labels(), n_measured), frameon=False, fontsize=7, loc="lower right"
        )
        return figure_png(fig)


def autocorrelation_figure(document: dict, residuals: pd.DataFrame, max_lag_s: float = 10.0) -> bytes | None:
    """The final model's residual autocorrelation per trial, with the ±1.96/√n band of white noise."""
    import matplotlib

    rows = residuals[residuals.model == model_key(document["final_terms"])]
    if rows.empty:
        return None
    with matplotlib.rc_context(MPL_STYLE):
        fig = new_figure(10, 3.0)
        ax = fig.subplots()
        n_min = None
        for i, (trial, r) in enumerate(rows.groupby("trial", sort=False)):
            x = r.residual_rad.to_numpy(float) - r.residual_rad.mean()
            dt = float(np.median(np.diff(r.time_s))) if len(r) > 1 else 1.0
            lags = np.arange(min(len(x) // 2, int(max_lag_s / dt)))
            acf = np.array([np.dot(x[: len(x) - k], x[k:]) for k in lags]) / np.dot(x, x)
            ax.plot(lags * dt, acf, "-", lw=0.8, color=TRIAL_COLOURS[i % len(TRIAL_COLOURS)], label=trial)
            n_min = len(x) if n_min is None else min(n_min, len(x))
        band = 1.96 / math.sqrt(n_min)
        ax.axhspan(-band, band, color="0.8", lw=0, label="white noise (95 %)")
        ax.set_xlabel("lag (s)")
        ax.set_ylabel("autocorrelation")
        trial_legend(fig, *ax.get_legend_handles_labels(), rows.trial.nunique(), fontsize=7)
        return figure_png(fig)


def figures_html(
    document: dict, residuals: pd.DataFrame, extinction: pd.DataFrame, caption, markers: dict | None = None
) -> str:
    """The residual and extinction figures and, when structure is left unexplained, the autocorrelation
    (``markers``: trial → the shape the report's other figures give it)."""
    group = esc(document.get("group", ""))
    n_trials = residuals.trial.nunique() if "trial" in residuals else 0
    colours = "each trial a colour" if n_trials <= len(TRIAL_COLOURS) else f"{n_trials} trials, the colours repeating"
    figures = [
        (
            residual_figure(document, residuals),
            f"Group {group}: residual (model − measured) of the baseline and of the model after each step, one "
            f"panel per model on its own scale, {colours}. Structure that repeats with the swing is physics "
            "the model misses; what is left at the end should be the tracking noise.",
            "residuals",
        ),
        (
            extinction_figure(document, extinction, markers),
            f"Group {group}: extinction curve, the amplitude lost over each half cycle against the amplitude at its "
            "start: measured (open markers, one shape per trial) and as each model's fitted curve predicts it (the "
            "baseline, the baseline with each first-round candidate and the models on the path; black: the final "
            "model). On log axes Coulomb friction gives a constant loss, linear damping and the history force a "
            "slope 1, quadratic drag a slope 2." + _off_axes(extinction) + _overlapping(document, extinction),
            "extinction curve",
        ),
    ]
    if document["unexplained"]:
        figures.append(
            (
                autocorrelation_figure(document, residuals),
                f"Group {group}: autocorrelation of the final model's residual per trial against lag; grey band: "
                "where white noise would stay (95 %). Correlation far outside it is the structure that no candidate "
                "removes.",
                "residual autocorrelation",
            )
        )
    return "".join(
        figure_html(png, caption(text), alt=f"discovery {what}, group {group}") for png, text, what in figures if png
    )
