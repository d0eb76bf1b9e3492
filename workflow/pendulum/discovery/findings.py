"""What discovery hands to the report: the one-line verdict, the residuals and the extinction curves per model."""

from __future__ import annotations

import math

import pandas as pd

from pendulum.discovery import diagnosis
from pendulum.fit.group import ordered
from pendulum.fit.uncertainty import Z95
from pendulum.model.effects import TERMS

RESIDUAL_COLUMNS = ["model", "trial", "time_s", "residual_rad"]
EXTINCTION_COLUMNS = ["model", "trial", "amplitude_rad", "mean_amplitude_rad", "amplitude_loss_rad"]


ANOTHER_FREQUENCY = (
    "trials at another pendulum length or payload (another swing frequency), declared as one body under "
    "`bodies:`: the history force's equivalent added mass falls as ω^−½ and its damping grows as ω^½, an added "
    "mass's and a linear damping's do not"
)
WIDER_AMPLITUDES = (
    "a record over a wider range of amplitudes (a higher release, recorded until the swing has nearly stopped): "
    "the loss per half cycle is constant for Coulomb friction, ∝ A for linear damping, ∝ A² for quadratic drag"
)


def separating_experiments(effects) -> list[tuple[str, str]]:
    """(short name, how) of the experiments that tell the effects of an indistinguishable group apart."""
    out = []
    if len({TERMS[e].extinction_power for e in effects}) > 1:
        out.append(("a wider range of amplitudes", WIDER_AMPLITUDES))
    if "history_force" in effects and "linear_damping" in effects:
        out.append(("another pendulum length", ANOTHER_FREQUENCY))
    return out or [("another pendulum length", ANOTHER_FREQUENCY)]


def plus_minus(value: float, error: float) -> str:
    """value ± error, the error to one significant digit (two when it starts with 1)."""
    if not (error > 0 and math.isfinite(error)):
        return f"{value:.4g}"
    exponent = math.floor(math.log10(error))
    digits = max(0, -exponent + (1 if error / 10**exponent < 2 else 0))
    return f"{value:.{digits}f} ± {error:.{digits}f}"


def _deg(rad: float) -> str:
    return f"{math.degrees(rad):.2g}°"


def verdict(document: dict) -> str:
    """One line: the missing effects with their coefficients (value ± 1.96σ, the 95 % interval of the
    report's tables) and the RMS before → after (in sample and held out), the indistinguishable groups, and
    whether structure is left unexplained."""
    base, check = document["baseline"], document["residual_check"]
    rms = (
        f"RMS {_deg(base['rms_rad'])} → {_deg(document['rms_rad'])} "
        f"(held out {_deg(base['held_out_rms_rad'])} → {_deg(document['held_out_rms_rad'])})"
    )
    parts = []
    for name in document["named_effects"]:
        term = TERMS[name]
        values = [  # value ± 1.96σ: the 95 % interval the report's tables show
            f"{term.symbol}{label[len(term.parameter) :]} = {plus_minus(e['value'], Z95 * e['stderr'])} {term.unit}"
            " (95 %)"
            for label, e in document["parameters"].items()
            if label.split("[")[0] == term.parameter
        ]
        parts.append(f"{term.label}, {', '.join(values)}")
    text = []
    if parts:
        text.append(f"missing effect{'s' if len(parts) > 1 else ''}: {'; '.join(parts)}; {rms}")
    for group in document["indistinguishable"]:
        names = " or ".join(TERMS[e].label for e in group["effects"])
        text.append(
            f"indistinguishable: {names} ({group['reason']}; {' or '.join(group['separated_by'])} would separate them)"
        )
    if document["unexplained"]:
        text.append(
            f"unexplained: the residual ({_deg(document['rms_rad'])} RMS) is {check['rms_over_noise']:.0f}× the noise "
            "floor and not white, and no candidate removes it" + pattern_phrase(document.get("residual_pattern"))
        )
    elif not parts and not document["indistinguishable"]:
        white = "" if check["whiteness"]["p_value"] >= 0.01 else ", not white"
        text.append(
            f"no missing effect: no candidate improves {' + '.join(base['terms'])} (RMS {_deg(document['rms_rad'])}, "
            f"{check['rms_over_noise']:.1f}× the noise floor{white})"
        )
    mass = document["parameters"].get("added_mass_kg", {})
    if mass.get("at_bound"):
        text.append(
            f"the swing is faster than the rig values allow with an added mass ≥ {mass['lower_bound']:g} kg: check "
            "length_m and mass_kg (for a swing in air, allow a negative added mass: fitting.added_mass_lower_kg)"
        )
    return "; ".join(text)


PATTERN_MEANING = {  # what each part of an unexplained residual (diagnosis.residual_pattern) says of the record
    "slow": "below half the swing frequency: a camera or stand creeping, a pivot settling, a vertical drifting; not "
    "the swing's dynamics",
    "swing_steady": "the swing's decay or period departs from the model's as no candidate's does: a damping or "
    "stiffness of another form, wrong rig values, or a swing whose plane or scale changes as seen",
    "swing_steady_timing": "the swing runs ahead of and behind the model by {wander} ms RMS: frame times that wander, "
    "a period that changes over the record as the model's does not, or rig values that leave the model's period "
    "wrong, its added mass held at a bound",
    "swing_steady_amplitude": "the swing's decay departs from the model's as no candidate's does: a damping of another "
    "form, or a scale that changes as seen",
    "swing_wobble": "the swing's amplitude or phase wobbling{every}: a swing not in one plane seen in projection, a "
    "support that sways, or another motion beating with the swing",
    "even_harmonic": "an equation symmetric in θ makes no such harmonic: most likely a lopsided angle measurement, a "
    "swing plane turned against the image plane or a pivot or vertical misplaced; or a torque that differs between "
    "the swing's two sides",
    "odd_harmonic": "the swing's shape departs from the model's: its restoring torque's form, a body that is no point "
    "mass, a flexible suspension",
}


TIMING_SHARE = 0.7  # a steady departure said to lie in the swing's timing (or, under 1 − this, its amplitude)
PATTERN_PLACE = {  # the same parts in a few words (the report's list of where the residual's power lies)
    "slow": "a slow drift of the zero",
    "swing_steady": "at the swing frequency, changing slowly",
    "swing_steady_timing": "at the swing frequency, in its timing",
    "swing_steady_amplitude": "at the swing frequency, in its amplitude",
    "swing_wobble": "in side bands about the swing frequency (a wobble)",
    "even_harmonic": "at twice the swing frequency",
    "odd_harmonic": "at three times the swing frequency",
}


def pattern_phrase(pattern: dict | None) -> str:
    """``; it lies mostly <where>, n % of its power (<what that means>)``: the dominant parts of an unexplained
    residual (:data:`PATTERN_PLACE`, :data:`PATTERN_MEANING`), or ''."""
    if not pattern or not pattern.get("shares") or not pattern.get("dominant"):
        return ""
    wobble = pattern.get("wobble_period_s")
    every = f", every {wobble:.3g} s" if wobble else ""
    wander = pattern.get("timing_wander_ms")
    parts = []
    for name in pattern["dominant"]:
        part = part_name(pattern, name)
        meaning = PATTERN_MEANING[part].format(every=every, wander=f"{wander or 0:.3g}")
        share = 100 * pattern["shares"][name] * pattern["structured"]
        parts.append(f"{PATTERN_PLACE[part]}, {share:.0f} % of its power ({meaning})")
    return "; it lies mostly " + "; and ".join(parts)


def part_name(pattern: dict, name: str) -> str:
    """``name``, or for the steady part at the swing frequency whether it lies in the swing's timing or amplitude
    (``steady_in_timing`` at least :data:`TIMING_SHARE`, or at most 1 − it)."""
    timing = pattern.get("steady_in_timing")
    if name != "swing_steady" or timing is None:
        return name
    if timing >= TIMING_SHARE:
        return "swing_steady_timing"
    return "swing_steady_amplitude" if timing <= 1 - TIMING_SHARE else name


def _key(terms) -> str:
    return "+".join(terms)


def tables(run, document: dict) -> tuple[pd.DataFrame, pd.DataFrame]:
    """Residuals of every model on the path (baseline, after each step, final) and the extinction curves.

    Residuals: ``model`` (its terms joined by ``+``), ``trial``, ``time_s``, ``residual_rad`` (model −
    measured) on the fitted samples. Extinction: ``model``
    (``measured``, or a model: those on the path and each first-round candidate's refit, predicted by
    the same half-cycle analysis on its fitted curve), ``trial``, ``amplitude_rad``,
    ``mean_amplitude_rad``, ``amplitude_loss_rad``.
    """
    path = [ordered(document["baseline"]["terms"])]
    for step in document["steps"]:
        path.append(ordered(path[-1] + (step["effect"],)))
    path = list(dict.fromkeys([*path, ordered(document["final_terms"])]))
    first = document["rounds"][0]["candidates"] if document["rounds"] else []
    candidates = [ordered(path[0] + (c["effect"],)) for c in first]
    residuals = []
    for terms in path:
        fit = run.fit(terms)
        for k, record in enumerate(run.records):
            mask = run.masks[k]
            residual = (fit.trial_curve(k) - record.theta_rad)[mask]
            residuals.append(
                pd.DataFrame(
                    {
                        "model": _key(terms),
                        "trial": record.trial,
                        "time_s": record.time_s[mask],
                        "residual_rad": residual,
                    }
                )
            )
    curves = [diagnosis.measured_half_cycles(run.fit(path[0])).assign(model="measured")]
    for terms in dict.fromkeys(path + candidates):
        curves.append(diagnosis.predicted_half_cycles(run.fit(terms)).assign(model=_key(terms)))
    return (
        pd.concat(residuals, ignore_index=True)[RESIDUAL_COLUMNS],
        pd.concat(curves, ignore_index=True)[EXTINCTION_COLUMNS],
    )
