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


def shared_file(relative: str) -> Path:
    """``../shared/<relative>`` (the real clips and Tracker exports beside the project); the test is skipped when it
    is not there, and fails under CI (``.ci/run`` sets ``CI``), whose clone has ``../shared`` beside it."""
    path = SHARED / relative
    if not path.exists():
        message = f"{path} not found (../shared beside the project)"
        if os.environ.get("CI"):
            pytest.fail(message + "; CI runs with ../shared beside its clone")
        pytest.skip(message)
    return path


class SnakemakeFiles(dict):
    """Stands for Snakemake's named input/output lists: attribute access and ``keys()``."""

    __getattr__ = dict.__getitem__


class FakeSnakemake:
    """The ``snakemake`` object a rule's script sees, for running the script with :func:`runpy.run_path`."""

    def __init__(self, inputs, output, log, params, wildcards=None):
        self.input, self.output, self.params, self.wildcards = (
            SnakemakeFiles(inputs),
            SnakemakeFiles(output),
            SnakemakeFiles(params),
            SnakemakeFiles(wildcards or {}),
        )
        self.log = [log]


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
# group (the fixture built once); every other test is scheduled on its own. The shared groups run first, the
# demo's (the longest) before the others, then the slow tier, then the fast (pytest.ini:
# --no-loadscope-reorder keeps this order).
SHARED_FIXTURES = ("demo_project", "small_build", "hard_videos")


def _wide_fixtures(item) -> set[tuple[str, str]]:
    """(where, name) of the project's (not pytest's) fixtures the test uses that live longer than one test."""
    info = getattr(item, "_fixtureinfo", None)
    wide = set()
    for name in info.names_closure if info else ():
        defs = info.name2fixturedefs.get(name)
        if defs and defs[-1].scope != "function" and defs[-1].baseid:
            wide.add((defs[-1].baseid, name))
    return wide


def _merged(groups: list, wide: list) -> list:
    """``groups`` with every two groups that use one fixture (``wide``: per test, its long-lived fixtures) made one,
    named by a shared fixture where one is among them (a fixture used from two groups would be built in each)."""
    parent: dict = {}

    def root(group):
        while parent.get(group, group) != group:
            group = parent[group]
        return group

    def rank(group):
        return SHARED_FIXTURES.index(group) if group in SHARED_FIXTURES else len(SHARED_FIXTURES)

    first_group: dict = {}
    for group, fixtures in zip(groups, wide, strict=True):
        for fixture in fixtures:
            a, b = root(first_group.setdefault(fixture, group)), root(group)
            if a != b:
                keep, drop = sorted((a, b), key=lambda g: (rank(g), g))
                parent[drop] = keep
    return [root(group) if group is not None else None for group in groups]


@pytest.hookimpl(tryfirst=True)  # before xdist's own hook turns the xdist_group marks into the tests' groups
def pytest_collection_modifyitems(config, items):
    """Tests that use a :data:`SLOW_FIXTURES` fixture are marked ``slow`` (besides those marked by hand); each
    test joins the xdist group of the first :data:`SHARED_FIXTURES` fixture it uses, else its file's when it uses
    one of its file's module fixtures, groups that use one fixture merged (:func:`_merged`); groups are ordered
    shared first, then slow, then fast."""
    groups, wide = [], []
    for item in items:
        names = set(getattr(item, "fixturenames", ()))
        if SLOW_FIXTURES & names:
            item.add_marker(pytest.mark.slow)
        fixtures = _wide_fixtures(item)
        group = next((f for f in SHARED_FIXTURES if f in names), None)
        if group is None and any(name not in SHARED_FIXTURES for _, name in fixtures):
            group = item.path.name
        groups.append(group)
        wide.append(fixtures)
    rank = {}
    groups = _merged(groups, wide)
    for item, group in zip(items, groups, strict=True):
        if group is not None:
            item.add_marker(pytest.mark.xdist_group(group))
        slow = item.get_closest_marker("slow") is not None
        order = SHARED_FIXTURES.index(group) if group in SHARED_FIXTURES else 10 if slow else 20
        rank[group or item.nodeid] = min(rank.get(group or item.nodeid, order), order)
    order = {id(item): rank[group or item.nodeid] for item, group in zip(items, groups, strict=True)}
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
    """One demo video, one variant and two unreadable videos, built (``workflow_run.small_project``): every rule
    in few jobs, the bytes the cluster-profile and interrupted-run tests must reproduce from their own copies of
    the project, and the two failures the bad-input test looks at. Its results are never changed."""
    from workflow_run import Build, digest, run, small_project

    work = small_project(tmp_path_factory.mktemp("small_build"))
    raw_before = digest(work / "data" / "raw", ("*",))
    proc = run(["-c2"], work, check=False)
    return Build(work, proc.returncode, proc.stdout + proc.stderr, raw_before)
