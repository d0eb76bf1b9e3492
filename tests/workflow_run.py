"""Running the Snakemake workflow from tests: a project copy, runs, dry-run plans, result digests."""

import hashlib
import re
import shutil
import subprocess
import sys
from dataclasses import dataclass
from pathlib import Path

from conftest import DEMO_RAW, DEMO_TRUTH, ROOT

SNAKEMAKE = [sys.executable, "-m", "snakemake"]
PROJECT_ITEMS = ("Snakefile", "config.yaml", "workflow", "profiles", "notebooks", "environment-lock.txt")


def run(args, cwd, check=True, **kwargs):
    proc = subprocess.run(SNAKEMAKE + list(args), cwd=cwd, capture_output=True, text=True, **kwargs)
    if check and proc.returncode != 0:
        raise AssertionError(f"snakemake {args} failed:\n{proc.stdout[-3000:]}\n{proc.stderr[-3000:]}")
    return proc


def copy_project(work: Path, raw_files=None) -> Path:
    """The workflow (code, config, profile, notebooks) and raw videos copied to ``work``."""
    work.mkdir(parents=True, exist_ok=True)
    for item in PROJECT_ITEMS:
        src = ROOT / item
        if src.exists():
            if src.is_dir():  # not the files other workers are writing (a module's .pyc, numba's cache) mid-copy
                shutil.copytree(src, work / item, ignore=shutil.ignore_patterns("*.pyc.*", "*.tmp.*"))
            else:
                shutil.copy2(src, work / item)
    raw = work / "data" / "raw"
    raw.mkdir(parents=True, exist_ok=True)
    for path in raw_files if raw_files is not None else sorted(DEMO_RAW.iterdir()):
        shutil.copy2(path, raw / Path(path).name)
    if raw_files is None:  # the demo's synthetic truth, which the report shows beside the estimates
        shutil.copytree(DEMO_TRUTH, work / "data" / "truth")
    return work


def one_variant(work: Path, variant: str = "quadratic", terms=("quadratic_drag",)) -> Path:
    """The project's config.yaml with a single model variant (fewer jobs for tests of the machinery)."""
    import yaml

    config = yaml.safe_load((work / "config.yaml").read_text())
    config["variants"] = {variant: list(terms)}
    (work / "config.yaml").write_text(yaml.safe_dump(config, sort_keys=False))
    return work


@dataclass(frozen=True)
class Build:
    """A project built once for several tests: its folder, Snakemake's exit code and output, and the digest of
    its data/raw before the build."""

    work: Path
    returncode: int
    output: str
    raw_before: dict


BAD_VIDEOS = {"truncated": "truncated MP4", "fake": "not a video"}  # trial → what its failure must say


def only_the_bad_videos_failed(work: Path) -> bool:
    """In a build of :func:`small_project`: its good trial built, its two bad videos failed, nothing else."""
    import pandas as pd

    status = pd.read_csv(work / "results/status/trials.csv", keep_default_na=False).set_index("trial").status
    return status.to_dict() == {"demo_p20": "ok", **dict.fromkeys(BAD_VIDEOS, "failed")}


def small_project(work: Path) -> Path:
    """One demo video (demo_p20), one variant, and two videos that cannot be read (``truncated.mp4``, the demo
    video's first 300 kB; ``fake.mp4``, a text file): every rule of the workflow in few jobs, and two trials that
    fail (the build ends non-zero, at its last step)."""
    work = one_variant(copy_project(work, raw_files=[DEMO_RAW / "demo_p20.mp4"]))
    raw = work / "data" / "raw"
    (raw / "truncated.mp4").write_bytes((DEMO_RAW / "demo_p20.mp4").read_bytes()[:300_000])
    (raw / "fake.mp4").write_text("this is a text file, not a video\n")
    return work


def planned_wildcards(dry_run_output: str) -> list[tuple[str, dict]]:
    """(rule, {wildcard: value}) of every job in a dry run (jobs without wildcards: empty dict)."""
    jobs, rule, wildcards = [], None, {}
    for line in dry_run_output.splitlines():
        m = re.match(r"^\s*(?:local)?rule (\w+):", line)
        if m:
            if rule is not None:
                jobs.append((rule, wildcards))
            rule, wildcards = m.group(1), {}
        m = re.match(r"^\s*wildcards: (.+)$", line)
        if m and rule:
            wildcards = dict(item.split("=", 1) for item in m.group(1).split(", "))
    if rule is not None:
        jobs.append((rule, wildcards))
    return jobs


def planned_jobs(dry_run_output: str) -> set[tuple[str, str | None]]:
    """(rule, trial or rig or None) of every job in a dry run."""
    return {(rule, w.get("trial", w.get("rig"))) for rule, w in planned_wildcards(dry_run_output)}


def digest(folder: Path, patterns=("*.csv", "*.json", "*.png", "*.html", "*.ipynb")) -> dict:
    return {
        str(p.relative_to(folder)): hashlib.sha256(p.read_bytes()).hexdigest()
        for pat in patterns
        for p in sorted(folder.rglob(pat))
    }
