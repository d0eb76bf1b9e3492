"""The README is a front door and docs/ holds the reference: every link and every file they name exists."""

import re
from pathlib import Path

import pytest

from conftest import ROOT

README_LIMIT_BYTES = 12_000
PAGES = [ROOT / "README.md", *sorted((ROOT / "docs").glob("*.md"))]

LINK = re.compile(r"\[(?:[^\]\[]|\[[^\]]*\])*\]\(([^()\s]+)(?:\s+\"[^\"]*\")?\)")
CODE_SPAN = re.compile(r"(`+)(.+?)\1")
# Named paths under these are outputs of a build (or local state), not files of the repository.
GENERATED = ("results/", "logs/", "benchmarks/jobs/", ".snakemake/", ".venv/")
FILE_SUFFIXES = (".py", ".smk", ".yaml", ".yml", ".md", ".ipynb", ".txt", ".cff", ".toml", ".ini", ".json", ".csv")


def prose(text: str) -> str:
    """The page without its code blocks (fenced, or indented four spaces), whose text is not Markdown."""
    text = re.sub(r"^```.*?^```", "", text, flags=re.S | re.M)
    return "\n".join(line for line in text.splitlines() if not line.startswith("    "))


def github_anchor(heading: str) -> str:
    """GitHub's anchor of a heading: lower case, punctuation other than - and _ dropped, spaces made -."""
    text = re.sub(r"\[([^\]]*)\]\([^)]*\)", r"\1", heading.strip())  # a link keeps its text
    text = re.sub(r"[^\w\- ]", "", text.lower())
    return text.replace(" ", "-")


def anchors(page: Path) -> set[str]:
    """Every heading anchor of a page, with GitHub's -1, -2 … for repeated headings."""
    seen: dict[str, int] = {}
    found = set()
    for line in prose(page.read_text(encoding="utf-8")).splitlines():
        match = re.match(r"#{1,6}\s+(.*?)\s*#*\s*$", line)
        if match:
            anchor = github_anchor(match.group(1))
            found.add(f"{anchor}-{seen[anchor]}" if anchor in seen else anchor)
            seen[anchor] = seen.get(anchor, 0) + 1
    return found


def broken_links(page: Path) -> list[str]:
    """The relative links of a page that name no file, or a heading its page does not have."""
    broken = []
    for target in LINK.findall(prose(page.read_text(encoding="utf-8"))):
        if re.match(r"[a-z][a-z0-9+.-]*:", target, re.I):  # https:, mailto: …: not in the repository
            continue
        path, _, anchor = target.partition("#")
        resolved = (page.parent / path).resolve() if path else page
        if not resolved.exists():
            broken.append(f"{target}: no such file")
        elif anchor and (resolved.suffix != ".md" or anchor not in anchors(resolved)):
            broken.append(f"{target}: no heading #{anchor} in {resolved.name}")
    return broken


def top_level_entries() -> set[str]:
    """The repository's top-level files and folders: a named path must start with one of them."""
    return {p.name for p in ROOT.iterdir()}


def named_paths(text: str, top: set[str]) -> list[str]:
    """Repository paths named in code spans: `workflow/pendulum/tracking/body.py`, `config.yaml`, `data/raw/` …

    A span counts when it is one word (or, in a command, a word naming a .py file) whose first part is a
    top-level entry of the repository and that looks like a path (has a / or a file suffix); globs and
    placeholders (<trial>, {name}, *) and outputs of a build (results/, logs/ …) are not checked.
    """
    names = []
    for _, span in CODE_SPAN.findall(prose(text)):
        words = span.split()
        candidates = words if len(words) == 1 else [w for w in words if w.endswith(".py")]
        for word in candidates:
            word = word.split("::", 1)[0]  # tests/test_x.py::test_name
            if any(c in word for c in "<>{}*[]") or word.startswith(GENERATED):
                continue
            if ("/" in word or word.endswith(FILE_SUFFIXES)) and word.split("/", 1)[0] in top:
                names.append(word)
    return names


@pytest.mark.parametrize("page", PAGES, ids=lambda p: str(p.relative_to(ROOT)))
def test_every_relative_link_reaches_a_file_and_heading(page):
    assert broken_links(page) == []


@pytest.mark.parametrize("page", PAGES, ids=lambda p: str(p.relative_to(ROOT)))
def test_every_repository_path_named_exists(page):
    top = top_level_entries()
    missing = [name for name in named_paths(page.read_text(encoding="utf-8"), top) if not (ROOT / name).exists()]
    assert missing == []


def test_the_readme_is_a_front_door_linking_every_reference_page():
    readme = ROOT / "README.md"
    assert readme.stat().st_size <= README_LIMIT_BYTES, f"README.md is {readme.stat().st_size} bytes"
    linked = {(ROOT / target.partition("#")[0]).resolve() for target in LINK.findall(readme.read_text())}
    assert [p.name for p in PAGES[1:] if p.resolve() not in linked] == []


def test_the_checks_catch_a_broken_link_a_missing_heading_and_a_missing_file(tmp_path):
    page = tmp_path / "page.md"
    (tmp_path / "other.md").write_text(
        "# Other page\n\n## Filming a trial: what works (and why)\n\n## Same\n\n## Same\n"
    )
    page.write_text(
        "# Title\n\nSee [ok](other.md#filming-a-trial-what-works-and-why), [second](other.md#same-1), "
        "[here](#title), [web](https://example.org/x.md), [gone](missing.md), [no heading](other.md#nowhere), "
        "[self](#nowhere-here).\n\n    [in a code block](also-missing.md)\n"
    )
    assert broken_links(page) == [
        "missing.md: no such file",
        "other.md#nowhere: no heading #nowhere in other.md",
        "#nowhere-here: no heading #nowhere-here in page.md",
    ]
    text = "`workflow/pendulum/no_such.py`, `config.yaml`, `data/raw/<trial>.yaml`, `results/x.csv`, `x.mp4`, `a b`"
    assert named_paths(text, {"workflow", "config.yaml", "data", "results"}) == [
        "workflow/pendulum/no_such.py",
        "config.yaml",
    ]
