"""Reruns, bad trials and interrupted runs: finished work stays finished, one bad file costs nothing else.

Dry runs (`snakemake -n`) on the demo build check what each kind of change
reruns; real runs check that a truncated and a fake video leave every other
result (and data/raw) intact, and that a run killed mid-way resumes to the
same bytes as an uninterrupted one.
"""

import json
import os
import re
import shutil
import signal
import subprocess
import time
from collections import Counter
from contextlib import contextmanager
from pathlib import Path

import pandas as pd
import pytest
import yaml

from conftest import demo_trials
from workflow_run import (
    BAD_VIDEOS,
    SNAKEMAKE,
    digest,
    only_the_bad_videos_failed,
    planned_wildcards,
    run,
    small_project,
)

VARIANTS = ("friction", "linear", "quadratic")
AGGREGATES = {"fit_joint", "fit_summary", "status_table", "check_trials", "all", "report", "discovery", "design"}


def plan(project, *args) -> Counter:
    """(rule, trial/rig/None) → number of planned jobs."""
    out = run(["-n", *args], project).stdout
    return Counter((rule, w.get("trial", w.get("rig"))) for rule, w in planned_wildcards(out))


@contextmanager
def edited(path: Path):
    """``path`` edited (a comment appended) inside the block; its bytes and time are restored after.

    Snakemake reruns on content, not on a newer time alone (it keeps checksums of small inputs).
    """
    stat, text = path.stat(), path.read_bytes()
    path.write_bytes(text + b"\n# edited\n")
    try:
        yield
    finally:
        path.write_bytes(text)
        os.utime(path, ns=(stat.st_atime_ns, stat.st_mtime_ns))


def test_touching_nothing_reruns_nothing(demo_project):
    assert "Nothing to be done" in run(["-n"], demo_project).stdout


def test_adding_a_video_runs_only_that_trial_and_the_aggregates(demo_project):
    extra = demo_project / "data/raw/extra_m05.mp4"
    shutil.copy(demo_project / "data/raw/demo_m05.mp4", extra)
    try:
        jobs = plan(demo_project)
    finally:
        extra.unlink()
    per_trial = {(rule, name) for rule, name in jobs if rule not in AGGREGATES}
    assert per_trial == {
        ("frames", "extra_m05"),
        ("tracks", "extra_m05"),
        ("angles", "extra_m05"),
        ("fit_trial", "extra_m05"),
    }, "the rig's geometry is kept: no other trial's angles or fits rerun"
    assert jobs[("fit_trial", "extra_m05")] == len(VARIANTS)
    assert jobs[("fit_joint", "paper_rig")] == len(VARIANTS)


def test_reestimating_the_geometry_is_a_deliberate_command(demo_project):
    extra = demo_project / "data/raw/extra_m05.mp4"
    shutil.copy(demo_project / "data/raw/demo_m05.mp4", extra)
    try:
        jobs = plan(demo_project, "--config", "reestimate_geometry=true")
    finally:
        extra.unlink()
    assert ("rig_geometry", "paper_rig") in jobs
    assert {name for rule, name in jobs if rule == "angles"} == set(demo_trials()) | {"extra_m05"}


def test_editing_one_variant_refits_only_that_variant(tmp_path, demo_project):
    config = yaml.safe_load((demo_project / "config.yaml").read_text())
    config["variants"]["linear"] = ["linear_damping"]
    changed = tmp_path / "variants.yaml"
    changed.write_text(yaml.safe_dump({"variants": config["variants"]}))
    out = run(["-n", "--configfile", str(changed)], demo_project).stdout
    jobs = planned_wildcards(out)
    assert {w["variant"] for _, w in jobs if "variant" in w} == {"linear"}
    rules = Counter(rule for rule, _ in jobs)
    assert rules["fit_trial"] == len(demo_trials())
    assert rules["fit_joint"] == 1
    assert set(rules) <= {"fit_trial"} | AGGREGATES


def test_editing_a_sidecar_rig_value_refits_that_trial_without_retracking(demo_project):
    sidecar = demo_project / "data/raw/demo_p05.yaml"
    sidecar.write_text("mass_kg: 3.60  # weighed again\n")
    try:
        jobs = plan(demo_project)
    finally:
        sidecar.unlink()
    per_trial = {(rule, name) for rule, name in jobs if rule not in AGGREGATES}
    assert per_trial == {("fit_trial", "demo_p05")}


def test_a_trial_skipped_by_its_sidecar_runs_no_job(demo_project):
    """`skip: <why>` in a sidecar (a reviewer, 2026-12-02: the star, refused on every run, kept the run red and
    could only be moved out of data/raw): no job of that trial; the status table and the aggregates again."""
    sidecar = demo_project / "data/raw/demo_p05.yaml"
    sidecar.write_text('skip: "the marker fell off at 3 s"\n')
    try:
        jobs = plan(demo_project)
        # a skipped trial's sidecar that defines a rig still defines it for the trials that name it
        sidecar.write_text("skip: true\nrig: tank_b\nmass_kg: 3.5\nlength_m: 0.76\nfrontal_area_m2: 0.032\n")
        (demo_project / "data/raw/demo_p20.yaml").write_text("rig: tank_b\n")
        moved = plan(demo_project)
    finally:
        sidecar.unlink()
        (demo_project / "data/raw/demo_p20.yaml").unlink(missing_ok=True)
    assert not [job for job in jobs if job[1] == "demo_p05"], jobs
    assert ("status_table", None) in jobs and ("check_trials", None) in jobs
    assert ("rig_geometry", "tank_b") in moved and not [job for job in moved if job[1] == "demo_p05"], moved


@pytest.mark.parametrize(
    "module,first_stage,untouched",
    [
        ("fit/output_error.py", "fit_trial", {"frames", "tracks", "rig_geometry", "angles"}),
        ("tracking/marker.py", "tracks", {"frames"}),
        ("angles/record.py", "angles", {"frames", "tracks"}),
    ],
)
def test_editing_a_library_module_reruns_the_stages_that_import_it(demo_project, module, first_stage, untouched):
    with edited(demo_project / "workflow/pendulum" / module):
        jobs = plan(demo_project)
    rules = {rule for rule, _ in jobs}
    assert first_stage in rules
    assert not rules & untouched, rules & untouched


def test_a_truncated_and_a_fake_video_cost_nothing_else(small_build):
    """The small build's two unreadable videos (``workflow_run.small_project``) beside its good one."""
    work, good = small_build.work, ["demo_p20"]
    assert small_build.returncode != 0, "the run must say that trials failed"
    assert digest(work / "data/raw", ("*",)) == small_build.raw_before, "data/raw was modified"
    status = pd.read_csv(work / "results/status/trials.csv", keep_default_na=False).set_index("trial")
    assert (status.loc[good, "status"] == "ok").all()
    for bad, problem in BAD_VIDEOS.items():
        assert status.loc[bad, "status"] == "failed"
        assert f"{bad}.mp4" in status.loc[bad, "reason"] and problem in status.loc[bad, "reason"]
        assert Path(work / status.loc[bad, "log"]).is_file()
    joint = json.loads((work / "results/fits/quadratic/joint/paper_rig.json").read_text())
    assert joint["status"] == "ok" and sorted(joint["trials"]) == good
    assert set(joint["excluded_trials"]) == set(BAD_VIDEOS)
    summary = pd.read_csv(work / "results/fits/summary.csv")
    assert set(summary.fit) == set(good) | {"joint:paper_rig"}
    report = (work / "results/report/report.html").read_text()
    assert "truncated.mp4" in report and "fake.mp4" in report and "truncated MP4" in report
    assert "2 of 3 trial(s) failed" in (work / "logs/status/check.log").read_text()
    assert not list((work / "results").rglob(".*.tmp*")), "a temporary file was left behind"
    assert "Shell command: None" not in small_build.output
    # the failed trials once, one line each, after Snakemake's own error lines (the Snakefile's onerror)
    tail = small_build.output[small_build.output.index("Exiting because a job execution failed") :]
    assert small_build.output.count("2 of 3 trial(s) failed") == 1 and "2 of 3 trial(s) failed;" in tail
    assert "\n  - fake, at tracks: " in tail or "\n  - fake, at frames: " in tail, tail
    # a rerun does not retry what failed for a reason that has not changed, and still says it failed
    results = digest(work / "results")
    again = run(["-c2"], work, check=False)
    assert again.returncode != 0
    assert {rule for rule, _ in planned_wildcards(again.stdout)} <= {"check_trials", "all"}
    assert digest(work / "results") == results  # (the build other tests compare with)


def test_the_terminal_shows_what_went_wrong_and_the_logs_hold_the_rest(small_build):
    """A job's progress and facts go to its log only; its warnings and errors to the terminal too."""
    work, terminal = small_build.work, small_build.output
    assert " INFO " not in terminal, [line for line in terminal.splitlines() if " INFO " in line][:5]
    assert re.search(r" ERROR .*fake\.mp4", terminal) and re.search(r" ERROR .*truncated\.mp4", terminal)
    tracks = (work / "logs/tracks/demo_p20.log").read_text()
    assert " INFO data/raw/demo_p20.mp4: detected a bright marker" in tracks and "frames usable" in tracks
    frames = (work / "logs/frames/demo_p20.log").read_text()
    assert re.search(r"INFO data/raw/demo_p20\.mp4: 660 frames of 1280×720 px \(h264, yuv420p\)", frames)


def _answers_ctrl_c() -> None:
    """In the build's process: SIGINT back to its default. A shell runs a background job (``… &``: CI started so,
    or under nohup) with SIGINT ignored, every process below inherits that, and Python then installs no
    KeyboardInterrupt: Snakemake never sees the Ctrl-C (the record's and CI's failures of this test)."""
    signal.signal(signal.SIGINT, signal.SIG_DFL)


def _kill_mid_run(work: Path, sig: int, after: str, options=(), delay_s: float = 0.0) -> None:
    """Start a build and send ``sig`` to its whole process group ``delay_s`` after the file ``after`` exists."""
    output = work.parent / f"killed-{sig}.log"
    with open(output, "w") as out:
        proc = subprocess.Popen(
            [*SNAKEMAKE, "-c2", *options],
            cwd=work,
            stdout=out,
            stderr=out,
            start_new_session=True,
            preexec_fn=_answers_ctrl_c,
        )
        deadline = time.time() + 300
        while time.time() < deadline and proc.poll() is None and not (work / after).exists():
            time.sleep(0.1)
        time.sleep(delay_s)
    assert proc.poll() is None, (
        f"the build ended (exit {proc.returncode}) before it could be interrupted:\n" + output.read_text()[-3000:]
    )
    os.killpg(proc.pid, sig)
    for _ in range(4):  # Snakemake drops a Ctrl-C that comes while it writes its log: pressed again, as a user would
        try:
            proc.wait(timeout=1.25)
            break
        except subprocess.TimeoutExpired:
            if sig == signal.SIGINT and "Terminating processes on user request" not in output.read_text():
                os.killpg(proc.pid, sig)
    proc.wait(timeout=120)


def test_an_interrupted_then_killed_run_resumes_to_the_same_bytes(tmp_path, small_build):
    """Ctrl-C (SIGINT) mid-build, a second into tracking (the job stopped, its outputs unfinished), then the
    rerun with --rerun-incomplete killed the moment the angles appear (SIGKILL: no clean-up, the lock left, the
    angles job caught between writing its outputs and Snakemake marking them complete): unlocked and rerun,
    the results are the clean build's bytes. One build carries both interruptions."""
    work = small_project(tmp_path / "p")
    # the Ctrl-C comes a second into the tracking job (not as an output appears: Snakemake is logging then)
    _kill_mid_run(work, signal.SIGINT, after="logs/tracks/demo_p20.log", delay_s=1.0)
    assert "Terminating processes on user request" in (tmp_path / f"killed-{signal.SIGINT}.log").read_text()
    assert not (work / "results/angles/demo_p20.json").exists()  # the interruption came mid-build
    _kill_mid_run(work, signal.SIGKILL, after="results/angles/demo_p20.json", options=["--rerun-incomplete"])
    assert not (work / "results/report/report.html").exists()  # both interruptions came before the end
    run(["--unlock"], work)  # a killed Snakemake cannot remove its lock
    assert run(["-c2", "--rerun-incomplete"], work, check=False).returncode != 0  # its two bad videos
    assert only_the_bad_videos_failed(work) and only_the_bad_videos_failed(small_build.work)
    assert digest(work / "results") == digest(small_build.work / "results")
    assert not list((work / "results").rglob(".*.tmp*"))
