"""What `follow` measures beyond the distance (depth during holds, reaching and holding stations),
how far a seed moves the start, and the medians over perturbed starts (`follow --seeds`)."""
import json
import math
import subprocess
import sys

import numpy as np
import pytest
from test_layered_control import still_state, table

from layered_swim.analysis.robustness import hold_spread, spread
from layered_swim.control.cycle_choice import TargetChooser
from layered_swim.control.targets import StationTarget
from layered_swim.episode import START_JITTER, WIDE_JITTER, jittered_start
from layered_swim.state import Start
from layered_swim.tasks.follow import hold_depth, station_metrics, stroke_spells


def test_depth_is_checked_only_while_the_target_holds_one():
    t = np.arange(0.0, 30.0, 1.0)
    target = np.zeros((30, 3))
    target[:, 2] = np.interp(t, [0, 10, 20, 29], [-0.3, -0.3, -2.3, -2.3])   # holds, dives 2 m over 10 s, holds
    pelvis = target.copy()
    pelvis[:, 2] += 0.5                           # always 0.5 m shallower...
    pelvis[25:, 2] = target[25:, 2] + 0.1         # ...but for the last 5 samples
    got = hold_depth(t, pelvis, target)
    holding = (t <= 9) | (t >= 21)                # np.gradient blurs the corners by one sample
    expected = np.where(t[holding] >= 25, 0.1, 0.5)
    assert got["hold_depth_error_m"] == pytest.approx(expected.mean())
    assert got["hold_depth_error_max_m"] == pytest.approx(0.5)
    first, second = got["holds"]                  # one per stretch the target holds its depth
    assert (first["target_z_m"], first["from_s"], first["to_s"]) == (-0.3, 0.0, 9.0)
    assert first["mean_error_m"] == first["max_error_m"] == pytest.approx(0.5)
    assert first["mean_above_m"] == pytest.approx(0.5)                 # short of it, not past it
    assert (second["target_z_m"], second["from_s"], second["to_s"]) == (-2.3, 21.0, 29.0)
    assert second["mean_error_m"] == pytest.approx((4 * 0.5 + 5 * 0.1) / 9)
    assert (second["max_error_m"], second["max_error_at_s"]) == (pytest.approx(0.5), 21.0)
    pelvis[25:, 2] = target[25:, 2] - 0.6         # now past it, deeper, at the end
    second = hold_depth(t, pelvis, target)["holds"][1]
    assert (second["max_error_m"], second["max_error_at_s"]) == (pytest.approx(0.6), 25.0)
    assert second["mean_above_m"] == pytest.approx((4 * 0.5 - 5 * 0.6) / 9)
    assert hold_depth(t, pelvis, np.zeros((30, 3)) - 0.3) == {}      # one depth: nothing to hold


def test_each_station_is_timed_to_reach_and_then_held():
    t = np.arange(0.0, 20.0, 0.5)
    d = np.where(t < 10, np.maximum(5.0 - t, 0.2), np.maximum(15.0 - t, 0.6))   # closes in at 1 m/s, twice
    d[(t >= 6) & (t < 7)] = 1.4                   # drifts out once while holding the first
    got = station_metrics(t, d, [0.0, 10.0])
    assert got["stations"] == [{"t_s": 0.0, "reach_s": 4.0, "held_within_m": 1.4},
                               {"t_s": 10.0, "reach_s": 4.0, "held_within_m": 1.0}]
    assert got["reached_all"] and got["worst_reach_s"] == 4.0 and got["worst_held_within_m"] == 1.4
    never = station_metrics(t, np.full(len(t), 3.0), [0.0, 10.0])
    assert not never["reached_all"] and never["worst_reach_s"] is None
    assert [s["reach_s"] for s in never["stations"]] == [None, None]
    assert len(station_metrics(t, d, [0.0, 10.0, 50.0])["stations"]) == 2       # the run ended before the last jump


@pytest.mark.parametrize("jitter", [START_JITTER, WIDE_JITTER])
def test_a_seed_moves_the_start_within_its_jitter(jitter):
    start = Start("prone", 0.15, 0.6, 0.0, (0.0, 0.0))
    moved = [jittered_start(start, np.random.default_rng(seed), jitter) for seed in range(1, 200)]
    headings = np.array([m.heading_rad for m in moved])
    xy = np.array([m.position_xy_m for m in moved])
    assert np.abs(headings).max() <= jitter.heading_rad and np.abs(xy).max() <= jitter.position_m
    assert np.abs(headings).max() > 0.9 * jitter.heading_rad and np.abs(xy).max() > 0.9 * jitter.position_m
    assert WIDE_JITTER.heading_rad == pytest.approx(math.radians(10.0)) and WIDE_JITTER.position_m == 0.3


def test_a_jumping_target_is_not_anticipated():
    """One second before the target jumps behind, the swimmer still heads for where it is."""
    target = StationTarget(np.array([[5.0, 0.0, 0.0], [-5.0, 0.0, 0.0]]), np.array([0.0, 1.0]))
    state = still_state(np.full(16, 1 / 16))
    assert TargetChooser(target, table(), "prone")(0, state, None).thrust_demand == pytest.approx(1.0)


def test_medians_count_a_run_that_never_got_there_as_worst():
    assert spread([3.0, 1.0, 2.0]) == {"median": 2.0, "min": 1.0, "max": 3.0}
    assert spread([3.0, None, None]) == {"median": None, "min": 3.0, "max": None}
    assert spread([None, None]) is None


def test_follow_seeds_reports_medians_over_perturbed_starts(tmp_path):
    out = tmp_path / "seeds"
    run = subprocess.run([sys.executable, "-m", "layered_swim", "follow", "jumping", "--seconds", "1", "--seeds", "2",
                          "--workers", "1", "--json", "--out", str(out)], capture_output=True, text=True, timeout=300)
    assert run.returncode == 0, run.stderr
    summary = json.loads(run.stdout)
    assert [r["seed"] for r in summary["runs"]] == [1, 2] and summary["start_jitter"]["position_m"] == 0.3
    distances = [r["mean_distance_m"] for r in summary["runs"]]
    assert distances[0] != distances[1]                       # two different starts
    assert summary["median"]["mean_distance_m"]["median"] == pytest.approx(np.median(distances))
    assert summary["reached_all_share"] == 0.0                # 4 m away, one second
    assert "holds" not in summary                             # its target never changes depth
    assert json.loads((out / "summary.json").read_text())["runs"] == summary["runs"]
    refused = subprocess.run([sys.executable, "-m", "layered_swim", "follow", "jumping", "--seconds", "1",
                              "--seeds", "2", "--backend", "sph"], capture_output=True, text=True, timeout=300)
    assert refused.returncode == 2 and refused.stderr.count("\n") == 1 and "--seeds" in refused.stderr


def _hold(z_m, from_s, to_s, max_error_m, above_m):
    return {"target_z_m": z_m, "from_s": from_s, "to_s": to_s, "mean_error_m": abs(above_m),
            "max_error_m": max_error_m, "max_error_at_s": from_s, "mean_above_m": above_m}


def test_the_holds_over_many_starts_say_which_one_misses_and_how_often():
    """Three starts of a path holding 0.3 m then 4 m; the third was cut short before the deep hold."""
    runs = [{"holds": [_hold(-0.3, 0, 10, 0.20, 0.10), _hold(-4.0, 30, 40, 0.50, -0.20)]},
            {"holds": [_hold(-0.3, 0, 10, 0.30, 0.12), _hold(-4.0, 30, 40, 0.25, 0.04)]},
            {"holds": [_hold(-0.3, 0, 10, 0.28, 0.08)]}]
    shallow, deep = hold_spread(runs)
    assert (shallow["target_z_m"], shallow["from_s"], shallow["to_s"]) == (-0.3, 0, 10)
    assert shallow["max_error_m"] == {"median": 0.28, "min": 0.20, "max": 0.30}
    assert shallow["mean_above_m"] == pytest.approx(0.10)
    assert deep["max_error_m"] == {"median": pytest.approx(0.375), "min": 0.25, "max": 0.50}   # two runs reached it
    assert deep["mean_above_m"] == pytest.approx(-0.08)
    assert (shallow["worst_in_runs"], deep["worst_in_runs"]) == (2, 1)
    assert hold_spread([{"holds": []}, {}]) == []


def test_follow_seeds_prints_each_hold(tmp_path):
    """The deep dive's target holds 0.3 m for 10 s, then dives: one hold in 11 s."""
    run = subprocess.run([sys.executable, "-m", "layered_swim", "follow", "deep_dive", "--seconds", "11", "--seeds",
                          "2", "--workers", "2", "--out", str(tmp_path / "seeds")],
                         capture_output=True, text=True, timeout=300)
    assert run.returncode == 0, run.stderr
    assert "hold 1 (z -0.30 m, 0.0-" in run.stdout and "the worst hold in 2 of 2 starts" in run.stdout


def test_the_summary_says_which_stroke_swam_when():
    """``auto`` switching breaststroke -> treading water -> breaststroke: three spells, each from its
    first sample to the next spell's first (the last to the run's last sample)."""
    time_s = np.arange(8) * 0.5
    strokes = np.array(["breaststroke"] * 3 + ["treading_water"] * 4 + ["breaststroke"])
    assert stroke_spells(time_s, strokes) == [
        {"stroke": "breaststroke", "from_s": 0.0, "to_s": 1.5},
        {"stroke": "treading_water", "from_s": 1.5, "to_s": 3.5},
        {"stroke": "breaststroke", "from_s": 3.5, "to_s": 3.5}]
    assert stroke_spells(time_s[:2], np.array(["front_crawl"] * 2)) == [
        {"stroke": "front_crawl", "from_s": 0.0, "to_s": 0.5}]
    assert stroke_spells(np.array([]), np.array([])) == []
