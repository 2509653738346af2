"""``experiment swim-generalisation`` (SWIM Figs. 4-6): its runs, and measure, describe and plot on
made-up results; one real swim of each controller on the training condition."""
import json

import numpy as np
import pytest

from layered_swim.analysis.experiments import EXPERIMENTS
from layered_swim.analysis.experiments import swim_generalisation as sg

PNG_MAGIC = b"\x89PNG\r\n\x1a\n"


def condition(config: dict) -> tuple:
    return tuple(json.dumps(config[k]) for k in sg.CONDITION)


def test_the_registry_lists_it():
    assert EXPERIMENTS["swim-generalisation"] is sg


def test_quick_runs_one_start_on_goal_0_each_condition_once_per_controller():
    configs = sg.configs(True, 0)
    json.dumps(configs, allow_nan=False)
    assert {c["starts"] for c in configs} == {1} and {c["goal"] for c in configs} == {0}
    by = {name: [condition(c) for c in configs if c["controller"] == name] for name in sg.CONTROLLERS}
    assert by["residual"] == by["layered"] and len(set(by["layered"])) == len(by["layered"])
    quiet = [c for c in configs if c["pool"] == "small" and c["speed_m_s"] == 0.0 and c["viscosity_m2_s"] is None
             and c["density_kg_m3"] == sg.FRESH_KG_M3]
    assert len(quiet) == 2                                   # fresh quiet water: in all three sweeps, swum once
    lateral = sorted(c["d_lat_m"] for c in configs if c["pool"] == "large" and c["controller"] == "layered")
    assert {-1.0, 1.25, 0.0} <= set(lateral) and lateral == sorted(sg.QUICK_D_LAT_M)
    residual = [c for c in configs if c["controller"] == "residual"]
    assert all(len(c["policy_sha256"]) == 16 for c in residual)
    assert all(c["policy_sha256"] is None for c in configs if c["controller"] == "layered")
    assert len(configs) < 60                                 # a few minutes on 2 cores


def test_the_full_run_covers_swims_ranges_with_three_goals_and_starts():
    configs = sg.configs(False, 0)
    small = [c for c in configs if c["pool"] == "small"]
    assert {c["goal"] for c in small} == {0, 1, 2} and {c["starts"] for c in configs} == {sg.STARTS}
    assert min(c["density_kg_m3"] for c in small) == 500.0 and max(c["density_kg_m3"] for c in small) == 2500.0
    assert max(c["viscosity_m2_s"] or 0.0 for c in small) == 5e-2
    assert max(c["speed_m_s"] for c in small) == 1.5
    assert {tuple(c["current_m_s"]) for c in small if c["direction"] == "-x upstream" and c["speed_m_s"] == 1.0} \
        == {(-1.0, 0.0, 0.0)}


def test_a_lateral_offset_is_the_pools_one_goal_on_swims_side_in_a_pool_wide_enough():
    config = {"pool": "large", "d_lat_m": 1.25}             # SWIM: + is to the right; ours: +y is the left
    pool = sg.sweep_pool(config)
    assert pool.goal_offsets_m == (-1.25,) and pool.width_m == pytest.approx(2 * (1.25 + sg.SIDE_ROOM_M))
    assert pool.goal_distance_m == sg.SWIM["fig4"]["goal_ahead_m"] and pool.horizon_s == 8.0
    assert sg.sweep_pool({"pool": "small", "d_lat_m": None}).goal_offsets_m == (0.0, 0.375, -0.375)
    assert sg.theta_lat_deg(-1.0) == pytest.approx(sg.SWIM["fig4"]["holds_left_deg"], abs=0.05)
    assert sg.theta_lat_deg(1.25) == pytest.approx(sg.SWIM["fig4"]["holds_right_deg"], abs=0.05)


def made_up(config: dict, residual_missing: bool = False) -> dict:
    """Pos grows with the offset, the density's distance from fresh water's and the inflow; swims in
    a 1 m/s or faster flow leave the pool, those in water lighter than 900 kg/m^3 sink."""
    if residual_missing and config["controller"] == "residual":
        return {"missing": "no [rl] extra"}
    pos = (0.1 + 0.2 * abs(config["d_lat_m"] or 0.0) + abs(config["density_kg_m3"] - sg.FRESH_KG_M3) / 1000.0
           + 0.3 * config["speed_m_s"])
    swim = {"pos_m": pos, "prog": 0.8, "dev_m": 0.05, "roll_deg": 0.1, "deepest_m": 0.3,
            "left_pool": config["speed_m_s"] >= 1.0, "sank": config["density_kg_m3"] < 900.0}
    return {"runs": [{"start": s, **swim} for s in range(config["starts"])]}


def test_measure_finds_each_controllers_holding_ranges_and_keeps_swims_points(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    configs = sg.configs(True, 0)
    numbers = sg.measure(configs, [made_up(c) for c in configs])
    assert list(tmp_path.iterdir()) == []                    # pure: no files
    rows = numbers["rows"]
    assert all(list(r) == list(rows[0]) for r in rows)
    summary = json.loads(json.dumps(numbers["summary"], allow_nan=False))
    for name in sg.CONTROLLERS:
        mine = summary[name]
        assert mine["lateral"]["holds_d_lat_m"] == [-0.375, 0.375]
        assert mine["density"]["holds_kg_m3"] == [920.0, sg.FRESH_KG_M3]
        assert mine["viscosity"]["holds_m2_s"] == [pytest.approx(sg.FRESH_M2_S), 0.05]
        assert mine["flow"]["pos_doubles_at_m_s"] == {d: 0.5 for d in sg.DIRECTIONS}
        assert mine["swims"] == 26 and mine["left_pool_or_sank"] == 9 and mine["missing"] is None
    ours = [r for r in rows if r["source"] == "ours"]
    assert len([r for r in ours if r["figure"] == "fig6" and r["direction"] == "quiet"]) == 2
    swim = [r for r in rows if r["source"] != "ours"]
    assert {r["figure"] for r in swim} == {"fig4", "fig5 density", "fig5 viscosity", "fig6"}
    assert {r["d_lat_m"] for r in swim if r["figure"] == "fig4"} == {None, -1.0, 1.25}
    assert any(r["pos_m"] == 0.254 for r in swim)            # Table 3's 3 m dynamic mean
    assert summary["figures"] == [sg.FIGURE, *sg.FIGURES.values()]

    outcome = sg.describe(numbers)
    assert "from -0.375 to +0.375 m" in outcome.ours and "from 920 to 997.05 kg/m^3" in outcome.ours
    assert "Pos more than doubles +x downstream at 0.5 m/s" in outcome.ours
    assert "9 of 26 swims left the pool" in outcome.ours and "SWIM: goals from d_lat -1 to +1.25 m" in outcome.ours
    assert "not in its text" in outcome.differs and "skin friction" in outcome.differs
    assert "small pool" in outcome.setting

    sg.plot(numbers, tmp_path / sg.FIGURE)
    assert sorted(p.name for p in tmp_path.iterdir()) == sorted([sg.FIGURE, *sg.FIGURES.values()])
    assert all(p.read_bytes()[:8] == PNG_MAGIC for p in tmp_path.iterdir())


def test_a_missing_residual_is_said_and_the_heuristic_still_drawn(tmp_path):
    configs = sg.configs(True, 0)
    numbers = sg.measure(configs, [made_up(c, residual_missing=True) for c in configs])
    assert numbers["summary"]["residual"]["missing"] == "no [rl] extra"
    assert all(r["pos_m"] is None for r in numbers["rows"] if r["controller"] == "residual")
    outcome = sg.describe(numbers)
    assert "The shipped residual did not swim: no [rl] extra." in outcome.ours
    assert "layered heuristic: straight ahead Pos 0.10 m" in outcome.ours
    sg.plot(numbers, tmp_path / sg.FIGURE)
    assert (tmp_path / sg.FIGURES["fig6"]).read_bytes()[:8] == PNG_MAGIC


def test_one_real_swim_of_each_controller_in_the_training_condition():
    pytest.importorskip("torch")
    from layered_swim.rl.policy import ResidualPolicy, evaluate_goals

    quiet = [c for c in sg.configs(True, 0) if c["pool"] == "small" and c["speed_m_s"] == 0.0
             and c["viscosity_m2_s"] is None and c["density_kg_m3"] == sg.FRESH_KG_M3]
    results = {c["controller"]: sg.run(c) for c in quiet}
    json.dumps(results, allow_nan=False)
    for result in results.values():
        [swim] = result["runs"]
        assert 0.0 < swim["pos_m"] < 0.3 and not swim["left_pool"] and not swim["sank"]
    # The residual swims as its training environment does: the same numbers as evaluate_goals.
    expected = evaluate_goals(ResidualPolicy.load(sg.POLICY), seeds=1, goals=[0])
    assert results["residual"]["runs"][0]["pos_m"] == expected["pos_m"]
    dense = sg.run({**next(c for c in quiet if c["controller"] == "residual"), "density_kg_m3": 1500.0})
    assert np.isfinite(dense["runs"][0]["pos_m"]) and dense["runs"][0]["pos_m"] != expected["pos_m"]


def test_the_experiment_says_it_wrote_all_four_figures(tmp_path, monkeypatch):
    from layered_swim.analysis.experiments.runner import run_experiment

    monkeypatch.setattr(sg, "run", made_up)         # one worker runs the sweep here, not in a process
    result = run_experiment(sg, tmp_path / "out", quick=True, workers=1)
    assert result["files"][:4] == [sg.FIGURE, *sg.FIGURES.values()]
    assert all((tmp_path / "out" / name).is_file() for name in result["files"])
