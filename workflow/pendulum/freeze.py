"""Frozen results folders: a build's results, report, configuration, environment and provenance,
copied to results/frozen/<tag>/ with a SHA-256 manifest, so that a result can be cited and verified.

A frozen folder is written once: it is built under a hidden temporary name and renamed into place,
an existing tag is refused, and its files are made read-only.
"""

from __future__ import annotations

import csv
import hashlib
import json
import os
import re
import shutil
from datetime import UTC, datetime
from pathlib import Path

import yaml

from pendulum.provenance import config_as_used, config_digest, git_state, installed_packages, software

TAG_PATTERN = re.compile(r"^[A-Za-z0-9][A-Za-z0-9_.+-]*$")
MANIFEST = "MANIFEST.sha256"
RAW_HASHES = "raw_inputs.sha256"
PLACEHOLDER_AUTHOR = {"name": "Unnamed authors (set citation.authors in config.yaml)"}
MAX_LISTED_FILES = 20


class FreezeError(RuntimeError):
    """A freeze that must not happen (no tag, tag taken, dirty tree); the message says what to do."""


def _listed(paths: list[str]) -> str:
    shown = ", ".join(paths[:MAX_LISTED_FILES])
    more = len(paths) - MAX_LISTED_FILES
    return shown + (f" and {more} more" if more > 0 else "")


def check_request(
    tag, allow_dirty: bool, frozen_dir: str | Path, code_root: str | Path, data: tuple = (), record=None
) -> dict:
    """Refuse a freeze before anything is built or touched; return the code's git state.

    Refused: no tag or an unsafe one, a tag whose folder exists, a tag frozen before whose folder is gone
    (``record``, that freeze's benchmark file, still there: Snakemake would take the freeze as done and say
    nothing), a work tree whose code differs from the commit (or no git work tree at all) unless ``allow_dirty``;
    data and config may differ (``provenance.NOT_CODE`` and ``data``, :func:`pendulum.provenance.data_paths`:
    the folder keeps the config as used and the data's hashes).
    """
    if tag is None or tag == "":
        raise FreezeError("the freeze target needs a name: snakemake -c1 freeze --config freeze_tag=NAME")
    if not isinstance(tag, str) or not TAG_PATTERN.match(tag) or len(tag) > 100:
        raise FreezeError(f"freeze_tag {tag!r}: use letters, digits and _ . + - (starting with a letter or digit)")
    folder = Path(frozen_dir) / tag
    if os.path.lexists(folder):
        raise FreezeError(f"{folder} already exists; a frozen folder is never overwritten: choose another freeze_tag")
    if record and os.path.exists(record):
        raise FreezeError(
            f"freeze_tag {tag} was frozen before ({record}), but {folder} is gone: a tag names one frozen folder "
            f"for good; choose another freeze_tag, or delete {record} to freeze under this one again"
        )
    git = git_state(code_root, tuple(data))
    if allow_dirty:
        return git
    if git["commit"] is None:
        raise FreezeError(
            f"{Path(code_root).resolve()} is not a git work tree, so the code version is unknown: freeze from a "
            "git clone, or with --config freeze_allow_dirty=true (the folder is then marked DIRTY)"
        )
    if git["dirty"]:
        raise FreezeError(
            f"the work tree differs from commit {git['commit'][:12]} in {_listed(git['dirty_files'])}: commit "
            "(or revert) these changes and freeze again, or freeze anyway with --config freeze_allow_dirty=true "
            "(the folder is then marked DIRTY)"
        )
    return git


def freeze_inputs(request: dict, results: list, excluded=()) -> list[str]:
    """The results a freeze copies (``results`` less ``excluded``, sorted), once `check_request` passes.

    The freeze rule's input function: a refused freeze stops while the DAG is built, so nothing runs.
    ``request`` holds ``tag``, ``allow_dirty``, ``frozen_dir``, ``code_root``, ``data`` and ``record``
    (:func:`check_request`).
    """
    check_request(
        request["tag"],
        request["allow_dirty"],
        request["frozen_dir"],
        request["code_root"],
        request.get("data", ()),
        request.get("record"),
    )
    return sorted({str(path) for path in results} - {str(path) for path in excluded})


def sha256_file(path: str | Path) -> str:
    digest = hashlib.sha256()
    with open(path, "rb") as f:
        for block in iter(lambda: f.read(1 << 20), b""):
            digest.update(block)
    return digest.hexdigest()


def sha256sum_line(digest: str, name: str) -> str:
    """One line of `sha256sum` output (a name holding a backslash or newline escaped as sha256sum does)."""
    if "\\" in name or "\n" in name or "\r" in name:
        name = name.replace("\\", "\\\\").replace("\n", "\\n").replace("\r", "\\r")
        return f"\\{digest}  {name}\n"
    return f"{digest}  {name}\n"


def raw_input_hashes(*paths: str | Path) -> str:
    """`sha256sum` lines of every file under each of ``paths`` (a folder: the raw folder, the truth folder) or of
    it (a file: a camera's clip), named as seen from the workflow's directory; a path that does not exist is
    left out."""
    files = set()
    for path in map(Path, paths):
        files |= {p for p in path.rglob("*") if p.is_file()} if path.is_dir() else {path} if path.is_file() else set()
    return "".join(sha256sum_line(sha256_file(p), p.as_posix()) for p in sorted(files))


def manifest(folder: str | Path) -> str:
    """`sha256sum` lines of every file in the folder except the manifest, sorted by path."""
    folder = Path(folder)
    files = sorted(
        (p.relative_to(folder).as_posix(), p) for p in folder.rglob("*") if p.is_file() and p.name != MANIFEST
    )
    return "".join(sha256sum_line(sha256_file(p), name) for name, p in files)


def _normalise(name: str) -> str:
    return re.sub(r"[-_.]+", "-", name).lower()


def lock_differences(lock_text: str, installed: list[str]) -> list[dict]:
    """Packages the lock file pins at a version other than the installed one (or that are not installed)."""
    have = {}
    for line in installed:
        name, _, version = line.partition("==")
        have[_normalise(name)] = version
    differences = []
    for line in lock_text.splitlines():
        m = re.match(r"^([A-Za-z0-9][A-Za-z0-9_.-]*)(?:\[[^\]]*\])?==([^\s;\\]+)", line)
        if m and have.get(_normalise(m.group(1))) != m.group(2):
            differences.append(
                {"package": m.group(1), "locked": m.group(2), "installed": have.get(_normalise(m.group(1)))}
            )
    return differences


def trial_outcomes(status_table: str | Path | None) -> dict:
    """Trials ok, failed (with stage and reason) and skipped by their sidecars (with why), from
    results/status/trials.csv, when frozen."""
    if status_table is None or not Path(status_table).is_file():
        return {}
    with open(status_table, newline="", encoding="utf-8") as f:
        rows = list(csv.DictReader(f))
    return {
        "ok": [r["trial"] for r in rows if r.get("status") == "ok"],
        "failed": [
            {"trial": r["trial"], "stage": r.get("stage", ""), "reason": r.get("reason", "")}
            for r in rows
            if r.get("status") not in ("ok", "skipped")
        ],
        "skipped": [{"trial": r["trial"], "reason": r.get("reason", "")} for r in rows if r.get("status") == "skipped"],
    }


def citation_cff(tag: str, frozen_at: datetime, git: dict, citation: dict | None, config_sha256: str) -> str:
    """CITATION.cff (Citation File Format 1.2.0) of a frozen folder: a dataset, version = tag."""
    citation = citation or {}
    title = citation.get("title", "Free-decay pendulum identification: added mass and drag coefficient")
    commit = git.get("commit")
    code = f"commit {commit}" if commit else "an unversioned work tree"
    if git.get("dirty"):
        code += " with uncommitted changes (see DIRTY)"
    document = {
        "cff-version": "1.2.0",
        "message": (
            "If you use these results, please cite them as below, with the SHA-256 of MANIFEST.sha256; "
            "verify the folder with `sha256sum -c MANIFEST.sha256`."
        ),
        "type": "dataset",
        "title": f"{title} (frozen results {tag})",
        "version": tag,
        "date-released": frozen_at.strftime("%Y-%m-%d"),
        "authors": citation.get("authors") or [PLACEHOLDER_AUTHOR],
        "abstract": (
            f"Results of the free-decay pendulum workflow, frozen as {tag} at "
            f"{frozen_at.strftime('%Y-%m-%dT%H:%M:%SZ')} from {code}; configuration SHA-256 {config_sha256}."
        ),
        "keywords": ["free-decay pendulum", "added mass", "drag coefficient", "ROV", "hydrodynamics"],
    }
    if commit:
        document["commit"] = commit
    if git.get("repository"):  # where the commit can be fetched (the origin remote)
        document["repository-code"] = git["repository"]
    return yaml.safe_dump(document, sort_keys=False, allow_unicode=True, width=100)


def dirty_note(git: dict) -> str:
    if git.get("commit") is None:
        return (
            "DIRTY: frozen outside a git work tree (freeze_allow_dirty=true); the code version is unknown, "
            "so these results cannot be rebuilt from a commit.\n"
        )
    files = "".join(f"  {path}\n" for path in git["dirty_files"])
    return (
        f"DIRTY: frozen from a work tree that differs from commit {git['commit']} (freeze_allow_dirty=true);\n"
        f"these results may not be reproducible from that commit. Changed or untracked files:\n{files}"
    )


def folder_readme(tag: str, provenance: dict, n_results: int) -> str:
    git = provenance["git"]
    commit = git["commit"] or "unknown (not a git work tree)"
    dirty = " — DIRTY, see DIRTY" if git.get("dirty") or git["commit"] is None else ""
    where = f" of {git['repository']}" if git.get("repository") else ""
    folders = sorted({Path(name).parent.as_posix() for name in provenance.get("sidecars") or []})
    sidecars = "".join(
        f"| `{folder}/*.yaml` | each trial's sidecar as used (its rig, values and settings) |\n" for folder in folders
    )
    return f"""# Frozen results: {tag}

Frozen {provenance["frozen_at_utc"]} from commit {commit}{where}{dirty}.

Verify every file: `sha256sum -c {MANIFEST}` in this folder. Verify the raw inputs:
`sha256sum -c results/frozen/{tag}/{RAW_HASHES}` from the workflow's directory.

| file | what |
| --- | --- |
| `results/` | the {n_results} result files as the workflow wrote them (no frame images) |
| `config.yaml` | the configuration as used (schema defaults filled in) |
{sidecars}| `provenance.json` | commit, dirty flag, command, time of freezing, software, config SHA-256, trials |
| `{RAW_HASHES}` | SHA-256 of every input file: the raw folder's, the truth files', the camera clips' |
| `environment-lock.txt` | the pinned environment of the commit (`pip install --require-hashes -r`) |
| `installed-packages.txt` | every package installed when freezing |
| `CITATION.cff` | how to cite this folder |
| `{MANIFEST}` | SHA-256 of every other file |
"""


def _stale_temporaries(frozen_dir: Path, tag: str) -> list[Path]:
    stale = []
    for path in frozen_dir.glob(f".{tag}.tmp-*"):
        try:
            os.kill(int(path.name.rsplit("-", 1)[1]), 0)
        except ProcessLookupError:
            stale.append(path)
        except (ValueError, PermissionError):
            continue
    return stale


def _result_name(path: str) -> Path:
    relative = Path(path)
    if relative.is_absolute() or ".." in relative.parts:
        raise FreezeError(f"{path}: results to freeze must lie inside the workflow's directory")
    return relative


def freeze(
    tag: str,
    results: list[str],
    lock_file: str | Path,
    config: dict,
    raw_dir: str | Path,
    code_root: str | Path,
    frozen_dir: str | Path = "results/frozen",
    allow_dirty: bool = False,
    command: str | None = None,
    citation: dict | None = None,
    frozen_at: datetime | None = None,
    log=None,
    sidecars: list[str] = (),
    data: tuple = (),
    inputs: tuple = (),
) -> tuple[Path, str]:
    """Write ``frozen_dir/tag/`` and return it with the SHA-256 of its manifest.

    ``results`` are paths relative to the workflow's directory (files or folders), copied to the
    same relative paths in the folder, and so are the trials' ``sidecars`` (each trial's rig, its own values and
    settings, a skip and why: the configuration as used is config.yaml and these). ``data``: the paths whose
    changes do not make the code dirty (:func:`pendulum.provenance.data_paths`); ``inputs``: the data files and
    folders hashed beside the raw folder (the truth folder, the camera clips). Nothing named ``tag`` exists
    unless every file was written.
    """
    git = check_request(tag, allow_dirty, frozen_dir, code_root, data)
    frozen_dir = Path(frozen_dir)
    frozen_at = (frozen_at or datetime.now(UTC)).astimezone(UTC)
    used = config_as_used(config)
    digest = config_digest(used)
    frozen_dir.mkdir(parents=True, exist_ok=True)
    for stale in _stale_temporaries(frozen_dir, tag):
        shutil.rmtree(stale, ignore_errors=True)
    tmp = frozen_dir / f".{tag}.tmp-{os.getpid()}"
    final = frozen_dir / tag
    try:
        tmp.mkdir()
        names = sorted({_result_name(path) for path in results})
        kept_sidecars = sorted({_result_name(path) for path in sidecars})
        for name in names + kept_sidecars:
            target = tmp / name
            target.parent.mkdir(parents=True, exist_ok=True)
            (shutil.copytree if name.is_dir() else shutil.copy2)(name, target)
        lock_text = Path(lock_file).read_text(encoding="utf-8")
        shutil.copyfile(lock_file, tmp / "environment-lock.txt")
        packages = installed_packages()
        (tmp / "installed-packages.txt").write_text("".join(f"{p}\n" for p in packages), encoding="utf-8")
        (tmp / RAW_HASHES).write_text(raw_input_hashes(raw_dir, *inputs), encoding="utf-8")
        header = (
            f"# Configuration as used for the frozen results {tag}: config.yaml and any --configfile/--config,\n"
            "# the schema's defaults filled in, the freeze's own keys left out. Its SHA-256 (canonical JSON,\n"
            f"# pendulum.provenance.config_digest): {digest}\n"
        )
        (tmp / "config.yaml").write_text(
            header + yaml.safe_dump(used, sort_keys=False, allow_unicode=True), encoding="utf-8"
        )
        status_table = Path("results/status/trials.csv")
        document = {
            "tag": tag,
            "frozen_at_utc": frozen_at.strftime("%Y-%m-%dT%H:%M:%SZ"),
            "command": command,
            "git": git,
            "dirty": bool(git["dirty"]) or git["commit"] is None,
            "freeze_allow_dirty": bool(allow_dirty),
            "config_sha256": digest,
            "software": software(),
            "environment_lock_differences": lock_differences(lock_text, packages),
            "raw_inputs": {
                "directory": Path(raw_dir).as_posix(),
                "also": [Path(path).as_posix() for path in inputs],
                "hashes": RAW_HASHES,
            },
            "trials": trial_outcomes(status_table if status_table in names else None),
            "results": [name.as_posix() for name in names],
            "sidecars": [name.as_posix() for name in kept_sidecars],
        }
        (tmp / "provenance.json").write_text(json.dumps(document, indent=2) + "\n", encoding="utf-8")
        (tmp / "CITATION.cff").write_text(citation_cff(tag, frozen_at, git, citation, digest), encoding="utf-8")
        if document["dirty"]:
            (tmp / "DIRTY").write_text(dirty_note(git), encoding="utf-8")
        (tmp / "README.md").write_text(folder_readme(tag, document, len(names)), encoding="utf-8")
        text = manifest(tmp)
        (tmp / MANIFEST).write_text(text, encoding="utf-8")
        for path in tmp.rglob("*"):
            if path.is_file():
                path.chmod(0o444)
        if os.path.lexists(final):
            raise FreezeError(f"{final} appeared while freezing; a frozen folder is never overwritten")
        os.rename(tmp, final)
    finally:
        if tmp.exists():
            shutil.rmtree(tmp, ignore_errors=True)
    manifest_sha256 = hashlib.sha256(text.encode()).hexdigest()
    if log is not None:
        log.info("froze %d result files into %s (commit %s)", len(names), final, git["commit"])
        if document["dirty"]:
            log.warning("marked DIRTY: %s", dirty_note(git).strip())
        failed = [entry["trial"] for entry in document["trials"].get("failed", [])]
        if failed:
            log.warning("frozen with failed trials (see results/status/trials.csv): %s", ", ".join(failed))
        if document["environment_lock_differences"]:
            differences = document["environment_lock_differences"]
            log.warning("installed packages differ from environment-lock.txt: %s", differences)
        if not citation or not citation.get("authors"):
            log.warning("CITATION.cff names no authors: set citation.authors in config.yaml before freezing")
        log.info("SHA-256 of %s (cite it with the tag and commit): %s", MANIFEST, manifest_sha256)
    return final, manifest_sha256
