"""Frozen results folders: complete, verified by `sha256sum -c`, never overwritten, dirty trees refused."""

import hashlib
import json
import os
import re
import shutil
import stat
import subprocess
from datetime import UTC, datetime
from pathlib import Path

import pytest
import yaml

from conftest import ROOT
from pendulum.freeze import (
    MANIFEST,
    FreezeError,
    check_request,
    citation_cff,
    freeze,
    lock_differences,
    manifest,
)
from pendulum.provenance import config_as_used, config_digest, repository_url
from workflow_run import run

TOP_LEVEL = {
    "CITATION.cff",
    "MANIFEST.sha256",
    "README.md",
    "config.yaml",
    "environment-lock.txt",
    "installed-packages.txt",
    "provenance.json",
    "raw_inputs.sha256",
}


def git(work, *args):
    proc = subprocess.run(
        ["git", "-c", "user.email=test@example.org", "-c", "user.name=test", "-c", "init.defaultBranch=main", *args],
        cwd=work,
        capture_output=True,
        text=True,
        check=True,
    )
    return proc.stdout.strip()


def sha256sum_check(folder, listing):
    return subprocess.run(["sha256sum", "--strict", "-c", listing], cwd=folder, capture_output=True, text=True)


def tree_bytes(folder: Path) -> dict:
    return {str(p.relative_to(folder)): p.read_bytes() for p in sorted(folder.rglob("*")) if p.is_file()}


@pytest.fixture(scope="module")
def repo(demo_project, tmp_path_factory):
    """The built demo project (results up to date) as a clean git work tree, with a tracked NOTES.md to dirty."""
    work = tmp_path_factory.mktemp("freeze") / "project"
    shutil.copytree(demo_project, work, symlinks=True)
    for name in (".gitignore", "environment-lock.txt"):
        shutil.copy2(ROOT / name, work / name)
    (work / "NOTES.md").write_text("A tracked file the tests edit.\n")
    git(work, "init", "-q")
    git(work, "add", "-A")
    git(work, "commit", "-q", "-m", "demo")
    assert git(work, "status", "--porcelain") == ""
    return work


@pytest.fixture(scope="module")
def frozen(repo):
    proc = run(["-c1", "freeze", "--config", "freeze_tag=t1"], repo)
    return repo / "results/frozen/t1", proc


def test_the_folder_holds_results_report_config_environment_and_provenance(frozen, repo):
    folder, _ = frozen
    files = {str(p.relative_to(folder)) for p in folder.rglob("*") if p.is_file()}
    assert TOP_LEVEL <= files
    results = {f for f in files if f.startswith("results/")}
    trials = sorted(p.stem for p in (repo / "data/raw").glob("*.mp4"))
    variants = sorted(yaml.safe_load((repo / "config.yaml").read_text())["variants"])
    expected = {"results/fits/summary.csv", "results/status/trials.csv", "results/geometry/paper_rig.json"}
    expected |= {"results/report/report.html", "results/report/report.ipynb"}
    for trial in trials:
        expected |= {f"results/tracks/{trial}.csv", f"results/tracks/{trial}.json", f"results/angles/{trial}.csv"}
        expected |= {f"results/frames/{trial}/{name}" for name in ("timeline.csv", "summary.json", "contact_sheet.png")}
        for v in variants:
            expected |= {f"results/fits/{v}/{trial}.{kind}" for kind in ("json", "curve.csv", "cycles.csv")}
    expected |= {f"results/fits/{v}/joint/paper_rig.json" for v in variants}
    assert expected <= results
    assert not any("/images/" in f or f.startswith("results/frozen") for f in results)
    assert "results/status/all_trials_ok.txt" not in results
    for path in expected:
        assert (folder / path).read_bytes() == (repo / path).read_bytes(), path
    assert (folder / "environment-lock.txt").read_bytes() == (repo / "environment-lock.txt").read_bytes()
    assert not (folder / "DIRTY").exists()
    assert all(not os.stat(folder / f).st_mode & (stat.S_IWUSR | stat.S_IWGRP | stat.S_IWOTH) for f in files)


def test_the_manifest_covers_every_file_and_verifies_with_sha256sum(frozen):
    folder, _ = frozen
    listed = [line.split("  ", 1)[1] for line in (folder / MANIFEST).read_text().splitlines()]
    on_disk = sorted(str(p.relative_to(folder)) for p in folder.rglob("*") if p.is_file() and p.name != MANIFEST)
    assert listed == on_disk
    proc = sha256sum_check(folder, MANIFEST)
    assert proc.returncode == 0, proc.stdout + proc.stderr


def test_raw_input_hashes_are_those_of_the_raw_files_and_the_truth_files(frozen, repo):
    """The truth files too: the frozen report shows the estimates beside them (until 2026-12-07 not hashed)."""
    folder, _ = frozen
    lines = dict(reversed(line.split("  ", 1)) for line in (folder / "raw_inputs.sha256").read_text().splitlines())
    raw = sorted(p for folder in ("data/raw", "data/truth") for p in (repo / folder).rglob("*") if p.is_file())
    assert any("data/truth/" in str(p) for p in raw)
    assert sorted(lines) == [str(p.relative_to(repo)) for p in raw]
    for path in raw:
        assert lines[str(path.relative_to(repo))] == hashlib.sha256(path.read_bytes()).hexdigest()
    proc = sha256sum_check(repo, folder / "raw_inputs.sha256")
    assert proc.returncode == 0, proc.stdout + proc.stderr


def test_provenance_names_the_commit_command_software_and_config(frozen, repo):
    folder, proc = frozen
    doc = json.loads((folder / "provenance.json").read_text())
    assert doc["tag"] == "t1"
    assert doc["git"]["commit"] == git(repo, "rev-parse", "HEAD")
    assert doc["git"]["dirty"] is False and doc["dirty"] is False and doc["git"]["dirty_files"] == []
    assert doc["command"] == "snakemake -c1 freeze --config freeze_tag=t1"
    frozen_at = datetime.strptime(doc["frozen_at_utc"], "%Y-%m-%dT%H:%M:%SZ").replace(tzinfo=UTC)
    assert abs((datetime.now(UTC) - frozen_at).total_seconds()) < 3600
    software = doc["software"]
    assert software["python"] and software["packages"]["snakemake"] and software["opencv_video"]["opencv"]
    assert "FFMPEG" in software["opencv_video"]["video_io"]
    assert doc["trials"]["failed"] == [] and len(doc["trials"]["ok"]) == 5
    # The config as used: defaults filled in, the freeze's own keys left out, digest reproducible from the file.
    used = yaml.safe_load((folder / "config.yaml").read_text())
    original = yaml.safe_load((repo / "config.yaml").read_text())
    assert used == config_as_used(original) and used["reestimate_geometry"] is False and "freeze_tag" not in used
    assert doc["config_sha256"] == config_digest(used) == config_digest({**original, "freeze_tag": "t1"})
    assert doc["config_sha256"] in (folder / "config.yaml").read_text()
    # The manifest's digest, the one to cite, is in the log.
    manifest_sha256 = hashlib.sha256((folder / MANIFEST).read_bytes()).hexdigest()
    assert manifest_sha256 in (repo / "logs/freeze/t1.log").read_text()


def test_citation_cff_names_the_tag_commit_and_date(frozen):
    folder, _ = frozen
    doc = json.loads((folder / "provenance.json").read_text())
    cff = yaml.safe_load((folder / "CITATION.cff").read_text())
    assert cff["cff-version"] == "1.2.0" and cff["message"] and cff["type"] == "dataset"
    assert "t1" in cff["title"] and cff["version"] == "t1"
    assert cff["date-released"] == doc["frozen_at_utc"][:10] and cff["commit"] == doc["git"]["commit"]
    assert cff["authors"] and all(a.get("name") or a.get("family-names") for a in cff["authors"])


def test_an_existing_tag_is_never_overwritten(frozen, repo):
    folder, _ = frozen
    before = tree_bytes(folder)
    summary = repo / "results/fits/summary.csv"
    mtime_ns = summary.stat().st_mtime_ns
    summary.touch()  # an input newer than the folder: still nothing may run
    try:
        proc = run(["-c1", "freeze", "--config", "freeze_tag=t1"], repo, check=False)
        plan = run(["-n", "freeze", "--config", "freeze_tag=t1"], repo, check=False)
    finally:
        os.utime(summary, ns=(mtime_ns, mtime_ns))
    out = proc.stdout + proc.stderr
    assert proc.returncode != 0 and "results/frozen/t1 already exists" in out and "never overwritten" in out
    assert plan.returncode != 0 and "already exists" in plan.stdout + plan.stderr
    assert tree_bytes(folder) == before
    assert sorted(p.name for p in (repo / "results/frozen").iterdir()) == ["t1"]


def test_a_dirty_tree_is_refused_unless_allowed_and_then_marked(frozen, repo):
    notes = repo / "NOTES.md"
    notes.write_text("changed\n")
    try:
        refused = run(["-c1", "freeze", "--config", "freeze_tag=t2"], repo, check=False)
        out = refused.stdout + refused.stderr
        assert refused.returncode != 0 and "NOTES.md" in out and "freeze_allow_dirty=true" in out
        assert not (repo / "results/frozen/t2").exists()
        run(["-c1", "freeze", "--config", "freeze_tag=t2", "freeze_allow_dirty=true"], repo)
    finally:
        git(repo, "checkout", "-q", "NOTES.md")
    folder = repo / "results/frozen/t2"
    doc = json.loads((folder / "provenance.json").read_text())
    assert doc["dirty"] is True and doc["git"]["dirty"] is True and doc["git"]["dirty_files"] == ["NOTES.md"]
    assert doc["freeze_allow_dirty"] is True and "NOTES.md" in (folder / "DIRTY").read_text()
    assert "DIRTY" in (folder / "README.md").read_text()
    # The report was rebuilt for the changed tree and says so in its provenance.
    assert "with uncommitted changes" in (folder / "results/report/report.html").read_text()
    proc = sha256sum_check(folder, MANIFEST)
    assert proc.returncode == 0, proc.stdout + proc.stderr


def test_a_tag_whose_folder_was_deleted_is_refused_by_the_workflow_and_the_freeze_says_what_to_cite(frozen, repo):
    """The run's last lines name the folder and its manifest's SHA-256 (a fresh-eyes user found them only in the
    log); deleting the folder and freezing its tag again is refused, non-zero (it was "Nothing to be done")."""
    proc = run(["-c1", "freeze", "--config", "freeze_tag=t3"], repo)
    folder = repo / "results/frozen/t3"
    cited = hashlib.sha256((folder / MANIFEST).read_bytes()).hexdigest()
    assert f"froze results/frozen/t3; cite it with the SHA-256 of its {MANIFEST}: {cited}" in proc.stderr
    for path in folder.rglob("*"):
        path.chmod(0o755 if path.is_dir() else 0o644)
    shutil.rmtree(folder)
    again = run(["-c1", "freeze", "--config", "freeze_tag=t3"], repo, check=False)
    assert again.returncode != 0 and not folder.exists()
    assert "freeze_tag t3 was frozen before (benchmarks/jobs/freeze/t3.tsv)" in again.stdout + again.stderr


def test_a_freeze_needs_a_safe_tag(repo):
    missing = run(["-n", "freeze"], repo, check=False)
    assert missing.returncode != 0 and "freeze_tag=NAME" in missing.stdout + missing.stderr
    unsafe = run(["-n", "freeze", "--config", "freeze_tag=../t1"], repo, check=False)
    assert unsafe.returncode != 0 and "freeze_tag" in unsafe.stdout + unsafe.stderr


def test_tampering_with_any_file_fails_the_manifest(frozen, tmp_path):
    folder, _ = frozen
    for change in ("edit", "delete"):
        copy = tmp_path / change
        shutil.copytree(folder, copy)
        target = copy / "results/fits/summary.csv"
        target.chmod(0o644)
        if change == "edit":
            target.write_bytes(target.read_bytes().replace(b"0", b"1", 1))
        else:
            target.unlink()
        proc = sha256sum_check(copy, MANIFEST)
        assert proc.returncode != 0 and "results/fits/summary.csv" in proc.stdout + proc.stderr


# Library level: outside git, failures, odd names, lock comparison.


def fake_workdir(root: Path) -> Path:
    (root / "results/fits").mkdir(parents=True)
    (root / "results/fits/summary.csv").write_text("variant,fit\nquadratic,a\n")
    (root / "results/status").mkdir(parents=True)
    (root / "results/status/trials.csv").write_text(
        "trial,source,rig,status,stage,reason,log\n"
        "a,data/raw/a.mp4,r,ok,,,\n"
        "b,data/raw/b.mp4,r,failed,tracks,no marker,logs/tracks/b.log\n"
    )
    (root / "data/raw").mkdir(parents=True)
    (root / "data/raw/a.mp4").write_bytes(b"not really a video")
    (root / "environment-lock.txt").write_text("numpy==0.0.1 \\\n    --hash=sha256:00\n")
    return root


def freeze_here(tag="x", results=("results/fits/summary.csv",), raw_dir="data/raw", **kwargs):
    return freeze(
        tag=tag,
        results=list(results),
        lock_file="environment-lock.txt",
        config={"raw_dir": raw_dir, "freeze_tag": tag},
        raw_dir=raw_dir,
        code_root=".",
        frozen_at=datetime(2024, 5, 6, 7, 8, 9, tzinfo=UTC),
        **kwargs,
    )


def test_outside_git_a_freeze_is_refused_unless_allowed_and_then_dirty(tmp_path, monkeypatch):
    monkeypatch.chdir(fake_workdir(tmp_path))
    with pytest.raises(FreezeError, match="not a git work tree"):
        check_request("x", False, "results/frozen", ".")
    folder, manifest_sha256 = freeze_here(
        results=["results/fits/summary.csv", "results/status/trials.csv"], allow_dirty=True
    )
    assert folder == Path("results/frozen/x")
    doc = json.loads((folder / "provenance.json").read_text())
    assert doc["git"]["commit"] is None and doc["dirty"] is True and doc["frozen_at_utc"] == "2024-05-06T07:08:09Z"
    assert "outside a git work tree" in (folder / "DIRTY").read_text()
    assert doc["environment_lock_differences"][0]["package"] == "numpy"
    assert doc["trials"] == {
        "ok": ["a"],
        "failed": [{"trial": "b", "stage": "tracks", "reason": "no marker"}],
        "skipped": [],
    }
    assert hashlib.sha256((folder / MANIFEST).read_bytes()).hexdigest() == manifest_sha256
    assert sha256sum_check(folder, MANIFEST).returncode == 0
    with pytest.raises(FreezeError, match="already exists"):
        freeze_here(allow_dirty=True)


def test_a_failed_freeze_leaves_nothing_named_after_its_tag(tmp_path, monkeypatch):
    monkeypatch.chdir(fake_workdir(tmp_path))
    with pytest.raises(FileNotFoundError):
        freeze_here(results=["results/fits/summary.csv", "results/fits/missing.csv"], allow_dirty=True)
    assert list(Path("results/frozen").iterdir()) == []
    with pytest.raises(FreezeError, match="inside the workflow"):
        freeze_here(results=["../elsewhere.csv"], allow_dirty=True)
    assert list(Path("results/frozen").iterdir()) == []


@pytest.mark.parametrize("tag", [None, "", "../up", ".hidden", "a/b", "a b"])
def test_unsafe_or_missing_tags_are_refused(tmp_path, tag):
    with pytest.raises(FreezeError, match="freeze_tag"):
        check_request(tag, True, tmp_path, tmp_path)


def test_the_manifest_escapes_names_as_sha256sum_does(tmp_path):
    for name in ("plain.csv", "with space.csv", "back\\slash.csv"):
        (tmp_path / name).write_text(name)
    (tmp_path / MANIFEST).write_text(manifest(tmp_path))
    proc = sha256sum_check(tmp_path, MANIFEST)
    assert proc.returncode == 0, proc.stdout + proc.stderr


def test_lock_differences_compare_normalised_names_and_versions():
    lock = "PyYAML==6.0.3 \\\n    --hash=sha256:ab\nopencv-python-headless==5.0.0.93\n# comment\nscipy==1.0\n"
    installed = ["pyyaml==6.0.3", "opencv_python_headless==5.0.0.93", "scipy==1.1"]
    assert lock_differences(lock, installed) == [{"package": "scipy", "locked": "1.0", "installed": "1.1"}]


def test_citation_takes_title_and_authors_from_config():
    text = citation_cff(
        "v2",
        datetime(2024, 5, 6, tzinfo=UTC),
        {"commit": "a" * 40, "dirty": False},
        {"title": "ROV X", "authors": [{"family-names": "Doe", "given-names": "Jane"}]},
        "f" * 64,
    )
    cff = yaml.safe_load(text)
    assert cff["title"] == "ROV X (frozen results v2)" and cff["authors"][0]["family-names"] == "Doe"
    assert cff["date-released"] == "2024-05-06" and re.fullmatch("a{40}", cff["commit"])


def test_the_repository_address_is_cited_where_the_clone_has_one():
    """A reader holding only the folder learns where the commit lives: the origin remote as a web address (an ssh
    remote turned into https, credentials and .git dropped), in CITATION.cff's repository-code."""
    assert repository_url("git@github.com:lab/pendulum.git") == "https://github.com/lab/pendulum"
    assert repository_url("ssh://git@gitlab.example.org/group/pendulum") == "https://gitlab.example.org/group/pendulum"
    assert (
        repository_url("ssh://git@gitlab.example.org:2222/group/pendulum.git")
        == "https://gitlab.example.org/group/pendulum"
    )
    assert repository_url("https://user:secret@github.com/lab/pendulum.git") == "https://github.com/lab/pendulum"
    assert repository_url("https://github.com/lab/pendulum") == "https://github.com/lab/pendulum"
    assert repository_url("/home/me/pendulum") is None and repository_url(None) is None
    git = {"commit": "a" * 40, "dirty": False, "repository": "https://github.com/lab/pendulum"}
    cff = yaml.safe_load(citation_cff("v3", datetime(2024, 5, 6, tzinfo=UTC), git, None, "f" * 64))
    assert cff["repository-code"] == "https://github.com/lab/pendulum" and cff["commit"] == "a" * 40
    without = yaml.safe_load(citation_cff("v3", datetime(2024, 5, 6, tzinfo=UTC), {"commit": "a" * 40}, None, "f" * 64))
    assert "repository-code" not in without


def test_the_trials_sidecars_are_frozen_with_the_results(tmp_path, monkeypatch):
    """A trial's sidecar says which rig it is on, its own values and a skip (a helper's frozen folder held none:
    a reader rebuilding from it would have put an air pendulum on the paper's rig). Kept at their own paths,
    covered by the manifest, listed in the provenance."""
    monkeypatch.chdir(fake_workdir(tmp_path))
    (tmp_path / "data/raw/a.yaml").write_text("rig: wooden_air\nlength_m: 0.334\n")
    (tmp_path / "data/raw/b.yaml").write_text('skip: "the marker fell off"\n')
    folder, _ = freeze_here(allow_dirty=True, sidecars=["data/raw/b.yaml", "data/raw/a.yaml"])
    for name in ("a", "b"):
        assert (folder / f"data/raw/{name}.yaml").read_bytes() == (tmp_path / f"data/raw/{name}.yaml").read_bytes()
    assert json.loads((folder / "provenance.json").read_text())["sidecars"] == ["data/raw/a.yaml", "data/raw/b.yaml"]
    assert "data/raw/a.yaml" in (folder / MANIFEST).read_text() and sha256sum_check(folder, MANIFEST).returncode == 0
    assert "| `data/raw/*.yaml` | each trial's sidecar as used" in (folder / "README.md").read_text()  # its guide too


def test_a_tag_frozen_before_whose_folder_is_gone_is_refused_not_taken_as_done(tmp_path):
    """A fresh-eyes user (2026-12-07) deleted results/frozen/v4 and froze v4 again: "Nothing to be done", exit 0, no
    folder (the freeze rule's only file, its benchmark, was still there). A tag names one folder for good."""
    record = tmp_path / "benchmarks/jobs/freeze/v4.tsv"
    check_request("v4", True, tmp_path / "results/frozen", tmp_path, record=record)  # never frozen: fine
    record.parent.mkdir(parents=True)
    record.write_text("s\n1.0\n")
    with pytest.raises(FreezeError, match=r"freeze_tag v4 was frozen before \(.*v4\.tsv\), but .*frozen/v4 is gone"):
        check_request("v4", True, tmp_path / "results/frozen", tmp_path, record=record)


def test_data_and_config_wherever_the_config_puts_them_leave_the_code_clean_and_are_hashed(tmp_path, monkeypatch):
    """A fresh-eyes user's freezes (2026-12-07) were refused as dirty for `raw_dir: mydata`, a camera clip in
    data/calibration/ (where docs/configuration.md puts it) and an untracked `--configfile run2.yaml`; and the
    truth files the frozen report shows, and the clips, were never hashed."""
    from pendulum.provenance import data_paths, git_state

    work = fake_workdir(tmp_path)
    monkeypatch.chdir(work)
    (work / "code.py").write_text("x = 1\n")
    git(work, "init", "-q")
    git(work, "add", "code.py", "environment-lock.txt")
    git(work, "commit", "-q", "-m", "code")
    for path in ("mydata/run 1.mp4", "truth/run 1.yaml", "data/calibration/lens.mp4", "run2.yaml"):
        (work / path).parent.mkdir(parents=True, exist_ok=True)
        (work / path).write_text(path)
    config = {
        "raw_dir": "mydata",
        "truth_dir": "truth",
        "cameras": {"tank": {"calibration_video": "data/calibration/lens.mp4", "square_size_m": 0.02}},
    }
    data = data_paths(config, [str(work / "run2.yaml"), "/elsewhere/other.yaml"], work)
    assert data == ("mydata", "truth", "data/calibration/lens.mp4", "run2.yaml")
    assert git_state(work)["dirty_files"] == [
        "data/calibration/lens.mp4",
        "mydata/run 1.mp4",
        "run2.yaml",
        "truth/run 1.yaml",
    ]
    assert git_state(work, data)["dirty"] is False
    check_request("v1", False, "results/frozen", work, data)  # not refused
    (work / "code.py").write_text("x = 2\n")
    with pytest.raises(FreezeError, match=r"differs from commit .* in code\.py: commit"):
        check_request("v1", False, "results/frozen", work, data)
    git(work, "checkout", "-q", "code.py")
    folder, _ = freeze_here(tag="v1", raw_dir="mydata", data=data, inputs=("truth", "data/calibration/lens.mp4"))
    hashed = [line.split("  ", 1)[1] for line in (folder / "raw_inputs.sha256").read_text().splitlines()]
    assert hashed == ["data/calibration/lens.mp4", "mydata/run 1.mp4", "truth/run 1.yaml"]
    assert sha256sum_check(work, folder / "raw_inputs.sha256").returncode == 0
    doc = json.loads((folder / "provenance.json").read_text())
    assert doc["dirty"] is False and doc["raw_inputs"]["also"] == ["truth", "data/calibration/lens.mp4"]


def test_a_workflow_in_a_folder_of_a_larger_repository_is_judged_on_its_own_folder(tmp_path):
    """git names changed files from the repository's top: a workflow kept in `sub/` of a larger repository had its
    data there (`sub/data/raw/…`) counted as code changes, and another project's files too (a reviewer,
    2026-12-07). Its own folder only, its paths as from it."""
    from pendulum.provenance import git_state

    (tmp_path / "sub").mkdir()
    (tmp_path / "sub/code.py").write_text("x = 1\n")
    (tmp_path / "other.py").write_text("y = 1\n")
    git(tmp_path, "init", "-q")
    git(tmp_path, "add", "-A")
    git(tmp_path, "commit", "-q", "-m", "two projects")
    (tmp_path / "sub/data/raw").mkdir(parents=True)
    (tmp_path / "sub/data/raw/a.mp4").write_text("video")
    (tmp_path / "other.py").write_text("y = 2\n")  # the other project's change
    assert git_state(tmp_path / "sub")["dirty"] is False
    (tmp_path / "sub/code.py").write_text("x = 2\n")
    assert git_state(tmp_path / "sub")["dirty_files"] == ["code.py"]
