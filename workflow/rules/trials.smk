# Trials: the raw folder's trials found and named, the configuration and sidecars validated
# before any job runs, the rigs and bodies they belong to, and the wildcards' patterns.
import sys
from pathlib import Path

sys.path.insert(0, str(Path(workflow.basedir) / "workflow"))

from pendulum.groups import (  # noqa: E402
    body_groups,
    discovery_groups,
    discovery_settings,
    group_trial_rigs,
    group_trials,
)
from pendulum.camera.raw_folder import (  # noqa: E402
    discover_trials,
    passed_over,
    raw_folder_problem,
)
from pendulum.trials import (  # noqa: E402
    GEOMETRY_KEYS,
    ConfigError,
    RIG_KEYS,
    add_sidecar_rigs,
    kept_geometry_trials,
    needs_rig_geometry,
    pooled_trials,
    rig_name,
    rig_trials,
    split_skipped,
    settings_of_trials,
    validate_config,
)

# `--config key=true` arrives as the string "true": make it the boolean it means.
for key, value in list(config.items()):
    if isinstance(value, str) and value.lower() in ("true", "false"):
        config[key] = value.lower() == "true"

validate_config(
    config, source="the configuration (config.yaml and any --configfile/--config)"
)

# a sidecar's `skip: <why>` leaves its trial out of every job (listed as skipped, failing nothing)
FOUND = discover_trials(config["raw_dir"])
PASSED_OVER = passed_over(config["raw_dir"])  # said in the run's last lines (Snakefile)
TRIALS, SKIPPED = split_skipped(FOUND)
# rigs defined in sidecars join config["rigs"] (a skipped trial's sidecar too: its rig may be the others')
SIDECAR_RIGS = add_sidecar_rigs(config, FOUND)
VIDEO_TRIALS = sorted(n for n, t in TRIALS.items() if t.kind == "video")
# each trial's merged settings (config, rig, sidecar; a bad sidecar stops the run here) and each rig's
# trials, computed once: the input functions and params of a thousand trials' jobs read them
SETTINGS = settings_of_trials(config, TRIALS)  # every bad sidecar named at once
RIG_TRIALS = rig_trials(SETTINGS)
# body → its rigs with trials (config `bodies`)
BODIES = body_groups(config, RIG_TRIALS)
RIGS_NEEDING_GEOMETRY = sorted(
    {
        SETTINGS[n]["rig_name"]
        for n in VIDEO_TRIALS
        if needs_rig_geometry(config, TRIALS[n])
    }
)


wildcard_constraints:
    trial=r"(?!(?:joint|summary)$)[A-Za-z0-9][A-Za-z0-9_.+-]*",
    rig=r"[A-Za-z0-9_.+-]+",
    variant=r"[A-Za-z0-9_.+-]+",
