"""The report's one-clause note on a trial's track: its path (a knock, a creep, a departure from one circle), a
second harmonic in its angles, and its timing (frames lost or repeated, breaks no slip explains)."""

from __future__ import annotations

import math

from pendulum.report.data import is_ok
from pendulum.report.format import fmt, is_finite
from pendulum.tracking.timing_notes import slip_counts


def tracking_note(tracks: dict | None, angles: dict | None) -> str:
    """A trial's path and timing findings in one clause ('' if none): a creeping camera (corrected), a path off
    one circle (carried by the angles), a second harmonic in its angles (perspective), frames lost or repeated
    under even stamps (times corrected), breaks in its track no slip explains (not corrected)."""
    tracks = tracks or {}
    if not is_ok(tracks):
        return ""
    parts = []
    path = tracks.get("path") or {}
    creep = path.get("creep") or {}
    knock = creep.get("knock") or {}
    handled = path.get("handled") or {}
    if moved := path.get("camera_motion"):
        parts.append(
            f"the camera moved in the hand by {fmt(moved['rms_px'], 2)} px RMS (measured from the still scene and "
            "taken out)"
        )
    if handled:
        held = "until it was set down" if handled.get("handled") == "before" else "from when it was picked up"
        parts.append(
            f"the camera was in the hand {held} at {fmt(handled['time_s'], 3)} s (those frames flagged, the path "
            "judged without them)"
        )
    if knock:
        parts.append(
            f"the pivot jumped by {fmt(math.hypot(*knock['shift_px']), 2)} px in the picture at "
            f"{fmt(knock['time_s'], 3)} s (the camera knocked or slid, or the thread slipping; corrected, its "
            "shaking flagged)"
        )
        if creep.get("degree"):  # the creep without the jump, first frame to last
            (ex, ey), (kx, ky) = creep["start_to_end_px"], knock["shift_px"]
            parts.append(f"the camera crept by {fmt(math.hypot(ex - kx, ey - ky), 2)} px (corrected)")
    elif path.get("corrected") and is_finite(creep.get("motion_px")):
        parts.append(f"the camera crept by {fmt(creep['motion_px'], 2)} px (corrected)")
    if path.get("departs") and is_finite(path.get("unexplained_angle_deg")):
        parts.append(
            "its swing is elliptical, out of the picture's plane (the path moves with the swing's speed), and "
            * bool(path.get("out_of_plane"))
            + f"its path is off one circle by {fmt(path['unexplained_rms_px'], 2)} px RMS "
            f"({fmt(path['unexplained_angle_deg'], 2)}°; not corrected, it stays in the angles)"
        )
    if change := (angles or {}).get("uncalibrated_size_change"):
        parts.append(
            f"its marker's image is {fmt(100 * (change - 1), 2)} % larger at one place on its path than at another: "
            "a wide lens or a turned swing plane, uncalibrated, which scales the angles (a GoPro-like lens: 8–17 % "
            "too large), and with them the drag and damping coefficients, beyond their intervals (the added mass, "
            "from the period, hardly; film a lens clip)"
        )
    if read := path.get("not_applied"):
        parts.append(
            f"its path read {'a knock' if read.get('knock') else 'a creep'} that such a view bends into it "
            "(not applied)"
        )
    harmonic = (angles or {}).get("second_harmonic") or {}
    if harmonic.get("present"):
        parts.append(
            f"its angles hold a second harmonic of {fmt(harmonic['amplitude_deg'], 2)}° (perspective: its "
            "distance from the camera changes with the swing; not corrected, it stays in the fits' residuals: "
            "film square-on to the swing plane, from farther away)"
        )
    lost, repeated, other = slip_counts(tracks.get("timing") or {})
    counts = [f"{lost} frame(s) lost"] * bool(lost) + [f"{repeated} repeated"] * bool(repeated)
    counts += [f"{other} slip(s) of the clock by part of a frame"] * bool(other)
    parts += [
        f"{', '.join(counts)} while the time stamps in the file stayed even (times corrected from the motion; "
        "near a turning point the motion cannot check the correction)"
    ] * bool(counts)
    breaks = ", ".join(map(str, (tracks.get("timing") or {}).get("unexplained") or []))
    parts += [
        f"a break in its track at frame {breaks} no slip of the clock explains (not corrected: the frames "
        "after it may be off in time, which biases its fits)"
    ] * bool(breaks)
    return ", ".join(parts)
