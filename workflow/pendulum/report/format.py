"""The report's vocabulary: names, symbols and units, numbers as a reader wants them, HTML pieces.

Every table and figure of the report writes coefficients, intervals and flags
through these functions, so that a value reads the same everywhere (two
significant figures of the uncertainty, a true minus sign, ×10ⁿ outside
0.001–99 999, "at bound" instead of a bound's rounding noise).
"""

from __future__ import annotations

import base64
import html
import math

from pendulum.model.effects import ADDED_MASS
from pendulum.model.rig import RIG_VALUE_UNITS

# ---------------------------------------------------------------------------
# Names, symbols and units

COEFFICIENTS = {  # parameter → (symbol as HTML, name, unit)
    ADDED_MASS: ("m<sub>a</sub>", "added mass", "kg"),
    "drag_area_m2": ("C<sub>d</sub>A", "drag area", "m²"),
    "drag_coefficient": ("C<sub>d</sub>", "drag coefficient", "–"),
    "linear_damping_nm_s": ("c", "linear damping", "N·m·s"),
    "friction_torque_nm": ("τ<sub>f</sub>", "friction torque", "N·m"),
}
PLAIN_SYMBOLS = {  # axis labels (matplotlib mathtext)
    ADDED_MASS: "$m_a$ (kg)",
    "drag_area_m2": "$C_dA$ (m²)",
    "drag_coefficient": "$C_d$",
    "linear_damping_nm_s": "$c$ (N·m·s)",
    "friction_torque_nm": "$\\tau_f$ (N·m)",
}
TERM_LABELS = {
    "quadratic_drag": "quadratic drag",
    "linear_damping": "linear damping",
    "coulomb_friction": "Coulomb friction",
}
RIG_LABELS = {  # rig value → (label, unit)
    key: (label, RIG_VALUE_UNITS[key])
    for key, label in (
        ("mass_kg", "mass m"),
        ("length_m", "length L (pivot to body centre)"),
        ("frontal_area_m2", "frontal area A"),
        ("displaced_volume_m3", "displaced volume V"),
        ("submerged_mass_kg", "submerged mass m − ρV (weighed in the fluid)"),
        ("fluid_density_kg_m3", "fluid density ρ"),
        ("gravity_m_s2", "gravity g"),
        ("body_inertia_kg_m2", "body inertia about the pivot I_p"),
        ("characteristic_length_m", "characteristic length D (KC)"),
        ("kinematic_viscosity_m2_s", "kinematic viscosity ν"),
    )
}
# Okabe–Ito colours (distinct for colour-blind readers and in greyscale print by marker)
PALETTE = ("#D55E00", "#E69F00", "#0072B2", "#009E73", "#CC79A7", "#56B4E9", "#F0E442", "#000000")
MARKERS = ("s", "^", "o", "D", "v", "P", "X", "*")
MINUS = "\u2212"


# ---------------------------------------------------------------------------
# Numbers as a reader wants them

_SUPERSCRIPT = str.maketrans("-0123456789", "⁻⁰¹²³⁴⁵⁶⁷⁸⁹")


def is_finite(value) -> bool:
    try:
        return value is not None and math.isfinite(float(value))
    except (TypeError, ValueError):
        return False


def as_number(value) -> float | None:
    """A table cell as a number (None where empty or not a number: e.g. a status table's period of a trial that
    failed before it was measured)."""
    try:
        return float(value)
    except (TypeError, ValueError):
        return None


def with_minus_sign(text: str) -> str:
    return text.replace("-", MINUS)


def _scientific(value: float, sig: int) -> str:
    mantissa, exponent = f"{value:.{sig - 1}e}".split("e")
    return with_minus_sign(f"{mantissa}×10{str(int(exponent)).translate(_SUPERSCRIPT)}")


def fmt(value, sig: int = 3) -> str:
    """``value`` to ``sig`` significant figures; ×10ⁿ outside 0.001–99 999; "—" when missing."""
    if not is_finite(value):
        return "—"
    value = float(value)
    if value == 0:
        return "0"
    if not 1e-3 <= abs(value) < 1e5:
        return _scientific(value, sig)
    decimals = max(0, sig - 1 - math.floor(math.log10(abs(value))))
    return with_minus_sign(f"{value:.{decimals}f}")


def decimals_for(uncertainty: float, digits: int = 2) -> int:
    """Decimal places that keep ``digits`` significant figures of ``uncertainty`` (≥ 0)."""
    return max(0, digits - 1 - math.floor(math.log10(abs(uncertainty))))


def fmt_at(value: float, decimals: int) -> str:
    return with_minus_sign(f"{value:.{decimals}f}")


def reaches_bound(entry: dict) -> bool:
    """Whether a coefficient's 95 % interval reaches its lower bound although the estimate is off it: the records
    and rig values do not resolve it from that bound (the apple in air: m_a 0.00037 kg, interval [0, 0.0011])."""
    low, bound = (entry.get("ci95") or [None])[0], entry.get("lower_bound")
    return not entry.get("at_bound") and is_finite(low) and is_finite(bound) and float(low) <= float(bound)


def estimate_parts(entry: dict | None) -> tuple[str, str]:
    """(value, qualifier) of one coefficient of a fit document, rounded to its uncertainty.

    The value keeps two significant figures of the 95 % interval's half-width;
    the qualifier is the interval ``[low, high]``, or for a coefficient at its
    bound ``(at bound; < upper)`` with the one-sided 95 % upper limit, plus
    ``not identifiable`` when flagged. Never prints a bound's rounding noise
    (4.3e-14) as a measurement.
    """
    if not entry or not is_finite(entry.get("value")):
        return "—", ""
    value = float(entry["value"])
    low, high = (entry.get("ci95") or [None, None])[:2]
    if entry.get("at_bound"):
        bound = entry.get("lower_bound", value)
        upper = f"< {fmt(high, 2)}" if is_finite(high) else "no upper limit"
        return fmt(bound if is_finite(bound) else value, 3), f"(at bound; {upper})"
    qualifier = ""
    if is_finite(low) and is_finite(high) and high > low:
        half = (float(high) - float(low)) / 2
        decimals = decimals_for(half)
        scale = max(abs(value), abs(float(low)), abs(float(high)))
        if decimals > 6 or scale >= 1e5:
            text, qualifier = fmt(value, 3), f"[{fmt(low, 3)}, {fmt(high, 3)}]"
        else:
            text = fmt_at(value, decimals)
            qualifier = f"[{fmt_at(float(low), decimals)}, {fmt_at(float(high), decimals)}]"
    else:
        text = fmt(value, 3)
    if entry.get("identifiable") is False:
        qualifier = f"{qualifier} not identifiable".strip()
    return text, qualifier


def format_estimate(entry: dict | None) -> str:
    """One coefficient as text, e.g. ``2.50 [2.26, 2.74]`` or ``0 (at bound; < 0.035)``."""
    return " ".join(p for p in estimate_parts(entry) if p)


# ---------------------------------------------------------------------------
# HTML pieces

esc = html.escape


def table_html(header: list, rows: list[list[str]], *, caption: str, table_id: str, row_attrs=None, note=None):
    """A table with its numbered caption above and a note below; cells are HTML (escape text first).

    ``header``: one row of header texts, or several rows of ready ``<th>`` cells.
    """
    if header and isinstance(header[0], list):
        head = "</tr><tr>".join("".join(row) for row in header)
    else:
        head = "".join(f"<th>{h}</th>" for h in header)
    body = []
    for i, row in enumerate(rows):
        attrs = (row_attrs[i] if row_attrs else None) or {}
        attr_text = "".join(f' {k}="{esc(str(v))}"' for k, v in attrs.items())
        body.append(f"<tr{attr_text}>" + "".join(row) + "</tr>")
    note_html = f'<p class="table-note">{note}</p>' if note else ""
    caption_html = f'<p class="caption">{caption}</p>' if caption else ""
    return (
        f'<div class="table-block">{caption_html}<div class="table-wrap"><table id="{table_id}">'
        f"<thead><tr>{head}</tr></thead><tbody>{''.join(body)}</tbody></table></div>{note_html}</div>"
    )


def td(content: str, cls: str | None = None, span: int = 1, title: str | None = None) -> str:
    attrs = f' class="{cls}"' if cls else ""
    attrs += f' colspan="{span}"' if span > 1 else ""
    attrs += f' title="{esc(title)}"' if title else ""
    return f"<td{attrs}>{content}</td>"


# Garbage in (issue 12): styled inline, so the marks read the same in any page the sections are shown in.
UNRELIABLE_STYLE = "color:#8a8a8a"
BADGE_STYLE = (
    "display:inline-block;padding:0 5px;margin:0 2px;border:1px solid #a33a00;border-radius:3px;"
    "color:#a33a00;background:#fff4ec;font-size:0.78rem;font-weight:600;font-style:normal;white-space:nowrap"
)


def garbage_badge(problem: str | None = None) -> str:
    """The "garbage in" mark of a fit on an unreliable record; ``problem`` (its first sentence) as tooltip."""
    title = f' title="{esc(problem)}"' if problem else ""
    return f'<span class="garbage-in" style="{BADGE_STYLE}"{title}>garbage in</span>'


def estimate_cell(entry: dict | None, missing: str = "—", unreliable: bool = False) -> str:
    """One coefficient's cell: value over its interval; ``unreliable`` (garbage in): struck through and grey."""
    if entry is None:
        return td(missing, "na", title="not a parameter of this variant")
    value, qualifier = estimate_parts({**entry, "identifiable": True} if unreliable else entry)
    title = entry.get("note") or entry.get("reason")
    if unreliable:  # the badge says why; "not identifiable" would repeat it
        return (
            f'<td class="num unreliable" style="{UNRELIABLE_STYLE}"'
            + (f' title="{esc(title)}"' if title else "")
            + f'><span class="v"><s>{esc(value)}</s></span><span class="q"><s>{esc(qualifier)}</s></span></td>'
        )
    flag = " flagged" if entry.get("at_bound") or entry.get("identifiable") is False else ""
    return td(f'<span class="v">{esc(value)}</span><span class="q">{esc(qualifier)}</span>', "num" + flag, title=title)


def png_data_uri(data: bytes) -> str:
    return "data:image/png;base64," + base64.b64encode(data).decode("ascii")


PHOTO_JPEG_QUALITY = 85  # a contact sheet of camera frames: 0.11 MB as JPEG against 0.92 MB as PNG (1280 × 540)


def photo_data_uri(png: bytes) -> str:
    """A PNG of camera frames (a contact sheet) as a JPEG data URI: the sensor's noise makes a PNG of them about
    eight times larger, and a report of many trials carries one per trial (the PNG as it is if it does not decode)."""
    import cv2
    import numpy as np

    image = cv2.imdecode(np.frombuffer(png, np.uint8), cv2.IMREAD_UNCHANGED)
    if image is None:
        return png_data_uri(png)
    ok, jpeg = cv2.imencode(".jpg", image, [cv2.IMWRITE_JPEG_QUALITY, PHOTO_JPEG_QUALITY])
    return "data:image/jpeg;base64," + base64.b64encode(jpeg.tobytes()).decode("ascii") if ok else png_data_uri(png)


def figure_html(png: bytes, caption: str, alt: str, cls: str = "") -> str:
    return (
        f'<figure class="{("fig " + cls).strip()}"><img src="{png_data_uri(png)}" alt="{esc(alt)}">'
        f"<figcaption>{caption}</figcaption></figure>"
    )
