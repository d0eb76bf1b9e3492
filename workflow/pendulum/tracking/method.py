"""Dot or body: which tracker follows a trial's pendulum, decided from the video and said.

``method: marker`` measures a marker disk (:func:`pendulum.tracking.marker.track_video`), ``body``
the swinging object's silhouette (:func:`pendulum.tracking.body.track_body`). ``auto`` (the default)
tries the marker first: a disk that detection finds and that is usable in at least
:data:`MARKER_USABLE_FRACTION` of the frames is the more precise measurement and is kept.
Otherwise (no disk, an ambiguous one, or one whose signal leaves its band in many frames,
as a shaded real body's does) the body is tracked too, and the track with more usable frames
is taken. Either way the track's ``attrs["method"]`` says which, and why.
"""

from __future__ import annotations

import math
import re

import pandas as pd

from pendulum.camera.video import VideoError
from pendulum.tracking import samples
from pendulum.tracking.body import BodyError, find_body, track_body
from pendulum.tracking.colour import (
    brightness_depends_on_wall,
    scaled_by_wall,
    track_by_colour,
    track_marker_by_colour,
)
from pendulum.tracking.look import track_by_look
from pendulum.tracking.marker import MarkerAbandoned, track_video
from pendulum.tracking.outline import centre_by_outline, sharper_outline
from pendulum.tracking.path_shape import path_departure
from pendulum.tracking.settings import TrackerSettings
from pendulum.tracking.timing import at_capture_rate, correct_slips

MARKER_USABLE_FRACTION = 0.95  # issue 23: a record ≥ 95 % usable; below it the body is tried too, the better kept


def usable_fraction(track: pd.DataFrame) -> float:
    """The share of the frames ``ok``, of those not ``held`` (a hand holds the body before the release or after a
    catch: no free swing to measure there)."""
    free = int((track.flag != "held").sum())
    return float((track.flag == "ok").sum()) / free if free else 0.0


def track_trial(path, settings: TrackerSettings, progress=None, keep_samples: bool = False) -> pd.DataFrame:
    """The track by ``settings.method`` (module docstring); ``attrs["method"]``: ``used``, ``reason``, ``tried``.
    Its ``time_s`` is put right where the camera lost or repeated frames under even time stamps
    (:func:`pendulum.tracking.timing.correct_slips`; ``attrs["timing"]``), then put at the camera's
    ``settings.capture_fps`` where the file plays at another rate (:func:`~pendulum.tracking.timing.at_capture_rate`).

    Raises :class:`~pendulum.camera.video.VideoError` when no method gives a record; the message holds
    what each one said. The clip's sampled frames, shared by the searches, are let go at the end (``keep_samples``:
    kept for the caller, who lets them go: :func:`pendulum.tracking.samples.release`).
    """
    try:
        track = centre_by_outline(_track_trial(path, settings, progress), settings)  # a sphere seen in part
        return at_capture_rate(correct_slips(track), settings.capture_fps)
    finally:
        if not keep_samples:
            samples.release()


def _track_trial(path, settings: TrackerSettings, progress=None) -> pd.DataFrame:
    method = settings.method
    if method == "marker":
        try:
            track = track_video(path, settings, progress=progress)
        except VideoError as error:
            tried = {"marker": f"failed: {error}"}
            track = _marker_by_colour(path, settings, None, tried, progress)
            if track is None:
                raise
        else:
            tried = {"marker": _usable(track)}
            track = _marker_by_colour(path, settings, track, tried, progress) or track
        colour = track.attrs.get("marker", {}).get("view") == "colour"
        reason = "method: marker given in the settings" + ("; " + _colour_reason(tried) if colour else "")
        track.attrs["method"] = {"used": "marker", "reason": reason, "tried": tried if colour else {}}
        return track
    if method == "body":
        tried = {}
        try:
            track = track_body(path, settings, progress=progress)
        except VideoError as error:  # a scene the body hides: its look
            tried["body"] = f"failed: {error}"
            track = _by_look(path, settings, error, tried, progress)
            if track is None:
                raise
        else:
            tried["body"] = _usable(track)
            track = _by_colour(path, settings, track, tried, progress)
            track = _by_look_if_closer(path, settings, track, tried, progress)
        track.attrs["method"] = {
            "used": "body",
            "reason": "method: body given in the settings" + _view(track, tried),
            "tried": tried,
        }
        return track
    tried: dict[str, str] = {}
    marker = None
    stopped = None  # a marker pass stopped early (it holds the most of the frames it could have had ok)
    try:
        marker = track_video(path, settings, progress=progress, abandon_below=MARKER_USABLE_FRACTION)
    except MarkerAbandoned as error:
        stopped = error
        tried["marker"] = stopped_text(stopped)
    except VideoError as error:
        tried["marker"] = f"failed: {error}"
    if marker is not None:
        fraction = usable_fraction(marker)
        tried["marker"] = f"usable in {100 * fraction:.1f} % of the frames"
        if fraction >= MARKER_USABLE_FRACTION:
            marker.attrs["method"] = {
                "used": "marker",
                "reason": (
                    "detection's disk-like spot (a marker dot, or a round body itself: a ball, a bauble) is"
                    if (marker.attrs.get("marker") or {}).get("found_by") == "detection"
                    else "a marker disk was found and is"
                )
                + f" usable in {100 * fraction:.1f} % of the frames",
                "tried": tried,
            }
            return marker
    colour = _marker_by_colour(path, settings, marker, tried, progress)
    if colour is not None and usable_fraction(colour) >= MARKER_USABLE_FRACTION:
        colour.attrs["method"] = {"used": "marker", "reason": _colour_reason(tried), "tried": tried}
        return colour
    if progress:
        progress(f"{path}: marker {tried['marker']}; tracking the swinging body itself")
    try:
        body = track_body(path, settings, progress=progress)
        tried["body"] = _usable(body)
        body = _by_look_if_closer(path, settings, _by_colour(path, settings, body, tried, progress), tried, progress)
    except VideoError as error:
        tried["body"] = f"failed: {error}"
        body = _by_look(path, settings, error, tried, progress) if isinstance(error, BodyError) else None
        if not isinstance(error, BodyError):  # too few frames usable, not a refusal (two bodies, not a pendulum)
            body, facts = track_by_colour(path, settings, None, progress)  # its colour, where its brightness fails
            tried["body_by_colour"] = facts.get("colour", "") if body is None else _usable(body)
            look = _by_look(path, settings, error, tried, progress)  # a scene it hides: its look, if more usable
            body = (
                look if look is not None and (body is None or usable_fraction(look) >= usable_fraction(body)) else body
            )
    if body is None:
        if _might_beat(stopped, colour):  # the whole marker pass after all: its record, or why there is none
            marker, tried["marker"] = _whole_marker_pass(path, settings, stopped, progress)
        marker = _more_usable(marker, colour)
        if marker is not None:
            marker.attrs["method"] = {
                "used": "marker",
                "reason": f"the body could not be tracked; the marker is {tried['marker']}" + _dot_view(marker, tried),
                "tried": tried,
            }
            return marker
        raise VideoError(
            f"{path}: neither a marker disk nor the body could be followed. Marker: {tried['marker'][8:]} "
            f"Body: {tried['body'][8:]}"
            + (f" The dot by its colour: {tried['marker_by_colour']}." if "marker_by_colour" in tried else "")
            + (f" By its colour: {tried['body_by_colour']}" if "body_by_colour" in tried else "")
            + (
                f" By its look: {tried['body_by_look'][8:]}"
                if tried.get("body_by_look", "").startswith("failed")
                else ""
            )
        )
    body_fraction = usable_fraction(body)
    if _might_beat(stopped, colour) and stopped.most_usable >= body_fraction:  # the marker might do as well
        marker, tried["marker"] = _whole_marker_pass(path, settings, stopped, progress)
    marker = _more_usable(marker, colour)
    if marker is not None and usable_fraction(marker) >= body_fraction:
        marker.attrs["method"] = {
            "used": "marker",
            "reason": f"the marker disk is usable in as many frames as the body ({tried['marker']})"
            + _dot_view(marker, tried),
            "tried": tried,
        }
        return marker
    why = (
        "no marker disk could be followed"
        if marker is None and stopped is None
        else f"the marker disk could not be followed ({tried['marker'][8:]})"
        if tried["marker"].startswith("failed: ")  # a stopped pass run whole that found none
        else f"the marker disk is {tried['marker']}"
    )
    body.attrs["method"] = {
        "used": "body",
        "reason": f"{why}; the body's silhouette {_silhouette(tried)}{_view(body, tried)}",
        "tried": tried,
    }
    return body


def _by_colour(path, settings: TrackerSettings, body: pd.DataFrame, tried: dict, progress=None) -> pd.DataFrame:
    """The body's track in the clip's colour view (:mod:`pendulum.tracking.colour`) where its brightness
    silhouette changes with the wall behind it and the colour view is usable in more frames; else ``body``.
    What the colour view gave goes into ``tried`` as ``body_by_colour``.

    Usable frames decide (where the brightness silhouette was scaled by the wall's gain before a darker band,
    :func:`~pendulum.tracking.colour.scaled_by_wall`, a colour view usable in 95 % of the frames is kept: the band
    leaves a body's colour as it was; docs/footage-notes.md), not how much each silhouette's area changes mid-swing: on
    the real clip's two-tone ball before hard-edged or bluish bands and filmed by hand, colour tracks 99.5–99.9 %
    usable were once dropped for a smaller change, for brightness tracks 89.8–95.0 % usable whose usable positions
    were off the clip without the band by as much or more (0.34–2.5 px RMS against 0.34–0.41 px,
    docs/footage-notes.md)."""
    if not brightness_depends_on_wall(body):
        return body
    colour, facts = track_by_colour(path, settings, body, progress)
    if colour is None:
        tried["body_by_colour"] = facts.get("colour", "not taken")
        return body
    tried["body_by_colour"] = _usable(colour)
    scaled = scaled_by_wall(body)  # its brightness scaled before a darker band: its colour, where usable
    if usable_fraction(colour) > usable_fraction(body) or (
        scaled and usable_fraction(colour) >= MARKER_USABLE_FRACTION
    ):
        colour.attrs["body"]["brightness"] = {"usable": tried["body"], "warning": body.attrs["body"].get("warning")}
        if (in_front := body.attrs["body"].get("in_front")) and "in_front" not in colour.attrs["body"]:
            colour.attrs["body"]["brightness"]["in_front_not_in_colour"] = in_front  # its colour seen there
        return sharper_outline(colour, body)  # a limb at the luma's resolution, not the chroma's
    return body


def _by_look(path, settings: TrackerSettings, error: VideoError, tried: dict, progress=None) -> pd.DataFrame | None:
    """The body followed by its look (:func:`pendulum.tracking.look.track_by_look`) where its silhouette was refused
    for a scene it hides (``error.refused``); None otherwise. What it gave goes into ``tried`` as ``body_by_look``."""
    if getattr(error, "refused", None) is None:
        return None
    try:
        track = track_by_look(path, settings, *error.refused, progress=progress)
    except VideoError as failure:
        tried["body_by_look"] = f"failed: {failure}"
        return None
    tried["body_by_look"] = _usable(track)
    return track


def _by_look_if_closer(path, settings: TrackerSettings, body: pd.DataFrame, tried: dict, progress=None):
    """The body followed by its look in place of its silhouette where that was measured against a scene filled in
    behind its path (``unseen_scene``: a body wider than its swing, a ghost of it left at its rest place) and the
    look is usable in as many frames, turns with its arm as a rigid body does, and keeps its path on one circle
    within half the silhouette's unexplained RMS (a helper's tank render: the silhouette 13 px RMS off the body,
    up to 56 px at the swing's ends, all ``ok``); ``body`` otherwise. What the look gave goes into ``tried``."""
    facts = body.attrs.get("body") or {}
    if not facts.get("unseen_scene") or facts.get("view") == "colour":
        return body
    try:
        look = track_by_look(path, settings, body, find_body(path, settings.start_px), progress=progress)
    except VideoError as failure:
        tried["body_by_look"] = f"failed: {failure}"
        return body
    tried["body_by_look"] = _usable(look)
    _, by_silhouette = path_departure(body)
    _, by_look = path_departure(look)
    left_silhouette = by_silhouette.get("unexplained_rms_px", math.inf)
    left_look = by_look.get("unexplained_rms_px", math.inf)
    look.attrs["body"]["silhouette_unexplained_rms_px"] = left_silhouette
    rigid = "warning" not in look.attrs["body"]["look"]["rotation"]
    measured = math.isfinite(left_look) and math.isfinite(left_silhouette)  # both paths judged (≥ 30 ok frames)
    if measured and rigid and usable_fraction(look) >= usable_fraction(body) and left_look <= 0.5 * left_silhouette:
        return look
    return body


def _marker_by_colour(path, settings: TrackerSettings, marker, tried: dict, progress=None):
    """The dot at the given ``start_px`` tracked by its colour (:func:`track_marker_by_colour`) where its brightness
    track is not usable in :data:`MARKER_USABLE_FRACTION` of the frames (or stopped before), and kept (returned)
    where usable in more frames than that track; None otherwise. A coloured sticker on a shiny bob (a clock's) is
    lost in the bob's shading and highlight in its brightness, not in its colour. Tried only where the user pointed
    at the dot: a spot detection found alone may be the body itself.
    What it gave goes into ``tried`` as ``marker_by_colour``."""
    if settings.start_px is None or (marker is not None and usable_fraction(marker) >= MARKER_USABLE_FRACTION):
        return None
    colour, facts = track_marker_by_colour(path, settings, settings.start_px, progress)
    if colour is None:
        tried["marker_by_colour"] = facts.get("colour", "not taken")
        return None
    tried["marker_by_colour"] = _usable(colour)
    return colour if marker is None or usable_fraction(colour) > usable_fraction(marker) else None


def _might_beat(stopped: MarkerAbandoned | None, colour: pd.DataFrame | None) -> bool:
    """Whether a stopped marker pass, run whole, could be usable in more frames than the dot's colour track."""
    return stopped is not None and (colour is None or stopped.most_usable > usable_fraction(colour))


def _more_usable(marker: pd.DataFrame | None, colour: pd.DataFrame | None) -> pd.DataFrame | None:
    """The marker's track usable in more frames: by its brightness, or (where usable in more) by its colour."""
    if colour is None or (marker is not None and usable_fraction(marker) >= usable_fraction(colour)):
        return marker
    return colour


def _colour_reason(tried: dict) -> str:
    """Why the dot was measured by its colour: what its colour and its brightness gave, the brightness pass's advice
    ("; check start_px …", "; film it …") left out: the colour view followed the dot there."""
    brightness = re.sub(r"; (check|give|film|widen)\b.*$", "", tried["marker"])
    return (
        f"the marker dot at start_px measured by its colour against its surround's, {tried['marker_by_colour']} "
        f"(by its brightness: {brightness})"
    )


def _dot_view(marker: pd.DataFrame, tried: dict) -> str:
    """The reason's clause for a marker measured by its colour (empty for its brightness)."""
    return "; " + _colour_reason(tried) if marker.attrs.get("marker", {}).get("view") == "colour" else ""


def _silhouette(tried: dict) -> str:
    body = tried["body"]
    return f"could not be followed ({body[8:]})" if body.startswith("failed") else f"is {body}"


def _usable(track: pd.DataFrame) -> str:
    held = int((track.flag == "held").sum())
    where = f" not held by hand ({held} held)" if held else ""
    return f"usable in {100 * usable_fraction(track):.1f} % of the frames{where}"


def _view(body: pd.DataFrame, tried: dict) -> str:
    """The reason's clause for a body measured by its colour or followed by its look (empty for its brightness)."""
    if body.attrs.get("body", {}).get("by") == "look":
        why = (
            "its silhouette has no scene to be measured against where it hides it"
            if tried["body"].startswith("failed")
            else f"measured against a scene filled in behind its path, it leaves "
            f"{body.attrs['body']['silhouette_unexplained_rms_px']:.2f} px RMS off one circle"
        )
        return f"; {why}: followed by its look (its picture aligned in every frame), {tried['body_by_look']}"
    if body.attrs.get("body", {}).get("view") != "colour":
        return ""
    if tried["body"].startswith("failed"):
        return f"; measured by its colour, {tried['body_by_colour']}"
    return (
        "; that silhouette changes with the wall behind the body (a shadow, a darker band), its colour does not: "
        f"measured by its colour, {tried['body_by_colour']}"
    )


def stopped_text(stopped: MarkerAbandoned) -> str:
    """What a marker pass stopped early gave, as ``tried`` says it: which spot it followed and where it stopped."""
    spot = stopped.settings
    found = "detection's" if stopped.detection is not None else "the given"
    radius = f", radius {spot.marker_radius_px:.1f} px" if spot.marker_radius_px else ""
    return (
        f"usable in under {100 * MARKER_USABLE_FRACTION:.0f} % of the frames: {found} disk-like spot ({spot.polarity}"
        f"{radius}: a marker dot, or the body itself where it has none) was not measurable "
        f"as a disk in more than {100 * (1 - MARKER_USABLE_FRACTION):.0f} % of the frames by frame "
        f"{stopped.at_frame}, where its pass was stopped"
    )


def _whole_marker_pass(
    path, settings: TrackerSettings, stopped: MarkerAbandoned, progress=None
) -> tuple[pd.DataFrame | None, str]:
    """The marker's track over the whole clip (no early stop; with the stopped pass's detection, not run again)
    and what it gave, as ``tried`` says it."""
    try:
        if stopped.detection is not None:
            marker = track_video(path, stopped.settings, progress=progress, detection=stopped.detection, asked=settings)
        else:
            marker = track_video(path, settings, progress=progress)
    except VideoError as error:
        return None, f"failed: {error}"
    return marker, _usable(marker)
