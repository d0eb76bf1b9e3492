"""The habits of a well-kept workflow: licence, citation, pinned style hooks, the catalog entry."""

import re

import yaml

from conftest import ROOT


def locked(package: str) -> str:
    match = re.search(rf"^{package}==([^\s\\]+)", (ROOT / "environment-lock.txt").read_text(), re.M)
    assert match, f"{package} is not in environment-lock.txt"
    return match.group(1)


def test_the_code_has_a_licence_and_the_citation_names_it():
    licence = (ROOT / "LICENSE").read_text()
    assert licence.startswith("MIT License") and "Permission is hereby granted, free of charge" in licence
    citation = yaml.safe_load((ROOT / "CITATION.cff").read_text())
    assert citation["cff-version"] == "1.2.0" and citation["type"] == "software" and citation["license"] == "MIT"
    assert citation["authors"] and citation["title"] and citation["message"]


def test_the_style_hooks_run_the_locked_versions():
    hooks = yaml.safe_load((ROOT / ".pre-commit-config.yaml").read_text())["repos"]
    revs = {repo["repo"].rsplit("/", 1)[-1]: repo["rev"] for repo in hooks}
    assert revs == {"ruff-pre-commit": f"v{locked('ruff')}", "snakefmt": f"v{locked('snakefmt')}"}


def test_the_snakefile_states_the_snakemake_it_needs_and_the_catalog_entry_is_honest():
    version = re.search(r'min_version\("([\d.]+)"\)', (ROOT / "Snakefile").read_text())
    assert version, "no min_version in the Snakefile"
    needed = tuple(int(p) for p in version.group(1).split("."))
    assert tuple(int(p) for p in locked("snakemake").split(".")[: len(needed)]) >= needed
    usage = yaml.safe_load((ROOT / ".snakemake-workflow-catalog.yml").read_text())["usage"]
    assert set(usage) == {"mandatory-flags", "software-stack-deployment", "report"}
    assert not any(usage["software-stack-deployment"].values())  # pip from the lock file, not conda/containers


def test_every_rule_records_its_time_and_memory_where_snakemake_users_look():
    """Snakemake's own ``benchmark:`` on every rule that runs a job (``all`` only gathers targets)."""
    rules = {}
    for path in sorted((ROOT / "workflow" / "rules").glob("*.smk")):
        text = path.read_text()
        # a path named once at the file's top (the freeze's, which its refusal of a reused tag reads too)
        named = dict(re.findall(r'^([A-Z_]+) = \(?\s*f?"(benchmarks/jobs/[^"]+\.tsv)"', text, re.M))
        for block in re.split(r"^rule ", text, flags=re.M)[1:]:
            name = block.split(":", 1)[0]
            bench = re.search(r'^    benchmark:\n\s+(?:f?"(benchmarks/jobs/[^"]+\.tsv)"|([A-Z_]+)\n)', block, re.M)
            rules[name] = (bench.group(1) or named.get(bench.group(2))) if bench else None
    assert len(rules) >= 15
    assert [name for name, bench in rules.items() if bench is None] == []
    assert len(set(rules.values())) == len(rules)  # one file per job, no two rules sharing one
    assert "benchmarks/jobs/" in (ROOT / ".gitignore").read_text().splitlines()


GROUP_CONFTEST = """
import importlib.util, os, pytest

spec = importlib.util.spec_from_file_location("suite_conftest", {conftest!r})
suite = importlib.util.module_from_spec(spec)
spec.loader.exec_module(suite)
pytest_collection_modifyitems = suite.pytest_collection_modifyitems


@pytest.fixture(scope="session")
def demo_project():
    return "built"


@pytest.fixture
def seen(request):
    yield
    with open(os.path.join({out!r}, request.node.name), "w") as f:
        f.write(os.environ["PYTEST_XDIST_WORKER"] + " " + request.node.nodeid)
"""


def _run_grouped(folder, files: dict):
    """tests/conftest.py's hook under ``pytest -n 2 --dist loadgroup`` on test ``files`` in ``folder``: the process,
    and per test the worker that ran it and its id as xdist saw it (``…@group`` when grouped)."""
    import os
    import subprocess
    import sys

    out = folder / "seen"
    out.mkdir()
    (folder / "conftest.py").write_text(GROUP_CONFTEST.format(conftest=str(ROOT / "tests/conftest.py"), out=str(out)))
    for name, text in files.items():
        (folder / name).write_text(text)
    env = {k: v for k, v in os.environ.items() if k != "PYTEST_ADDOPTS"}
    proc = subprocess.run(
        [sys.executable, "-m", "pytest", "-n", "2", "--dist", "loadgroup", "-p", "no:cacheprovider", "-q"]
        + ["-c", "/dev/null", "--rootdir", str(folder), str(folder)],
        cwd=folder,
        capture_output=True,
        text=True,
        env=env,
        timeout=120,
    )
    seen = {p.name: p.read_text().split(" ", 1) for p in out.iterdir()}
    return proc, seen


def test_the_tests_that_share_a_build_run_in_one_worker(tmp_path):
    """pytest.ini's ``--dist loadgroup`` with tests/conftest.py's groups, run for real: the tests of two files that use
    ``demo_project`` run in one worker (one build), as do a file's tests that use its module fixture; the others are
    not grouped (spread one by one). pytest 9.2 broke this silently (pytest-dev/pytest-xdist#1386: every test ran
    alone and each worker built the demo)."""
    files = {}
    for name in ("a", "b"):
        tests = [f"def test_{name}_demo_{i}(demo_project, seen):\n    pass\n" for i in range(4)]
        tests += [f"def test_{name}_alone_{i}(seen):\n    pass\n" for i in range(4)]
        files[f"test_{name}.py"] = "\n\n".join(tests)
    module = ["import pytest\n\n\n@pytest.fixture(scope='module')\ndef built():\n    return 1\n"]
    module += [f"def test_c_module_{i}(built, seen):\n    pass\n" for i in range(6)]
    files["test_c.py"] = "\n\n".join(module)
    proc, seen = _run_grouped(tmp_path, files)
    assert proc.returncode == 0, proc.stdout + proc.stderr
    assert len(seen) == 22
    assert len({worker for name, (worker, _) in seen.items() if "_demo_" in name}) == 1, seen
    assert len({worker for name, (worker, _) in seen.items() if "_module_" in name}) == 1, seen
    assert all(nodeid.endswith("@demo_project") for name, (_, nodeid) in seen.items() if "_demo_" in name), seen
    assert not any("@" in nodeid for name, (_, nodeid) in seen.items() if "_alone_" in name), seen


def test_a_module_fixture_used_inside_and_outside_a_shared_group_is_built_in_one_worker(tmp_path):
    """A file's module fixture that one test uses beside ``demo_project``: all its tests join the demo's group
    (else it would be built in two workers)."""
    text = "import pytest\n\n\n@pytest.fixture(scope='module')\ndef built():\n    return 1\n\n\n"
    tests = [f"def test_d_{i}(built, seen{', demo_project' if i == 0 else ''}):\n    pass\n" for i in range(6)]
    text += "\n\n".join(tests)
    proc, seen = _run_grouped(tmp_path, {"test_d.py": text})
    assert proc.returncode == 0, proc.stdout + proc.stderr
    assert len(seen) == 6 and len({worker for worker, _ in seen.values()}) == 1, seen
    assert all(nodeid.endswith("@demo_project") for _, nodeid in seen.values()), seen
