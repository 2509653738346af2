"""The console script, run as a subprocess the way people run it."""
import importlib
import json
import os
import subprocess
import sys
from pathlib import Path

import pytest

from layered_swim.body.layout import joint_layout
from layered_swim.body.model import load_body
from layered_swim.control.calibration import load_table
from layered_swim.control.stroke import load_stroke

REPO = Path(__file__).resolve().parents[1]
SUMMARY_KEYS = {"stroke", "seconds", "mean_speed_m_s", "stroke_rate_cpm", "distance_per_cycle_m",
                "peak_shoulder_roll_deg", "mean_head_height_m", "horizontal_drift_m_s",
                "final_pelvis_depth_m", "note"}


def cli(*args, cwd=REPO):
    env = {**os.environ, "PYTHONPATH": str(REPO) + os.pathsep + os.environ.get("PYTHONPATH", "")}
    return subprocess.run([sys.executable, "-m", "layered_swim", *args], cwd=cwd, env=env,
                          capture_output=True, text=True, timeout=120)


def assert_one_line_error(result, *words):
    assert result.returncode == 2, result.stderr
    assert result.stdout == ""
    assert "Traceback" not in result.stderr
    lines = result.stderr.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith("layered-swim: error: "), result.stderr
    for word in words:
        assert word in lines[0]


def test_strokes_lists_rest():
    result = cli("strokes")
    assert result.returncode == 0, result.stderr
    rest = [line for line in result.stdout.splitlines() if line.startswith("rest ")]
    assert rest and "15.0" in rest[0] and "float" in rest[0]
    # Each calibrated stroke's speed range, from its slowest working tempo (its min_tempo) to the
    # fastest measured, read off its calibration table's pace.
    crawl = [line for line in result.stdout.splitlines() if line.startswith("front_crawl ")][0]
    low, high = (float(v) for v in crawl.split()[2].split("-"))
    stroke = load_stroke("front_crawl", joint_layout(load_body()))
    pace = load_table(stroke).pace
    assert low == pytest.approx(pace.speed_at(stroke.steering.min_tempo), abs=0.005)
    assert high == pytest.approx(max(pace.speed_m_s), abs=0.005)
    assert 0.5 < low < high < 2.0


def test_run_json(tmp_path):
    out = tmp_path / "run"
    result = cli("run", "--stroke", "rest", "--seconds", "2", "--json", "--out", str(out))
    assert result.returncode == 0, result.stderr
    summary = json.loads(result.stdout)
    assert SUMMARY_KEYS <= set(summary)
    assert summary["stroke"] == "rest" and summary["seconds"] == pytest.approx(2.0)
    assert "settle" in summary["note"]
    assert {p.name for p in out.iterdir()} == {"summary.json", "config.json", "log.npz", "timeseries.csv",
                                               ".layered-swim-output", ".layered-swim.lock"}
    config = json.loads((out / "config.json").read_text())
    assert config["swim"]["seconds"] == 2.0 and config["stroke"]["name"] == "rest"
    assert config["medium"]["rho_kg_m3"] > 0 and config["physics_hz"] == 480


def test_an_abbreviated_option_is_an_error_not_another_option():
    """``follow --seed 3`` is not ``--seeds 3`` (three swims where one seed was meant)."""
    assert_one_line_error(cli("follow", "figure_eight", "--seed", "3"), "--seed")


def test_unknown_stroke(tmp_path):
    assert_one_line_error(cli("run", "--stroke", "no_such_stroke", "--out", str(tmp_path)), "no_such_stroke")


@pytest.mark.parametrize("args, words", [
    (["--density", "nan"], ["density"]),
    (["--seconds", "-1"], ["seconds"]),
    (["--stroke", "missing/stroke.yaml"], ["missing/stroke.yaml"]),
])
def test_bad_input(tmp_path, args, words):
    argv = ["run", "--stroke", "rest", "--out", str(tmp_path / "x"), *args]
    assert_one_line_error(cli(*argv), *words)


def test_malformed_stroke_file(tmp_path):
    bad = tmp_path / "bad.yaml"
    bad.write_text("name: bad\nperiod_s: [1, 2\n")
    assert_one_line_error(cli("run", "--stroke", str(bad), "--out", str(tmp_path / "x")), str(bad))


def test_validate_drag_json():
    result = cli("validate", "drag", "--json")
    assert result.returncode == 0, result.stderr
    rows = {row["speed_m_s"]: row for row in json.loads(result.stdout)}
    for speed in (1.0, 1.5, 2.0):
        row = rows[speed]
        assert row["reference_n"] == pytest.approx(23.5 * speed**2)
        assert 0.8 < row["drag_n"] / row["reference_n"] < 1.2



def test_app_is_a_command_too():
    """`layered-swim app` is what `python app.py` opens: the same options, the same help."""
    result = cli("app", "--help")
    assert result.returncode == 0, result.stderr
    assert result.stdout.startswith("usage: layered-swim app ") and "--stroke" in result.stdout
    shim = subprocess.run([sys.executable, str(REPO / "app.py"), "--help"], cwd=REPO, capture_output=True, text=True,
                          timeout=60)
    assert shim.returncode == 0 and shim.stdout.startswith("usage: app.py ")
    assert shim.stdout.split("\noptions:")[1] == result.stdout.split("\noptions:")[1]


def test_every_command_is_a_module_and_the_cli_only_puts_them_together():
    import layered_swim.commands as package
    from layered_swim import cli

    names = {p.stem for p in Path(package.__file__).parent.glob("*.py")} - {"__init__", "options", "tables"}
    assert {name.replace("_", "-") for name in names} == set(cli.COMMANDS)       # fit_stroke is fit-stroke
    for name in names:
        module = importlib.import_module(f"layered_swim.commands.{name}")
        assert callable(module.add_parser) and callable(module.run), name
    assert len((REPO / "layered_swim" / "cli.py").read_text().splitlines()) <= 150


def test_help_loads_no_heavy_module():
    """--help stays fast: PyBullet and torch load only inside a command's run()."""
    for program in (["-m", "layered_swim"], [str(REPO / "app.py")]):
        result = subprocess.run([sys.executable, "-X", "importtime", *program, "--help"], cwd=REPO,
                                capture_output=True, text=True, timeout=60)
        assert result.returncode == 0, result.stderr
        imported = {line.split("|")[-1].strip().split(".")[0] for line in result.stderr.splitlines() if "|" in line}
        assert not imported & {"pybullet", "torch", "numpy"}, program


def test_bench_at_the_default_rate():
    result = cli("bench", "--seconds", "0.1", "--json")
    assert result.returncode == 0, result.stderr
    timing = json.loads(result.stdout)
    assert timing["physics_hz"] == 480 and timing["steps"] == 48
    assert 0 < timing["bare_step_us"] < timing["loop_step_us"]
