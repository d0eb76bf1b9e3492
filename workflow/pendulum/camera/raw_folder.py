"""The raw folder: which of its files are trials (a video or an angle table), their names and their sidecars.

A trial is named after its file (:func:`trial_name`); its sidecar is found beside it (:func:`_sidecar_of`); a file
that is no trial and no sidecar is :func:`passed_over` (named in the run's last lines); a folder that is missing or
holds no trial stops a plain run (:func:`raw_folder_problem`).
"""

from __future__ import annotations

import re
from pathlib import Path

from pendulum.camera.video import VIDEO_EXTENSIONS
from pendulum.trials import ConfigError, Trial, all_problems, read_sidecar

ANGLE_TABLE_EXTENSIONS = (".csv",)
NOT_IN_A_NAME = re.compile(r"[^A-Za-z0-9_.+-]+")  # spaces, brackets, accents, …: each run becomes one _
RESERVED_NAMES = ("joint", "summary")  # file names of the aggregate fits


# Latin letters that Unicode does not decompose into a base letter and a mark
LATIN_LETTERS = str.maketrans(
    {
        "ß": "ss",
        "æ": "ae",
        "Æ": "AE",
        "ø": "o",
        "Ø": "O",
        "œ": "oe",
        "Œ": "OE",
        "þ": "th",
        "Þ": "Th",
        "ð": "d",
        "Ð": "D",
        "ł": "l",
        "Ł": "L",
        "đ": "d",
        "Đ": "D",
    }
)
SIDECAR_EXTENSIONS = (".yaml", ".yml")


def trial_name(stem: str) -> str:
    """The trial's name from its file's stem: accents dropped (``é`` → ``e``, ``ß`` → ``ss``), then every run of
    characters other than letters, digits and ``_ . + -`` becomes one ``_``, and ``_ . + -`` at either end are
    dropped (``run 7 (left)`` → ``run_7_left``, ``VID 2026-11-25 14.03`` → ``VID_2026-11-25_14.03``). Where
    that drops letters or digits of another script (``опыт 1``), or leaves nothing, ``_`` and the first 8 hex
    digits of the stem's SHA-1 are added, so different names stay different (``опыт 1`` → ``1_3f2a…``). The
    name is used in results/ paths; the file keeps its own name (the status table and report show it)."""
    import hashlib
    import unicodedata

    folded = unicodedata.normalize("NFKD", stem.translate(LATIN_LETTERS))
    plain = "".join(c for c in folded if not unicodedata.combining(c))
    name = NOT_IN_A_NAME.sub("_", plain).strip("_.+-")
    lost = any(c.isalnum() and not c.isascii() for c in plain)  # letters or digits of another script
    if lost or not name:
        digest = hashlib.sha1(stem.encode("utf-8", "surrogateescape")).hexdigest()[:8]
        name = f"{name}_{digest}" if name else f"trial_{digest}"
    return name


def _sidecars_of(path: Path, name: str) -> list[Path]:
    """The trial's sidecars: its file's name with .yaml (or .yml) for its extension or after it (``run1.yaml`` or
    ``run1.mp4.yaml``), or its trial name with .yaml (or .yml); one at most is right (:func:`_sidecar_of`)."""
    candidates = [path.with_suffix(ext) for ext in SIDECAR_EXTENSIONS]
    candidates += [path.with_name(path.name + ext) for ext in SIDECAR_EXTENSIONS]
    candidates += [path.with_name(name + ext) for ext in SIDECAR_EXTENSIONS if name != path.stem]
    return [c for c in dict.fromkeys(candidates) if c.is_file()]


def _sidecar_of(path: Path, name: str, found: list[Path]) -> Path | None:
    """The trial's sidecar of those :func:`_sidecars_of` found; two of them refused naming both."""
    if len(found) > 1:
        raise ConfigError(f"{found[0]} and {found[1]} are both sidecars of {path} (trial {name!r}); keep one of them")
    return found[0] if found else None


def discover_trials(raw_dir: str | Path) -> dict[str, Trial]:
    """Every video (:data:`~pendulum.camera.video.VIDEO_EXTENSIONS`) and angle table (.csv) in ``raw_dir``, by trial
    name (:func:`trial_name`).

    Hidden files (``.DS_Store``, macOS's ``._name.mp4`` copies) are not data and are passed over. Two files
    whose trial names differ only in case are refused (they would be one file on macOS and Windows), as is a
    sidecar that belongs to no trial (it would be silently ignored); other files are :func:`passed_over`. A folder
    that is missing or holds no trial gives none (:func:`raw_folder_problem` says why, where a run needs them).
    """
    raw_dir = Path(raw_dir)
    trials: dict[str, Trial] = {}
    if not raw_dir.is_dir():
        return trials
    used: set[Path] = set()
    problems: list[str] = []
    misnamed = False  # a clash or a reserved name among the problems: not the sidecars' alone
    files = [
        p
        for p in sorted(raw_dir.iterdir())
        if not p.name.startswith(".") and p.is_file() and p.suffix.lower() in VIDEO_EXTENSIONS + ANGLE_TABLE_EXTENSIONS
    ]
    same_name: dict[str, list[Path]] = {}  # names that differ only in case are one file on macOS and Windows
    for path in files:
        same_name.setdefault(trial_name(path.stem).lower(), []).append(path)
    for path in files:  # every problem named at once, with the sidecars'
        suffix = path.suffix.lower()
        name = trial_name(path.stem)
        found = _sidecars_of(path, name)
        used.update(found)  # a file refused for its name keeps its sidecar: none is said to be of no trial
        clash = same_name[name.lower()]
        if name.lower() in RESERVED_NAMES:
            problems.append(f"{path}: {name!r} is reserved for the aggregate fits; rename the file")
            misnamed = True
            continue
        if len(clash) > 1:
            misnamed = True
            if path == clash[0]:
                listing = f"{clash[1]} and {clash[0]} both" if len(clash) == 2 else f"{', '.join(map(str, clash))} all"
                problems.append(
                    f"{listing} give trial {name!r} (a trial's name is its file name with spaces, brackets and other "
                    "signs made _, and names that differ only in case are one file on macOS and Windows); rename "
                    + ("one of them" if len(clash) == 2 else "all but one of them")
                )
            continue
        kind = "video" if suffix in VIDEO_EXTENSIONS else "angles"
        trial = Trial(name, kind, str(path))
        try:
            if (sidecar := _sidecar_of(path, name, found)) is not None:
                trial.sidecar, trial.sidecar_path = read_sidecar(sidecar), str(sidecar)
        except ConfigError as exc:
            problems.append(str(exc))
        trials[name] = trial
    stray = [
        p
        for p in sorted(raw_dir.iterdir())
        if p.suffix.lower() in SIDECAR_EXTENSIONS and p.is_file() and not p.name.startswith(".") and p not in used
    ]
    problems += [
        f"{path}: a sidecar of no trial (no video or angle table named {path.stem} or with that trial name), so it "
        "would be ignored; name it after its video, with .yaml for the video's extension or after it "
        "(data/raw/run1.yaml or data/raw/run1.mp4.yaml for data/raw/run1.mp4), or move it out of the raw folder"
        for path in stray
    ]
    if misnamed and len(problems) > 1:
        raise ConfigError(f"{len(problems)} problems in the raw folder:\n" + "\n".join(problems))
    if problems:
        raise ConfigError(all_problems(problems, "sidecars"))
    return trials


def passed_over(raw_dir: str | Path) -> list[Path]:
    """The files in ``raw_dir`` that are no trial and no sidecar, but could be meant as one: a video in a container not
    read as one (its extension), notes kept beside the videos, or a video or angle table whose name starts with a dot
    (hidden: passed over like ``.DS_Store``, but named; macOS's ``._name.mp4`` copies are not)."""
    trial_kinds = VIDEO_EXTENSIONS + ANGLE_TABLE_EXTENSIONS
    if not Path(raw_dir).is_dir():
        return []

    def named(p: Path) -> bool:
        if p.name.startswith("."):  # hidden: named only where it is a video or table, not an AppleDouble copy
            return p.suffix.lower() in trial_kinds and not p.name.startswith("._")
        return p.suffix.lower() not in trial_kinds + SIDECAR_EXTENSIONS

    return [p for p in sorted(Path(raw_dir).iterdir()) if p.is_file() and named(p)]


def raw_folder_problem(raw_dir: str | Path, trials: dict) -> str | None:
    """Why a plain run would build nothing, or None where ``trials`` (:func:`discover_trials` of the folder, skipped
    ones too) has any: the raw folder is missing or holds no trial (the run said "1 of 1 steps (100%) done" and
    left an earlier report standing as if new: a fresh-eyes user, 2026-12-07). Asked by the default target only:
    a camera's calibration needs no trial."""
    if trials:
        return None
    raw_dir = Path(raw_dir)
    if not raw_dir.is_dir():
        kind = "a file, not a folder" if raw_dir.exists() else "no such folder"
        return (
            f"{raw_dir}: {kind} (config raw_dir, the folder of the trials' videos and angle tables); make it and put "
            "the videos in it, or set raw_dir to the folder that holds them"
        )
    folders = [f"{p.name}/" for p in sorted(raw_dir.iterdir()) if p.is_dir() and not p.name.startswith(".")]
    others = [p.name for p in passed_over(raw_dir)] + folders
    return (
        f"{raw_dir}: no video ({', '.join(VIDEO_EXTENSIONS)}) or angle table ({', '.join(ANGLE_TABLE_EXTENSIONS)}) "
        "in it"
        + (f" (passed over: {', '.join(others[:5])}{', …' if len(others) > 5 else ''})" if others else "")
        + "; put the trials' files in it"
        + (" (the files in its folders are not read)" if folders else "")
        + ", or set raw_dir to the folder that holds them"
    )
