import os
import sys
from pathlib import Path

import pytest

# One BLAS thread per process: the suite and its workflow runs already use both cores, and
# oversubscribed OpenBLAS made small SVDs ~100x slower on a busy 2-core machine.
os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")
ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "workflow"))
SHARED = ROOT.parent / "shared"
DEMO_SPEC = ROOT / "data" / "synthetic" / "demo.yaml"
DEMO_RAW = ROOT / "data" / "raw"
DEMO_TRUTH = ROOT / "data" / "truth"


# Fixtures that render videos, run the workflow or fit many records (seconds to minutes, once per session or
# module): a test that uses one is in the slow tier. `pytest -m "not slow"` is the fast tier a developer
# runs on every change; the full suite (what CI runs) is every test.
SLOW_FIXTURES = {
    "demo_project",  # the README's build of the demo videos
    "small_build",
    "hard_videos",
    "project",
    "repo",
    "frozen",
    "report_project",
    "demo",  # tests/test_angles.py: the demo videos tracked
    "demo_tracks",
    "fast_video",
    "render_dir",
    "optics_dir",
    "barrel_calibration",
    "two_movers",
    "rendered",
    "graded_clip",
    "apple",
    "results",  # tests/test_discovery_statistics.py: discovery over seeds
    "recovery_fits",
    "coverage_fits",
    "fitted",
}


# Session fixtures that several files share: under pytest-xdist (pytest.ini runs one worker per core) the tests
# that use one are one group, run by one worker, so it is built once and a test that changes and restores it
# (demo_project) never races another worker. A test that uses a module fixture of its file is in that file's
# group (the fixture built once); every other test is scheduled on its own. Groups run longest first
# (pytest.ini: --no-loadscope-reorder keeps this order): the shared builds, then the slow tier, then the rest.
SHARED_FIXTURES = ("demo_project", "small_build", "hard_videos")


def _uses_a_module_fixture(item) -> bool:
    """A fixture of the project's (not pytest's) that lives longer than one test, other than the shared ones."""
    info = getattr(item, "_fixtureinfo", None)
    for name, defs in info.name2fixturedefs.items() if info else ():
        if defs and defs[-1].scope != "function" and defs[-1].baseid and name not in SHARED_FIXTURES:
            return True
    return False


@pytest.hookimpl(tryfirst=True)  # before xdist's own hook turns the xdist_group marks into the tests' groups
def pytest_collection_modifyitems(config, items):
    """Tests that use a :data:`SLOW_FIXTURES` fixture are marked ``slow`` (besides those marked by hand); each
    test joins the xdist group of the first :data:`SHARED_FIXTURES` fixture it uses, else its file's when it uses
    one of its file's module fixtures; groups are ordered shared first, then slow, then fast."""
    keys, rank = [], {}
    for item in items:
        names = set(getattr(item, "fixturenames", ()))
        if SLOW_FIXTURES & names:
            item.add_marker(pytest.mark.slow)
        group = next((f for f in SHARED_FIXTURES if f in names), None)
        if group is None and _uses_a_module_fixture(item):
            group = item.path.name
        if group is not None:
            item.add_marker(pytest.mark.xdist_group(group))
        key = group or item.nodeid
        slow = item.get_closest_marker("slow") is not None
        order = SHARED_FIXTURES.index(group) if group in SHARED_FIXTURES else 10 if slow else 20
        rank[key] = min(rank.get(key, order), order)
        keys.append(key)
    order = {id(item): rank[key] for item, key in zip(items, keys, strict=True)}
    items.sort(key=lambda item: order[id(item)])  # stable: a file's tests keep their order


def demo_trials():
    from pendulum.synthetic.experiment import load_specs

    return [s.name for s in load_specs(DEMO_SPEC)]


@pytest.fixture(scope="session")
def hard_videos(tmp_path_factory):
    """Short synthetic videos the demo lacks: a dark marker on a bright scene, 5 % occluded frames."""
    from dataclasses import replace

    from pendulum.synthetic.experiment import generate_trial, load_specs
    from pendulum.synthetic.specs import Occlusions

    out = tmp_path_factory.mktemp("hard_videos")
    base = {s.name: s for s in load_specs(DEMO_SPEC)}["demo_p20"]
    dark = replace(
        base, name="dark_marker", seed=101, duration_s=10.0, camera=replace(base.camera, polarity="dark", roll_deg=0.7)
    )
    occluded = replace(
        base, name="occluded", seed=102, duration_s=10.0, occlusions=Occlusions(fraction_of_frames=0.05, event_frames=5)
    )
    for spec in (dark, occluded):
        generate_trial(spec, out, out, progress=None)
    return out


@pytest.fixture(scope="session")
def demo_project(tmp_path_factory):
    """One full build of the demo videos (README's build command) in a project copy, shared by the workflow tests.

    Tests that change it restore it; tests that need a changed project copy it.
    """
    from workflow_run import copy_project, run

    work = copy_project(tmp_path_factory.mktemp("demo_project"))
    run(["-c2"], work)
    return work


@pytest.fixture(scope="session")
def small_build(tmp_path_factory):
    """One demo video, one variant, built (``workflow_run.small_project``): every rule in few jobs, the bytes the
    cluster-profile and interrupted-run tests must reproduce. Tests copy it, never change it."""
    from workflow_run import run, small_project

    work = small_project(tmp_path_factory.mktemp("small_build"))
    run(["-c2"], work)
    return work
