"""Groups of trials from the configuration: the bodies of config ``bodies`` and the discovery groups.

Config-level only (no numerics): the workflow reads these when it is parsed. Every function takes
``by_rig``, the trial names of each rig (:func:`pendulum.trials.rig_trials`, computed once), and
the trials' merged settings where it needs rig values (:func:`pendulum.trials.trial_settings`).
"""

from __future__ import annotations

from pendulum.trials import ConfigError

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
            f"{sorted(config['variants'])}: keep that variant (discovery adds terms to it), or set "
            "discovery/baseline to one of them (discovery and the design then run again)"
        )
    return None


def discovery_groups(config: dict, by_rig: dict[str, list[str]]) -> dict[str, list[str]]:
    """Group name → its rigs that have trials: each body of config ``bodies``, then every other rig by itself.

    A body is one vehicle swung on several rigs (arm lengths, payloads); discovery pools its rigs'
    trials with the body's hydrodynamic coefficients shared and each rig's torques its own.
    """
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


def body_groups(config: dict, by_rig: dict[str, list[str]]) -> dict[str, list[str]]:
    """Body name → its rigs that have trials, for the bodies of config ``bodies`` (their joint body fits)."""
    bodies = config.get("bodies") or {}
    return {g: rigs for g, rigs in discovery_groups(config, by_rig).items() if g in bodies}


def group_trials(by_rig: dict[str, list[str]], groups: dict, group: str) -> list[str]:
    """The trials of a group's rigs."""
    if group not in groups:
        raise ValueError(f"no discovery group {group!r} (a body or a rig with trials)")
    return sorted(n for rig in groups[group] for n in by_rig[rig])


def group_trial_rigs(settings: dict[str, dict], by_rig: dict[str, list[str]], groups: dict, group: str) -> dict:
    """Trial → its rig's name and values (a sidecar may override values) and the rig's stated tolerances;
    ``settings``: each trial's :func:`pendulum.trials.trial_settings`."""
    return {
        name: {
            "name": settings[name]["rig_name"],
            "values": settings[name]["rig"],
            "tolerances": settings[name]["tolerances"],
        }
        for name in group_trials(by_rig, groups, group)
    }


# A fit of a group of trials (joint, body, discovery, design) holds its Jacobian, samples × (3 per trial + the
# coefficients): dense below SPARSE_FROM_TRIALS trials (pendulum.fit.output_error's, the same number), sparse from
# there (each sample's row holds at most 9 nonzeros: 12 B each in a CSR matrix), with a few square matrices of
# (3 per trial + the coefficients)² float64 (normal matrix, sandwich, their inverses) and, for the rank check, the
# trials' QR-compressed rows (at most 9 per trial, as wide: pendulum.fit.uncertainty.compressed_rows). Peaks
# measured on 2026-12-03 (copies of the demo's records, ~630 samples each): discovery 0.29 GB for 40 trials, 0.41 GB
# for 160 (3.34 GB while it held the dense Jacobian), the design 0.34 GB for 160. Declared with 10 times what is
# held above 0.3 GB, at least 2000 MB.
SPARSE_FROM_TRIALS = 11
GROUP_JOB_BASE_MB, GROUP_JOB_COPIES, GROUP_JOB_MIN_MB = 300, 10, 2000


def group_job_mem_mb(samples_per_trial: list[int]) -> int:
    """Memory (MB) a group fit's job declares: max(2000, 300 + 10 H) MB (rounded up to 100 MB), H what it holds:
    the Jacobian of N trials of S samples in all (S (3N + 6) × 8 B dense, below SPARSE_FROM_TRIALS trials; else
    S × 9 × 12 B sparse and its compressed rows, 9N × (3N + 6) × 8 B) and a square matrix of (3N + 6)² × 8 B."""
    n, samples = len(samples_per_trial), sum(samples_per_trial)
    columns = 3 * n + 6
    dense = n < SPARSE_FROM_TRIALS
    jacobian_mb = (samples * columns * 8 if dense else samples * 9 * 12 + 9 * n * columns * 8) / 1e6
    held_mb = jacobian_mb + columns**2 * 8 / 1e6
    return max(GROUP_JOB_MIN_MB, -(-int(GROUP_JOB_BASE_MB + GROUP_JOB_COPIES * held_mb) // 100) * 100)
