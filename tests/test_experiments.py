"""The experiments' parts: every module has the ones ``runner.py`` calls, the runner writes the
CSV, figure, summary and report from them, and ``measure``, ``plot`` and ``describe`` each do one
job on made-up results (no swim). The real runs from the command line: test_analysis_cli.py."""
import csv
import inspect
import json
import sys

import numpy as np
import pytest

from layered_swim.analysis.experiments import EXPERIMENTS, hand_force, turn
from layered_swim.analysis.experiments.runner import Outcome, run_experiment

PNG_MAGIC = b"\x89PNG\r\n\x1a\n"
PARTS = {"configs": ["quick", "seed"], "run": ["config"], "measure": ["configs", "results"],
         "plot": ["numbers", "path"], "describe": ["numbers"]}


@pytest.mark.parametrize("module", EXPERIMENTS.values(), ids=list(EXPERIMENTS))
def test_every_experiment_has_the_parts_the_runner_calls(module):
    for name in ("NAME", "TITLE", "PAPER", "FIGURE", "CSV"):
        assert isinstance(getattr(module, name), str)
    for name, parameters in PARTS.items():
        assert list(inspect.signature(getattr(module, name)).parameters) == parameters, name
    assert not hasattr(module, "finish")


# A stand-in experiment for the runner: its run is the identity, its numbers the configs' x.
NAME, TITLE, PAPER, FIGURE, CSV = "fake", "A fake experiment", "The paper's finding.", "fake.png", "fake.csv"


def configs(quick: bool, seed: int) -> list[dict]:
    return [{"x": 1.5}, {"x": 2.5}]


def run(config: dict) -> dict:
    return {"y": 2.0 * config["x"]}


def measure(configs: list[dict], results: list[dict]) -> dict:
    return {"rows": [{"x": c["x"], "y": r["y"]} for c, r in zip(configs, results)],
            "summary": {"total_y": sum(r["y"] for r in results)}, "private": "for plot and describe only"}


def plot(numbers: dict, path) -> None:
    path.write_bytes(PNG_MAGIC)


def describe(numbers: dict) -> Outcome:
    return Outcome(f"y adds up to {numbers['summary']['total_y']:g}", "made up", differs=numbers["private"])


def test_the_runner_writes_the_csv_figure_summary_and_report_from_the_parts(tmp_path):
    summary = run_experiment(sys.modules[__name__], tmp_path, workers=1)
    assert summary["total_y"] == 8.0 and "private" not in summary
    assert summary["ours"] == "y adds up to 8" and summary["differs"] == "for plot and describe only"
    assert json.loads((tmp_path / "summary.json").read_text()) == {k: v for k, v in summary.items() if k != "files"}
    with (tmp_path / CSV).open() as f:
        assert list(csv.DictReader(f)) == [{"x": "1.5", "y": "3"}, {"x": "2.5", "y": "5"}]
    assert (tmp_path / FIGURE).read_bytes() == PNG_MAGIC
    report = (tmp_path / "report.md").read_text()
    assert "**Ours:** y adds up to 8" in report and "**Setting:** made up" in report


def made_up_hand_force(buoyancy: bool = True) -> dict:
    """One 1.02 s cycle at 480 Hz: a force that swells to 100 N and back, steady buoyancy."""
    t = np.arange(1, 490) / 480.0
    force = np.stack([100.0 * np.sin(np.pi * t / 1.02) ** 2, 10.0 * np.sin(2 * np.pi * t), np.full_like(t, 4.5)],
                     axis=1)
    return {"time_s": t.tolist(), "force_n": force.tolist(),
            "buoyancy_n": [[0.0, 0.0, 4.5]] * len(t) if buoyancy else None, "period_s": 1.02,
            "physics_hz": 480, "control_hz": 120, "backend": "plate" if buoyancy else "sph"}


def test_hand_force_measure_is_pure_and_describe_words_its_numbers(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    configs_ = hand_force.configs(False, 0)
    result = made_up_hand_force()
    numbers = hand_force.measure(configs_, [result])
    assert list(tmp_path.iterdir()) == []                    # no files
    assert numbers["summary"] == hand_force.measure(configs_, [made_up_hand_force()])["summary"]
    assert len(numbers["rows"]) == 489 and numbers["rows"][0]["buoyancy_z_n"] == 4.5
    s = json.loads(json.dumps(numbers["summary"]))           # JSON-able as it is
    assert s["peak_force_n"] == pytest.approx(100.1, abs=0.1) and s["peak_time_s"] == pytest.approx(0.51, abs=0.01)
    assert s["mean_buoyancy_n"] == 4.5 and s["backend"] == "plate"
    outcome = hand_force.describe(numbers)
    assert f"a peak of {s['peak_force_n']:.0f} N at t = 0.51 s" in outcome.ours and "Buoyancy adds" in outcome.ours
    assert "thin plates" in outcome.setting and "120 Hz control rate" in outcome.differs
    sph = hand_force.describe(hand_force.measure(configs_, [made_up_hand_force(buoyancy=False)]))
    assert sph.ours.startswith("In SPH water") and "includes the buoyancy" in sph.ours
    hand_force.plot(numbers, tmp_path / hand_force.FIGURE)
    assert [p.name for p in tmp_path.iterdir()] == [hand_force.FIGURE]
    assert (tmp_path / hand_force.FIGURE).read_bytes()[:8] == PNG_MAGIC


def test_turn_measures_each_weights_rate_and_describes_them(tmp_path):
    configs_ = turn.configs(True, 0)
    period_s = 1.0
    t = np.arange(0.0, (turn.BASIC_CYCLES + configs_[0]["perturbed_cycles"]) * period_s, 0.05)
    perturbed = np.clip(t - turn.BASIC_CYCLES * period_s, 0.0, None)
    results = [{"time_s": t.tolist(), "yaw_deg": (rate * perturbed).tolist(), "period_s": period_s}
               for rate in (0.5, 5.0, 10.0)]
    numbers = turn.measure(configs_, results)
    assert numbers["summary"]["turn_deg_per_cycle"] == pytest.approx({"0": 0.5, "0.5": 5.0, "1": 10.0})
    assert list(numbers["rows"][0]) == ["time_s", "yaw_deg_weight_0", "yaw_deg_weight_0.5", "yaw_deg_weight_1"]
    ours = turn.describe(numbers).ours
    assert "+10.0 deg per cycle at weight 1" in ours and "+5.0 at weight 0.5" in ours and "drift of +0.5" in ours
    turn.plot(numbers, tmp_path / turn.FIGURE)
    assert (tmp_path / turn.FIGURE).read_bytes()[:8] == PNG_MAGIC
