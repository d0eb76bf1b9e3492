# Provenance: the library modules each stage's script imports (its `code` input, so that
# editing a stage's science reruns that stage only) and the report's commit, configuration
# digest and package versions.
import functools
import os
import platform

from pendulum.io import write_text  # noqa: E402
from pendulum.provenance import (
    code_digest_text,
    config_digest,
    data_paths,
    git_state,
    imported_modules,
    package_versions,
)  # noqa: E402

LIBRARY_DIR = Path(workflow.basedir) / "workflow" / "pendulum"
# the user's data and configuration wherever the config puts them: their changes are not the code's (the report's
# provenance, a freeze's dirty check)
DATA_PATHS = data_paths(config, workflow.configfiles, workflow.basedir)
SCRIPTS_DIR = Path(workflow.basedir) / "workflow" / "scripts"


def _module_file(name):
    """The file of a dotted `pendulum` module (a package by its __init__.py), else None."""
    parts = name.split(".")[1:]
    for path in (
        LIBRARY_DIR.joinpath(*parts).with_suffix(".py"),
        LIBRARY_DIR.joinpath(*parts, "__init__.py"),
    ):
        if parts and path.is_file():
            return path
    return None


def _with_packages(path):
    """A module's file and the __init__.py of every package above it (Python runs them on import)."""
    files = {path}
    for parent in path.parents:
        if parent == LIBRARY_DIR.parent:
            break
        files.add(parent / "__init__.py")
    return files


@functools.lru_cache(maxsize=None)  # each file read once per Snakemake run
def _library_imports(path):
    """The `pendulum` module files a Python file imports (absolute or relative, also inside functions)."""
    package = path.parent.relative_to(LIBRARY_DIR.parent).parts
    names = {
        n
        for n in imported_modules(path.read_text(), package)
        if n == "pendulum" or n.startswith("pendulum.")
    }
    files = {_module_file(n) for n in names} - {None}
    return frozenset(f for file in files for f in _with_packages(file))


def script_code(script):
    """The library modules a stage's script imports, directly or through each other.

    Declared as the rule's `code` input, so that editing the science of a stage
    reruns that stage (and what depends on it), not the others.
    """
    seen, todo = set(), set(_library_imports(SCRIPTS_DIR / script))
    while todo:
        path = todo.pop()
        if path not in seen:
            seen.add(path)
            todo |= _library_imports(path)
    files = [LIBRARY_DIR / "__init__.py", SCRIPTS_DIR / "_setup.py"]
    files += sorted(seen - {LIBRARY_DIR / "__init__.py"})
    return [os.path.relpath(f) for f in files]


def code_digest(script):
    """The one code input of a per-trial rule: results/code/<script>.sha256, the digest of
    :func:`script_code` (rule code_digest). Same reruns as declaring every module (Snakemake compares
    a small input's content: a module edited reruns the digest, and the stage only if it changed),
    at one input per job instead of about 25 (the dry run of a thousand trials)."""
    return f"results/code/{Path(script).stem}.sha256"


def report_provenance():
    """Commit (time, dirty flag), configuration digest and package versions; nothing time-dependent."""
    git = git_state(workflow.basedir, DATA_PATHS)
    return {
        "commit": git["commit"],
        "commit_time_utc": git["commit_time_utc"],
        "dirty": git["dirty"],
        "dirty_files": git["dirty_files"],
        "config_sha256": config_digest(config),
        "python": platform.python_version(),
        "packages": package_versions(),
    }
