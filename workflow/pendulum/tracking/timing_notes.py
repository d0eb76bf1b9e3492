"""What :func:`pendulum.tracking.timing.find_slips` found, in words: the tracks job's log and the report's notes."""

from __future__ import annotations

import numpy as np


def slip_counts(timing: dict) -> tuple[int, int, int]:
    """Frames lost (whole periods late), frames repeated, and other slips of the clock (parts of a period)."""
    slips = timing.get("slips") or []
    lost = sum(round(p) for _, p in slips if abs(p - round(p)) < 0.1 and p > 0)
    other = sum(1 for _, p in slips if not (abs(p - round(p)) < 0.1 and p > 0))
    return int(lost), len(timing.get("repeated") or []), other


UNCHECKED_FRACTION = 0.2  # below this share of a record where a lost frame would stand out, the check is said unmade


def break_sentence(timing: dict) -> str:
    """The breaks :func:`find_slips` found and no slip explains (``unexplained``), in one sentence ('' when none)."""
    breaks = timing.get("unexplained") or []
    if not breaks:
        return ""
    return (
        f"the track breaks at frame {', '.join(str(f) for f in breaks)} in a way no slip of the clock explains "
        "(frames lost in a row, two slips close together, or the picture moving): the frames after it may be off "
        "in time or place"
    )


def slip_sentence(timing: dict) -> str:
    """What :func:`correct_slips` found, in one sentence ('' when nothing)."""
    slips, repeated = timing.get("slips") or [], timing.get("repeated") or []
    others = [
        _picture_sentence(timing.get("picture_steps") or []),
        _look_sentence(timing.get("look_steps") or []),
        _place_sentence(timing),
        break_sentence(timing),
    ]
    checked = timing.get("checked_fraction")
    if checked is not None and float(checked) < UNCHECKED_FRACTION and not slips and not repeated:
        others.append(
            f"lost or repeated frames could be told from the motion in only {100 * float(checked):.0f} % of this "
            "record (a slip of one frame stands out only where the body moves fast and its track is clean): its frame "
            "times are the stamps' as they are"
        )
    moved = "; ".join(s for s in others if s)
    if not slips and not repeated:
        return moved
    parts = []
    lost = [(f, round(p)) for f, p in slips if abs(p - round(p)) < 0.1 and p > 0]
    if lost:
        parts.append(f"{sum(n for _, n in lost)} frame(s) lost (before frame {', '.join(str(f) for f, _ in lost)})")
    if repeated:
        parts.append(f"{len(repeated)} repeated (frame {', '.join(str(f) for f in repeated)}, flagged duplicate)")
    other = [(f, p) for f, p in slips if not (abs(p - round(p)) < 0.1 and p > 0)]
    if other:
        parts.append("slipped its clock by " + ", ".join(f"{p:+.2f} of a frame period at frame {f}" for f, p in other))
    checked = 100 * float(timing.get("checked_fraction") or 0.0)
    return (
        "under even time stamps the camera " + "; ".join(parts) + ": found from the motion, the frame times put "
        f"right (by up to {1e3 * float(timing.get('max_shift_s') or 0.0):.1f} ms); a slip shows where the pendulum "
        f"moves fast ({checked:.0f} % of this record)" + (f"; {moved}" if moved else "")
    )


def _picture_sentence(steps: list) -> str:
    """The picture's own steps (:func:`_moved_picture`) in words, or ''."""
    if not steps:
        return ""
    where = ", ".join(f"{float(np.hypot(*d)):.1f} px at frame {f}" for f, d in steps)
    return (
        f"the picture itself moved by {where} (a knock or the camera's stabiliser, not its clock): the positions "
        "after it are off by that much, which the angles carry"
    )


def _look_sentence(steps: list) -> str:
    """The breaks in the motion where the body's look changed (:func:`_look_steps`) in words, or ''."""
    if not steps:
        return ""
    where = ", ".join(f"frame {f} ({ratio:g}×)" for f, _, ratio in steps)
    return (
        f"the track's motion breaks where the body's measured size steps by several times its usual change ({where}): "
        "the point measured moved on the body (a print or marking turning into view), not the camera's clock; not "
        "taken for lost frames"
    )


def _place_sentence(timing: dict) -> str:
    """The breaks at one place of the path (:func:`_at_one_place`) in words, or ''."""
    places = timing.get("scene_places") or []
    if not places:
        return ""
    (px, py) = np.mean([p for _, p in places], axis=0)
    return (
        f"the track's motion breaks {len(places)} times where the body passes one place of its path (about "
        f"({px:.0f}, {py:.0f}) px; frame {', '.join(str(f) for f, _ in places)}): something behind it there biases its "
        "positions (an edge, a reflection), not the camera's clock; not taken for lost frames"
    )
