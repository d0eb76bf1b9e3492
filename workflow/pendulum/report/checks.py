"""The sections a reader checks the results by: header, tracking quality, provenance (the truth: truth.py)."""

from __future__ import annotations

import re
from pathlib import Path

from pendulum.outcomes import MISFIT_MARK, misfit_trials, usable_percent
from pendulum.report.data import ReportData, failure_text, is_ok, problem_text, record_problems
from pendulum.report.format import (
    as_number,
    decimals_for,
    esc,
    fmt,
    fmt_at,
    garbage_badge,
    is_finite,
    photo_data_uri,
    table_html,
    td,
    with_minus_sign,
)
from pendulum.tracking.timing_notes import slip_sentence

# One note a line; the table within the page, its column 1400 px wide (in a 1120 px column a minimum of 14em cut the
# notes mid-word and 10em made each real clip's row 1,000 px tall: two reviewers, 2026-12-02).
NOTES_STYLE = "max-width:30em;min-width:20em;overflow-wrap:anywhere"
# Frames-stage warnings that :func:`frame_notes` says in its own words (video.probe's sentences).
_NOTED = ("trimmed clip", "variable frame rate", "rotate the picture")


NEUTRAL = "\x00"  # marks a note that states a fact (the method used, a release by hand), not a warning


def _note(html: str) -> str:
    """One note of the tracking table, set apart from the next; a fact (``NEUTRAL`` first) in the page's muted ink,
    not the warnings' colour."""
    if html.startswith(NEUTRAL):
        return f'<div style="margin:0 0 0.5em;color:var(--muted)">{html[1:]}</div>'
    return f'<div style="margin:0 0 0.5em">{html}</div>'


def in_front_text(box_px) -> str:
    """The note on something static in front of the swing (the tracks JSON's ``body.in_front.box_px``)."""
    x, y, w, h = box_px
    return (
        f"something in front of the swing hides part of the body at x {x}–{x + w - 1}, y {y}–{y + h - 1} px (a post, "
        "a strut, a clamp): the frames in which the body reaches it are flagged occluded"
    )


def marker_text(tracks: dict) -> str:
    """The marker the tracker followed (tracks JSON ``marker``): polarity and radius, and whether detection found
    them (``detection`` present: config and sidecar left polarity or radius to it) or they were given; a body's,
    and the ``start_px`` the user pointed at one of two pendulums with."""
    method = tracks.get("method") or {}
    if method.get("used") == "body":
        body = tracks.get("body") or {}
        radius = body.get("radius_px")
        size = f", r {radius:.1f} px" if isinstance(radius, (int, float)) else ""
        how = " by colour" if body.get("view") == "colour" else ""
        start = (tracks.get("settings") or {}).get("start_px")
        at = f", at start_px ({start[0]:g}, {start[1]:g})" if isinstance(start, list) and len(start) == 2 else ""
        return f"body{how}{size}, " + ("given" if "given in the settings" in method.get("reason", "") else "auto") + at
    marker = tracks.get("marker") or {}
    if not marker:
        return "—"
    radius = marker.get("marker_radius_px")
    size = f", r {radius:.1f} px" if isinstance(radius, (int, float)) else ""
    if marker.get("view") == "colour":  # the colour view's polarity is its own, and start_px the user's
        return f"dot by colour{size}, at start_px"
    return f"{marker.get('polarity', '?')}{size}, " + ("detected" if tracks.get("detection") else "given")


def frame_notes(frames: dict) -> list[str]:
    """What is notable about a video's frames (the frames stage's summary.json), as short notes; [] if clean.

    A trimmed clip's discarded packets, a variable frame rate, rotation metadata (frames used as stored),
    a bit depth above 8, dropped frames and duplicate time stamps; then every other warning of the
    stage (truncated or damaged file, stated rate unlike the frames'), without its path prefix.
    """
    notes = []
    if frames.get("discarded_packets"):
        notes.append(f"trimmed clip: {frames['discarded_packets']} packet(s) before the first shown frame discarded")
    if frames.get("variable_frame_rate"):
        interval = frames.get("frame_interval_s")
        details = [f"{frames['irregular_intervals']} irregular intervals"] if frames.get("irregular_intervals") else []
        details += [f"median {fmt(1e3 * interval, 3)} ms"] if is_finite(interval) else []
        notes.append("variable frame rate" + (f" ({', '.join(details)})" if details else ""))
    if is_finite(frames.get("rotation_deg")) and float(frames["rotation_deg"]) % 360:
        notes.append(f"rotation metadata {float(frames['rotation_deg']):g}°: frames used as stored")
    if is_finite(frames.get("bit_depth")) and int(frames["bit_depth"]) > 8:
        pixel_format = f" ({frames['pixel_format']})" if frames.get("pixel_format") else ""
        notes.append(f"{int(frames['bit_depth'])}-bit{pixel_format}")
    for key, text in (("dropped_frames", "dropped frame(s)"), ("duplicate_timestamps", "duplicate time stamp(s)")):
        if frames.get(key):
            notes.append(f"{frames[key]} {text}")
    prefix = f"{frames.get('video')}: "
    for warning in frames.get("warnings") or []:
        if not any(k in warning for k in _NOTED):
            notes.append(warning.removeprefix(prefix))
    return notes


def method_note(method: dict, body: dict) -> str:
    """The tracking table's note for a body tracked without a marker: how, in how many frames, and what the
    marker gave (the method's full reason is the note's tooltip and in the tracks JSON)."""
    tried = method.get("tried") or {}
    if not tried:  # forced, or a track from before ``tried`` existed
        return f"tracked the body: {method.get('reason', '')}"
    colour = body.get("view") == "colour"
    look = body.get("by") == "look"  # its own picture aligned in every frame (tracking.look)
    usable = tried.get("body_by_look" if look else "body_by_colour" if colour else "body", "")
    # the shares each method gave when one was chosen (before the frames the phone lost or repeated were found:
    # the flags column has the record's final count)
    how = "look (its picture aligned in every frame)" if look else "colour" if colour else "silhouette"
    note = f"tracked the body itself by its {how}, {usable} when the method was chosen"
    if look:
        silhouette = tried.get("body", "")
        rotation = (body.get("look") or {}).get("rotation") or {}
        note += "; its silhouette " + (
            "had no scene to be measured against where the body hides it"
            if silhouette.startswith("failed")
            else f"{silhouette}, measured against a scene filled in behind its path"
        )
        if "slope" in rotation:
            note += f"; its turn {rotation['slope']:+.3f}× the arm's (rigid: −1)"
    if colour:
        brightness = tried.get("body", "")
        note += "; its brightness silhouette " + (
            "could not be followed" if brightness.startswith("failed") else f"{brightness}, changing with the wall"
        )
    if not colour and not look and body.get("wall_gain") is not None:  # scaled before a darker band (wall_gain)
        note += (
            f"; measured against the wall behind each part of it (a darker band behind part of the swing: the "
            f"body's contrast there scaled up by as much as {1 / body['wall_gain']:.1f}×)"
        )
    marker = tried.get("marker", "")
    if marker:
        note += "; a marker disk " + ("could not be found" if marker.startswith("failed") else marker.split(":")[0])
    centre = body.get("centre") or {}
    if centre.get("by") == "outline":  # a ball seen in part, turning on its string (tracking.outline)
        note += (
            f"; measured by the centre of its round outline ({fmt(centre.get('outline_radius_px'), 3)} px in radius): "
            "only part of the ball stands out, and that part's centroid moves as it turns"
        )
        if (body.get("outline_view") or {}).get("used") == "brightness":
            note += " (its outline in the brightness view: the luma's limb is sharper than the chroma's)"
    return note


def dot_colour_note(method: dict) -> str:
    """The tracking table's note for a marker dot tracked by its colour (the method's full reason is its tooltip)."""
    tried = method.get("tried") or {}
    brightness = tried.get("marker", "")
    return f"tracked the dot at start_px by its colour, {tried.get('marker_by_colour', '')}; by its brightness " + (
        "it could not be followed" if brightness.startswith("failed") else brightness.split(":")[0]
    )


def period_text(angles: dict) -> str:
    """The angle record's mean period over ± its standard error (two figures of it: 2.07824, ± 0.00025) as HTML;
    "—" where the record has none."""
    period, stderr = angles.get("period_s"), angles.get("period_stderr_s")
    if not is_finite(period):
        return "—"
    if not is_finite(stderr) or stderr <= 0:
        return fmt(period, 5)
    places = decimals_for(stderr)  # two lines, as Table 3's intervals: the table keeps to the page
    return f'<span class="v">{fmt_at(period, places)}</span><span class="q">± {fmt_at(stderr, places)}</span>'


def changes_text(dirty: bool | None, files: list | None, shown: int = 5) -> str:
    """The provenance table's 'uncommitted changes': no, unknown, or yes with the files that differ."""
    if dirty is None:
        return "unknown"
    if not dirty:
        return "no"
    if not files:
        return "yes"
    more = f" and {len(files) - shown} more" if len(files) > shown else ""
    return "yes: " + ", ".join(files[:shown]) + more


def failure_cell(document: dict | None, said: set[str], span: int = 1) -> str:
    """A failed stage's cell in a trial's row: its failure sentence, or "—" when the row says it already
    (a later stage that failed because an earlier one did carries the same sentence); adds it to ``said``."""
    text = failure_text(document)
    if text in said:
        return td("—", "na", span=span)
    said.add(text)
    return td(esc(text), "na fail", span=span)


CALIBRATION_MODELS = ("rational", "fisheye")  # the lens models view.calibrate_lens compares


def calibration_rows(calibration: dict) -> list[list[str]]:
    """One row per camera setup (``results/calibration/<setup>.json``): lens model chosen, held-out reprojection
    RMS of each model (px), focal length (px), plane board and its tilt (°), views used (held out)."""
    rows = []
    for setup, doc in sorted(calibration.items()):
        if not is_ok(doc):
            rows.append([td(esc(setup)), td(esc(failure_text(doc)), "na fail", span=7)])
            continue
        models = doc.get("models") or {}
        held_out = [
            td(esc(fmt((models.get(m) or {}).get("held_out_rms_px"), 3)), "num" if m in models else "na")
            for m in CALIBRATION_MODELS
        ]
        focal = doc.get("focal_length_px")
        views, held = doc.get("views"), doc.get("held_out_views")
        plane = doc.get("plane")
        rows.append(
            [
                td(esc(setup)),
                td(esc(doc.get("chosen_model") or "none (ideal lens)")),
                *held_out,
                td(esc(", ".join(fmt(f, 4) for f in focal)) if focal else "—", "num" if focal else "na"),
                td(esc(plane_words(plane)) if plane else "no", "num"),
                td(
                    (f"{len(views)}" + (f" ({len(held)} held out)" if held else "")) if views else "—",
                    "num" if views else "na",
                ),
                coverage_cell(doc),
            ]
        )
    return rows


def plane_words(plane: dict) -> str:
    """The plane board's tilt, and whether a square-on board's corner noise alone reads as much."""
    tilt, noise = plane.get("plane_tilt_deg"), plane.get("square_on_tilt_deg")
    if not is_finite(noise):  # a calibration from before the noise was measured
        return f"yes, tilt {fmt(tilt, 2)}°"
    if is_finite(tilt) and float(tilt) <= float(noise):
        return f"yes, square-on (tilt {fmt(tilt, 2)}°: a square-on board's corner noise reads up to {fmt(noise, 2)}°)"
    return f"yes, tilt {fmt(tilt, 2)}° (a square-on board's corner noise reads up to {fmt(noise, 2)}°)"


def coverage_cell(doc: dict) -> str:
    """The share of the frame the lens clip's board reached, with the calibration's warnings (red where any)."""
    share = (doc.get("board_coverage") or {}).get("share")
    warnings = doc.get("warnings") or []
    if share is None and not warnings:
        return td("—", "na")
    text = (f"{100 * share:.0f} %" if share is not None else "") + "".join(f"; {w}" for w in warnings)
    return td(esc(text.removeprefix("; ")), "num fail" if warnings else "num")


MANY_TRIALS = 3  # more trials than this: the summary says their like findings together


def misfits_together(warnings: list[str]) -> list[str]:
    """``warnings`` with more than :data:`MANY_TRIALS` trials' misfit warnings (``trial X: residual RMS a° is n×
    the record's noise …``) said in one: the trials, their ranges, what it means."""
    pattern = re.compile(r"^trial (\S+): residual RMS ([0-9.]+)° is ([0-9.]+)× the record's noise")
    found = [(w, m) for w in warnings if (m := pattern.match(w)) and MISFIT_MARK in w]
    if len(found) <= MANY_TRIALS:
        return warnings
    rms = sorted(float(m.group(2)) for _, m in found)
    ratios = sorted(float(m.group(3)) for _, m in found)
    together = (
        f"{len(found)} trials' residuals ({', '.join(m.group(1) for _, m in found)}) are {rms[0]:g}–{rms[-1]:g}° RMS, "
        f"{ratios[0]:g}–{ratios[-1]:g}× their records' noise, and smooth: the model {MISFIT_MARK}; its coefficients "
        "absorb it and their intervals do not cover that error"
    )
    first = warnings.index(found[0][0])
    rest = [w for w in warnings if w not in {w for w, _ in found}]
    return rest[:first] + [together] + rest[first:]


class CheckSections(ReportData):
    """What was built from which code, the synthetic truth, tracking quality, failures and provenance."""

    def header(self) -> str:
        p = self.provenance
        commit = p.get("commit")
        built = (
            f"Code: commit <code>{esc(commit[:12])}</code> of {esc(str(p.get('commit_time_utc')))}"
            + (' <span class="warn">with uncommitted changes</span>' if p.get("dirty") else "")
            if commit
            else 'Code: <span class="warn">version not recorded (not built from a git commit)</span>'
        )
        failed = self.failed_trials()
        n_failed = len(failed)
        n_recorded = sum(is_finite(as_number(v)) for v in (failed["period_s"] if "period_s" in failed else []))
        n_garbage = sum(bool(self.trial_problems(t)) for t in self.trials)
        status = self.status if self.status is not None and "status" in self.status else None
        n_skipped = int((status.status == "skipped").sum()) if status is not None else 0
        n_misfit = len(misfit_trials(status)) if status is not None else 0
        return (
            "<header><h1>Free-decay pendulum: added mass and drag coefficient</h1>"
            f'<p class="subtitle">{len(self.trials)} trial(s) on {len(self.rig_names)} rig(s), '
            f"{len(self.variants)} model variant(s) fitted side by side"
            + (f', <span class="warn">{n_failed} trial(s) failed</span>' if n_failed else "")
            + (f" ({n_recorded} of them after their angle records were made)" if n_recorded else "")
            + (f', <span class="warn">{n_misfit} trial(s) that no variant fits</span>' if n_misfit else "")
            + (f", {n_skipped} skipped by their sidecars" if n_skipped else "")
            + (
                f', <span class="warn">{n_garbage} trial(s) on unreliable records</span> {garbage_badge()}'
                if n_garbage
                else ""
            )
            + f". {built}.</p>"
            '<p class="subtitle">Equation of motion: (I<sub>p</sub> + m<sub>a</sub>L²) θ̈ = −(mg − B) L sin θ '
            "− ½ρC<sub>d</sub>AL³ θ̇|θ̇| − c θ̇ − τ<sub>f</sub> sgn θ̇; each variant keeps a subset of the "
            "damping terms (quadratic drag alone is the paper's equation (4), written there for the arc s = Lθ). "
            "Tables 1–3 follow the layout of the paper this tool grew from, <i>Identification of Hydrodynamics "
            "Coefficient of Underwater Vehicle Using Free Decay Pendulum Method</i>: Table 1 the rig values as "
            "configured, Tables 2–3 these trials' fits, not the paper's. Intervals are 95 % (statistical and "
            "rig-value systematic errors combined)." + self._model_form_note() + "</p></header>"
        )

    def _model_form_note(self) -> str:
        """What no interval holds: the equation's own form (a point mass where a rig states no I_p; the rod)."""
        point = [
            r
            for r in self.rig_names
            if self.rig_values_used(r)[0].get("body_inertia_kg_m2") is None
            and "body_inertia_kg_m2" not in self.rig_values_used(r)[1]
        ]
        where = (
            f" On rig{'s' if len(point) > 1 else ''} {esc(', '.join(point))} no I<sub>p</sub> "
            "(<code>body_inertia_kg_m2</code>) is stated: the body is a point mass, I<sub>p</sub> = mL², and its "
            "own inertia about its centre I<sub>cg</sub> is counted in m<sub>a</sub> (as I<sub>cg</sub>/L²)."
            if point
            else ""
        )
        return (
            " They do not hold the equation's own form: m, B and the drag are the body's; the rod's (or string's) own "
            "mass, buoyancy and drag are not in it." + where + " What the coefficients are: m<sub>a</sub> is the added "
            "mass as swung on this pendulum (a body that turns with the swing adds its rotational added inertia about "
            "its centre, as I<sub>a</sub>/L²; a vehicle's added mass along one axis is this less that, for the axis "
            "it was swung along); C<sub>d</sub> and c are those of the oscillating flow at the trials' "
            "Keulegan–Carpenter numbers (KC in Table 3), not steady-flow values; c and τ<sub>f</sub> may be the "
            "rig's (its bearing) as much as the body's."
        )

    def calibration_table(self) -> str:
        """Table: each camera setup's calibration (lens model chosen by held-out error, focal length, plane)."""
        header = [
            "camera setup",
            "lens model chosen",
            "held-out reprojection RMS, rational (px)",
            "held-out reprojection RMS, fisheye (px)",
            "focal length f<sub>x</sub>, f<sub>y</sub> (px)",
            "plane board",
            "views used",
            "frame the board reached",
        ]
        caption = self.table_caption(
            "Camera calibration (results/calibration/&lt;setup&gt;.json): the lens model chosen by the RMS "
            "reprojection error of checkerboard views held out of the fit (the rational model only when more than "
            "5 % below the fisheye's), the focal length of the chosen model, and whether a board held in the swing "
            "plane gave the plane's homography (its tilt against the image plane). Views used: checkerboard views "
            "found in the lens clip (in brackets, how many of them were held out for the choice). The frame the board "
            "reached: the share of a 16 × 9 grid over the frame that some view's board covered (the lens model is "
            "extrapolated beyond it), and what the calibration warns of. A lens clip whose held-out views are over "
            "1 px RMS off is refused; over 0.5 px, or a board that reached under half the frame, is warned about."
        )
        return table_html(header, calibration_rows(self.calibration), caption=caption, table_id="calibration-table")

    def tracking_section(self) -> str:
        """Per trial: frames, flags by kind, samples used; then the contact sheets."""
        rows, sheets, attrs = [], [], []
        variant_for = {t: self.recommended(self.trials[t]["rig"]) for t in self.trials}
        for trial in self.trial_order():
            frames, tracks, angles = (self.docs.get((trial, k)) for k in ("frames", "tracks", "angles"))
            kind = self.trials[trial].get("kind", "video")
            said: set[str] = set()  # a failure propagated to the later stages is said once, where it happened
            if kind != "video":
                frame_cells = [td("angle table (no video)", "na", span=4)]
            elif not is_ok(frames):
                frame_cells = [failure_cell(frames, said, span=4)]
            else:
                fps = frames.get("mean_fps") if is_finite(frames.get("mean_fps")) else frames.get("nominal_fps")
                variable = ' <span class="warn">variable</span>' if frames.get("variable_frame_rate") else ""
                base = (tracks or {}).get("time_base") or {}  # a slow-motion clip: the camera's rate (capture_fps)
                filmed = f" (filmed at {esc(fmt(base['capture_fps'], 4))})" if base.get("capture_fps") else ""
                frame_cells = [
                    td(str(frames.get("n_frames", "—")), "num"),
                    td(esc(fmt(fps, 4)) + variable + filmed, "num"),
                    td(
                        str(frames.get("dropped_frames", "—")),
                        "num" + (" fail" if frames.get("dropped_frames") else ""),
                    ),
                    td(
                        str(frames.get("duplicate_timestamps", "—")),
                        "num" + (" fail" if frames.get("duplicate_timestamps") else ""),
                    ),
                ]
            marker_cell = td(esc(marker_text(tracks)) if kind == "video" and is_ok(tracks) else "—", "na")
            if kind != "video":
                flag_cell = td("—", "na")
            elif is_ok(tracks):
                flags = tracks.get("flags") or {}
                bad = {k: n for k, n in sorted(flags.items()) if k != "ok" and n}
                share = "" if (usable := usable_percent(flags)) is None else f" ({usable:.1f} %)"
                flag_cell = td(f"ok {flags.get('ok', 0)}{share}" + "".join(f", {esc(k)} {n}" for k, n in bad.items()))
            else:
                flag_cell = failure_cell(tracks, said)
            if is_ok(angles):
                angle_cells = [
                    td(str(angles.get("n_samples", "—")), "num"),
                    td(str(angles.get("n_flagged", "—")), "num"),
                    td(esc(fmt(angles.get("noise_deg"), 2)), "num"),
                    td(period_text(angles), "num"),
                ]
            else:
                angle_cells = [failure_cell(angles, said, span=4)]
            fit = self.fits.get((variant_for[trial], trial)) if variant_for[trial] else None
            fitted = td(str(fit["n_samples"]), "num") if is_ok(fit) else td("—", "na")
            notes = [esc(n) for n in frame_notes(frames)] if kind == "video" and is_ok(frames) else []
            method = (tracks or {}).get("method") or {}
            if kind == "video" and is_ok(tracks) and method.get("used") == "body":
                short = method_note(method, (tracks or {}).get("body") or {})
                notes.append(f'{NEUTRAL}<span title="{esc(method.get("reason", ""))}">{esc(short)}</span>')
                if ((tracks or {}).get("body") or {}).get("warning"):
                    notes.append(esc(tracks["body"]["warning"]))
                if box := ((tracks or {}).get("body") or {}).get("in_front", {}).get("box_px"):
                    notes.append(esc(in_front_text(box)))
            if kind == "video" and is_ok(tracks) and ((tracks or {}).get("marker") or {}).get("view") == "colour":
                short = dot_colour_note(method)
                notes.append(f'{NEUTRAL}<span title="{esc(method.get("reason", ""))}">{esc(short)}</span>')
            if kind == "video" and is_ok(tracks) and slip_sentence((tracks or {}).get("timing") or {}):
                notes.append(esc(slip_sentence(tracks["timing"])))
            notes += [esc(w) for w in (angles.get("warnings") or [])] if is_ok(angles) else []
            if is_ok(angles) and angles.get("held_frames") and is_finite(angles.get("hold_angle_deg")):
                notes.append(
                    f"{NEUTRAL}released by hand in view at {angles['release_time_s']:.2f} s from "
                    f"{with_minus_sign(format(angles['hold_angle_deg'], '+.1f'))}° (found from the free swing's "
                    f"start; {angles['held_frames']} frames held before it)"
                )
            problems = record_problems(fit) or self.trial_problems(trial)
            if problems:
                found = problem_text(trial, problems[0], first_clause=True)
                notes.insert(0, f"{garbage_badge(problems[0])} {esc(found)}")
            rows.append(
                [td(esc(trial)), td(self.angle_label(trial), "num")]
                + frame_cells
                + [marker_cell, flag_cell]
                + angle_cells
                + [fitted, f'<td class="warncell notes" style="{NOTES_STYLE}">' + "".join(map(_note, notes)) + "</td>"]
            )
            attrs.append({"data-trial": trial, **({"data-notes": str(len(notes))} if notes else {})})
            files = self.files.get("trials", {}).get(trial, {})
            # the track drawn over the key frames where the track exists, else the plain contact sheet
            sheet = files.get("track_sheet") if is_ok(tracks) else None
            sheet = sheet if sheet and Path(sheet).is_file() else files.get("contact_sheet")
            if sheet and Path(sheet).is_file():
                sheets.append((trial, Path(sheet).read_bytes(), is_ok(frames)))
        header = [
            "trial",
            "release",
            "frames",
            "fps",
            "dropped",
            "duplicate stamps",
            "marker",
            "tracker flags by kind",
            "angle samples",
            "flagged",
            "angle noise (°)",
            "period (s)",
            "samples fitted",
            "notes",
        ]
        caption = self.table_caption(
            "Tracking quality per trial: frames in the video (from the container: dropped frames and duplicate time "
            "stamps), the marker followed (polarity and radius; “detected” when config and sidecar left them to the "
            "marker detection, “given” otherwise; “body”: the swinging object's silhouette was tracked, where no "
            "marker disk is usable or `method: body` says so; “dot by colour”: the coloured dot at start_px "
            "followed by its colour, where its brightness fails), the tracker's flags by kind (flagged frames are "
            "never interpolated; “held”: the body with a hand before its release or after a catch, the release then "
            "found from the free swing's start), the angle samples from "
            "release to rest and how many of them are flagged, the angle record's noise (σ from the fifth "
            "differences of the whole record: Table 2's record noise), the record's mean period (from the times it "
            "crosses the middle of its swing, ± its standard error: the mean over the record, which amplitude, damping "
            "and friction all move a little from the small-swing period), and the "
            "samples the "
            "recommended variant's fit used (after the release transient and outliers). fps: mean rate of the "
            "frames the decoder yields (“variable”: a variable-frame-rate file, every frame keeps its own time "
            "stamp). Notes: only what is notable — a trimmed clip's discarded packets, rotation metadata, more than "
            "8 bits, dropped or duplicate frames, frames the camera lost or repeated under even time stamps (found "
            "from the motion, their times put right), other warnings of the frames stage, and a record that failed "
            "the fit's garbage checks."
        )
        out = table_html(header, rows, caption=caption, table_id="tracking-table", row_attrs=attrs)
        if self.calibration:
            out += self.calibration_table()
        if sheets:
            caption = self.figure_caption(
                "Contact sheets: key frames of each video with the track drawn over them (grey: the tracked path; "
                "a green ring: the position tracked at that frame, red where flagged), for a visual check that the "
                "track sits on the pendulum, and of the scene and lighting."
            )
            items = "".join(
                f'<figure class="sheet"><img src="{photo_data_uri(data)}" alt="contact sheet of {esc(t)}">'
                f"<figcaption>{esc(t)}{'' if ok else ' (failed)'}</figcaption></figure>"
                for t, data, ok in sheets
            )
            out += f'<div class="sheets">{items}</div><p class="figcaption">{caption}</p>'
        return out

    def provenance_section(self) -> str:
        """Commit, configuration digest, fit settings and package versions."""
        p = self.provenance
        items = [
            ("commit", f"<code>{esc(str(p.get('commit') or 'not a git work tree'))}</code>"),
            ("commit time (UTC)", esc(str(p.get("commit_time_utc") or "—"))),
            ("uncommitted changes", esc(changes_text(p.get("dirty"), p.get("dirty_files")))),
            ("configuration SHA-256", f"<code>{esc(str(p.get('config_sha256') or '—'))}</code>"),
            ("Python", esc(str(p.get("python") or "—"))),
        ]
        items += [(f"{esc(k)}", esc(str(v or "not installed"))) for k, v in sorted((p.get("packages") or {}).items())]
        items += [(f"fitting.{esc(k)}", esc(str(v))) for k, v in sorted(self.fitting.items())]
        rows = [[td(k), td(v)] for k, v in items]
        caption = self.table_caption(
            "Provenance: the code version, the digest of the configuration as used, the fit settings and the "
            "versions of the packages the results depend on."
        )
        return table_html(["item", "value"], rows, caption=caption, table_id="provenance-table")
