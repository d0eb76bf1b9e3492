"""Discovery groups: a body swung on one or more rigs (config ``bodies``), else one rig; the discovery settings."""

from __future__ import annotations

import logging
from dataclasses import dataclass
from pathlib import Path

import pandas as pd

from pendulum.fit.records import AngleRecord, FitSettings, load_record
from pendulum.io import read_json
from pendulum.status import fitted_trials, is_failed
from pendulum.trials import ConfigError, Trial, rig_name, rig_trials, trial_settings

DISCOVERY_DEFAULTS = {
    "baseline": "quadratic",
    "candidates": ["linear_damping", "coulomb_friction", "quadratic_drag", "history_force", "restoring_correction"],
    "alpha": 0.01,
}


def discovery_settings(config: dict) -> dict | None:
    """Config ``discovery`` with its defaults; None (no discovery) when the default baseline is not a variant.

    A baseline named in config that is not a variant stops the run with the names.
    """
    given = config.get("discovery") or {}
    settings = {**DISCOVERY_DEFAULTS, **given}
    if settings["baseline"] in config["variants"]:
        return settings
    if "baseline" in given:
        raise ConfigError(
            f"config.yaml: discovery/baseline {settings['baseline']!r} is not one of variants "
            f"{sorted(config['variants'])}"
        )
    return None


def discovery_groups(config: dict, trials: dict[str, Trial]) -> dict[str, list[str]]:
    """Group name → its rigs that have trials: each body of config ``bodies``, then every other rig by itself.

    A body is one vehicle swung on several rigs (arm lengths, payloads); discovery pools its rigs'
    trials with the body's hydrodynamic coefficients shared and each rig's torques its own.
    """
    by_rig = rig_trials(config, trials)
    groups, owner = {}, {}
    for body, rigs in sorted((config.get("bodies") or {}).items()):
        for rig in rigs:
            if rig not in config["rigs"]:
                raise ConfigError(
                    f"config.yaml: bodies/{body} names rig {rig!r}, not one of rigs {sorted(config['rigs'])}"
                )
            if rig in owner:
                raise ConfigError(
                    f"config.yaml: rig {rig!r} is in bodies {owner[rig]!r} and {body!r}; a rig carries one body"
                )
            owner[rig] = body
        if body in config["rigs"] and body not in rigs:
            raise ConfigError(f"config.yaml: body {body!r} has the name of another rig; rename it")
        members = sorted(r for r in rigs if r in by_rig)
        if members:
            groups[body] = members
    for rig in sorted(by_rig):
        if rig not in owner:
            groups[rig] = [rig]
    return groups


def group_trials(config: dict, trials: dict[str, Trial], groups: dict, group: str) -> list[str]:
    """The trials of a group's rigs."""
    if group not in groups:
        raise ValueError(f"no discovery group {group!r} (a body or a rig with trials)")
    by_rig = rig_trials(config, trials)
    return sorted(n for rig in groups[group] for n in by_rig[rig])


def group_trial_rigs(config: dict, trials: dict[str, Trial], groups: dict, group: str) -> dict:
    """Trial → its rig's name and values (a sidecar may override values) and the rig's stated tolerances."""
    out = {}
    for name in group_trials(config, trials, groups, group):
        settings = trial_settings(config, trials[name])
        out[name] = {
            "name": rig_name(config, trials[name]),
            "values": settings["rig"],
            "tolerances": settings["tolerances"],
        }
    return out


def body_groups(config: dict, trials: dict[str, Trial]) -> dict[str, list[str]]:
    """Body name → its rigs that have trials, for the bodies of config ``bodies`` (their joint body fits)."""
    bodies = config.get("bodies") or {}
    return {g: rigs for g, rigs in discovery_groups(config, trials).items() if g in bodies}


def group_records(
    names: list[str], angle_paths: dict, angle_info: dict, trial_rigs: dict, settings: FitSettings
) -> list[AngleRecord]:
    """The fit records of a group's trials, each with its own rig's values and tolerances (:func:`group_trial_rigs`)."""
    return [
        load_record(
            pd.read_csv(angle_paths[n]),
            n,
            trial_rigs[n]["values"],
            settings,
            tolerances=trial_rigs[n]["tolerances"],
            angle_info=angle_info[n],
            source=angle_paths[n],
        )
        for n in names
    ]


@dataclass
class GroupInputs:
    """A group's trials that can be fitted (with their records), those left out and why, the fits to start from."""

    names: list[str]
    excluded: dict[str, str]
    records: list[AngleRecord]
    rigs: list[str]  # each record's rig
    starts: list[dict]  # the rigs' joint fits, then each trial's own fit (start values, kept samples)
    angle_paths: dict[str, str]
    angle_info: dict[str, dict]


def load_group(inputs, trial_rigs: dict, settings: FitSettings, log: logging.Logger, context: str) -> GroupInputs:
    """Read a group rule's inputs (``angles``, ``angle_info``, ``fits``, ``joint`` paths) into fit records.

    Trials whose angles or fit failed, or whose fit rests on an unreliable record, are left
    out (:func:`pendulum.status.fitted_trials`); ``names`` may be empty.
    """
    angle_paths = {Path(p).stem: p for p in inputs.angles}
    angle_info = {Path(p).stem: read_json(p) for p in inputs.angle_info}
    fits = {Path(p).stem: read_json(p) for p in inputs.fits}
    joints = [doc for doc in map(read_json, inputs.joint) if not is_failed(doc)]
    names, excluded = fitted_trials(trial_rigs, angle_info, fits, log, context)
    return GroupInputs(
        names,
        excluded,
        group_records(names, angle_paths, angle_info, trial_rigs, settings),
        [trial_rigs[n]["name"] for n in names],
        joints + [fits[n] for n in names],
        angle_paths,
        angle_info,
    )
