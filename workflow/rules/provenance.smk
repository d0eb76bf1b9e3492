# Provenance: the library modules each stage's script imports (its `code` input, so that
# editing a stage's science reruns that stage only) and the report's commit, configuration
# digest and package versions.
import ast
import functools
import os
import platform

from pendulum.provenance import config_digest, git_state, package_versions  # noqa: E402

LIBRARY_DIR = Path(workflow.basedir) / "workflow" / "pendulum"
SCRIPTS_DIR = Path(workflow.basedir) / "workflow" / "scripts"


@functools.lru_cache(maxsize=None)  # each file parsed once per Snakemake run
def _library_imports(path):
    """Names of the `pendulum` modules a Python file imports (absolute or relative)."""
    names = set()
    for node in ast.walk(ast.parse(Path(path).read_text())):
        if isinstance(node, ast.ImportFrom):
            source = node.module or ""
            if node.level and path.parent == LIBRARY_DIR:
                names |= {source} if source else {a.name for a in node.names}
            elif source == "pendulum":
                names |= {a.name for a in node.names}
            elif source.startswith("pendulum."):
                names.add(source.split(".")[1])
        elif isinstance(node, ast.Import):
            names |= {
                a.name.split(".")[1]
                for a in node.names
                if a.name.startswith("pendulum.")
            }
    return frozenset(n for n in names if (LIBRARY_DIR / f"{n}.py").is_file())


def script_code(script):
    """The library modules a stage's script imports, directly or through each other.

    Declared as the rule's `code` input, so that editing the science of a stage
    reruns that stage (and what depends on it), not the others.
    """
    seen, todo = set(), set(_library_imports(SCRIPTS_DIR / script))
    while todo:
        name = todo.pop()
        if name not in seen:
            seen.add(name)
            todo |= _library_imports(LIBRARY_DIR / f"{name}.py")
    files = [LIBRARY_DIR / "__init__.py", SCRIPTS_DIR / "_setup.py"]
    files += [LIBRARY_DIR / f"{n}.py" for n in sorted(seen)]
    return [os.path.relpath(f) for f in files]


def report_provenance():
    """Commit (time, dirty flag), configuration digest and package versions; nothing time-dependent."""
    git = git_state(workflow.basedir)
    return {
        "commit": git["commit"],
        "commit_time_utc": git["commit_time_utc"],
        "dirty": git["dirty"],
        "dirty_files": git["dirty_files"],
        "config_sha256": config_digest(config),
        "python": platform.python_version(),
        "packages": package_versions(),
    }
