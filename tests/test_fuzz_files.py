"""Property-based fuzzing of every file kind the project reads: random mutations of the shipped
files (wrong types, NaN and infinities, huge values, deleted and extra fields, random bytes).
Each either loads into finite numbers or fails with one ConfigError line, never anything else.
Bounded: a fixed number of examples per kind, no deadline surprises, well under a minute."""
import copy
import json
import shutil
from pathlib import Path

import numpy as np
import pytest
import yaml
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from layered_swim.body.layout import joint_layout
from layered_swim.body.model import DEFAULT_BODY_FILE, load_body
from layered_swim.config import ConfigError
from layered_swim.control.calibration import load_table
from layered_swim.control.stroke import STROKES_DIR, load_stroke
from layered_swim.control.targets import TRAJECTORIES_DIR, load_trajectory
from layered_swim.fluid.flow_field import WATER_DIR, load_water
from layered_swim.recorder import read_log
from layered_swim.render.replay import LogReplay

EXAMPLES = 90         # per file kind; seven kinds: 630 cases
FUZZ = settings(max_examples=EXAMPLES, deadline=None, derandomize=True,
                suppress_health_check=[HealthCheck.function_scoped_fixture, HealthCheck.too_slow])
LAYOUT = joint_layout(load_body())
ODD_VALUES = st.one_of(
    st.none(), st.booleans(), st.integers(min_value=-10**30, max_value=10**30),
    st.floats(allow_nan=True, allow_infinity=True), st.sampled_from([1e308, -1e308, 1e-320, 0.0, -1.0, 1e6]),
    st.text(max_size=12), st.lists(st.floats(allow_nan=True), max_size=4),
    st.dictionaries(st.text(max_size=5), st.integers(), max_size=3))


def _paths(tree, prefix=()):
    """Every place in a parsed YAML/JSON tree: dict keys and list items, nested."""
    yield prefix
    if isinstance(tree, dict):
        for key, value in tree.items():
            yield from _paths(value, prefix + (key,))
    elif isinstance(tree, list):
        for i, value in enumerate(tree):
            yield from _paths(value, prefix + (i,))


@st.composite
def mutated(draw, tree):
    """``tree`` with one to three places replaced by an odd value, deleted, or given an extra field."""
    tree = copy.deepcopy(tree)
    for _ in range(draw(st.integers(1, 3))):
        places = [p for p in _paths(tree) if p]
        if not places:
            return draw(ODD_VALUES)
        *parent_path, last = draw(st.sampled_from(places))
        parent = tree
        for key in parent_path:
            parent = parent[key]
        action = draw(st.sampled_from(["replace", "replace", "delete", "extra"]))
        if action == "replace":
            parent[last] = draw(ODD_VALUES)
        elif action == "delete":
            del parent[last]
        elif isinstance(parent, dict):
            parent[draw(st.text(min_size=1, max_size=8))] = draw(ODD_VALUES)
        else:
            parent.append(draw(ODD_VALUES))
    return tree


def _file_text(draw, original_text: str) -> bytes:
    """A mutated YAML tree, or the original bytes flipped, truncated or replaced by random bytes."""
    how = draw(st.sampled_from(["tree", "tree", "tree", "bytes", "truncate", "random"]))
    raw = original_text.encode()
    if how == "tree":
        return yaml.safe_dump(draw(mutated(yaml.safe_load(original_text))), allow_unicode=True).encode()
    if how == "truncate":
        return raw[:draw(st.integers(0, len(raw)))]
    if how == "random":
        return draw(st.binary(max_size=200))
    data = bytearray(raw)
    for _ in range(draw(st.integers(1, 8))):
        data[draw(st.integers(0, len(data) - 1))] = draw(st.integers(0, 255))
    return bytes(data)


def loads_or_one_line(load):
    """``load()``'s result, or None after checking its error is a single non-empty line."""
    try:
        return load()
    except ConfigError as err:
        message = str(err)
        assert message.strip() and "\n" not in message, message
        return None


@pytest.fixture(scope="module")
def folder(tmp_path_factory):
    return tmp_path_factory.mktemp("fuzz")


@given(data=st.data())
@FUZZ
def test_stroke_files(data, folder):
    path = folder / "stroke.yaml"
    path.write_bytes(_file_text(data.draw, (STROKES_DIR / "breaststroke.yaml").read_text()))
    stroke = loads_or_one_line(lambda: load_stroke(str(path), LAYOUT))
    if stroke is not None:
        assert np.isfinite(stroke.table).all() and 0.2 <= stroke.period_s <= 20


@given(data=st.data())
@FUZZ
def test_trajectory_files(data, folder):
    name = data.draw(st.sampled_from(sorted(p.name for p in TRAJECTORIES_DIR.glob("*.yaml"))))
    path = folder / "path.yaml"
    path.write_bytes(_file_text(data.draw, (TRAJECTORIES_DIR / name).read_text()))
    target = loads_or_one_line(lambda: load_trajectory(path))
    if target is not None:
        points = np.array([target.position(t) for t in (0.0, 1.0, 60.0, 3600.0)])
        assert np.isfinite(points).all() and np.abs(points).max() < 1e6


@given(data=st.data())
@FUZZ
def test_water_files(data, folder):
    name = data.draw(st.sampled_from(sorted(p.name for p in WATER_DIR.glob("*.yaml"))))
    path = folder / "water.yaml"
    path.write_bytes(_file_text(data.draw, (WATER_DIR / name).read_text()))
    flow = loads_or_one_line(lambda: load_water(path))
    if flow is not None:
        points = np.array([[0.0, 0.0, -0.3], [5.0, 2.5, 0.0], [1e3, -1e3, -50.0]])
        velocity = np.concatenate([flow.velocity_m_s(points, t) for t in (0.0, 1.0, 3600.0)])
        assert np.isfinite(velocity).all() and np.abs(velocity).max() < 1e3


@given(data=st.data())
@FUZZ
def test_calibration_files(data, folder):
    stroke = load_stroke("breaststroke", LAYOUT)
    directory = folder / "calibration"
    directory.mkdir(exist_ok=True)
    original = (STROKES_DIR / "calibration" / "breaststroke.yaml").read_text()
    (directory / "breaststroke.yaml").write_bytes(_file_text(data.draw, original))
    table = loads_or_one_line(lambda: load_table(stroke, directory))
    if table is not None:
        assert all(np.isfinite(rows).all() for rows in table.turn_rad.values())
        assert np.isfinite(table.weight_for("yaw_left", 0.1, 1.0))


@given(data=st.data())
@FUZZ
def test_body_files(data, folder):
    path = folder / "body.yaml"
    path.write_bytes(_file_text(data.draw, Path(str(DEFAULT_BODY_FILE)).read_text()))
    body = loads_or_one_line(lambda: load_body(path))
    if body is not None:
        assert np.isfinite(body.half_extents_m).all() and np.isfinite(body.mass_kg).all()


@pytest.fixture(scope="module")
def run_folder(tmp_path_factory):
    """A real run folder (a short swim), written once."""
    from layered_swim.runs import run_swim
    from layered_swim.spec import SwimSpec

    out = tmp_path_factory.mktemp("run") / "r"
    run_swim(SwimSpec(stroke="breaststroke", seconds=0.5), out)
    return out


def _mutated_log(draw, log: dict) -> dict:
    log = dict(log)
    name = draw(st.sampled_from(sorted(log)))
    how = draw(st.sampled_from(["nan", "shape", "delete", "dtype", "empty"]))
    array = log[name]
    if how == "nan" and array.dtype.kind == "f":
        array = array.copy()
        array.flat[draw(st.integers(0, array.size - 1))] = draw(st.sampled_from([np.nan, np.inf, -np.inf]))
        log[name] = array
    elif how == "shape":
        log[name] = array.reshape(-1)[: max(0, array.size - draw(st.integers(1, 5)))]
    elif how == "delete":
        del log[name]
    elif how == "dtype":
        log[name] = np.array([draw(st.text(max_size=4))] * max(1, len(array)))
    else:
        log[name] = array[:0]
    return log


def _copy(run_folder, target):
    shutil.rmtree(target, ignore_errors=True)
    shutil.copytree(run_folder, target)
    return target


@given(data=st.data())
@FUZZ
def test_run_folder_logs(data, run_folder, folder):
    target = _copy(run_folder, folder / "replayed")
    how = data.draw(st.sampled_from(["arrays", "arrays", "bytes", "truncate", "random"]))
    raw = (run_folder / "log.npz").read_bytes()
    if how == "arrays":
        with np.load(run_folder / "log.npz") as original:
            np.savez(target / "log.npz", **_mutated_log(data.draw, {k: original[k] for k in original.files}))
    elif how == "truncate":
        (target / "log.npz").write_bytes(raw[:data.draw(st.integers(0, len(raw) - 1))])
    elif how == "random":
        (target / "log.npz").write_bytes(data.draw(st.binary(max_size=300)))
    else:
        flipped = bytearray(raw)
        for _ in range(data.draw(st.integers(1, 16))):
            flipped[data.draw(st.integers(0, len(raw) - 1))] ^= 0xFF
        (target / "log.npz").write_bytes(bytes(flipped))
    replay = loads_or_one_line(lambda: LogReplay(target))
    if replay is not None:
        assert np.isfinite(replay.segment_pos_m).all() and np.isfinite(replay.time_s).all()


@given(data=st.data())
@FUZZ
def test_run_folder_configs(data, run_folder, folder):
    target = _copy(run_folder, folder / "configured")
    original = (run_folder / "config.json").read_text()
    if data.draw(st.booleans()):
        text = json.dumps(data.draw(mutated(json.loads(original))))
        (target / "config.json").write_text(text)
    else:
        (target / "config.json").write_bytes(_file_text(data.draw, original))
    replay = loads_or_one_line(lambda: LogReplay(target))
    if replay is not None:
        assert np.isfinite(replay.current_m_s).all()
    assert read_log(target)["time_s"].size > 0
