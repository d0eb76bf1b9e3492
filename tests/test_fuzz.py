"""Property-based (fuzz) tests of the input readers: malformed input ends in a documented error, never a crash.

Every reader a user's file reaches is fed a few hundred generated malformed inputs
(deterministic: ``derandomize=True``). The only exceptions allowed are the documented
ones, ``ConfigError`` and ``InputError`` (both ``ValueError``), with a one-line message
that names the file. Inputs that are accepted must give something usable.
"""

import copy
import math
import tempfile
from pathlib import Path

import numpy as np
import pandas as pd
import pytest
import yaml
from hypothesis import HealthCheck, event, given, settings
from hypothesis import strategies as st

from conftest import ROOT
from pendulum.angles.record import InputError, angles_from_track, angles_from_tracker_csv, read_tracker_csv
from pendulum.fit.records import FitSettings
from pendulum.model.rig import Rig
from pendulum.tracking.settings import FLAGS, TrackerSettings
from pendulum.trials import RIG_KEYS, ConfigError, Trial, read_sidecar, trial_settings, validate_config

FUZZ = settings(
    max_examples=200, deadline=None, derandomize=True, database=None, suppress_health_check=[HealthCheck.too_slow]
)
BASE_CONFIG = yaml.safe_load((ROOT / "config.yaml").read_text())

numbers = st.one_of(
    st.floats(allow_nan=True, allow_infinity=True),
    st.floats(-1e3, 1e3),
    st.integers(-(10**6), 10**6),
    st.sampled_from([0, 0.0, -0.0, 1e-300, 1e300, -1e300]),
)
scalars = st.one_of(numbers, st.text(max_size=12), st.booleans(), st.none())
values = st.recursive(
    scalars,
    lambda inner: st.lists(inner, max_size=3) | st.dictionaries(st.text(max_size=8), inner, max_size=3),
    max_leaves=6,
)


def assert_documented(exc: BaseException, *classes, source: str | None = None) -> None:
    """The error is one of ``classes``, with a one-line message naming ``source``."""
    assert isinstance(exc, classes), f"{type(exc).__name__}: {exc}"
    message = str(exc)
    event(f"refused: {message.split(': ', 1)[-1][:40]}")
    assert message and "\n" not in message, repr(message)
    if source is not None:
        assert source in message, message


# --- angle tables (data/raw/<trial>.csv) ---------------------------------------------------------------

cells = st.one_of(
    st.floats(allow_nan=True, allow_infinity=True).map(repr),
    st.floats(-200, 200).map(lambda v: f"{v:.6g}"),
    st.sampled_from(["", " ", "nan", "NA", "abc", "1,5", "1e999", "-", "0x10", '"3"', "1;2"]),
    st.text(alphabet=st.characters(blacklist_categories=("Cs",)), max_size=6),
)
headers = st.lists(st.sampled_from(["t_s", "theta_deg", "x", "T_S", "theta", ""]), min_size=0, max_size=4)


@st.composite
def angle_csv_text(draw):
    """A CSV-like text: random header and cells, or a decaying swing with some rows broken."""
    sep = draw(st.sampled_from([",", ";", "\t"]))
    if draw(st.booleans()):
        n = draw(st.integers(0, 400))
        t = np.arange(n) / draw(st.sampled_from([30.0, 60.0, 1e6, 0.5]))
        swing = draw(st.floats(0.0, 90.0)) * np.exp(-0.1 * t) * np.cos(2 * np.pi * t / draw(st.floats(0.05, 50)))
        rows = [[f"{a:.6f}", f"{b:.6f}"] for a, b in zip(t, swing, strict=True)]
        for _ in range(draw(st.integers(0, 6))):
            if rows:
                i, j = draw(st.integers(0, len(rows) - 1)), draw(st.integers(0, 1))
                rows[i][j] = draw(cells)
        if rows and draw(st.booleans()):
            order = draw(st.permutations(range(len(rows))))
            rows = [rows[i] for i in order]
        header = ["t_s", "theta_deg"]
    else:
        header = draw(headers)
        rows = draw(st.lists(st.lists(cells, min_size=len(header), max_size=len(header)), max_size=30))
    lines = [sep.join(header)] + [sep.join(r) for r in rows]
    return "\n".join(lines) + draw(st.sampled_from(["", "\n", "\n\n", "\n,,,\n"]))


@pytest.mark.slow
@FUZZ
@given(text=angle_csv_text())
def test_angle_csv_reader_never_crashes(text):
    with tempfile.TemporaryDirectory() as tmp:
        path = Path(tmp) / "trial.csv"
        path.write_text(text, encoding="utf-8", errors="surrogatepass")
        try:
            table, info = angles_from_tracker_csv(
                read_tracker_csv(path), vertical_deg=0.0, length_m=0.5, source=str(path)
            )
        except Exception as exc:  # noqa: BLE001 - the property is about which exceptions
            assert_documented(exc, InputError, source=str(path))
            return
    assert len(table) == info.n_samples >= 1
    assert np.isfinite(table.time_s).all() and table.time_s.is_monotonic_increasing
    ok = table.flag == "ok"
    assert np.isfinite(table.theta_rad[ok]).all() and table.theta_rad[~ok].isna().all()


@pytest.mark.slow
@FUZZ
@given(
    columns=st.dictionaries(
        st.sampled_from(["t_s", "theta_deg", "other"]), st.lists(scalars, min_size=0, max_size=40), max_size=3
    )
)
def test_angle_table_objects_never_crash(columns):
    """The reader's second half on any DataFrame (mixed types, ragged columns padded with None)."""
    n = max((len(v) for v in columns.values()), default=0)
    frame = pd.DataFrame({k: list(v) + [None] * (n - len(v)) for k, v in columns.items()})
    try:
        angles_from_tracker_csv(frame, vertical_deg=0.0, length_m=0.5, source="data/raw/x.csv")
    except Exception as exc:  # noqa: BLE001
        assert_documented(exc, InputError, source="data/raw/x.csv")


# --- sidecars (data/raw/<trial>.yaml) ---------------------------------------------------------------------

sidecar_keys = st.sampled_from(
    [
        *RIG_KEYS,
        "rig",
        "pivot_px",
        "vertical_deg",
        "marker_radius_px",
        "polarity",
        "start_px",
        "mass",
        "lenght_m",
        "1",
        "",
    ]
)


@st.composite
def sidecar_text(draw):
    kind = draw(st.sampled_from(["mapping", "value", "text"]))
    if kind == "mapping":
        doc = draw(st.dictionaries(sidecar_keys, values, max_size=4))
        return yaml.safe_dump(doc, allow_unicode=True)
    if kind == "value":
        return yaml.safe_dump(draw(values), allow_unicode=True)
    return draw(st.text(max_size=60))


@pytest.mark.slow
@FUZZ
@given(text=sidecar_text())
def test_sidecar_reader_never_crashes(text):
    with tempfile.TemporaryDirectory() as tmp:
        path = Path(tmp) / "trial.yaml"
        path.write_bytes(text.encode("utf-8", errors="surrogatepass"))
        try:
            sidecar = read_sidecar(path)
            settings_ = trial_settings(
                BASE_CONFIG, Trial("trial", "video", str(path.with_suffix(".mp4")), sidecar, str(path))
            )
        except Exception as exc:  # noqa: BLE001
            assert_documented(exc, ConfigError, source=str(path))
            return
    # accepted: the merged values make a pendulum and a tracker
    Rig.from_mapping(settings_["rig"])
    TrackerSettings.from_config(settings_["tracking"])


@FUZZ
@given(data=st.binary(max_size=80))
def test_sidecar_bytes_never_crash(data):
    with tempfile.TemporaryDirectory() as tmp:
        path = Path(tmp) / "trial.yaml"
        path.write_bytes(data)
        try:
            read_sidecar(path)
        except Exception as exc:  # noqa: BLE001
            assert_documented(exc, ConfigError, source=str(path))


# --- the configuration ------------------------------------------------------------------------------------


def _paths(doc, prefix=()):
    yield prefix
    if isinstance(doc, dict):
        for key, value in doc.items():
            yield from _paths(value, (*prefix, key))


@st.composite
def mutated_config(draw):
    """The shipped config with a few keys replaced, deleted, renamed or added at random places."""
    config = copy.deepcopy(BASE_CONFIG)
    for _ in range(draw(st.integers(1, 3))):
        paths = [p for p in _paths(config) if p]
        path = draw(st.sampled_from(paths))
        parent = config
        for key in path[:-1]:
            parent = parent[key]
        action = draw(st.sampled_from(["replace", "delete", "rename", "add", "number"]))
        if action == "replace":
            parent[path[-1]] = draw(values)
        elif action == "number":
            parent[path[-1]] = draw(numbers)
        elif action == "delete":
            del parent[path[-1]]
        elif action == "rename":
            parent[str(path[-1])[:-1] or "x"] = parent.pop(path[-1])
        elif isinstance(parent, dict):
            parent[draw(st.text(max_size=8))] = draw(values)
    return config


@pytest.mark.slow
@FUZZ
@given(config=mutated_config())
def test_config_validation_never_crashes_and_what_it_accepts_works(config):
    try:
        validate_config(config)
    except Exception as exc:  # noqa: BLE001
        assert_documented(exc, ConfigError, source="config.yaml")
        return
    for values in config["rigs"].values():
        Rig.from_mapping(values)
    TrackerSettings.from_config(config["tracking"])
    FitSettings(**config["fitting"])


# --- track → angles ---------------------------------------------------------------------------------------

coordinates = st.one_of(
    st.floats(allow_nan=True, allow_infinity=True), st.floats(-1e4, 1e4), st.sampled_from([0.0, 1e300, -1e300, 1e-300])
)


@st.composite
def tracks(draw):
    """A marker track: random rows, or a swing with NaN runs, frozen stretches, spikes and huge values."""
    n = draw(st.integers(0, 300))
    if draw(st.booleans()):
        x = np.array(draw(st.lists(coordinates, min_size=n, max_size=n)), float)
        y = np.array(draw(st.lists(coordinates, min_size=n, max_size=n)), float)
    else:
        t = np.arange(n) / 30.0
        amp = draw(st.floats(0.0, 1.5))
        theta = amp * np.exp(-draw(st.floats(0, 2)) * t) * np.cos(2 * np.pi * t / draw(st.floats(0.1, 20)))
        hold = draw(st.integers(0, 60))
        theta[:hold] = amp
        radius = draw(st.sampled_from([0.0, 1e-6, 3.0, 500.0, 1e12]))
        x, y = 640 + radius * np.sin(theta), 70 + radius * np.cos(theta)
        for _ in range(draw(st.integers(0, 5))):
            if n:
                i = draw(st.integers(0, n - 1))
                j = min(n, i + draw(st.integers(1, 40)))
                what = draw(st.sampled_from(["nan", "freeze", "spike", "huge"]))
                if what == "nan":
                    x[i:j] = np.nan
                elif what == "freeze":
                    x[i:j], y[i:j] = x[i], y[i]
                elif what == "spike":
                    x[i] += draw(st.floats(-100, 100))
                else:
                    y[i:j] = draw(coordinates)
    times = np.arange(n) / 30.0
    if n and draw(st.booleans()):
        times = np.array(draw(st.lists(st.floats(allow_nan=True, allow_infinity=True), min_size=n, max_size=n)))
    flags = draw(st.lists(st.sampled_from(FLAGS), min_size=n, max_size=n)) if draw(st.booleans()) else ["ok"] * n
    frame = pd.DataFrame({"frame": np.arange(n), "time_s": times, "x_px": x, "y_px": y, "quality": 1.0, "flag": flags})
    drop = draw(st.sampled_from([None, None, None, "flag", "time_s", "quality"]))
    return frame.drop(columns=drop) if drop else frame


pivots = st.one_of(
    st.just((640.0, 70.0)), st.tuples(coordinates, coordinates), st.lists(st.floats(-1e3, 1e3), min_size=0, max_size=3)
)


@pytest.mark.slow
@FUZZ
@given(track=tracks(), pivot=pivots, vertical=st.floats(-45, 45), length=st.floats(1e-3, 10))
def test_track_to_angles_never_crashes(track, pivot, vertical, length):
    try:
        table, info = angles_from_track(
            track, pivot_px=pivot, vertical_deg=vertical, length_m=length, source="results/tracks/x.csv"
        )
    except Exception as exc:  # noqa: BLE001
        assert_documented(exc, InputError, source="results/tracks/x.csv")
        return
    ok = (table.flag == "ok").to_numpy()
    assert np.isfinite(table.theta_rad.to_numpy()[ok]).all()
    assert np.all(np.abs(table.theta_rad.to_numpy()[ok]) <= math.pi + 1e-9)
    assert info.n_samples == len(table)


@pytest.mark.parametrize("n", [0, 1, 2, 3, 9])
def test_tiny_tracks_are_refused_with_the_file_named(n):
    track = pd.DataFrame(
        {"frame": range(n), "time_s": np.arange(n) / 30, "x_px": 1.0, "y_px": 2.0, "quality": 1.0, "flag": "ok"}
    )
    with pytest.raises(InputError, match=r"x\.csv: only \d+ valid angle samples"):
        angles_from_track(track, pivot_px=(0, 0), vertical_deg=0, length_m=1, source="x.csv")
