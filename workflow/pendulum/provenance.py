"""Where a result came from: code version, configuration digest, software versions.

Used by the report (its provenance section) and by the freeze target
(`provenance.json` of a frozen results folder). Nothing here reads the clock:
the report must be byte-identical between two builds of the same commit.
"""

from __future__ import annotations

import ast
import copy
import hashlib
import json
import os
import platform
import re
import subprocess
from importlib import metadata
from pathlib import Path

import yaml

CORE_PACKAGES = (
    "snakemake",
    "opencv-python-headless",
    "numpy",
    "scipy",
    "numba",
    "pandas",
    "matplotlib",
    "papermill",
    "nbconvert",
    "ipykernel",
    "jsonschema",
    "pyyaml",
)

# Paths whose changes do not make a work tree "dirty": what the workflow writes, the user's
# data (hashed when a result is frozen; truth files of synthetic trials are data too; wherever the config puts
# them: data_paths)
# and config.yaml (recorded as used, with its digest, in every report and frozen folder): a
# researcher following README "Your own videos" edits these, not the code.
NOT_CODE = ("results", "logs", ".snakemake", ".venv", "data/raw", "data/truth", "config.yaml")


# Config keys that say what to do with finished results (freeze and cite them), not how
# they are made: left out of the configuration as used and of its digest.
RUN_ONLY_KEYS = ("freeze_tag", "freeze_allow_dirty", "citation")
CONFIG_SCHEMA = Path(__file__).resolve().parents[1] / "schemas" / "config.schema.yaml"


def _fill_defaults(value, schema: dict):
    if not isinstance(value, dict):
        return value
    filled = dict(value)
    for key, sub in (schema.get("properties") or {}).items():
        if key in filled:
            filled[key] = _fill_defaults(filled[key], sub)
        elif "default" in sub:
            filled[key] = copy.deepcopy(sub["default"])
    return filled


def config_as_used(config: dict) -> dict:
    """The configuration a build used: the schema's defaults filled in, `RUN_ONLY_KEYS` left out."""
    schema = yaml.safe_load(CONFIG_SCHEMA.read_text())
    filled = _fill_defaults(copy.deepcopy(dict(config)), schema)
    return {key: value for key, value in filled.items() if key not in RUN_ONLY_KEYS}


def config_digest(config: dict) -> str:
    """SHA-256 of the configuration as used (`config_as_used`; canonical JSON: sorted keys, no spaces).

    The same whether or not the schema's defaults are written out and whatever the run-only keys say.
    """
    text = json.dumps(config_as_used(config), sort_keys=True, separators=(",", ":"), default=str)
    return hashlib.sha256(text.encode()).hexdigest()


def _git(root: Path, *args: str) -> str | None:
    try:
        proc = subprocess.run(["git", *args], cwd=root, capture_output=True, text=True, timeout=30)
    except (OSError, subprocess.TimeoutExpired):
        return None
    # Only the trailing newline: `status --porcelain` lines begin with a space (" M file").
    return proc.stdout.rstrip("\n") if proc.returncode == 0 else None


def repository_url(remote: str | None) -> str | None:
    """A git remote as the web address a reader can open: ``git@host:owner/repo.git`` and
    ``ssh://git@host/owner/repo`` become ``https://host/owner/repo``; credentials in an https address
    (``https://user:token@host/…``) are dropped; ``.git`` at the end is dropped. None for a local path."""
    if not remote:
        return None
    remote = remote.strip()
    if match := re.fullmatch(r"ssh://(?:[^@/]+@)?([\w.-]+)(?::\d+)?/(.+?)/?", remote):  # a port is the ssh server's
        remote = f"https://{match.group(1)}/{match.group(2)}"
    elif match := re.fullmatch(r"[\w.-]+@([\w.-]+):(.+?)/?", remote):  # scp-like: user@host:path
        remote = f"https://{match.group(1)}/{match.group(2)}"
    if not re.match(r"https?://", remote):
        return None
    remote = re.sub(r"^(https?://)[^/@]*@", r"\1", remote)
    return remote[:-4] if remote.endswith(".git") else remote


def data_paths(config: dict, configfiles=(), root: str | Path = ".") -> tuple[str, ...]:
    """The user's data and configuration where the config puts them, as paths relative to ``root`` (those inside
    it): ``raw_dir``, ``truth_dir``, each camera setup's clips and the configuration files (config.yaml and any
    ``--configfile``). Like :data:`NOT_CODE`, changes there do not make the code dirty (a fresh-eyes user's
    ``raw_dir: mydata``, a camera's clip in data/calibration/ and an untracked ``--configfile`` each refused a
    freeze, 2026-12-07)."""
    root = os.path.abspath(root)
    given = [config.get("raw_dir"), config.get("truth_dir")]
    for setup in (config.get("cameras") or {}).values():
        given += [(setup or {}).get("calibration_video"), (setup or {}).get("plane_video")]
    given += list(configfiles)
    out = []
    for path in given:
        if not path:
            continue
        # as git names it: the path itself, not where a link points (a raw folder linked in from a data disk)
        relative = os.path.relpath(os.path.normpath(os.path.join(root, str(path))), root)
        if relative != "." and not relative.startswith(".."):  # outside the work tree: never in git's status
            out.append(Path(relative).as_posix())
    return tuple(dict.fromkeys(out))


def git_state(root: str | Path = ".", data: tuple[str, ...] = ()) -> dict:
    """Commit, its UTC commit time, whether the code differs from it, and the repository's address.

    Outside a git work tree every field is None. `dirty_files` lists changed or untracked paths outside
    :data:`NOT_CODE` (results/, logs/, .snakemake/, .venv/, data/raw/, data/truth/ and config.yaml, which is
    recorded as used, with its digest, instead) and outside ``data`` (:func:`data_paths`). `repository` is the
    ``origin`` remote as a web address (:func:`repository_url`; None without one or for a local path).
    """
    root = Path(root)
    commit = _git(root, "rev-parse", "HEAD")
    if commit is None:
        return {"commit": None, "commit_time_utc": None, "dirty": None, "dirty_files": None, "repository": None}
    commit_time = _git(root, "log", "-1", "--format=%cd", "--date=format-local:%Y-%m-%dT%H:%M:%SZ")
    # the workflow's own folder, its paths as from it (git names them from the repository's top: a workflow kept in
    # a folder of a larger repository was refused for its data there, and for the other projects' changes)
    prefix = _git(root, "rev-parse", "--show-prefix") or ""
    status = _git(root, "-c", "core.quotepath=off", "status", "--porcelain", "--untracked-files=all", "--", ".") or ""
    dirty_files = sorted(
        path
        for path in (
            line[3:].split(" -> ")[-1].strip('"').removeprefix(prefix) for line in status.splitlines() if line.strip()
        )
        if not any(path == p or path.startswith(p + "/") for p in NOT_CODE + tuple(data))
    )
    return {
        "commit": commit,
        "commit_time_utc": commit_time,
        "dirty": bool(dirty_files),
        "dirty_files": dirty_files,
        "repository": repository_url(_git(root, "remote", "get-url", "origin")),
    }


def code_digest_text(paths) -> str:
    """``sha256  path`` of each file, one per line, sorted by path: one small file whose content changes
    exactly when one of the files does (a stage's code, declared as one input instead of every module)."""
    lines = sorted(f"{hashlib.sha256(Path(p).read_bytes()).hexdigest()}  {Path(p).as_posix()}" for p in paths)
    return "\n".join(lines) + "\n"


# An import statement on its own lines (a parenthesised one, comments inside included, or a continued one
# spans several).
IMPORT_STATEMENT = re.compile(
    r"^[ \t]*(?:from[ \t]+[\w.]+[ \t]+import[ \t]*(?:\((?:[^)#]|#[^\n]*)*\)|(?:[^\n]*\\\n)*[^\n]*)"
    r"|import[ \t]+(?:[^\n]*\\\n)*[^\n]*)",
    re.M,
)
# An import after other code on its line (`x = 1; import a`, `if TYPE_CHECKING: import a`): not seen above.
IMPORT_AFTER_CODE = re.compile(r"[;:][ \t]*(?:from[ \t]+[\w.]+[ \t]+)?import[ \t]")


def imported_modules(source: str, package: tuple[str, ...] = ()) -> set[str]:
    """The dotted names a Python source imports at any depth (also inside functions): ``import a.b`` gives
    ``a.b``; ``from a import b`` gives ``a`` and ``a.b`` (b may be a module); a relative import is resolved
    against ``package`` (the importing module's package, e.g. ``("pendulum", "fit")``).

    Only the import statements are parsed, not the whole module (~50× faster: the workflow runs this on
    its library every time Snakemake parses it); where one of them does not parse on its own (a docstring
    line that reads like an unfinished import), or an import follows other code on its line, the whole
    source is parsed instead. A docstring line that reads like a whole import counts too: a stage may then depend on
    a module it does not import (a rerun too many, never one too few).
    """
    if IMPORT_AFTER_CODE.search(source):
        nodes = list(ast.walk(ast.parse(source)))
    else:
        nodes = []
        for match in IMPORT_STATEMENT.finditer(source):
            try:
                nodes += ast.parse(match.group(0).strip()).body
            except SyntaxError:
                nodes = list(ast.walk(ast.parse(source)))
                break
    names = set()
    for node in nodes:
        if isinstance(node, ast.ImportFrom):
            base = package[: len(package) - (node.level - 1)] if node.level else ()
            module = ".".join(base + ((node.module,) if node.module else ()))
            names.add(module)
            names |= {f"{module}.{a.name}" for a in node.names}
        elif isinstance(node, ast.Import):
            names |= {a.name for a in node.names}
    return names


def package_versions(names=CORE_PACKAGES) -> dict[str, str | None]:
    """Installed version of each named distribution (None when not installed)."""
    versions = {}
    for name in names:
        try:
            versions[name] = metadata.version(name)
        except metadata.PackageNotFoundError:
            versions[name] = None
    return versions


def installed_packages() -> list[str]:
    """Every installed distribution as `name==version`, sorted (a `pip freeze` without pip)."""
    return sorted(
        {f"{d.metadata['Name']}=={d.version}" for d in metadata.distributions() if d.metadata["Name"]},
        key=str.lower,
    )


def opencv_video_backend() -> dict:
    """OpenCV version and the video I/O backends it was built with (FFMPEG and its library versions)."""
    import cv2

    info = cv2.getBuildInformation()
    section = info.split("Video I/O:", 1)[-1].split("\n\n", 1)[0]
    backends = {}
    for line in section.splitlines():
        m = re.match(r"\s+(\w[\w ]*?):\s+(.+)$", line)
        if m:
            backends[m.group(1).strip()] = m.group(2).strip()
    return {"opencv": cv2.__version__, "video_io": backends}


def software() -> dict:
    """Python, platform and the versions of the packages a result depends on."""
    return {
        "python": platform.python_version(),
        "implementation": platform.python_implementation(),
        "platform": platform.platform(terse=True),
        "packages": package_versions(),
        "opencv_video": opencv_video_backend(),
    }


def provenance(root: str | Path = ".", config: dict | None = None) -> dict:
    """Everything above in one document (no timestamps except the commit's)."""
    document = {"git": git_state(root), "software": software()}
    if config is not None:
        document["config_sha256"] = config_digest(config)
    return document
