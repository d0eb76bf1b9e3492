"""Trials: discovery in the raw folder, sidecars, and each trial's merged settings."""

from __future__ import annotations

import math
import re
from dataclasses import dataclass, field
from pathlib import Path

import jsonschema
import yaml

from pendulum.video import VIDEO_EXTENSIONS

SCHEMA_DIR = Path(__file__).resolve().parents[1] / "schemas"
RIG_KEYS = (
    "mass_kg",
    "length_m",
    "frontal_area_m2",
    "displaced_volume_m3",
    "fluid_density_kg_m3",
    "gravity_m_s2",
    "body_inertia_kg_m2",
    "characteristic_length_m",
    "kinematic_viscosity_m2_s",
)
GEOMETRY_KEYS = ("pivot_px", "vertical_deg")
TRACKING_KEYS = ("marker_radius_px", "polarity", "start_px")
ANGLE_TABLE_EXTENSIONS = (".csv",)
TRIAL_NAME = re.compile(r"^[A-Za-z0-9][A-Za-z0-9_.+-]*$")
RESERVED_NAMES = ("joint", "summary")  # file names of the aggregate fits


class ConfigError(ValueError):
    """A configuration or sidecar problem; the message names the file and the key."""


def _validate(document: dict, schema_name: str, source: str) -> None:
    schema = yaml.safe_load((SCHEMA_DIR / schema_name).read_text())
    validator = jsonschema.Draft202012Validator(schema)
    errors = sorted(validator.iter_errors(document), key=lambda e: list(e.absolute_path))
    if errors:
        lines = []
        for err in errors:
            where = "/".join(str(p) for p in err.absolute_path) or "(top level)"
            lines.append(f"  {where}: {err.message}")
        raise ConfigError(f"{source} is invalid:\n" + "\n".join(lines))


def validate_config(config: dict, source: str = "config.yaml") -> None:
    """Schema check plus cross-references (default rig exists)."""
    _validate(config, "config.schema.yaml", source)
    empty = [name for name, terms in config["variants"].items() if terms is None]
    if empty:
        raise ConfigError(f"{source}: variants {empty} have no term list (use [] for added mass only)")
    for rig, values in config["rigs"].items():
        for key, sigma in (values.get("tolerances") or {}).items():
            value = values.get(key)
            if not math.isfinite(sigma):
                raise ConfigError(f"{source}: rigs/{rig}/tolerances/{key} is {sigma!r}; give a finite 1σ")
            if value is not None and sigma > 0.25 * abs(value):
                raise ConfigError(
                    f"{source}: rigs/{rig}/tolerances/{key} = {sigma:g} is {100 * sigma / abs(value):.0f} % of "
                    f"{key} = {value:g}; tolerances are 1σ in the value's own unit (e.g. {0.01 * abs(value):.3g} "
                    "for 1 %), not fractions"
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


def discover_trials(raw_dir: str | Path) -> dict[str, Trial]:
    """Every video (.mp4/.avi/.mov) and angle table (.csv) in ``raw_dir``, by file stem."""
    raw_dir = Path(raw_dir)
    trials: dict[str, Trial] = {}
    if not raw_dir.is_dir():
        return trials
    for path in sorted(raw_dir.iterdir()):
        suffix = path.suffix.lower()
        if not path.is_file() or suffix not in VIDEO_EXTENSIONS + ANGLE_TABLE_EXTENSIONS:
            continue
        name = path.stem
        if not TRIAL_NAME.match(name):
            raise ConfigError(f"{path}: trial names may hold letters, digits and _ . + - only")
        if name in RESERVED_NAMES:
            raise ConfigError(f"{path}: {name!r} is reserved for the aggregate fits; rename the file")
        if name in trials:
            raise ConfigError(f"{path}: trial {name!r} also comes from {trials[name].path}; rename one")
        kind = "video" if suffix in VIDEO_EXTENSIONS else "angles"
        trial = Trial(name, kind, str(path))
        sidecar = path.with_suffix(".yaml")
        if sidecar.is_file():
            try:
                doc = yaml.safe_load(sidecar.read_text()) or {}
            except yaml.YAMLError as exc:
                raise ConfigError(f"{sidecar}: not valid YAML ({exc})") from exc
            if not isinstance(doc, dict):
                raise ConfigError(f"{sidecar}: must be a mapping of keys to values")
            _validate(doc, "sidecar.schema.yaml", str(sidecar))
            trial.sidecar, trial.sidecar_path = doc, str(sidecar)
        trials[name] = trial
    return trials


def rig_trials(config: dict, trials: dict[str, Trial]) -> dict[str, list[str]]:
    """Trial names of each rig (every trial, video or angle table)."""
    by_rig: dict[str, list[str]] = {}
    for name in sorted(trials):
        by_rig.setdefault(rig_name(config, trials[name]), []).append(name)
    return by_rig


def rig_name(config: dict, trial: Trial) -> str:
    name = trial.sidecar.get("rig", config["default_rig"])
    if name not in config["rigs"]:
        raise ConfigError(
            f"{trial.sidecar_path}: rig {name!r} is not one of rigs {sorted(config['rigs'])} in config.yaml"
        )
    return name


def trial_settings(config: dict, trial: Trial) -> dict:
    """Rig values, geometry and tracking settings of one trial: config, then rig, then sidecar."""
    rig = rig_name(config, trial)
    merged_rig = {**config["rigs"][rig]}
    merged_rig.update({k: v for k, v in trial.sidecar.items() if k in RIG_KEYS + GEOMETRY_KEYS})
    tracking = {**config["tracking"]}
    tracking.update({k: v for k, v in trial.sidecar.items() if k in TRACKING_KEYS})
    return {
        "rig_name": rig,
        "rig": {k: merged_rig[k] for k in RIG_KEYS if k in merged_rig},
        "tolerances": dict(config["rigs"][rig].get("tolerances") or {}),
        "pivot_px": merged_rig.get("pivot_px"),
        "vertical_deg": merged_rig.get("vertical_deg"),
        "geometry_from_sidecar": any(k in trial.sidecar for k in GEOMETRY_KEYS),
        "tracking": tracking,
    }


def needs_rig_geometry(config: dict, trial: Trial) -> bool:
    """True when a video trial's pivot or vertical must be estimated from the rig's pooled tracks."""
    s = trial_settings(config, trial)
    return trial.kind == "video" and (s["pivot_px"] is None or s["vertical_deg"] is None)


def pooled_trials(config: dict, trials: dict[str, Trial], rig: str) -> list[str]:
    """Video trials whose tracks define the rig's estimated geometry (not those with their own)."""
    return sorted(
        name
        for name, t in trials.items()
        if t.kind == "video" and rig_name(config, t) == rig and not trial_settings(config, t)["geometry_from_sidecar"]
    )
