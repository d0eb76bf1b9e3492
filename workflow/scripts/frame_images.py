"""Snakemake adapter: write every decoded frame (luma) of one video as an image."""

from pathlib import Path

import _setup  # noqa: F401
from pendulum.camera.video import iter_luma
from pendulum.io import script_logger, write_png

sm = snakemake  # noqa: F821
log = script_logger(sm.log[0], "frame_images")
out = Path(sm.output.images)
out.mkdir(parents=True, exist_ok=True)
for index, t, y in iter_luma(sm.input.video):
    write_png(y, out / f"frame_{index:06d}.{sm.params.image_format}")
    if index % 200 == 0:
        log.info("%s: wrote frame %d (t = %.3f s)", sm.input.video, index, t)
