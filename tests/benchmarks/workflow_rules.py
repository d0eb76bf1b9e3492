"""What the workflow's rules declare (threads, resources, script), read from workflow/rules/*.smk."""

import re
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]


def rule_declarations() -> dict[str, dict]:
    """Rule → threads, mem_mb, runtime and script, read from workflow/rules/*.smk (a resource given by a
    function of the job's inputs: its name)."""
    rules = {}
    for smk in sorted((ROOT / "workflow" / "rules").glob("*.smk")):
        for block in re.split(r"^rule ", smk.read_text(), flags=re.M)[1:]:
            name = block.split(":", 1)[0].strip()
            body = re.split(r"^\S", block.split("\n", 1)[1], flags=re.M)[0]
            found = {}
            for key, pattern in (
                ("threads", r"^\s+threads:\s*(\d+)"),
                ("mem_mb", r"^\s+mem_mb=(\w+)"),
                ("runtime", r"^\s+runtime=(\w+)"),
                ("script", r"^\s+\"\.\./scripts/(\w+)\.py\""),
            ):
                match = re.search(pattern, body, re.M)
                value = match.group(1) if match else None
                found[key] = int(value) if value and value.isdigit() and key != "script" else value
            rules[name] = found
    return rules
