"""The parallel sweep: results in order, cached by configuration, the same with any worker count."""
import json

from layered_swim.analysis import sweep

CALLS = []


def square(config: dict) -> dict:
    CALLS.append(config["x"])
    return {"x": config["x"], "square": config["x"] ** 2}


def cube(config: dict) -> dict:
    return {"cube": config["x"] ** 3}


def test_results_in_order_and_cached(tmp_path):
    CALLS.clear()
    configs = [{"x": x} for x in (3, 1, 2)]
    assert [r["square"] for r in sweep.run_sweep(square, configs, tmp_path, workers=1)] == [9, 1, 4]
    assert sorted(CALLS) == [1, 2, 3] and len(list(tmp_path.glob("*.json"))) == 3
    CALLS.clear()
    again = sweep.run_sweep(square, configs + [{"x": 5}], tmp_path, workers=1)
    assert [r["square"] for r in again] == [9, 1, 4, 25] and CALLS == [5]    # only the new one ran
    stored = json.loads(next(tmp_path.glob("*.json")).read_text())
    assert set(stored) == {"config", "result"}


def test_a_damaged_entry_is_computed_again(tmp_path):
    CALLS.clear()
    sweep.run_sweep(square, [{"x": 4}], tmp_path, workers=1)
    next(tmp_path.glob("*.json")).write_text("{not json")
    assert sweep.run_sweep(square, [{"x": 4}], tmp_path, workers=1)[0]["square"] == 16 and CALLS == [4, 4]


def test_key_follows_task_and_config():
    assert sweep.cache_key(square, {"x": 1}) == sweep.cache_key(square, {"x": 1})
    assert sweep.cache_key(square, {"x": 1}) != sweep.cache_key(square, {"x": 2})
    assert sweep.cache_key(square, {"x": 1}) != sweep.cache_key(cube, {"x": 1})


def test_two_workers_give_the_same_results(tmp_path):
    configs = [{"x": x} for x in range(5)]
    assert sweep.run_sweep(square, configs, None, workers=2) == sweep.run_sweep(square, configs, None, workers=1)


def test_ray_tasks_give_the_same_results_and_fill_the_same_cache(tmp_path):
    """``ray_address="local"``: a Ray runtime started here runs the jobs; the results, their order
    and the cache are the local processes'."""
    import ray

    def power(config: dict) -> dict:      # nested: Ray ships it by value (its workers cannot import tests/)
        return {"power": config["x"] ** 4}

    configs = [{"x": x} for x in range(4)]
    try:
        on_ray = sweep.run_sweep(power, configs, tmp_path, workers=2, ray_address="local")
    finally:
        ray.shutdown()
    assert on_ray == sweep.run_sweep(power, configs, None, workers=1) == [{"power": x ** 4} for x in range(4)]
    assert len(list(tmp_path.glob("*.json"))) == 4


def test_a_run_does_not_depend_on_the_hash_seed(tmp_path):
    """Sweeps run in fresh processes, each with its own hash seed: nothing may iterate a set
    where the order reaches the numbers (it did, in the per-cycle weight blending)."""
    import os
    import subprocess
    import sys
    from pathlib import Path

    repo = Path(__file__).resolve().parents[1]
    outputs = []
    for seed in ("0", "1"):
        env = {**os.environ, "PYTHONHASHSEED": seed, "PYTHONPATH": str(repo)}
        run = subprocess.run([sys.executable, "-m", "layered_swim", "follow", "straight_line", "--seconds", "4",
                              "--json", "--out", str(tmp_path / seed)],
                             cwd=repo, env=env, capture_output=True, text=True, timeout=120)
        assert run.returncode == 0, run.stderr
        outputs.append(json.loads(run.stdout)["mean_distance_m"])
    assert outputs[0] == outputs[1]
