"""A group's trials read for a joint fit: their angle records with each rig's values, and the fits to start from
(the groups themselves: :mod:`pendulum.groups`)."""

from __future__ import annotations

import logging
from dataclasses import dataclass
from pathlib import Path

import pandas as pd

from pendulum.fit.records import AngleRecord, FitSettings, load_record
from pendulum.io import read_json
from pendulum.status import fitted_trials, is_failed


def group_records(
    names: list[str], angle_paths: dict, angle_info: dict, trial_rigs: dict, settings: FitSettings
) -> list[AngleRecord]:
    """The fit records of a group's trials, each with its own rig's values and tolerances
    (:func:`pendulum.groups.group_trial_rigs`)."""
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
