"""Headless runs: an episode per command, run, measured and written to a folder.

``run_swim`` is ``layered-swim run`` (free swimming), ``follow_run`` is ``follow`` (a trajectory
file), ``goal_run`` is ``goal`` (SWIM's benchmark: one episode reset onto each goal in turn);
``bench_step`` times one physics step bare and through the episode loop.
"""
from __future__ import annotations

import json
import math
import platform
import time
from dataclasses import asdict
from importlib import metadata
from pathlib import Path

import numpy as np

from layered_swim.config import ConfigError
from layered_swim.control.layered import Layers
from layered_swim.control.policy import TempoControl
from layered_swim.control.stroke import available_strokes
from layered_swim.control.targets import load_trajectory
from layered_swim.episode import Episode
from layered_swim.fluid.medium import Medium, preset
from layered_swim.recorder import DEFAULT_LOG_HZ, Recorder
from layered_swim.tasks import FollowTarget, FreeSwim, GoalReaching, swim_benchmark as bench
from layered_swim.tasks.goal import GOAL_METRICS

MAX_SECONDS = 3600.0
MIN_SECONDS = 0.1        # a few log samples, so the metrics have a time span
BENCH_REPEATS = 5       # bare and loop timed in turn, the fastest of each kept: other load only adds time
BENCH_WARMUP_S = 0.5     # compiles (or loads) the numba fluid kernels before timing
GOAL_TEMPO = TempoControl(min_tempo=0.3, near_m=0.2, far_m=1.0)   # slow strokes: the goal line is slow


def make_medium(fluid: str = "fresh_water", density_kg_m3: float | None = None,
                current_m_s=(0.0, 0.0, 0.0)) -> Medium:
    medium = preset(fluid).with_(current_m_s=tuple(float(c) for c in current_m_s))
    return medium if density_kg_m3 is None else medium.with_(rho_kg_m3=float(density_kg_m3))


def package_version() -> str:
    try:
        return metadata.version("layered-swim")
    except metadata.PackageNotFoundError:
        return "unknown (not installed)"


def resolved_config(episode: Episode, arguments: dict, log_hz: int) -> dict:
    sim = episode.sim
    return {
        "arguments": arguments,
        "stroke_file": episode.stroke.source,
        "stroke": episode.stroke_spec.model_dump(mode="json"),
        "body_file": sim.body.source,
        "lung_air_l": sim.body.lung_air_l,
        "medium": asdict(sim.fluid.medium),
        "fluid_backend": {"name": sim.fluid.name, "settings": sim.fluid.settings()},
        "gravity_m_s2": sim.config.gravity_m_s2,
        "physics_hz": sim.config.physics_hz,
        "control_hz": sim.config.control_hz,
        "log_hz": log_hz,
        "cycles_per_s": sim.controller.cycles_per_s,
        "task": episode.task.name,
        "seed": episode.seed,
        "versions": versions(),
    }


def versions() -> dict:
    return {"layered_swim": package_version(), "python": platform.python_version(),
            "numpy": np.__version__, "pybullet": metadata.version("pybullet")}


def default_out_dir(stroke: str, root: Path = Path("runs")) -> Path:
    """``runs/<stroke>-<YYYYmmdd-HHMMSS>``, with a counter when that folder already exists."""
    base = root / f"{Path(stroke).stem}-{time.strftime('%Y%m%d-%H%M%S')}"
    path, n = base, 1
    while path.exists():
        path, n = base.with_name(f"{base.name}-{n}"), n + 1
    return path


def swim(episode: Episode, seconds: float, observers=(), progress: bool = False) -> Episode:
    """Run ``episode`` for ``seconds`` (a progress bar with ``progress``) and close it; its task
    keeps what it observed."""
    try:
        episode.run(seconds, observers=observers, progress=progress)
    finally:
        episode.close()
    return episode


def record(episode: Episode, seconds: float, log_hz: int = DEFAULT_LOG_HZ, progress: bool = False,
           joint_work: bool = False) -> Recorder:
    """``swim`` logging at ``log_hz``; returns the log."""
    try:
        recorder = Recorder(episode.sim, log_hz, joint_work=joint_work)
    except BaseException:
        episode.close()
        raise
    swim(episode, seconds, [recorder], progress)
    return recorder


def run_swim(stroke: str, seconds: float = 30.0, lung_air_l: float | None = None,
             density: float | None = None, out_dir: str | Path | None = None, seed: int = 0,
             physics_hz: int = 480, tempo: float = 1.0, fluid: str = "fresh_water",
             log_hz: int = DEFAULT_LOG_HZ, progress: bool = False, backend: str = "plate") -> dict:
    """Run ``stroke`` for ``seconds`` and write summary.json, log.npz, timeseries.csv and
    config.json into ``out_dir`` (default: ``runs/<stroke>-<timestamp>``); returns the summary."""
    out_dir = Path(out_dir) if out_dir is not None else default_out_dir(stroke)
    arguments = {"stroke": stroke, "seconds": seconds, "lung_air_l": lung_air_l, "density": density,
                 "out_dir": str(out_dir), "seed": seed, "physics_hz": physics_hz, "tempo": tempo,
                 "fluid": fluid, "log_hz": log_hz, "backend": backend}
    check_seconds(seconds)
    episode = Episode(stroke, FreeSwim(sample_hz=log_hz), medium=make_medium(fluid, density), backend=backend,
                      lung_air_l=lung_air_l, physics_hz=physics_hz, tempo=tempo, seed=seed)
    recorder = record(episode, seconds, log_hz, progress)
    result = episode.metrics()
    out_dir.mkdir(parents=True, exist_ok=True)
    recorder.save(out_dir)
    write_json(out_dir / "summary.json", result)
    write_json(out_dir / "config.json", resolved_config(episode, arguments, log_hz))
    return result


def follow_run(trajectory: str, stroke: str = "breaststroke", layers: Layers = Layers(), current=(0.0, 0.0, 0.0),
               density: float | None = None, seconds: float = 60.0, out_dir: str | Path | None = None) -> dict:
    check_seconds(seconds)
    target = load_trajectory(trajectory)
    episode = Episode(stroke, FollowTarget(target), medium=make_medium(density_kg_m3=density, current_m_s=current),
                      layers=layers)
    out = Path(out_dir) if out_dir is not None else None
    if out is None:
        swim(episode, seconds)
    else:
        out.mkdir(parents=True, exist_ok=True)
        record(episode, seconds).save(out)
    result = {"trajectory": target.name, "stroke": stroke, "layers": layers.describe(),
              "current_m_s": list(current), "seconds": seconds, **episode.metrics()}
    if out is not None:
        np.savez_compressed(out / "track.npz", **episode.task.track())
        write_json(out / "summary.json", result)
        write_json(out / "config.json", {"trajectory": str(target.source), "trajectory_spec": _dump(target.spec),
                                         "stroke": stroke, "layers": layers.describe(), "current_m_s": list(current),
                                         "density_kg_m3": density, "seconds": seconds,
                                         "stroke_file": episode.stroke.source,
                                         "cycles_per_s_at_tempo_1": 1.0 / episode.stroke.period_s})
    return result


def goal_episode(pool_name: str, stroke: str, current=(0.0, 0.0, 0.0), layers: Layers = Layers()) -> Episode:
    """An episode of SWIM's goal reaching in ``pool_name``; ``reset(goal=k)`` picks the goal."""
    return Episode(stroke, GoalReaching(bench.pool(pool_name)), medium=make_medium(current_m_s=current),
                   layers=layers, tempo_control=GOAL_TEMPO)


def reach_goal(episode: Episode, goal: int, observers=()) -> dict:
    """Swim to goal ``goal`` for the pool's horizon: Pos, Prog, Dev and Roll."""
    episode.reset(goal=goal)
    episode.run(episode.task.duration_s, observers=observers)
    return episode.metrics()


def goal_run(pool_name: str, stroke: str, current=(0.0, 0.0, 0.0), layers: Layers = Layers()) -> dict:
    episode = goal_episode(pool_name, stroke, current, layers)
    try:
        per_goal = [reach_goal(episode, k) for k in range(len(episode.task.goals))]
    finally:
        episode.close()
    mean = {k: float(np.mean([g[k] for g in per_goal])) for k in GOAL_METRICS}
    return {"pool": pool_name, "stroke": stroke, "layers": layers.describe(), "current_m_s": list(current),
            **mean, "goals": per_goal, "swim_published": bench.SWIM_PUBLISHED.get(pool_name)}


def check_seconds(seconds: float) -> None:
    if not (math.isfinite(seconds) and MIN_SECONDS <= seconds <= MAX_SECONDS):
        raise ConfigError(f"seconds must be between {MIN_SECONDS:g} and {MAX_SECONDS:g}, got {seconds}")


def write_json(path: Path, data) -> None:
    path.write_text(json.dumps(data, indent=2, allow_nan=False) + "\n")


def _dump(spec):
    return spec.model_dump(mode="json") if spec is not None else None


def bench_step(seconds: float = 5.0, physics_hz: int = 480, stroke: str | None = None) -> dict:
    """Microseconds per physics step: (a) the bare PyBullet step of the floating body (no fluid,
    no PD), (b) the whole loop (state read, fluid, wrenches, PD, step) through the episode runner. Each is timed BENCH_REPEATS times, alternating so that a burst of
    load elsewhere hits both, and the fastest repeat counts (the usual rule for timing: noise
    never makes code faster)."""
    check_seconds(seconds)
    if stroke is None:
        stroke = "front_crawl" if "front_crawl" in available_strokes() else "rest"
    episode = Episode(stroke, physics_hz=physics_hz)
    steps = int(round(seconds * physics_hz))
    world = episode.sim.world

    def bare() -> None:
        for _ in range(steps):   # PyBullet alone: the reference the loop is measured against
            world.step()

    def timed(run) -> float:
        episode.reset()
        t0 = time.perf_counter()
        run()
        return (time.perf_counter() - t0) / steps * 1e6

    try:
        episode.run(BENCH_WARMUP_S)
        pairs = [(timed(bare), timed(lambda: episode.run(steps=steps))) for _ in range(BENCH_REPEATS)]
        bare_us, loop_us = min(p[0] for p in pairs), min(p[1] for p in pairs)
    finally:
        episode.close()
    return {"stroke": episode.stroke.name, "physics_hz": physics_hz, "steps": steps, "repeats": BENCH_REPEATS,
            "bare_step_us": bare_us, "loop_step_us": loop_us, "loop_to_bare_ratio": loop_us / bare_us,
            "realtime_factor": 1e6 / (loop_us * physics_hz)}
