"""The library's layout: one package per stage, no import circles, no reaching into private names, small modules.

The import graph of `workflow/pendulum` is built from the source with `ast` (absolute `pendulum.x` imports,
relative imports, imports inside functions and under ``TYPE_CHECKING``), so it sees what a reader sees.
"""

import ast
from pathlib import Path

LIBRARY = Path(__file__).resolve().parents[1] / "workflow" / "pendulum"
MAX_LINES = 550
MAX_TOP_MODULES = 7  # plumbing beside the stage packages (io, status, outcomes, provenance, freeze, trials, groups)


def module_files(library: Path = LIBRARY) -> dict[str, Path]:
    """Dotted module name → file, a package by its ``__init__.py``."""
    out = {}
    for path in sorted(library.rglob("*.py")):
        parts = path.relative_to(library.parent).with_suffix("").parts
        if parts[-1] == "__init__":
            parts = parts[:-1]
        out[".".join(parts)] = path
    return out


def _resolve(name: str, modules) -> str | None:
    """The longest prefix of a dotted name that is a module of the library."""
    parts = name.split(".")
    for n in range(len(parts), 0, -1):
        candidate = ".".join(parts[:n])
        if candidate in modules:
            return candidate
    return None


def import_graph(library: Path = LIBRARY):
    """(edges, private): module → the library modules it imports; (importer, module, name) of private names."""
    modules = module_files(library)
    edges: dict[str, set[str]] = {m: set() for m in modules}
    private: list[tuple[str, str, str]] = []
    for name, path in modules.items():
        package = name if path.name == "__init__.py" else name.rpartition(".")[0]
        aliases: dict[str, str] = {}  # local name bound to a library module → that module
        tree = ast.parse(path.read_text(encoding="utf-8"), filename=str(path))
        for node in ast.walk(tree):
            if isinstance(node, ast.Import):
                for alias in node.names:
                    target = _resolve(alias.name, modules)
                    if target:
                        edges[name].add(target)
                        if alias.asname:
                            aliases[alias.asname] = target
            elif isinstance(node, ast.ImportFrom):
                if node.level:
                    base = package.split(".")
                    base = base[: len(base) - (node.level - 1)]
                    source = ".".join(base + ([node.module] if node.module else []))
                else:
                    source = node.module or ""
                for alias in node.names:
                    submodule = f"{source}.{alias.name}"
                    if submodule in modules:  # `from pendulum.fit import decay`: the module itself
                        edges[name].add(submodule)
                        aliases[alias.asname or alias.name] = submodule
                        continue
                    target = _resolve(source, modules)
                    if target is None:
                        continue
                    edges[name].add(target)
                    if _is_private(alias.name) and target != name:
                        private.append((name, target, alias.name))
        for node in ast.walk(tree):  # `module._name` through a module imported whole
            if isinstance(node, ast.Attribute) and isinstance(node.value, ast.Name) and _is_private(node.attr):
                target = aliases.get(node.value.id)
                if target and target != name:
                    private.append((name, target, node.attr))
        edges[name].discard(name)
    return edges, private


def _is_private(name: str) -> bool:
    return name.startswith("_") and not (name.startswith("__") and name.endswith("__"))


def circles(edges: dict[str, set[str]]) -> list[list[str]]:
    """The groups of modules that import each other (strongly connected, more than one module), sorted."""
    index: dict[str, int] = {}
    low: dict[str, int] = {}
    stack: list[str] = []
    on_stack: set[str] = set()
    groups: list[list[str]] = []

    def strongconnect(v):  # Tarjan's algorithm
        index[v] = low[v] = len(index)
        stack.append(v)
        on_stack.add(v)
        for w in sorted(edges.get(v, ())):
            if w not in index:
                strongconnect(w)
                low[v] = min(low[v], low[w])
            elif w in on_stack:
                low[v] = min(low[v], index[w])
        if low[v] == index[v]:
            group = []
            while True:
                w = stack.pop()
                on_stack.discard(w)
                group.append(w)
                if w == v:
                    break
            if len(group) > 1:
                groups.append(sorted(group))

    for v in sorted(edges):
        if v not in index:
            strongconnect(v)
    return groups


def cycle_in(group: list[str], edges) -> list[str]:
    """A shortest closed path through the group's first module, by breadth-first search inside the group."""
    start, members = group[0], set(group)
    previous = {start: None}
    queue = [start]
    while queue:
        v = queue.pop(0)
        for w in sorted(edges[v] & members):
            if w == start:
                path = [v]
                while previous[path[-1]] is not None:
                    path.append(previous[path[-1]])
                return [*reversed(path), start]
            if w not in previous:
                previous[w] = v
                queue.append(w)
    return group


def test_graph_sees_absolute_relative_and_function_imports(tmp_path):
    lib = tmp_path / "pendulum"
    (lib / "stage").mkdir(parents=True)
    (lib / "__init__.py").write_text('"""The library."""\n')
    (lib / "stage" / "__init__.py").write_text('"""A stage."""\n')
    (lib / "stage" / "a.py").write_text("from .b import thing\n")
    (lib / "stage" / "b.py").write_text("def f():\n    from pendulum.stage import c\n    return c._hidden\n")
    (lib / "stage" / "c.py").write_text("from ..stage.a import _helper\n")
    edges, private = import_graph(lib)
    assert edges["pendulum.stage.a"] == {"pendulum.stage.b"}
    assert edges["pendulum.stage.b"] == {"pendulum.stage.c"}
    assert edges["pendulum.stage.c"] == {"pendulum.stage.a"}
    assert circles(edges) == [["pendulum.stage.a", "pendulum.stage.b", "pendulum.stage.c"]]
    assert cycle_in(circles(edges)[0], edges) == [
        "pendulum.stage.a",
        "pendulum.stage.b",
        "pendulum.stage.c",
        "pendulum.stage.a",
    ]
    assert sorted(private) == [
        ("pendulum.stage.b", "pendulum.stage.c", "_hidden"),
        ("pendulum.stage.c", "pendulum.stage.a", "_helper"),
    ]


def test_no_import_cycles():
    edges, _ = import_graph()
    groups = circles(edges)
    assert not groups, "import circles:\n" + "\n".join(
        f"{', '.join(g)}: e.g. {' → '.join(cycle_in(g, edges))}" for g in groups
    )


def test_no_private_names_across_modules():
    _, private = import_graph()
    assert not private, "private names used from another module (make them public where shared):\n" + "\n".join(
        f"{importer} uses {module}.{name}" for importer, module, name in sorted(set(private))
    )


def test_top_level_is_stage_packages_and_a_little_plumbing():
    modules = sorted(p.stem for p in LIBRARY.glob("*.py") if p.name != "__init__.py")
    packages = sorted(p.name for p in LIBRARY.iterdir() if p.is_dir() and (p / "__init__.py").is_file())
    assert len(packages) >= 5, f"stage packages: {packages}"
    assert len(modules) <= MAX_TOP_MODULES, f"{len(modules)} modules at the top of workflow/pendulum: {modules}"


def test_every_package_says_what_it_takes_and_gives():
    for init in sorted(LIBRARY.rglob("__init__.py")):
        doc = ast.get_docstring(ast.parse(init.read_text(encoding="utf-8")))
        assert doc and len(doc.strip().splitlines()) == 1, f"{init}: a one-line docstring"


def test_no_module_is_long():
    sizes = {path: len(path.read_text(encoding="utf-8").splitlines()) for path in module_files().values()}
    long = {str(p.relative_to(LIBRARY.parent)): n for p, n in sizes.items() if n > MAX_LINES}
    assert not long, f"modules over {MAX_LINES} lines: {long}"


def test_the_workflows_code_inputs_see_every_import_the_parser_sees():
    """`pendulum.provenance.imported_modules` reads only import statements (the workflow's `code` inputs,
    on every Snakemake call): on every module and script of the workflow it gives exactly what a full
    parse gives, and on the tests at least that (an import inside a string template is extra)."""
    import sys

    sys.path.insert(0, str(LIBRARY.parent))
    from pendulum.provenance import imported_modules

    def parsed(source: str, package: tuple) -> set:
        names = set()
        for node in ast.walk(ast.parse(source)):
            if isinstance(node, ast.ImportFrom):
                base = package[: len(package) - (node.level - 1)] if node.level else ()
                module = ".".join(base + ((node.module,) if node.module else ()))
                names |= {module} | {f"{module}.{a.name}" for a in node.names}
            elif isinstance(node, ast.Import):
                names |= {a.name for a in node.names}
        return names

    workflow = sorted(LIBRARY.parent.rglob("*.py"))
    assert len(workflow) > 80
    for path in workflow:
        package = path.parent.relative_to(LIBRARY.parent).parts
        source = path.read_text(encoding="utf-8")
        assert imported_modules(source, package) == parsed(source, package), path
    for path in sorted(LIBRARY.parents[1].joinpath("tests").rglob("*.py")):
        source = path.read_text(encoding="utf-8")
        assert parsed(source, ()) <= imported_modules(source, ()), path
    # a relative import, one inside a function, a parenthesised and a continued one
    text = "from . import a\ndef f():\n    from ..b import (\n        c,\n        d,\n    )\nimport e.f, \\\n    g\n"
    assert imported_modules(text, ("p", "q")) == {"p.q", "p.q.a", "p.b", "p.b.c", "p.b.d", "e.f", "g"}
    # a comment with a parenthesis inside the parentheses; imports after code on their line; a docstring line that
    # reads like an unfinished import: never an import missed
    assert imported_modules("from a import (\n    b,  # (c)\n    d,\n)\n") == {"a", "a.b", "a.d"}
    assert imported_modules("x = 1; import a.b\nif T: from c import d\n") == {"a.b", "c", "c.d"}
    assert imported_modules('"""\nfrom x import (\n"""\nimport a\n') == {"a"}
