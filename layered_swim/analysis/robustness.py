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
from layered_swim.episode import WIDE_JITTER
from layered_swim.learned import steering_for
from layered_swim.outputs import COMMAND_KEY, OutputFolder, claim, write_json
from layered_swim.runs import follow_run, versions
from layered_swim.spec import MIN_SECONDS, SwimSpec

HEADLINES = ("mean_distance_m", "max_distance_m", "final_distance_m", "mean_heading_error_deg",
             "hold_depth_error_m", "hold_depth_error_max_m", "worst_reach_s", "worst_held_within_m")
MAX_SEEDS = 1000


def follow_one(config: dict) -> dict:
    """One perturbed run (module level: worker processes pickle it): ``config`` is a SwimSpec's dump."""
    spec = SwimSpec.model_validate(config)
    result = follow_run(spec, steering=steering_for(spec))
    return {k: v for k, v in result.items() if k in HEADLINES or k in ("seed", "reached_all", "stations", "holds")}


def spread(values: list) -> dict | None:
    """Median, min and max of a headline over the runs; a run without it (a station never reached)
    counts as infinitely bad, and a median that is infinite is None."""
    if all(v is None for v in values):
        return None
    x = np.array([math.inf if v is None else float(v) for v in values])
    finite = lambda v: float(v) if math.isfinite(v) else None     # noqa: E731
    return {"median": finite(np.median(x)), "min": finite(x.min()), "max": finite(x.max())}


def hold_spread(runs: list[dict]) -> list[dict]:
    """Per stretch the target holds a depth (the same stretches in every run: only the start moves;
    a run cut short has fewer), the spread of its largest depth error over the runs that reached
    it, the median of how far the pelvis stayed above it, and in how many runs it was the worst
    hold: which part of a path misses, and how often."""
    held = [r["holds"] for r in runs if r.get("holds")]
    if not held:
        return []
    worst = [max(range(len(h)), key=lambda k: h[k]["max_error_m"]) for h in held]
    stretches = max(held, key=len)
    return [{"target_z_m": first["target_z_m"], "from_s": first["from_s"], "to_s": first["to_s"],
             "max_error_m": spread([h[k]["max_error_m"] for h in held if len(h) > k]),
             "mean_above_m": float(np.median([h[k]["mean_above_m"] for h in held if len(h) > k])),
             "worst_in_runs": worst.count(k)}
            for k, first in enumerate(stretches)]


def follow_seeds(spec: SwimSpec, seeds: int = 10, out_dir: OutputFolder | str | Path | None = None,
                 workers: int = 2, progress: bool = False, ray_address: str | None = None) -> dict:
    """``spec`` (a follow task) from seeds 1..``seeds``, each start moved within ``WIDE_JITTER``;
    with ``spec.policy``, a trained residual drives its own reference controller."""
    if not 1 <= seeds <= MAX_SEEDS:
        raise ConfigError(f"--seeds must be between 1 and {MAX_SEEDS}, got {seeds}")
    steering = steering_for(spec)            # a bad policy: one line here, not in every worker
    layers = spec.layer_set if steering is None else steering.layers
    common = {"trajectory": spec.task.trajectory, "stroke": spec.stroke, "layers": layers.describe(),
              "current_m_s": list(spec.medium.current_m_s), "density_kg_m3": spec.medium.density_kg_m3,
              "seconds": spec.seconds, **({"policy": spec.policy} if spec.policy else {}),
              **({"water": spec.medium.flow.name} if spec.medium.flow else {})}
    configs = [spec.with_(seed=seed, jitter="wide").model_dump(mode="json") for seed in range(1, seeds + 1)]
    out = None
    if out_dir is not None:       # the first start checked here (files, stroke, path), then the folder claimed
        follow_run(spec.with_(seconds=MIN_SECONDS), steering=steering)
        out = claim(out_dir)
    runs = run_sweep(follow_one, configs, None, workers, progress, desc="starts", ray_address=ray_address)
    summary = {**common, "seeds": seeds, "start_jitter": asdict(WIDE_JITTER),
               "median": {k: s for k in HEADLINES if (s := spread([r.get(k) for r in runs])) is not None},
               "runs": runs}
    if holds := hold_spread(runs):
        summary["holds"] = holds
    if any("reached_all" in r for r in runs):
        summary["reached_all_share"] = float(np.mean([bool(r.get("reached_all")) for r in runs]))
    if out is not None:
        write_json(out / "config.json", {COMMAND_KEY: "follow", "swim": spec.model_dump(mode="json"), "seeds": seeds,
                                         "start_jitter": asdict(WIDE_JITTER), "versions": versions()})
        write_json(out / "summary.json", summary)
    return summary
