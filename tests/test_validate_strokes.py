"""`layered-swim validate strokes`: the velocity perturbation method, the ✔/✘ logic, the
measurements' observers and the command's JSON, on hand-made numbers and one short sweep."""
import json
import math
import os
import subprocess
import sys
from pathlib import Path
from types import SimpleNamespace

import numpy as np
import pytest

from layered_swim import cli as cli_module
from layered_swim.analysis import active_drag, head_clearance, validation_report
from layered_swim.analysis.reference_ranges import MUST_HOLD, Range, at_least, at_most, must_hold, within
from layered_swim.analysis.stroke_validation import passes, validation_rows
from layered_swim.analysis.swim_observers import JointWork, TowedBuoy
from layered_swim.config import ConfigError
from layered_swim.episode import Episode
from layered_swim.recorder import Recorder

REPO = Path(__file__).resolve().parents[1]


# --- the velocity perturbation method ---------------------------------------------------------

def test_vpm_against_a_hand_computed_case():
    # F_b = 10 N, v1 = 1.5, v2 = 1.4 m/s: 10 * 1.4 * 2.25 / (3.375 - 2.744) = 31.5 / 0.631
    assert active_drag.vpm_active_drag_n(10.0, 1.5, 1.4) == pytest.approx(49.9208, abs=1e-4)


def test_vpm_recovers_the_drag_of_a_constant_power_swimmer():
    # A swimmer of drag 20 v^2 N putting out 20 * 1.5^3 W: towing a 5 v^2 N buoy it slows to
    # v2 with 25 v2^3 = 67.5 W. The method gives back 20 * 1.5^2 = 45 N.
    v2 = (20.0 * 1.5**3 / 25.0) ** (1.0 / 3.0)
    assert active_drag.vpm_active_drag_n(active_drag.buoy_drag_n(5.0, v2), 1.5, v2) == pytest.approx(45.0)
    # The same swimmer putting out 10 % more with the buoy: the power ratio accounts for it.
    v2 = (1.1 * 20.0 * 1.5**3 / 25.0) ** (1.0 / 3.0)
    assert active_drag.vpm_active_drag_n(5.0 * v2**2, 1.5, v2, power_ratio=1.1) == pytest.approx(45.0)


def test_vpm_unreadable_and_bad_input():
    assert active_drag.vpm_active_drag_n(5.0, 1.0, 1.0) is None            # the buoy did not slow it
    assert active_drag.vpm_active_drag_n(5.0, 1.0, 1.1) is None
    for args in ((0.0, 1.0, 0.9), (5.0, math.nan, 0.9), (5.0, 1.0, -0.9)):
        with pytest.raises(ConfigError):
            active_drag.vpm_active_drag_n(*args)
    assert active_drag.narita_active_drag_n(1.0) == pytest.approx(32.2)
    assert active_drag.propelling_efficiency(40.0, 1.5, 600.0) == pytest.approx(0.1)
    assert active_drag.propelling_efficiency(None, 1.5, 600.0) is None
    assert active_drag.window_rate([0.0, 1.0, 2.0], [0.0, 10.0, 30.0], 0.5, 1.5) == pytest.approx(15.0)


# --- ✔/✘ ----------------------------------------------------------------------------------------

def test_passes_is_a_closed_range_and_none_when_unmeasured():
    rng = Range(1.2, 1.8, "x")
    assert passes(1.2, rng) and passes(1.8, rng) and passes(1.5, rng)
    assert passes(1.19, rng) is False and passes(1.81, rng) is False
    assert passes(None, rng) is None and passes(math.nan, rng) is None
    assert passes(250.0, at_most(200.0, "x")) is False and passes(-1e9, at_most(200.0, "x"))
    assert passes(1.8, at_least(1.8, "x")) and passes(-6.5, within(6.0, "x")) is False


def _crawl_figures(**changes) -> dict:
    figures = {"mean_speed_m_s": 1.5, "stroke_rate_cpm": 52.0, "distance_per_cycle_m": 1.9, "speed_fluctuation_pct": 17,
               "pitch_deg": 4.0, "body_inclination_deg": 3.0, "shoulder_roll_deg": 50.0, "hip_roll_deg": 35.0,
               "peak_hand_force_n": 150.0,
               "active_drag_n": 32.2 * 1.5**3.3, "resistive_force_summed_n": 130.0, "joint_power_w": 400.0,
               "positive_joint_power_w": 600.0, "propelling_efficiency": 0.4, "face_breath_cycles_pct": 0.0,
               "face_under_time_pct": 100.0, "head_top_above_time_pct": 0.0}
    return {**figures, **changes}


def test_rows_check_every_target_and_reference():
    rows = validation_rows("front_crawl", _crawl_figures())
    must = {r["quantity"]: r for r in rows if r["kind"] == "must"}
    assert set(must) == set(MUST_HOLD["front_crawl"]) | {"active_drag_n"}
    assert all(r["ok"] for r in must.values())
    assert must["active_drag_n"]["low"] == pytest.approx(0.7 * 32.2 * 1.5**3.3)
    assert must["distance_per_cycle_m"]["high"] is None and must["joint_power_w"]["low"] is None  # open: no inf
    json.dumps(rows, allow_nan=False)
    reference = {r["quantity"]: r for r in rows if r["kind"] == "reference"}
    assert reference["mean_speed_m_s"]["ok"] is False            # faster than recreational 0.8-1.2 m/s
    summed = [r for r in rows if r["quantity"] == "resistive_force_summed_n"]
    assert len(summed) == 1 and summed[0]["kind"] == "measured" and summed[0]["ok"] is None
    assert "not active drag" in summed[0]["label"]
    assert not any(r["quantity"].startswith(("face", "head")) for r in rows)   # crawl has no such target

    failing = {r["quantity"]: r["ok"] for r in validation_rows("front_crawl", _crawl_figures(
        pitch_deg=-7.0, body_inclination_deg=20.0, joint_power_w=1200.0, active_drag_n=None)) if r["kind"] == "must"}
    assert failing["pitch_deg"] is False and failing["joint_power_w"] is False
    assert failing["body_inclination_deg"] is False              # a level pelvis is not enough
    assert failing["active_drag_n"] is None                    # not measured: neither ✔ nor a number


def test_face_rows_for_breaststroke_and_backstroke():
    breast = {r["quantity"]: r for r in validation_rows("breaststroke", _crawl_figures(face_breath_cycles_pct=100.0))}
    assert breast["face_breath_cycles_pct"]["ok"] is True and "face_under_time_pct" not in breast
    back = {r["quantity"]: r for r in validation_rows("backstroke", _crawl_figures(face_under_time_pct=0.5))}
    assert back["face_under_time_pct"]["ok"] is False
    assert must_hold("backstroke", 1.0) == MUST_HOLD["backstroke"]          # Narita's target is the crawl's


def test_range_text_and_marks():
    def text(quantity, low, high, kind="must"):
        return validation_report.range_text({"quantity": quantity, "low": low, "high": high, "kind": kind})
    assert text("peak_hand_force_n", None, 200.0) == "<= 200"
    assert text("distance_per_cycle_m", 1.8, None) == ">= 1.80"
    assert text("pitch_deg", -6.0, 6.0) == "within +-6.0"
    assert text("face_under_time_pct", 0.0, 0.0) == "= 0.0"
    assert text("mean_speed_m_s", 1.2, 1.8) == "1.20 - 1.80"
    assert validation_report.MARKS[True] == "✔" and validation_report.MARKS[False] == "✘"


# --- what the swims measure --------------------------------------------------------------------

def test_face_height_and_clearance():
    prone = (0.0, math.sqrt(0.5), 0.0, math.sqrt(0.5))          # local +x (the face) turned down
    assert head_clearance.face_height_m([0.0, 0.0, 0.1], prone, 0.085) == pytest.approx(0.015)
    assert head_clearance.face_height_m([0.0, 0.0, 0.1], (0.0, 0.0, 0.0, 1.0), 0.085) == pytest.approx(0.1)
    t = np.linspace(0.0, 3.0, 301)
    height = np.where((t % 1.0) < 0.2, 0.05, -0.1)
    height[(t >= 2.0) & (t < 3.0)] = -0.1                       # no breath in the third cycle
    assert head_clearance.cycles_above_pct(t, height, [0.0, 1.0, 2.0, 3.0]) == pytest.approx(100 * 2 / 3)
    assert head_clearance.time_below_pct(t, np.full_like(t, 0.01), 0.0, 3.0) == 0.0


def test_towed_buoy_pulls_against_the_motion_and_counts_its_impulse():
    pushes = []
    sim = SimpleNamespace(steps=0, state=SimpleNamespace(com_vel_m_s=np.array([1.2, 0.0, -0.5])),
                          push=lambda force, segment: pushes.append((np.array(force), segment)))
    buoy = TowedBuoy(5.0, physics_hz=480, log_hz=120)
    for step in range(1, 9):
        sim.steps = step
        buoy(sim)
    force, segment = pushes[-1]
    assert segment == "pelvis" and force == pytest.approx([-5.0 * 1.2**2, 0.0, 0.0])   # horizontal, k v^2
    a = buoy.arrays()
    assert a["time_s"] == pytest.approx([4 / 480, 8 / 480])
    # The pull set after step 1 acts from step 2 on: 7 steps of 7.2 N by step 8.
    assert a["impulse_ns"][-1] == pytest.approx(7 * 7.2 / 480)
    with pytest.raises(ConfigError):
        TowedBuoy(-1.0, 480, 120)


def test_joint_work_matches_the_recorder_and_positive_work_bounds_it():
    episode = Episode("front_crawl")
    try:
        sim = episode.sim
        recorder, work = Recorder(sim, 120, joint_work=True), JointWork(sim, 120)
        episode.run(0.5, observers=[recorder, work])
    finally:
        episode.close()
    net = recorder.arrays()["joint_work_j"]
    a = work.arrays()
    assert a["net_j"] == pytest.approx(net, rel=1e-9, abs=1e-9)
    assert np.all(np.diff(a["positive_j"]) >= 0.0) and a["positive_j"][-1] > net[-1] > 0.0


# --- the command --------------------------------------------------------------------------------

def _cli(*args):
    env = {**os.environ, "PYTHONPATH": str(REPO) + os.pathsep + os.environ.get("PYTHONPATH", "")}
    return subprocess.run([sys.executable, "-m", "layered_swim", *args], cwd=REPO, env=env, capture_output=True,
                          text=True, timeout=300)


def test_validate_strokes_json_on_a_short_swim(tmp_path):
    out = tmp_path / "validation"
    result = _cli("validate", "strokes", "--seconds", "7", "--settle", "1", "--workers", "2", "--json",
                  "--out", str(out))
    assert result.returncode == 0, result.stderr
    report = json.loads(result.stdout)
    assert set(report["strokes"]) == {"front_crawl", "breaststroke", "backstroke", "butterfly", "treading_water"}
    assert report["seconds"] == 7.0 and report["settle_s"] == 1.0 and report["out_dir"] == str(out)
    assert "Kolmogorov & Duplishcheva 1992" in report["method"]["active_drag"]
    for stroke, entry in report["strokes"].items():
        assert entry["error"] is None, f"{stroke}: {entry['error']}"
        for row in entry["rows"]:
            assert {"quantity", "label", "unit", "value", "kind", "low", "high", "ok", "source"} <= set(row)
            assert row["ok"] in (True, False, None) and row["kind"] in ("must", "reference", "measured")
    crawl = report["strokes"]["front_crawl"]["vpm"]
    assert crawl["towing_speed_m_s"] < crawl["free_speed_m_s"] and crawl["buoy_force_n"] > 0.0
    assert report["strokes"]["treading_water"]["vpm"] is None
    must = report["must"]
    assert must["total"] == sum(1 for e in report["strokes"].values() for r in e["rows"] if r["kind"] == "must")
    assert must["held"] + len(must["failed"]) == must["total"]
    assert {p.name for p in out.iterdir()} >= {"summary.json", "config.json", "report.md", "validation.png"}
    assert "✔" in (out / "report.md").read_text() or "✘" in (out / "report.md").read_text()


@pytest.mark.parametrize("argv, words", [
    (["validate", "strokes", "--seconds", "-1"], ["seconds"]),
    (["validate", "strokes", "--seconds", "5", "--settle", "6"], ["settle"]),
    (["validate", "strokes", "--backend", "sph"], ["plate"]),
    (["validate", "drag", "--seconds", "5"], ["--seconds", "validate strokes"]),
])
def test_bad_input_is_one_line(argv, words, capfd, tmp_path):
    assert cli_module.main(argv + ["--out", str(tmp_path / "never")] if argv[1] == "strokes" else argv) == 2
    err = capfd.readouterr().err.strip().splitlines()
    assert len(err) == 1 and err[0].startswith("layered-swim: error: ")
    assert all(word in err[0] for word in words)
    assert not (tmp_path / "never").exists()          # refused before the folder is touched
