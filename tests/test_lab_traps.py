"""Three traps a lab walks into: file names with spaces, numbers as people write them, a full disk."""

import copy
import errno
import logging
import os
import re
import subprocess
import sys
from pathlib import Path

import pytest
import yaml

from conftest import ROOT
from pendulum import io
from pendulum.camera.raw_folder import discover_trials, passed_over, trial_name
from pendulum.status import run_stage
from pendulum.trials import ConfigError, trial_settings, validate_config

CONFIG = yaml.safe_load((ROOT / "config.yaml").read_text())

# --- file names: any the operating system allows ------------------------------------------------------------


@pytest.mark.parametrize(
    "stem,name",
    [
        ("run 7 (left)", "run_7_left"),
        ("VID 2026-11-25 14.03", "VID_2026-11-25_14.03"),
        ("Versuch 3 – Kugel, 20°", "Versuch_3_Kugel_20"),
        ("été [2]", "ete_2"),
        ("_take-1_", "take-1"),
        ("demo_p05", "demo_p05"),  # a name that was already fine stays as it is
        ("Pendel groß – Prüfung", "Pendel_gross_Prufung"),
    ],
)
def test_a_trial_is_named_after_its_file_with_spaces_and_signs_made_underscores(stem, name):
    assert trial_name(stem) == name


def test_a_file_name_of_signs_only_still_gives_a_usable_trial_name():
    name = trial_name("(( ))")
    assert name.startswith("trial_") and len(name) == 14 and name == trial_name("(( ))")
    assert name != trial_name("[ ]")


def test_names_in_another_script_stay_apart():
    """Letters outside Latin script cannot be kept in a results/ path here; a digest of the whole name keeps
    `опыт 1` and `опыт 2` (and `(1)`) apart instead of all becoming `1`."""
    names = {stem: trial_name(stem) for stem in ("опыт 1", "опыт 2", "(1)", "振り子")}
    assert names["(1)"] == "1" and names["опыт 1"].startswith("1_") and names["опыт 2"].startswith("2_")
    assert len(set(names.values())) == 4 and names["振り子"].startswith("trial_")


def test_a_sidecar_may_be_named_after_the_file_or_the_trial_but_never_silently_ignored(tmp_path):
    (tmp_path / "run 7 (left).mp4").write_bytes(b"")
    (tmp_path / "run_7_left.yml").write_text("mass_kg: 3.6\n")  # the trial's name, .yml
    assert discover_trials(tmp_path)["run_7_left"].sidecar == {"mass_kg": 3.6}
    (tmp_path / "run 7 (left).yaml").write_text("mass_kg: 3.7\n")
    with pytest.raises(ConfigError, match=r"are both sidecars of .*run 7 \(left\)\.mp4 \(trial 'run_7_left'\)"):
        discover_trials(tmp_path)
    (tmp_path / "run_7_left.yml").unlink()
    (tmp_path / "run 8.yaml").write_text("mass_kg: 3.5\n")  # a typo'd or orphaned sidecar
    with pytest.raises(ConfigError, match=r"run 8\.yaml: a sidecar of no trial .* would be ignored"):
        discover_trials(tmp_path)
    (tmp_path / "run 8.yaml").unlink()
    # the video's whole name with .yaml after it, as a phone's IMG_0042.MOV gets IMG_0042.MOV.yaml (a fresh-eyes
    # user's, 2026-12-03: refused with a message that told them to do what they had done)
    (tmp_path / "IMG_0042.MOV").write_bytes(b"")
    (tmp_path / "IMG_0042.MOV.yaml").write_text("mass_kg: 0.18\n")
    assert discover_trials(tmp_path)["IMG_0042"].sidecar == {"mass_kg": 0.18}
    (tmp_path / "IMG_0042.yaml").write_text("mass_kg: 0.18\n")
    with pytest.raises(ConfigError, match=r"are both sidecars of .*IMG_0042\.MOV"):
        discover_trials(tmp_path)


def test_hidden_files_are_not_trials_and_names_differing_in_case_are_refused(tmp_path):
    (tmp_path / "run 9.mp4").write_bytes(b"")
    (tmp_path / "._run 9.mp4").write_bytes(b"\x00\x05\x16\x07")  # macOS's AppleDouble copy on a USB stick
    (tmp_path / ".DS_Store").write_bytes(b"")
    assert sorted(discover_trials(tmp_path)) == ["run_9"]
    assert passed_over(tmp_path) == []  # the AppleDouble copy and .DS_Store are no one's data
    (tmp_path / ".run 10.mp4").write_bytes(b"")  # a video hidden by its name: passed over, but named at the end
    assert sorted(discover_trials(tmp_path)) == ["run_9"] and passed_over(tmp_path) == [tmp_path / ".run 10.mp4"]
    (tmp_path / "Run 9.mov").write_bytes(b"")
    (tmp_path / "run 9.yaml").write_text("mass_kg: 0.18\n")  # the clashing pair's sidecar: not one of no trial
    for name in ("clip.mkv", "Clip.m4v", "CLIP.mp4", "joint.mp4"):
        (tmp_path / name).write_bytes(b"")
    with pytest.raises(ConfigError) as error:  # every clash at once (a helper renamed files over three runs)
        discover_trials(tmp_path)
    lines = str(error.value).splitlines()
    assert lines[0] == "3 problems in the raw folder:" and len(lines) == 4, lines
    assert re.search(r"CLIP\.mp4, .*Clip\.m4v, .*clip\.mkv all give trial 'CLIP'.*all but one of them", lines[1])
    assert re.search(r"joint\.mp4: 'joint' is reserved for the aggregate fits", lines[3]), lines
    assert re.search(r"run 9\.mp4 and .*Run 9\.mov both give trial .*differ only in case.*rename one of them", lines[2])
    for name in ("Run 9.mov", "run 9.yaml", "clip.mkv", "Clip.m4v", "CLIP.mp4", "joint.mp4"):
        (tmp_path / name).unlink()
    (tmp_path / "Joint.mp4").write_bytes(b"")
    with pytest.raises(ConfigError, match=r"'Joint' is reserved for the aggregate fits"):
        discover_trials(tmp_path)


def test_files_with_spaces_and_brackets_are_trials_and_keep_their_own_names(tmp_path):
    for file in ("run 7 (left).mp4", "VID 2026-11-25 14.03.MOV", "demo_p05.mp4", "table (exported).csv"):
        (tmp_path / file).write_bytes(b"")
    (tmp_path / "run 7 (left).yaml").write_text("mass_kg: 3.6\n")
    trials = discover_trials(tmp_path)
    assert sorted(trials) == ["VID_2026-11-25_14.03", "demo_p05", "run_7_left", "table_exported"]
    assert trials["run_7_left"].path == str(tmp_path / "run 7 (left).mp4")
    assert trials["run_7_left"].sidecar == {"mass_kg": 3.6}  # its sidecar: the same file name, .yaml
    assert trials["table_exported"].kind == "angles"


def test_a_raw_folder_that_is_missing_or_holds_no_trial_is_said_naming_what_it_holds(tmp_path):
    """A fresh-eyes user's runs (2026-12-07): `--config raw_dir=data/rawx` (no such folder) and a folder holding only
    `apple.m4v` both ended "1 of 1 steps (100%) done", exit 0, nothing said, the previous run's report left standing
    as if new. The plain run's target now stops with this (tests/test_workflow.py); a camera's calibration, which
    needs no trial, is not stopped (a reviewer)."""
    from pendulum.camera.raw_folder import raw_folder_problem

    assert discover_trials(tmp_path / "rawx") == {} and passed_over(tmp_path / "rawx") == []
    problem = raw_folder_problem(tmp_path / "rawx", {})
    assert re.search(r"rawx: no such folder \(config raw_dir.*set raw_dir to the folder", problem), problem
    (tmp_path / "a file").write_text("")
    assert "a file: a file, not a folder" in raw_folder_problem(tmp_path / "a file", {})
    (tmp_path / "notes.txt").write_text("swing 3 was bumped\n")
    (tmp_path / "clip.m2ts").write_bytes(b"")
    (tmp_path / ".DS_Store").write_bytes(b"")
    assert discover_trials(tmp_path) == {}
    problem = raw_folder_problem(tmp_path, discover_trials(tmp_path))
    assert re.search(
        r"no video \(\.mp4, .*\) or angle table \(\.csv\) in it \(passed over: a file, clip\.m2ts, notes\.txt\); put "
        r"the trials' files in it, or set raw_dir",
        problem,
    ), problem
    (tmp_path / "day 1").mkdir()  # videos sorted into folders: not read, and said so
    (tmp_path / "day 1" / "run1.mp4").write_bytes(b"")
    problem = raw_folder_problem(tmp_path, discover_trials(tmp_path))
    assert re.search(r"notes\.txt, day 1/\); .* \(the files in its folders are not read\)", problem), problem
    (tmp_path / "run1.mp4").write_bytes(b"")
    assert raw_folder_problem(tmp_path, discover_trials(tmp_path)) is None


def test_a_phones_camcorders_and_recorders_containers_are_videos_and_other_files_are_said_to_be_passed_over(
    tmp_path, capsys
):
    """.m4v (a phone's export), .MTS (a camcorder's), .mkv and .webm (screen and webcam recorders), .3gp are read as
    videos (the decoder reads each: tests/test_phone_files.py); a file that is none of a video, an angle table or a
    sidecar is listed in the run's last lines, not dropped unsaid."""
    from pendulum.outcomes import print_outcome

    for name in ("IMG_0001.m4v", "00012.MTS", "take.mkv", "webcam.webm", "old.3gp", "run.mp4", "notes.txt", "a.mpg"):
        (tmp_path / name).write_bytes(b"")
    (tmp_path / "run.yaml").write_text("mass_kg: 0.18\n")
    (tmp_path / "._run.mp4").write_bytes(b"\x00")
    trials = discover_trials(tmp_path)
    assert sorted(trials) == ["00012", "IMG_0001", "old", "run", "take", "webcam"]
    assert {t.kind for t in trials.values()} == {"video"}
    assert [p.name for p in passed_over(tmp_path)] == ["a.mpg", "notes.txt"]
    print_outcome(tmp_path / "check.log", since_s=0, passed_over=passed_over(tmp_path))
    err = capsys.readouterr().err
    assert f"Passed over in {tmp_path.as_posix()} (no video or angle table by its extension): a.mpg, notes.txt" in err


def test_two_files_giving_one_trial_name_are_refused_naming_both(tmp_path):
    (tmp_path / "run 7.mp4").write_bytes(b"")
    (tmp_path / "run_7.mp4").write_bytes(b"")
    with pytest.raises(ConfigError, match=r"run_7\.mp4 and .*run 7\.mp4 both give trial 'run_7'.*rename one"):
        discover_trials(tmp_path)


# --- numbers as people write them ----------------------------------------------------------------------------


@pytest.mark.parametrize(
    "text,key,value",
    [
        ("displaced_volume_m3: 5e-05\n", "displaced_volume_m3", 5e-05),  # YAML 1.1: text; YAML 1.2: a number
        ("displaced_volume_m3: 5E-5\n", "displaced_volume_m3", 5e-05),
        ("kinematic_viscosity_m2_s: 1e-6\n", "kinematic_viscosity_m2_s", 1e-06),
        ("mass_kg: 3\n", "mass_kg", 3),  # a whole number for a float
        ("mass_kg: +3.5\n", "mass_kg", 3.5),
        ("pivot_px: [3e2, -1.2e3]\n", "pivot_px", [300.0, -1200.0]),
    ],
)
def test_sidecar_numbers_as_people_write_them(tmp_path, text, key, value):
    (tmp_path / "trial.mp4").write_bytes(b"")
    (tmp_path / "trial.yaml").write_text(text)
    trials = discover_trials(tmp_path)
    assert trials["trial"].sidecar[key] == value
    settings = trial_settings(CONFIG, trials["trial"])
    if key in settings["rig"]:
        assert settings["rig"][key] == value and isinstance(settings["rig"][key], (int, float))


def test_config_numbers_as_people_write_them():
    text = (ROOT / "config.yaml").read_text()
    config = yaml.safe_load(text)
    rig = config["rigs"][config["default_rig"]]
    rig["displaced_volume_m3"], rig["frontal_area_m2"] = "25e-4", "3.22E-2"
    config["frames"]["contact_sheet_tiles"] = 16.0  # a whole float where a whole number is wanted
    assert yaml.safe_load("v: 5e-05")["v"] == "5e-05"  # what PyYAML (and Snakemake's config) gives
    validate_config(config)
    assert rig["displaced_volume_m3"] == 0.0025 and rig["frontal_area_m2"] == 0.0322
    assert config["frames"]["contact_sheet_tiles"] == 16 and isinstance(config["frames"]["contact_sheet_tiles"], int)


@pytest.mark.parametrize(
    "change,message",
    [
        (lambda c: c["rigs"]["paper_rig"].update(mass_kg="3.5 kg"), r"mass_kg is '3.5 kg', not a number"),
        (lambda c: c["rigs"]["paper_rig"].update(mass_kg="3,5"), r"mass_kg is '3,5', not a number"),
        (lambda c: c["frames"].update(contact_sheet_tiles=16.5), r"contact_sheet_tiles is 16.5, not a whole number"),
        (lambda c: c["frames"].update(contact_sheet_tiles="1e1.5"), r"contact_sheet_tiles is '1e1.5'"),
    ],
)
def test_what_is_not_a_number_is_still_refused(change, message):
    config = copy.deepcopy(CONFIG)
    change(config)
    with pytest.raises(ConfigError, match=message):
        validate_config(config)


# --- a full disk, a read-only folder, a quota ---------------------------------------------------------------


@pytest.mark.parametrize(
    "code,words",
    [
        (errno.ENOSPC, "the disk is full"),
        (errno.EROFS, "the file system is read-only"),
        (errno.EDQUOT, "the disk quota is exceeded"),
    ],
)
def test_a_write_that_fails_names_the_file_and_how_to_resume(tmp_path, monkeypatch, code, words):
    out = tmp_path / "results" / "fits" / "x.json"
    io.write_json({"a": 1}, out)

    def full(self, *args, **kwargs):
        raise OSError(code, os.strerror(code), str(self))

    monkeypatch.setattr(Path, "write_text", full)
    with pytest.raises(io.WriteFailure) as caught:
        io.write_json({"a": 2}, out)
    message = str(caught.value)
    assert message.startswith(f"{out} could not be written: {words}")
    assert "--rerun-incomplete" in message and "\n" not in message
    monkeypatch.undo()
    assert io.read_json(out) == {"a": 1}  # the old file whole, no temporary left
    assert sorted(p.name for p in out.parent.iterdir()) == ["x.json"]


def test_a_full_disk_is_not_the_trials_fault(tmp_path):
    """A stage that cannot write fails the job (a rerun resumes) instead of marking the trial failed."""
    written = []

    def work():
        raise io.write_failure(OSError(errno.ENOSPC, "No space left on device", "results/x/.t.csv.tmp12"))

    with pytest.raises(io.WriteFailure, match=r"results/x/t\.csv could not be written: the disk is full"):
        run_stage("tracks", logging.getLogger("t"), work, written.append)
    assert written == []


SCRIPT = """
import errno, sys, types
sys.path.insert(0, {scripts!r})
__main__ = sys.modules["__main__"]
__main__.snakemake = types.SimpleNamespace(threads=1, log=[{log!r}])
import _setup
{raise_}
"""


@pytest.mark.parametrize(
    "raise_,expected",
    [
        (
            "raise OSError(errno.ENOSPC, 'No space left on device', 'results/report/.report.html.tmp4242')",
            "error: results/report/report.html could not be written: the disk is full (No space left on device)",
        ),
        (  # the report's notebook kernel: papermill re-raises the kernel's error by name and text
            "class PapermillExecutionError(Exception):\n"
            "    ename, evalue = 'OSError', '[Errno 28] No space left on device: results/report/fig.png'\n"
            "raise PapermillExecutionError('cell 3')",
            "error: an output could not be written: the disk is full (No space left on device)",
        ),
    ],
)
def test_a_script_that_cannot_write_says_one_sentence_and_keeps_the_traceback_in_its_log(tmp_path, raise_, expected):
    log = tmp_path / "job.log"
    code = SCRIPT.format(scripts=str(ROOT / "workflow" / "scripts"), log=str(log), raise_=raise_)
    proc = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, cwd=tmp_path)
    assert proc.returncode == 1
    assert proc.stderr.startswith(expected) and proc.stderr.count("\n") == 1, proc.stderr
    assert "Traceback" not in proc.stderr and "snakemake -c2 --rerun-incomplete" in proc.stderr
    assert "Traceback" in log.read_text()


def test_any_other_error_of_a_script_keeps_its_traceback(tmp_path):
    code = SCRIPT.format(
        scripts=str(ROOT / "workflow" / "scripts"), log=str(tmp_path / "job.log"), raise_="raise KeyError('x')"
    )
    proc = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, cwd=tmp_path)
    assert proc.returncode == 1 and "Traceback" in proc.stderr and "KeyError: 'x'" in proc.stderr
