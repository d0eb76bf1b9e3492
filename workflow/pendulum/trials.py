"""Trials: discovery in the raw folder, sidecars, and each trial's merged settings."""

from __future__ import annotations

import difflib
import math
import re
from dataclasses import dataclass, field
from pathlib import Path

import jsonschema
import yaml

from pendulum.model.rig import BUOYANCY_KEYS, RIG_VALUE_UNITS

SCHEMA_DIR = Path(__file__).resolve().parents[1] / "schemas"
RIG_KEYS = tuple(RIG_VALUE_UNITS)  # every rig value a rig or sidecar may state
GEOMETRY_KEYS = ("pivot_px", "vertical_deg")
REQUIRED_RIG_KEYS = ("mass_kg", "length_m", "frontal_area_m2")  # a rig defined in a sidecar must give these
TRACKING_KEYS = ("marker_radius_px", "polarity", "start_px", "method", "capture_fps")
# a number as YAML 1.2 (and a person) writes it; PyYAML (YAML 1.1) leaves 5e-05 or 1e3 as text
NUMBER_TEXT = re.compile(r"^[-+]?(\.[0-9]+|[0-9]+(\.[0-9]*)?)([eE][-+]?[0-9]+)?$")


class ConfigError(ValueError):
    """A configuration or sidecar problem; the message names the file and the key."""


TYPE_WORDS = {
    "number": "a number",
    "integer": "a whole number",
    "string": "text",
    "boolean": "true or false",
    "array": "a list",
    "object": "a mapping (key: value lines)",
    "null": "empty",
}

BOUND_WORDS = {
    "exclusiveMinimum": "greater than",
    "minimum": "at least",
    "exclusiveMaximum": "less than",
    "maximum": "at most",
}


def _short(value, limit: int = 60) -> str:
    text = repr(value)
    return text if len(text) <= limit else text[: limit - 1] + "…"


def _schema_problem(err: jsonschema.ValidationError) -> str:
    """One schema error in words: where, what is wrong and, for a misspelt key, the likely key."""
    where = "/".join(str(p) if str(p).isprintable() else repr(p) for p in err.absolute_path)  # a key '\n' on one line
    at = f" in {where}" if where else ""
    kind, value = err.validator, err.instance
    if kind == "additionalProperties" and isinstance(value, dict):
        known = list(err.schema.get("properties", {}))
        unknown = [k for k in value if k not in known]
        parts = []
        for key in unknown:
            close = difflib.get_close_matches(str(key), known, n=1, cutoff=0.6)
            parts.append(f"unknown key {_short(key)}{at}" + (f" (did you mean {close[0]!r}?)" if close else ""))
        return "; ".join(parts) or err.message
    if kind == "required":
        return f"missing key {err.message.split(chr(39))[1]!r}{at}" if "'" in err.message else err.message
    if kind == "type":
        expected = err.validator_value if isinstance(err.validator_value, list) else [err.validator_value]
        words = " or ".join(TYPE_WORDS.get(t, t) for t in expected)
        return f"{where or 'the document'} is {_short(value)}, not {words}"
    if kind in ("enum", "const"):
        return f"{where or 'the value'} is {_short(value)}, not one of {err.validator_value}"
    if kind in BOUND_WORDS:
        return f"{where} is {_short(value)}; it must be {BOUND_WORDS[kind]} {err.validator_value:g}"
    if kind == "minProperties" and where == "variants":
        return "no model variants: give at least one under variants (e.g. quadratic: [quadratic_drag])"
    return f"{where or 'the document'}: {err.message}"


def _as_number(value, expected: list):
    """``value`` as the number a person meant where the schema wants one (``expected``: its types), or None.

    Text that YAML 1.2 reads as a number (``5e-05``, ``1E3``, ``+2.5``: PyYAML's YAML 1.1 leaves exponents
    without a dot as text) becomes a float, or an int where only a whole number is wanted and it is one;
    a whole float (``60.0``) where a whole number is wanted becomes an int.
    """
    wants_number, wants_integer = "number" in expected, "integer" in expected
    if isinstance(value, str) and (wants_number or wants_integer) and NUMBER_TEXT.match(value.strip()):
        number = float(value)
        if wants_number:
            return number
        return int(number) if math.isfinite(number) and number.is_integer() else None
    if isinstance(value, float) and wants_integer and math.isfinite(value) and value.is_integer():
        return int(value)
    return None


def _set_at(document, path, value) -> None:
    *parents, last = list(path)
    for key in parents:
        document = document[key]
    document[last] = value


def _with_context(errors):
    """Schema errors and, under oneOf/anyOf, the errors of each alternative."""
    for err in errors:
        yield err
        yield from _with_context(err.context or ())


def _numbers_as_written(document, validator) -> None:
    """Numbers written as people write them, read as numbers in place (:func:`_as_number`); again until none is
    left (a fix can uncover another error under oneOf)."""
    changed = True
    while changed:
        changed = False
        for err in _with_context(validator.iter_errors(document)):
            if err.validator != "type" or not err.absolute_path:
                continue
            expected = err.validator_value if isinstance(err.validator_value, list) else [err.validator_value]
            number = _as_number(err.instance, expected)
            if number is not None:
                _set_at(document, err.absolute_path, number)
                changed = True


# JSON Schema counts 16.0 as an integer; here a whole float is made an int (:func:`_as_number`), so code
# given a whole number gets an int
STRICT_INTEGERS = jsonschema.validators.extend(
    jsonschema.Draft202012Validator,
    type_checker=jsonschema.Draft202012Validator.TYPE_CHECKER.redefine(
        "integer", lambda _checker, value: isinstance(value, int) and not isinstance(value, bool)
    ),
)


def _validate(document, schema_name: str, source: str) -> None:
    if not isinstance(document, dict):
        raise ConfigError(f"{source}: must be a mapping of keys to values, not {type(document).__name__}")
    schema = yaml.safe_load((SCHEMA_DIR / schema_name).read_text())
    validator = STRICT_INTEGERS(schema)
    _numbers_as_written(document, validator)
    errors = sorted(validator.iter_errors(document), key=lambda e: [str(p) for p in e.absolute_path])
    if errors:
        problems = list(dict.fromkeys(_schema_problem(e) for e in errors))
        more = f" (and {len(problems) - 3} more)" if len(problems) > 3 else ""
        raise ConfigError(f"{source}: " + "; ".join(problems[:3]) + more)
    bad = _non_finite(document)
    if bad:
        raise ConfigError(f"{source}: {bad[0]} is {bad[1]}; give a finite number")


def _non_finite(value, where: str = ""):
    """(path, value) of the first NaN or infinite number in a document, or None."""
    if isinstance(value, float) and not math.isfinite(value):
        return where, value
    items = value.items() if isinstance(value, dict) else enumerate(value) if isinstance(value, list) else ()
    for key, item in items:
        found = _non_finite(item, f"{where}/{key}" if where else str(key))
        if found:
            return found
    return None


def check_rig_values(values: dict, where: str) -> None:
    """Physical sense of a rig's values: the pendulum must sink (weight above buoyancy)."""
    mass, volume = values.get("mass_kg"), values.get("displaced_volume_m3") or 0.0
    rho, g = values.get("fluid_density_kg_m3", 1000.0), values.get("gravity_m_s2", 9.81)
    if mass is None:
        return
    submerged = values.get("submerged_mass_kg")  # the body weighed hung in the fluid, m − ρV: its buoyancy
    if submerged is not None:
        if volume:
            raise ConfigError(f"{where}: gives both displaced_volume_m3 and submerged_mass_kg: give one")
        if not 0 < submerged <= mass:
            floats = "must be above 0 (at 0 or below the body floats)"
            raise ConfigError(f"{where}: submerged_mass_kg {submerged:g} {floats} and at most mass_kg {mass:g}")
        return
    weight, buoyancy = mass * g, rho * volume * g
    if buoyancy >= weight:
        water = (
            " (not given: water's 1000 kg/m³ assumed; a rig in air gives fluid_density_kg_m3: 1.2)"
            if "fluid_density_kg_m3" not in values
            else ""
        )
        raise ConfigError(
            f"{where}: the pendulum floats: buoyancy ρ V g = {rho:g} × {volume:g} × {g:g} = {buoyancy:.4g} N is not "
            f"below the weight m g = {mass:g} × {g:g} = {weight:.4g} N; check mass_kg, displaced_volume_m3 (m³) and "
            f"fluid_density_kg_m3{water}"
        )


def check_tolerances(tolerances: dict, values: dict, where: str) -> None:
    """Each 1σ tolerance finite and at most a quarter of its value (a fraction given for an absolute 1σ)."""
    for key, sigma in tolerances.items():
        value = values.get(key)
        if not math.isfinite(sigma):
            raise ConfigError(f"{where}/{key} is {sigma!r}; give a finite 1σ")
        if value is not None and sigma > 0 and value == 0:
            raise ConfigError(f"{where}/{key} = {sigma:g} is the tolerance of a {key} of 0; give the value or drop it")
        if value is not None and sigma > 0.25 * abs(value):
            raise ConfigError(
                f"{where}/{key} = {sigma:g} is {100 * sigma / abs(value):.0f} % of {key} = {value:g}; tolerances "
                f"are 1σ in the value's own unit (e.g. {0.01 * abs(value):.3g} for 1 %), not fractions"
            )


def trial_tolerances(rig: dict, sidecar: dict) -> dict:
    """The 1σ tolerances stated for one trial's rig values: the rig's, less those of values its sidecar changes
    (the rig's tolerance was stated for the rig's value, not this one: a 5 g scale error is 0.14 % of a 3.5 kg
    vehicle and 2.8 % of a 180 g apple), then the sidecar's own ``tolerances``. A value left without one takes
    the default fraction (:data:`pendulum.fit.records.DEFAULT_RELATIVE_TOLERANCES`) downstream."""
    stated = rig.get("tolerances") or {}
    kept = {k: v for k, v in stated.items() if k not in sidecar or sidecar[k] == rig.get(k)}
    return {**kept, **(sidecar.get("tolerances") or {})}


def validate_config(config: dict, source: str = "config.yaml") -> None:
    """Schema check, finite numbers, rigs that sink, and cross-references (default rig exists)."""
    if isinstance(config, dict) and config.get("variants") in (None, [], {}) and "variants" in config:
        raise ConfigError(
            f"{source}: no model variants: give at least one under variants (e.g. quadratic: [quadratic_drag])"
        )
    if isinstance(config, dict) and isinstance(config.get("variants"), dict):
        empty = [name for name, terms in config["variants"].items() if terms is None]
        if empty:
            raise ConfigError(f"{source}: variants {empty} have no term list (use [] for added mass only)")
    _validate(config, "config.schema.yaml", source)
    for rig, values in config["rigs"].items():
        check_rig_values(values, f"{source}: rigs/{rig}")
        check_tolerances(values.get("tolerances") or {}, values, f"{source}: rigs/{rig}/tolerances")
    cameras = config.get("cameras") or {}
    for rig, values in config["rigs"].items():
        if values.get("camera") is not None and values["camera"] not in cameras:
            raise ConfigError(
                f"{source}: rigs/{rig}/camera is {values['camera']!r}, not one of cameras {sorted(cameras)}"
            )
    for name, setup in cameras.items():
        if not setup.get("calibration_video") and not setup.get("plane_video"):
            raise ConfigError(
                f"{source}: cameras/{name} gives neither calibration_video (lens) nor plane_video (swing plane)"
            )
    if config["default_rig"] not in config["rigs"]:
        raise ConfigError(
            f"{source}: default_rig {config['default_rig']!r} is not one of rigs {sorted(config['rigs'])}"
        )


@dataclass
class Trial:
    name: str
    kind: str  # "video" or "angles" (an angle table entering at the angles stage)
    path: str
    sidecar: dict = field(default_factory=dict)
    sidecar_path: str | None = None


def split_skipped(trials: dict[str, Trial]) -> tuple[dict[str, Trial], dict[str, dict]]:
    """The trials to build, and those whose sidecar says ``skip: <why>`` (or ``true``), name → ``source``,
    ``reason``: no job runs for them; the status table and the report list them as skipped; they fail nothing."""
    for t in trials.values():
        if isinstance(t.sidecar.get("skip"), str) and not t.sidecar["skip"].strip():
            raise ConfigError(
                f'{t.sidecar_path}: skip is blank; write why the trial is left out (skip: "the marker '
                'fell off"), or true'
            )
    skipped = {
        name: {
            "source": t.path,
            "reason": f"skipped by {t.sidecar_path}"
            + (f": {t.sidecar['skip'].strip()}" if isinstance(t.sidecar["skip"], str) else " (no reason given)"),
        }
        for name, t in trials.items()
        if t.sidecar.get("skip")  # a reason, or true
    }
    return {name: t for name, t in trials.items() if name not in skipped}, skipped


def read_sidecar(path: str | Path) -> dict:
    """A trial's sidecar YAML, validated; every problem raises :class:`ConfigError` naming the file."""
    path = Path(path)
    try:
        text = path.read_text(encoding="utf-8")
    except UnicodeDecodeError as exc:
        raise ConfigError(f"{path}: not a text file (byte {exc.start} is not UTF-8); write it as plain YAML") from exc
    try:
        doc = yaml.safe_load(text)
    except yaml.YAMLError as exc:
        mark = getattr(exc, "problem_mark", None)
        at = f"line {mark.line + 1}, column {mark.column + 1}: " if mark is not None else ""
        problem = getattr(exc, "problem", None) or str(exc).splitlines()[0]
        raise ConfigError(f"{path}: not valid YAML ({at}{problem}); fix the file") from exc
    if doc is None:
        return {}
    if not isinstance(doc, dict):
        hint = ""
        if isinstance(doc, str) and re.search(r"^\s*[A-Za-z_]\w*:\S", doc):  # rig:air is YAML text, rig: air a key
            hint = f" (it reads as the text {doc.strip()[:40]!r}: write a space after each key's colon, e.g. rig: air)"
        raise ConfigError(
            f"{path}: must be a mapping of keys to values (e.g. mass_kg: 3.5), not {type(doc).__name__}{hint}"
        )
    _validate(doc, "sidecar.schema.yaml", str(path))
    return doc


def rig_trials(settings: dict[str, dict]) -> dict[str, list[str]]:
    """Trial names of each rig (every trial, video or angle table), from their :func:`settings_of_trials`."""
    by_rig: dict[str, list[str]] = {}
    for name in sorted(settings):
        by_rig.setdefault(settings[name]["rig_name"], []).append(name)
    return by_rig


def rig_name(config: dict, trial: Trial) -> str:
    name = trial.sidecar.get("rig", config["default_rig"])
    if name not in config["rigs"]:
        rigs = sorted(config["rigs"])
        digits = re.findall(r"\d+", str(name))  # not another year's or number's rig
        close = [r for r in rigs if r.lower() == str(name).lower()] or [
            r for r in difflib.get_close_matches(str(name), rigs, 1) if re.findall(r"\d+", r) == digits
        ]
        raise ConfigError(
            f"{trial.sidecar_path}: rig {name!r} is not one of rigs {rigs} (config.yaml's, and those the sidecars "
            f"define); {f'did you mean {close[0]!r}? Or ' if close else ''}define it there, or give its "
            f"{', '.join(REQUIRED_RIG_KEYS)} in this sidecar"
        )
    return name


def settings_of_trials(config: dict, trials: dict[str, Trial]) -> dict[str, dict]:
    """Each trial's :func:`trial_settings`, by name; every bad sidecar named at once (one :class:`ConfigError`, a
    line each), not the first of hundreds per run."""
    settings, problems = {}, []
    for name in sorted(trials):
        try:
            settings[name] = trial_settings(config, trials[name])
        except ConfigError as exc:
            problems.append(str(exc))
    if problems:
        raise ConfigError(all_problems(problems, "sidecars"))
    return settings


def all_problems(problems: list[str], what: str) -> str:
    """One message for several problems, a line each (one alone: itself)."""
    return problems[0] if len(problems) == 1 else f"{len(problems)} {what} have problems:\n" + "\n".join(problems)


def add_sidecar_rigs(config: dict, trials: dict[str, Trial]) -> list[str]:
    """Rigs defined in sidecars, added to ``config["rigs"]``; returns their names.

    A sidecar that names a rig not in config and gives at least its
    mass_kg, length_m and frontal_area_m2 defines that rig (its rig values,
    ``tolerances`` and ``camera``; the first such sidecar by trial name). Its other trials may
    name it without values. The geometry (pivot, vertical) stays estimated.
    """
    added = []
    for name in sorted(trials):
        trial = trials[name]
        rig = trial.sidecar.get("rig")
        if rig is None or rig in config["rigs"] or not all(k in trial.sidecar for k in REQUIRED_RIG_KEYS):
            continue
        values = {k: trial.sidecar[k] for k in RIG_KEYS if k in trial.sidecar}
        check_rig_values(values, f"{trial.sidecar_path} (defining rig {rig})")
        if trial.sidecar.get("camera") is not None:
            if trial.sidecar["camera"] not in (config.get("cameras") or {}):
                raise ConfigError(
                    f"{trial.sidecar_path}: camera {trial.sidecar['camera']!r} is not one of cameras "
                    f"{sorted(config.get('cameras') or {})} in config.yaml"
                )
            values["camera"] = trial.sidecar["camera"]
        if trial.sidecar.get("tolerances"):  # the defining sidecar's tolerances are the rig's
            check_tolerances(trial.sidecar["tolerances"], values, f"{trial.sidecar_path}: tolerances")
            values["tolerances"] = dict(trial.sidecar["tolerances"])
        config["rigs"][rig] = values
        added.append(rig)
    return added


def trial_settings(config: dict, trial: Trial) -> dict:
    """Rig values, geometry and tracking settings of one trial: config, then rig, then sidecar."""
    rig = rig_name(config, trial)
    merged_rig = {**config["rigs"][rig]}
    own_mass = trial.sidecar.get("mass_kg", merged_rig.get("mass_kg")) != merged_rig.get("mass_kg")
    if own_mass and "submerged_mass_kg" in merged_rig and not set(BUOYANCY_KEYS) & set(trial.sidecar):
        raise ConfigError(
            f"{trial.sidecar_path}: gives mass_kg {trial.sidecar['mass_kg']:g} on rig {rig}, which states its buoyancy "
            "by submerged_mass_kg (weighed at its own mass): give this trial's submerged_mass_kg, weighed as it swung, "
            "or its displaced_volume_m3"
        )
    for given, replaced in (BUOYANCY_KEYS, BUOYANCY_KEYS[::-1]):  # a sidecar's own buoyancy replaces the rig's
        if given in trial.sidecar:
            merged_rig.pop(replaced, None)
    merged_rig.update({k: v for k, v in trial.sidecar.items() if k in RIG_KEYS + GEOMETRY_KEYS})
    if any(k in RIG_KEYS for k in trial.sidecar):
        check_rig_values(merged_rig, f"{trial.sidecar_path} (with rig {rig})")
    tolerances = trial_tolerances(config["rigs"][rig], trial.sidecar)
    check_tolerances(trial.sidecar.get("tolerances") or {}, merged_rig, f"{trial.sidecar_path}: tolerances")
    tracking = {**config["tracking"]}
    tracking.update({k: v for k, v in trial.sidecar.items() if k in TRACKING_KEYS})
    camera = config["rigs"][rig].get("camera")
    if "camera" in trial.sidecar and trial.sidecar["camera"] != camera:
        raise ConfigError(
            f"{trial.sidecar_path}: camera {trial.sidecar['camera']!r} differs from rig {rig}'s camera {camera!r}; "
            "camera setups belong to a rig: define a rig for this camera (in config or in this sidecar)"
        )
    return {
        "rig_name": rig,
        "rig": {k: merged_rig[k] for k in RIG_KEYS if k in merged_rig},
        "tolerances": tolerances,
        "pivot_px": merged_rig.get("pivot_px"),
        "vertical_deg": merged_rig.get("vertical_deg"),
        "geometry_from_sidecar": any(k in trial.sidecar for k in GEOMETRY_KEYS),
        "own_pivot": "pivot_px" in trial.sidecar,
        "camera": camera,
        "tracking": tracking,
    }


def needs_rig_geometry(config: dict, trial: Trial) -> bool:
    """True when a video trial's pivot or vertical must be estimated from the rig's pooled tracks.

    A trial whose sidecar gives its own pivot_px but no vertical estimates the
    vertical from its own track (at the angles stage), not from the rig's.
    """
    s = trial_settings(config, trial)
    if trial.kind != "video" or s["own_pivot"]:
        return False
    return s["pivot_px"] is None or s["vertical_deg"] is None


def pooled_trials(config: dict, trials: dict[str, Trial], rig: str) -> list[str]:
    """Video trials whose tracks define the rig's estimated geometry (not those with their own).

    When every trial of the rig gives a vertical_deg of its own (but no pivot),
    their tracks are pooled for the pivot.
    """
    videos = [n for n, t in trials.items() if t.kind == "video" and rig_name(config, t) == rig]
    pooled = sorted(n for n in videos if not trial_settings(config, trials[n])["geometry_from_sidecar"])
    if not pooled:
        pooled = sorted(n for n in videos if not trial_settings(config, trials[n])["own_pivot"])
    return pooled


def kept_geometry_trials(document: dict | None, current: list[str], video_trials) -> list[str]:
    """The trials a rig's kept geometry (its JSON ``document``) stays estimated from; ``current`` where it must be
    estimated again.

    Kept while every trial its pivot rests on (``trials`` less ``rejected_trials``) is still one of the rig's
    (``current``) and every trial it read (``input_trials``) still exists (``video_trials``), also one that has
    since left for another rig: a clip that failed or was left out of the pooled pivot (another pendulum) and is
    then given its own rig by a sidecar changes nothing the rig's geometry rests on, so its other trials are not
    rebuilt (a reviewer's apple rebuilt 7 angle records and 21 fits, byte for byte the same, 2026-12-02)."""
    kept = (document or {}).get("input_trials")
    if not kept:
        return current
    used = set(document.get("trials") or kept) - set(document.get("rejected_trials") or {})
    if not used <= set(current) or not set(kept) <= set(video_trials):
        return current
    return sorted(kept)
