"""The report's figures: measured and fitted records, consistency across releases, extinction curves.

Matplotlib figures drawn outside pyplot in one style (:data:`MPL_STYLE`) and
embedded as PNG without a software stamp, so identical inputs give identical
bytes.
"""

from __future__ import annotations

import io

import numpy as np

from pendulum.fit.uncertainty import Z95, Z95_ONE_SIDED
from pendulum.model.effects import ADDED_MASS
from pendulum.report.data import ReportData, is_ok, record_problems, true_value
from pendulum.report.format import MARKERS, PLAIN_SYMBOLS, esc, figure_html, fmt, is_finite

FIGURE_DPI = 110
PNG_COLOURS = 256  # a figure's palette (figure_png)


def figure_png(fig) -> bytes:
    """A matplotlib figure as PNG bytes of 256 colours (Pillow's fast octree: a third of the bytes of the full
    colour image, which a lab's 85 trials made 15.6 MB of a report; lines and text look the same), no software or
    date stamp: identical bytes for identical input."""
    from PIL import Image

    buffer = io.BytesIO()
    fig.savefig(buffer, format="png", dpi=FIGURE_DPI, metadata={"Software": None})
    image = Image.open(io.BytesIO(buffer.getvalue())).convert("RGB")
    out = io.BytesIO()
    image.quantize(PNG_COLOURS, method=Image.Quantize.FASTOCTREE).save(out, format="PNG")
    return out.getvalue()


def log_ticks(axis) -> None:
    """Ticks at 1, 2, 5 × 10ⁿ labelled as plain numbers (no crowded minor labels); an axis spanning less
    than a factor 3 (local C_d from 1.0 to 1.9 showed the single label "1") gets 3–5 evenly stepped ticks."""
    from matplotlib.ticker import FuncFormatter, LogLocator, MaxNLocator, NullFormatter

    class ReadableLogLocator(LogLocator):
        def tick_values(self, vmin, vmax):
            low, high = sorted((vmin, vmax))
            if low > 0 and high / low < 3.0:
                return MaxNLocator(nbins=4, steps=[1, 2, 2.5, 5, 10]).tick_values(low, high)
            return super().tick_values(vmin, vmax)

    axis.set_major_locator(ReadableLogLocator(subs=(1.0, 2.0, 5.0)))
    axis.set_major_formatter(FuncFormatter(lambda v, _: f"{v:g}"))
    axis.set_minor_formatter(NullFormatter())


EXTINCTION_LABELS = ("amplitude A at the half cycle's start (°)", "amplitude loss per half cycle ΔA (°)")


def log_axes(ax, xlabel: str, ylabel: str) -> None:
    """Both axes logarithmic with :func:`log_ticks`, and labelled."""
    ax.set_xscale("log")
    ax.set_yscale("log")
    log_ticks(ax.xaxis)
    log_ticks(ax.yaxis)
    ax.set_xlabel(xlabel)
    ax.set_ylabel(ylabel)


def trials_collapsed(handles: list, labels: list[str], n_trials: int) -> tuple[list, list[str]]:
    """A legend's entries with its first ``n_trials`` (one marker per trial) made one entry where the trials are
    more than the marker shapes (beyond, the shapes repeat and a legend of every name outgrows its figure)."""
    if n_trials <= len(MARKERS):
        return handles, labels
    every = f"measured: {n_trials} trials (open markers, the shapes repeat)"
    return [handles[0], *handles[n_trials:]], [every, *labels[n_trials:]]


def new_figure(width_in: float, height_in: float):
    """A figure outside pyplot (no global state, nothing shown twice in the notebook)."""
    from matplotlib.figure import Figure

    return Figure(figsize=(width_in, height_in), layout="constrained")


MPL_STYLE = {
    "font.size": 9,
    "axes.titlesize": 10,
    "axes.labelsize": 9,
    "legend.fontsize": 8,
    "xtick.labelsize": 8,
    "ytick.labelsize": 8,
    "axes.grid": True,
    "grid.alpha": 0.3,
    "axes.spines.top": False,
    "axes.spines.right": False,
    "svg.hashsalt": "pendulum",
    "path.simplify": False,
}


RECORDS_SHOWN = 12  # more trials' record figures than this: folded by rig


class FigureSections(ReportData):
    """Per-trial fits and residuals, coefficients against release and KC, extinction curve and local C_d."""

    def trial_figures(self) -> str:
        """Per trial: measured θ(t) with each variant's fit, and each variant's residual beneath."""
        import matplotlib

        out = []  # (rig, figure)
        for trial in self.trial_order():
            curves = {v: self.curve(v, trial) for v in self.order if is_ok(self.fits.get((v, trial)))}
            curves = {v: c for v, c in curves.items() if not c.empty}
            if not curves:
                continue
            with matplotlib.rc_context(MPL_STYLE):
                fig = new_figure(10, 3.0 + 1.05 * len(curves))
                grid = fig.add_gridspec(1 + len(curves), 1, height_ratios=[3.0] + [1.0] * len(curves))
                ax = fig.add_subplot(grid[0])
                base = next(iter(curves.values()))
                t = base.time_s.to_numpy(float)
                measured = np.degrees(base.theta_measured_rad.to_numpy(float))
                used = base.flag.isin(["fitted", "release_transient"]).to_numpy()
                # measured dots beneath the fitted curves (at 30–60 samples per second they hid them)
                ax.plot(t[used], measured[used], ".", ms=2.2, color="0.6", label="measured", zorder=2)
                bad = ~used & np.isfinite(measured)
                if bad.any():
                    ax.plot(t[bad], measured[bad], "x", ms=4, color="#C00000", label="outlier / flagged", zorder=5)
                start = self.fits[(next(iter(curves)), trial)]["trials"][trial]["fit_start_s"]
                for v, c in curves.items():
                    ax.plot(
                        c.time_s,
                        np.degrees(c.theta_fitted_rad),
                        "-",
                        lw=1.0,
                        color=self.colour[v],
                        label=f"{v} fit",
                        zorder=4,
                    )
                ax.axvspan(min(0.0, float(np.nanmin(t))), start, color="0.85", lw=0, zorder=0)
                ax.set_ylabel("θ (°)")
                ax.set_title(f"{trial}: release {self.angle_label(trial)}", loc="left")
                ax.legend(loc="upper right", ncol=len(curves) + 2, frameon=False)
                for i, (v, c) in enumerate(curves.items()):
                    rax = fig.add_subplot(grid[1 + i], sharex=ax)
                    fitted = c.flag == "fitted"
                    r = np.degrees(c.residual_rad.to_numpy(float))
                    rax.plot(c.time_s[fitted], r[fitted.to_numpy()], "-", lw=0.6, color=self.colour[v])
                    rax.axhline(0, color="0.3", lw=0.6)
                    lim = float(np.nanmax(np.abs(r[fitted.to_numpy()]))) if fitted.any() else 1.0
                    rax.set_ylim(-1.15 * lim, 1.15 * lim)
                    rms = self.fits[(v, trial)]["rms_deg"]
                    rax.text(
                        0.995,
                        0.92,
                        f"{v}: RMS {fmt(rms, 2)}°",
                        transform=rax.transAxes,
                        ha="right",
                        va="top",
                        fontsize=8,
                    )
                    rax.set_ylabel("resid. (°)")
                    if i < len(curves) - 1:
                        rax.tick_params(labelbottom=False)
                rax.set_xlabel("time since release (s)")
                ax.tick_params(labelbottom=False)
                png = figure_png(fig)
            caption = self.figure_caption(
                f"Trial <b>{esc(trial)}</b> (release {self.angle_label(trial)}, KC "
                f"{fmt(self.kc(next(iter(curves)), trial), 2)}). Top: measured angle (dots) and each variant's fitted "
                "θ(t); grey band: release transient, not fitted. Below: residual (fitted − measured) of each "
                "variant on its own scale — structure that repeats with the swing is physics the variant misses."
            )
            alt = f"measured and fitted angle of {trial}"
            out.append((self.trials[trial]["rig"], figure_html(png, caption, alt=alt)))
        if len(out) <= RECORDS_SHOWN:
            return "".join(html for _, html in out) or "<p>No fitted curves to show.</p>"
        # many trials (a lab's hundred: 33,000 px of figures): each rig's folded, its count and rig named
        rigs = list(dict.fromkeys(rig for rig, _ in out))
        return f"<p>{len(out)} trials' records, folded by rig: open one to see them.</p>" + "".join(
            f"<details><summary>Rig <b>{esc(rig)}</b>: the records of {sum(r == rig for r, _ in out)} trials"
            f"</summary>{''.join(html for r, html in out if r == rig)}</details>"
            for rig in rigs
        )

    def consistency_figure(self) -> str:
        """Each coefficient against release angle and against KC, per variant, joint fit as a band."""
        import matplotlib

        names = [
            n
            for n in (ADDED_MASS, "drag_coefficient", "linear_damping_nm_s", "friction_torque_nm")
            if any(self._has(v, n) for v in self.order)
        ]
        out = []
        for rig in self.rig_names:
            trials = [t for t in self.rig_trials(rig) if any(is_ok(self.fits.get((v, t))) for v in self.order)]
            if len(trials) < 2:
                out.append(f"<p>Rig {esc(rig)}: {len(trials)} fitted trial(s), nothing to compare across releases.</p>")
                continue
            with matplotlib.rc_context(MPL_STYLE):
                fig = new_figure(10, 2.3 * len(names) + 0.5)
                axes = fig.subplots(len(names), 2, squeeze=False, sharex="col")
                for row, name in enumerate(names):
                    for col, xkind in enumerate(("release", "kc")):
                        ax = axes[row][col]
                        variants = [v for v in self.order if self._has(v, name)]
                        for k, v in enumerate(variants):
                            xs, ys, lo, hi, hollow = [], [], [], [], []
                            for t in trials:
                                fit = self.fits.get((v, t))
                                if not is_ok(fit) or name not in fit["parameters"] or record_problems(fit):
                                    continue  # failed, or a fit on an unreliable record: not a measurement
                                e = fit["parameters"][name]
                                x = self.release_deg(t) if xkind == "release" else self.kc(v, t)
                                if x is None:
                                    continue
                                offset = k - (len(variants) - 1) / 2
                                xs.append(x + 1.2 * offset if xkind == "release" else x * 1.03**offset)
                                # at the bound: the one-sided 95 % limit, as Table 3 gives it (statistical here)
                                z = Z95_ONE_SIDED if e.get("at_bound") else Z95
                                half = z * float(e.get("stderr_statistical") or 0.0)
                                ys.append(e["value"])
                                lo.append(half if not e.get("at_bound") else 0.0)
                                hi.append(half)
                                hollow.append(bool(e.get("at_bound")))
                            if not xs:
                                continue
                            xs, ys, lo, hi, hollow = map(np.asarray, (xs, ys, lo, hi, hollow))
                            colour = self.colour[v]
                            ax.errorbar(xs, ys, yerr=[lo, hi], fmt="none", ecolor=colour, elinewidth=1, capsize=2)
                            ax.scatter(
                                xs[~hollow], ys[~hollow], marker=self.marker[v], s=22, color=colour, label=v, zorder=3
                            )
                            if hollow.any():
                                ax.scatter(
                                    xs[hollow],
                                    ys[hollow],
                                    marker=self.marker[v],
                                    s=22,
                                    facecolor="white",
                                    edgecolor=colour,
                                    zorder=3,
                                    label=f"{v} (at bound)",
                                )
                            joint = self.joint.get((v, rig))
                            if is_ok(joint) and name in joint["parameters"]:
                                je = joint["parameters"][name]
                                scale = max(1.0, float(je.get("scale_factor") or 1.0))
                                half = 1.96 * scale * float(je.get("stderr_statistical") or 0.0)
                                bound = je.get("lower_bound")
                                low = je["value"] - half
                                low = max(low, float(bound)) if is_finite(bound) else low
                                ax.axhspan(low, je["value"] + half, color=colour, alpha=0.18, lw=0)
                                ax.axhline(je["value"], color=colour, lw=0.8, alpha=0.9)
                        truth = {true_value(self.truth.get(t), name) for t in trials if t in self.truth} - {None}
                        if len(truth) == 1:
                            ax.axhline(truth.pop(), color="black", ls="--", lw=1, label="truth")
                        if xkind == "kc":
                            ax.set_xscale("log")
                            log_ticks(ax.xaxis)
                        if row == 0:
                            ax.set_title(
                                "against release angle" if xkind == "release" else "against Keulegan–Carpenter number",
                                loc="left",
                            )
                        if row == len(names) - 1:
                            ax.set_xlabel(
                                "release angle (°)"
                                if xkind == "release"
                                else "KC of the first fitted swing (as the record shows it)"
                            )
                        if col == 0:
                            ax.set_ylabel(PLAIN_SYMBOLS[name])
                handles = {}
                for ax in axes.flat:
                    for h, label in zip(*ax.get_legend_handles_labels(), strict=True):
                        handles.setdefault(label, h)
                fig.legend(
                    handles.values(),
                    handles.keys(),
                    loc="outside upper center",
                    ncol=min(len(handles), 7),
                    frameon=False,
                )
                png = figure_png(fig)
            unreliable = sorted({t for t in trials for v in self.order if record_problems(self.fits.get((v, t)))})
            caption = self.figure_caption(
                f"Consistency across the trials of rig {esc(rig)}: each coefficient of each trial's fit against the "
                "release angle (left) and the Keulegan–Carpenter number (right), per variant (markers slightly "
                "offset sideways). Error bars: 95 % statistical intervals — what the consistency test compares; the "
                "rig values' systematic error moves all trials together and is left out here (it is in Table 3). "
                "Line and band: each variant's joint fit with its statistical 95 % interval widened by the scale "
                "factor S. Hollow markers: at the lower bound, the bar its one-sided 95 % statistical limit"
                + ("; dashed: truth." if self.truth else ".")
                + (
                    f" Not plotted: the fits of {esc(', '.join(unreliable))} (unreliable records, Table 3)."
                    if unreliable
                    else ""
                )
                + " A model that captures the physics gives the same value at every release."
            )
            out.append(figure_html(png, caption, alt=f"coefficients against release angle and KC, rig {rig}"))
        return "".join(out) or "<p>No per-trial fits to compare.</p>"

    def extinction_figure(self) -> str:
        """Amplitude loss per half cycle against amplitude (each variant's prediction) and local C_d against KC."""
        import matplotlib

        out = []
        for rig in self.rig_names:
            variant = self.recommended(rig)
            trials = [t for t in self.rig_trials(rig) if variant and is_ok(self.fits.get((variant, t)))]
            if not trials:
                continue
            with matplotlib.rc_context(MPL_STYLE):
                fig = new_figure(10, 4.2)
                ax, bx = fig.subplots(1, 2)
                grey = ("0.1", "0.35", "0.55", "0.7", "0.45")
                not_drawn = shown = measured = 0  # half cycles with no measured loss: off a log axis
                for i, t in enumerate(trials):
                    c = self.cycles(variant, t)
                    if c.empty:
                        continue
                    measured += 1
                    not_drawn += int((c.amplitude_loss_rad <= 0).sum())
                    shown += len(c)
                    ax.plot(
                        c.amplitude_deg,
                        np.degrees(c.amplitude_loss_rad),
                        self.trial_marker[t],
                        ms=4,
                        mfc="none",
                        mec=grey[i % len(grey)],
                        label=f"{t} (measured)",
                    )
                    bx.plot(
                        c.keulegan_carpenter_number,
                        c.local_drag_coefficient,
                        self.trial_marker[t],
                        ms=4,
                        mfc="none",
                        mec=grey[i % len(grey)],
                        label=t,
                    )
                for v in self.order:
                    first = True
                    for t in trials:
                        if not is_ok(self.fits.get((v, t))):
                            continue
                        c = self.cycles(v, t)
                        if c.empty or "predicted_amplitude_loss_rad" not in c:
                            continue
                        c = c.sort_values("amplitude_deg")
                        ax.plot(
                            c.amplitude_deg,
                            np.degrees(c.predicted_amplitude_loss_rad),
                            "-",
                            lw=1.1,
                            color=self.colour[v],
                            alpha=0.85,
                            label=f"{v} prediction" if first else None,
                        )
                        first = False
                log_axes(ax, *EXTINCTION_LABELS)
                ax.set_title("extinction curve", loc="left")
                ax.legend(*trials_collapsed(*ax.get_legend_handles_labels(), measured), frameon=False, fontsize=7)
                joint = self.joint.get((variant, rig), {})
                cd = joint.get("parameters", {}).get("drag_coefficient") if is_ok(joint) else None
                if cd:
                    bx.axhspan(cd["ci95"][0], cd["ci95"][1], color=self.colour[variant], alpha=0.15, lw=0)
                    bx.axhline(cd["value"], color=self.colour[variant], lw=1, label=f"{variant} joint $C_d$")
                truth = {true_value(self.truth.get(t), "drag_coefficient") for t in trials if t in self.truth} - {None}
                if len(truth) == 1:
                    bx.axhline(truth.pop(), color="black", ls="--", lw=1, label="truth")
                log_axes(bx, "Keulegan–Carpenter number of the half cycle", "local $C_d$ (all loss charged to drag)")
                bx.set_title("local drag coefficient", loc="left")
                bx.legend(*trials_collapsed(*bx.get_legend_handles_labels(), measured), frameon=False, fontsize=7)
                png = figure_png(fig)
            caption = self.figure_caption(
                f"Rig {esc(rig)}. Left: the extinction curve — loss of amplitude over each half cycle against the "
                "amplitude at its start, measured (open markers, one per trial; amplitudes about the record's own "
                "swing centre) and as each variant's fitted curve predicts it"
                + (
                    f" ({not_drawn} of {shown} measured half cycles lost no amplitude, within noise, and are off these "
                    "log axes)"
                    if not_drawn
                    else ""
                )
                + ". On these log axes Coulomb friction "
                "gives a constant loss, linear damping a slope 1 and quadratic drag a slope 2: a variant that lacks a "
                "term misses one end of the curve. Right: the local drag coefficient of each half cycle, charging all "
                "of its loss to quadratic drag, against its KC number (its speed from the energy at the half "
                "cycle's mean amplitude and the variant's fitted inertia)"
                + (f"; band: the {esc(variant)} joint C<sub>d</sub> (95 %)" if cd else "")
                + ". Where the local value climbs at small KC, the loss there is not quadratic drag. Half cycles run "
                "from one turning point of the fitted record to the next: the release swing, before the first "
                "turning point, is not among them, so the largest KC of the coefficients table (the first fitted "
                "swing's, measured on the record) lies beyond the right-hand panel: a wide release's KC describes "
                "its first swing, and every later half cycle runs at a smaller one."
            )
            out.append(figure_html(png, caption, alt=f"extinction curve and local drag coefficient, rig {rig}"))
        return "".join(out) or "<p>No half-cycle tables to show.</p>"
