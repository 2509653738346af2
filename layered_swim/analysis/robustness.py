"""Is a result luck? The same follow task from many perturbed starts, summarised by medians.

``follow_seeds`` swims ``trajectory`` once per seed 1..N, each start moved within
``WIDE_JITTER`` (heading +-10 deg, position +-0.3 m: a start a user might give), in parallel
processes, and reports every run and the median (with the range) of each headline number.
"""
from __future__ import annotations

import math
from dataclasses import asdict
from pathlib import Path

import numpy as np

from layered_swim.analysis.sweep import run_sweep
from layered_swim.config import ConfigError
from layered_swim.control.layered import Layers
from layered_swim.episode import WIDE_JITTER
from layered_swim.outputs import COMMAND_KEY, OutputFolder, claim, write_json
from layered_swim.runs import MIN_SECONDS, check_seconds, follow_run, versions

HEADLINES = ("mean_distance_m", "max_distance_m", "final_distance_m", "mean_heading_error_deg",
             "hold_depth_error_m", "hold_depth_error_max_m", "worst_reach_s", "worst_held_within_m")
MAX_SEEDS = 1000


def follow_one(config: dict) -> dict:
    """One perturbed run (module level: worker processes pickle it); with ``policy``, a learned
    residual drives its reference controller."""
    layers, steered = Layers.parse(config["layers"]), {}
    if config.get("policy"):
        from layered_swim.rl.policy import follow_steering

        layers, steered = follow_steering(config["policy"], config["stroke"])
    result = follow_run(config["trajectory"], config["stroke"], layers, config["current_m_s"],
                        config["density_kg_m3"], config["seconds"], seed=config["seed"], jitter=WIDE_JITTER, **steered)
    return {k: v for k, v in result.items() if k in HEADLINES or k in ("seed", "reached_all", "stations")}


def spread(values: list) -> dict | None:
    """Median, min and max of a headline over the runs; a run without it (a station never reached)
    counts as infinitely bad, and a median that is infinite is None."""
    if all(v is None for v in values):
        return None
    x = np.array([math.inf if v is None else float(v) for v in values])
    finite = lambda v: float(v) if math.isfinite(v) else None     # noqa: E731
    return {"median": finite(np.median(x)), "min": finite(x.min()), "max": finite(x.max())}


def follow_seeds(trajectory: str, stroke: str, layers: Layers, current=(0.0, 0.0, 0.0), density: float | None = None,
                 seconds: float = 60.0, seeds: int = 10, out_dir: OutputFolder | str | Path | None = None,
                 workers: int = 2, progress: bool = False, policy: str | None = None) -> dict:
    """``policy``: a trained residual (its file) drives its own reference controller instead."""
    check_seconds(seconds)
    if not 1 <= seeds <= MAX_SEEDS:
        raise ConfigError(f"--seeds must be between 1 and {MAX_SEEDS}, got {seeds}")
    common = {"trajectory": trajectory, "stroke": stroke, "layers": layers.describe(), "current_m_s": list(current),
              "density_kg_m3": density, "seconds": seconds, **({"policy": str(policy)} if policy else {})}
    configs = [{**common, "seed": seed} for seed in range(1, seeds + 1)]
    out = None
    if out_dir is not None:       # the first start checked here (files, stroke, path), then the folder claimed
        follow_run(trajectory, stroke, layers, current, density, min(seconds, MIN_SECONDS))
        out = claim(out_dir)
    runs = run_sweep(follow_one, configs, None, workers, progress, desc="starts")
    summary = {**common, "seeds": seeds, "start_jitter": asdict(WIDE_JITTER),
               "median": {k: s for k in HEADLINES if (s := spread([r.get(k) for r in runs])) is not None},
               "runs": runs}
    if any("reached_all" in r for r in runs):
        summary["reached_all_share"] = float(np.mean([bool(r.get("reached_all")) for r in runs]))
    if out is not None:
        write_json(out / "config.json", {COMMAND_KEY: "follow", **common, "seeds": seeds,
                                         "start_jitter": asdict(WIDE_JITTER), "versions": versions()})
        write_json(out / "summary.json", summary)
    return summary
