"""``analyze``, ``compare`` and ``experiment`` from the command line: a tiny swim writes every
file and they parse; bad input is one line and exit status 2."""
import csv
import json

import pytest
from test_cli import assert_one_line_error, cli

PNG_MAGIC = b"\x89PNG\r\n\x1a\n"
ANALYSIS_FILES = {"summary.json", "config.json", "cycles.csv", "profiles.csv", "speed.png", "limb_forces.png",
                  "propulsion_power.png", "attitude.png", "report.md"}


def test_tiny_analyze_writes_files_that_parse(tmp_path):
    out = tmp_path / "bs"
    result = cli("analyze", "--stroke", "breaststroke", "--seconds", "6.5", "--settle", "1", "--out", str(out),
                 "--json")
    assert result.returncode == 0, result.stderr
    printed = json.loads(result.stdout)
    assert {p.name for p in out.iterdir() if not p.name.startswith('.layered-swim')} == ANALYSIS_FILES
    summary = json.loads((out / "summary.json").read_text())
    assert summary["stroke"] == printed["stroke"] == "breaststroke"
    assert summary["cycles"] >= 2 and 35.0 < summary["stroke_rate_cpm"]["mean"] < 45.0     # 39.6 nominal
    assert summary["mechanical_power_w"]["mean"] > 0 and 0 < summary["propelling_efficiency"] < 1
    verdicts = {row["quantity"]: row["verdict"] for row in summary["comparison"]}
    # elite breaststrokers swim 50-60 cycles a minute; the re-authored stroke swims 39.6
    assert verdicts["stroke_rate_cpm"] == "below" and verdicts["mean_speed_m_s"] in ("below", "inside", "above")
    with (out / "cycles.csv").open() as f:
        rows = list(csv.DictReader(f))
    assert len(rows) == summary["cycles"] and float(rows[0]["duration_s"]) == pytest.approx(1.517, abs=0.03)
    with (out / "profiles.csv").open() as f:
        assert len(list(csv.DictReader(f))) == 101
    for png in ("speed.png", "limb_forces.png", "propulsion_power.png", "attitude.png"):
        assert (out / png).read_bytes()[:8] == PNG_MAGIC
        assert f"]({png})" in (out / "report.md").read_text()
    config = json.loads((out / "config.json").read_text())
    assert config["swim"]["seconds"] == 6.5 and config["log_hz"] == 120


def test_hand_force_experiment(tmp_path):
    result = cli("experiment", "hand-force", "--out", str(tmp_path), "--no-progress", "--json")
    assert result.returncode == 0, result.stderr
    summary = json.loads(result.stdout)
    assert summary["experiment"] == "hand-force" and summary["peak_force_n"] > 0
    for name in ("hand_force.png", "hand_force.csv", "summary.json", "config.json", "report.md"):
        assert (tmp_path / name).is_file()
    assert len(list((tmp_path / "cache").glob("*.json"))) == 1


def test_experiment_list():
    result = cli("experiment", "list")
    assert result.returncode == 0, result.stderr
    names = {line.split()[0] for line in result.stdout.splitlines()[1:]}
    assert names == {"hand-force", "turn", "palm-rule", "layers-in-current", "density-sweep", "current-sweep",
                     "perturbation", "swim-table", "swim-generalisation", "robustness"}


@pytest.mark.parametrize("args, words", [
    (["analyze", "--stroke", "no_such_stroke"], ["no_such_stroke"]),
    (["analyze", "--stroke", "breaststroke", "--density", "nan"], ["density"]),
    (["analyze", "--stroke", "breaststroke", "--seconds", "3", "--settle", "5"], ["settle"]),
    (["analyze", "--stroke", "breaststroke", "--seconds", "2", "--settle", "1"], ["cycles"]),
    (["compare", "--strokes", "breaststroke,nope"], ["nope"]),
    (["experiment", "no-such-experiment"], ["no-such-experiment"]),
])
def test_bad_input(tmp_path, args, words):
    assert_one_line_error(cli(*args, "--out", str(tmp_path / "x")), *words)
