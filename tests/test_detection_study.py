"""Random scenes with every real-camera fault at once, no marker hints (issue 12's acceptance).

The scenes are drawn by ``tests/benchmarks/detection_study.py`` (its ``random_scene``): polarity, marker
radius 5–20 px, release ±(5–30)°, rig, roll, stripes (vertical, horizontal or slanted), a second disk of
the marker's grey (line mover or bubbles) and letterbox or pillarbox borders. The study judges 120 of them
(seeds 1000–1039, 2000–2039 and 3000–3039); here the first twelve seeds from 7000 on that draw the cheap
camera, none left out, as a guard that runs with the suite.
"""

import math
import sys
from pathlib import Path

import pytest

sys.path.insert(0, str(Path(__file__).resolve().parent / "benchmarks"))

from detection_study import evaluate_scene, random_scene  # noqa: E402

from pendulum.synthetic.experiment import generate_trial  # noqa: E402

# The first twelve seeds from 7000 whose scene is a 640×360, 30 fps camera (6 s clips): none chosen by
# outcome. Measured: all 12 pass (starts within 0.044 px, radii within 0.03 px, angle RMS ≤ 0.015°).
SEEDS = (7006, 7009, 7015, 7017, 7019, 7022, 7026, 7030, 7033, 7035, 7036, 7038)
CLIP_S = 6.0
ALLOWED_FAILURES = 2


@pytest.mark.slow
def test_random_faulty_scenes_are_found_and_tracked_or_refused_never_taken_wrongly(tmp_path):
    """A scene passes when detection finds the marker (its start within 1 px of the truth), its radius is
    within 10 % of the rendered one, and tracking with config.yaml's values (no hints) flags ≥ 95 % of the
    frames after the release ``ok`` with the angle RMS ≤ 0.05° against the truth (true pivot).

    Two rules, from the binomial distribution over n = 12 scenes:
    * never wrong: a scene detection does not pass must end in a DetectionError (which names what it saw
      and the sidecar values that settle it), never in a marker elsewhere. 0 allowed: were 20 % of
      scenes silently wrong, 12 without one would have a chance of 0.8¹² = 6.9 %.
    * at most ALLOWED_FAILURES = 2 failures: the study fails 2 of 120 scenes (1.7 %; one-sided 95 % upper
      limit 5.2 %); at that limit the chance of more than 2 in 12 is 2.1 % (0.09 % at 1.7 %), so a sound
      detector rarely fails this; one failing half the scenes passes it with a chance of 1.9 %, one failing a
      quarter with 39 %.
    """
    rows = []
    for seed in SEEDS:
        spec = random_scene(seed, CLIP_S)
        assert (spec.camera.width_px, spec.camera.fps) == (640, 30.0)
        folder = tmp_path / str(seed)
        generate_trial(spec, folder, folder, progress=None)
        row = evaluate_scene(spec, folder)
        radius_ok = row["det"] and abs(row["r_det"] / row["r_true"] - 1) <= 0.10
        rows.append((seed, row["passed"] and radius_ok, row))
    summary = "\n".join(
        f"seed {seed}: r {row['r_true']:.2f}/{row.get('r_det', math.nan):.2f} px, ok "
        f"{row.get('ok%', math.nan):.1f} %, angle RMS {row.get('rms', math.nan):.4f}° {row['error']}"
        for seed, _, row in rows
    )
    wrong = [seed for seed, _, row in rows if not row["det"] and not row["error"].startswith("detection: ")]
    assert not wrong, summary
    failed = [seed for seed, good, _ in rows if not good]
    assert len(failed) <= ALLOWED_FAILURES, summary


@pytest.mark.slow
@pytest.mark.parametrize("seed", [3031, 2012, 3001])
def test_a_start_interrupted_by_another_objects_blob_is_still_found(tmp_path, seed):
    """Held-out scenes of the study where another object's blob sits on the marker's circle next to the start:
    in 3031 (held two samples, then a blob 60 px off in the third) both searches dropped the held start with
    the blob, and an early version then took a spot next to the blob for the start (60 px off: tracked on
    the wrong object); in 2012 the quantile search's first-sample blob is another object's; in 3001 the
    first sample's spot on the refitted circle is another object's while the marker is held still in the
    next eight (it was taken for the start, 5.9° off). The start must be the marker's (within 1 px) and the
    scene must pass."""
    spec = random_scene(seed, 10.0)
    generate_trial(spec, tmp_path, tmp_path, progress=None)
    row = evaluate_scene(spec, tmp_path)
    assert row["det"] and row["start"] <= 1.0 and row["passed"], row


@pytest.mark.slow
@pytest.mark.parametrize("seed", [1010, 2034])
def test_two_searches_that_disagree_are_settled_by_which_path_is_a_pendulums(tmp_path, seed):
    """Held-out scenes where the median and the quantile searches found different objects and detection ended in
    "not sure which object is the marker": in 1010 the median search's arc is blobs of several objects (32 of 72
    samples pass the continuity test, against 75 of 75 on the quantile search's); in 2034 (a 5° swing, inside the
    median background) the median search follows the line mover on a circle fitted about (252, −339) px, its samples
    13.5° to one side of the vertical below it, the marker's 3.1°. The marker must be found and the scene pass."""
    spec = random_scene(seed, 10.0)
    generate_trial(spec, tmp_path, tmp_path, progress=None)
    row = evaluate_scene(spec, tmp_path)
    assert row["det"] and row["start"] <= 1.0 and row["passed"], row


@pytest.mark.slow
def test_a_line_mover_with_more_support_does_not_beat_the_markers_curved_arc(tmp_path):
    """Scene 1021 (bright 20 px marker, 8° swing, a line mover of the marker's grey): the line mover's path
    (fitted circle of arm 960 px, a straight line fits it as well) held more response than the marker's
    clearly curved arc and was taken for the marker (31° RMS). A clearly curved arc hanging below its pivot,
    with at least half a flat path's support, now comes first (a rule putting every curved arc first took a
    body edge in the demo's 5° trials: see test_detection)."""
    spec = random_scene(1021, 10.0)
    generate_trial(spec, tmp_path, tmp_path, progress=None)
    row = evaluate_scene(spec, tmp_path)
    assert row["det"] and row["start"] <= 1.0 and row["passed"], row
