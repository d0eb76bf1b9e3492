"""What no further trial narrows: the rig values' tolerances behind a coefficient's interval, and how precisely
they would have to be measured to reach a target width.

A coefficient's systematic variance is Σ_i s_i², s_i its shift when input i moves by its 1σ tolerance u_i
(the fits' error budget); the shift is linear in u_i. The 95 % half-width is 1.96 √(σ_stat² + Σ s_i²), so the
target half-width T is reached with input i measured to u_i' = u_i √(T²/1.96² − σ_stat² − Σ_{j≠i} s_j²) / |s_i|
when that root is real; otherwise input i alone cannot do it and the next largest is needed as well.
"""

from __future__ import annotations

import math

from pendulum.fit.uncertainty import Z95
from pendulum.model.rig import RIG_VALUE_UNITS, tolerances_alike

INPUT_WORDS = {  # error-budget input → (words in a sentence, unit)
    key: (words, RIG_VALUE_UNITS[key])
    for key, words in (
        ("mass_kg", "the rig's mass"),
        ("length_m", "the arm length"),
        ("frontal_area_m2", "the frontal area"),
        ("displaced_volume_m3", "the displaced volume"),
        ("submerged_mass_kg", "the submerged mass (the body weighed in the fluid)"),
        ("fluid_density_kg_m3", "the fluid's density"),
        ("body_inertia_kg_m2", "the body's moment of inertia"),
        ("gravity_m_s2", "gravity"),
    )
}


BUOYANCY_INPUTS = ("displaced_volume_m3", "fluid_density_kg_m3", "mass_kg")  # what one reading in the fluid settles


def split_key(key: str) -> tuple[str, str | None]:
    """``displaced_volume_m3[short_arm]`` → (``displaced_volume_m3``, ``short_arm``)."""
    base, _, rig = key.partition("[")
    return base, (rig.rstrip("]") or None)


def largest_input(entry: dict, rig_values_only: bool = False) -> tuple[str, float]:
    """The error-budget input that moves a coefficient most, and by how much per 1σ (``("", 0.0)`` without a
    budget); ``rig_values_only``: of the rig values' tolerances (not the estimated pivot)."""
    budget = {
        k: v for k, v in (entry.get("error_budget") or {}).items() if not (rig_values_only and k.startswith("pivot"))
    }
    if not budget:
        return "", 0.0
    key = max(budget, key=lambda k: abs(budget[k]))
    return key, abs(float(budget[key]))


def input_words(key: str) -> str:
    """An error-budget input in words (``pivot_px (axis 1)`` → "the pivot position")."""
    base, rig = split_key(key)
    words = "the pivot position" if base.startswith("pivot") else INPUT_WORDS.get(base, (base, ""))[0]
    return words + (f" of rig {rig}" if rig else "")


SUPERSCRIPT = str.maketrans("-0123456789", "⁻⁰¹²³⁴⁵⁶⁷⁸⁹")


def _number(value: float, unit: str) -> str:
    """±value in two significant digits, ×10ⁿ where plain digits would be long (±2.0×10⁻⁵ m³)."""
    if value and not 1e-3 <= abs(value) < 1e4:
        exponent = math.floor(math.log10(abs(value)))
        text = f"{value / 10**exponent:.2g}×10{str(exponent).translate(SUPERSCRIPT)}"
    else:
        text = f"{value:.2g}"
    return f"±{text} {unit}".rstrip()


def stated_by_rig(trial_rigs: dict) -> dict:
    """Rig → the 1σ tolerances all its trials state alike (``trial_rigs``: trial → ``name``, ``tolerances``, as
    :func:`pendulum.groups.group_trial_rigs`); a value one trial's sidecar states and another's does not is the
    default share for some of them, so it is not 'as stated' for the rig."""
    by_rig: dict[str, list] = {}
    for entry in trial_rigs.values():
        by_rig.setdefault(entry["name"], []).append(dict(entry.get("tolerances") or {}))
    return {rig: tolerances_alike(stated)[0] for rig, stated in by_rig.items()}


def _tolerance_text(key: str, tolerances: dict, stated: dict) -> str:
    """Today's 1σ tolerance of an input, and whether it was stated or is the default share of the value."""
    base, rig = split_key(key)
    unit = INPUT_WORDS.get(base, ("", ""))[1]
    rig_name = rig or next(iter(tolerances), None)
    value = (tolerances.get(rig_name) or {}).get(base)
    if value is None:
        return ""
    if base in (stated.get(rig_name) or {}):
        return f"{_number(value, unit)}, 1σ, as stated"
    return (
        f"{_number(value, unit)}, 1σ: the default share of its value; state yours under rigs.{rig_name}.tolerances "
        "in config.yaml, or under tolerances in the sidecar that gives the value"
    )


def percent(value: float) -> str:
    """A percentage in two figures, never in e-notation: 3.9, 47, 190, 2300."""
    rounded = float(f"{value:.2g}")
    if rounded == 0:
        return "0"
    decimals = max(0, 1 - math.floor(math.log10(abs(rounded))))
    return f"{rounded:.{decimals}f}"


def measurement_advice(
    name: str, words: str, entry: dict, parameter: dict, target: float, tolerances: dict, stated: dict
) -> dict:
    """Why ``target`` (95 % half-width / value) cannot be reached by trials, and which inputs to measure how well.

    ``entry``: today's (value, stderr_statistical, stderr_systematic); ``parameter``: the coefficient's reported
    entry (``error_budget``: input → shift per 1σ); ``tolerances`` / ``stated``: rig → input → 1σ (all, stated).
    """
    value = abs(entry["value"])
    if not value > 1e-6 * Z95 * math.hypot(entry["stderr_statistical"], entry.get("stderr_systematic", 0.0)):
        return {  # at its bound (zero): no share of it is an interval
            "limited_by": "",
            "measure": [],
            "sentence": f"{words} is at zero (its bound): an interval of ±{100 * target:g} % of it cannot be reached",
        }
    budget = {k: abs(float(v)) for k, v in (parameter.get("error_budget") or {}).items() if v}
    order = sorted(budget, key=lambda k: -budget[k])
    if not order:
        return {"limited_by": "", "measure": [], "sentence": f"±{100 * target:g} % for {words} cannot be reached"}
    allowed = (target * value / Z95) ** 2 - entry["stderr_statistical"] ** 2
    floor = 100 * entry["floor_relative_halfwidth95"]
    first = order[0]
    head = (
        f"±{100 * target:g} % for {words} cannot be reached by more trials: the rig values' tolerances alone give "
        f"±{percent(floor)} % (95 %), most of it from {input_words(first)}"
    )
    tolerance = _tolerance_text(first, tolerances, stated)
    head += f" ({tolerance}: ±{percent(100 * Z95 * budget[first] / value)} %)" if tolerance else ""
    # the fewest largest inputs that, measured better by one common factor f, bring the target within reach
    total = sum(budget[k] ** 2 for k in order)
    for n in range(1, len(order) + 1):
        rest = total - sum(budget[k] ** 2 for k in order[:n])
        if allowed - rest > 0:
            break
    else:
        return {
            "limited_by": first,
            "measure": [],
            "sentence": head + f"; the statistical part alone exceeds ±{100 * target:g} %",
        }
    chosen = order[:n]
    factor = math.sqrt((allowed - rest) / sum(budget[k] ** 2 for k in chosen))
    measure, steps = [], []
    for key in chosen:
        base, rig = split_key(key)
        today_1s = (tolerances.get(rig or next(iter(tolerances), None)) or {}).get(base)
        to = None if today_1s is None else today_1s * factor
        measure.append({"input": key, "to_1sigma": to, "factor": factor})
        unit = INPUT_WORDS.get(base, ("", ""))[1]
        steps.append(input_words(key) + ("" if to is None else f" to {_number(to, unit)}"))
    listing = steps[0] if len(steps) == 1 else ", ".join(steps[:-1]) + " and " + steps[-1]
    times = f"{1 / factor:.2g}× as precisely" if factor > 0 else "exactly"
    sentence = head + f". Measuring {listing} (1σ; {times} as today) would reach ±{100 * target:g} %"
    if any(split_key(k)[0] == "displaced_volume_m3" for k in chosen):  # a weighed rig has no volume entry
        # the reading stands for the buoyancy's inputs alone: another input in the list is still to be measured
        others = [input_words(k) for k in chosen if split_key(k)[0] not in BUOYANCY_INPUTS]
        sentence += (
            "; or weigh the body hung in the fluid and state that reading as submerged_mass_kg (m − ρV) in place of "
            "the volume: one scale reading settles the buoyancy, which the volume and density set together"
            + (f" ({' and '.join(others)} still to be measured as above)" if others else "")
        )
    return {
        "limited_by": first,
        "measure": measure,
        "sentence": sentence,
    }
