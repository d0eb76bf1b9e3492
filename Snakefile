"""Free-decay pendulum identification: raw videos → frames → tracks → angles → fits."""


configfile: "config.yaml"


include: "workflow/rules/common.smk"
include: "workflow/rules/frames.smk"
include: "workflow/rules/tracks.smk"
include: "workflow/rules/angles.smk"
include: "workflow/rules/fits.smk"


rule all:
    default_target: True
    input:
        all_targets(),
