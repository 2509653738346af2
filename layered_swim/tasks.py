"""Target following (``follow``) and SWIM's goal-reaching benchmark (``goal``).

Both run the layered controller toward a target and log swimmer and target over time; the
metrics are pure functions (``analysis/swim_benchmark.py``, below).
"""
from __future__ import annotations

import math
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from layered_swim.analysis import swim_benchmark as bench
from layered_swim.body.model import load_body
from layered_swim.control.pose import joint_layout, unit_vector
from layered_swim.control.stroke import load_stroke
from layered_swim.control.layered import Layers
from layered_swim.control.policy import TempoControl
from layered_swim.control.steering import attitude, wrap_angle
from layered_swim.control.targets import Target, load_trajectory
from layered_swim.runs import _check_seconds, _write_json, build_swim, make_medium
from layered_swim.sim.recorder import Recorder

TRACK_HZ = 20      # target-tracking samples per second


@dataclass
class Track:
    """Swimmer (centre of mass) and target over time."""

    time_s: list
    swimmer_m: list
    target_m: list
    heading_error_rad: list
    roll_rad: list

    def arrays(self) -> dict[str, np.ndarray]:
        return {"track_time_s": np.array(self.time_s), "swimmer_m": np.array(self.swimmer_m),
                "target_m": np.array(self.target_m), "heading_error_rad": np.array(self.heading_error_rad),
                "roll_rad": np.array(self.roll_rad)}


def swim_toward(target: Target, stroke: str, seconds: float, layers: Layers, current, density,
                start_xy=(0.0, 0.0), start_speed=None, tempo: TempoControl | None = None,
                recorder_dir: Path | None = None, on_step=None) -> tuple[Track, dict]:
    """Swim toward ``target`` and track swimmer and target at TRACK_HZ; ``on_step(sim)``, when
    given, runs after every physics step (experiments push the swimmer from there)."""
    setup = build_swim(stroke, medium=make_medium(density_kg_m3=density).with_(current_m_s=tuple(current)),
                       target=target, layers=layers, tempo_control=tempo)
    sim, start = setup.sim, setup.stroke.start
    speed = start.speed_m_s if start_speed is None else start_speed
    sim.reset(start.posture, start.depth_m, speed, position_xy_m=start_xy)
    mass = sim.body.mass_fraction
    posture = start.posture
    track = Track([], [], [], [], [])
    every = sim.config.physics_hz // TRACK_HZ
    recorder = Recorder(sim) if recorder_dir is not None else None

    def sample(s) -> None:
        if s.steps % every:
            return
        com = mass @ s.state.pos_m
        goal = target.position(s.time_s)
        att = attitude(s.state.quat_xyzw[0], s.state.quat_xyzw[2], posture)
        track.time_s.append(s.time_s)
        track.swimmer_m.append(com)
        track.target_m.append(goal)
        track.heading_error_rad.append(wrap_angle(math.atan2(goal[1] - com[1], goal[0] - com[0]) - att.heading_rad))
        track.roll_rad.append(att.roll_rad)

    def every_step(s) -> None:
        if recorder is not None:
            recorder(s)
        if on_step is not None:
            on_step(s)
        sample(s)

    try:
        sample(sim)
        sim.run(seconds, every_step=every_step)
    finally:
        sim.close()
    if recorder is not None:
        recorder.save(recorder_dir)
    return track, {"stroke_file": setup.stroke.source, "cycles_per_s_at_tempo_1": 1.0 / setup.stroke.period_s}


def tracking_metrics(track: Track) -> dict:
    a = track.arrays()
    distance = np.linalg.norm(a["swimmer_m"] - a["target_m"], axis=1)
    return {"mean_distance_m": float(distance.mean()), "max_distance_m": float(distance.max()),
            "final_distance_m": float(distance[-1]),
            "mean_heading_error_deg": float(np.degrees(np.abs(a["heading_error_rad"])).mean())}


def follow_run(trajectory: str, stroke: str = "breaststroke", layers: Layers = Layers(), current=(0.0, 0.0, 0.0),
               density: float | None = None, seconds: float = 60.0, out_dir: str | Path | None = None) -> dict:
    _check_seconds(seconds)
    target = load_trajectory(trajectory)
    out = Path(out_dir) if out_dir is not None else None
    if out is not None:
        out.mkdir(parents=True, exist_ok=True)
    track, info = swim_toward(target, stroke, seconds, layers, current, density, recorder_dir=out)
    result = {"trajectory": target.name, "stroke": stroke, "layers": layers.describe(),
              "current_m_s": list(current), "seconds": seconds, **tracking_metrics(track)}
    if target.kind == "line":
        a = track.arrays()
        start = target.position(0.0)
        direction = unit_vector(target.position(1.0) - start)
        speed = float(np.linalg.norm(target.position(1.0) - start))
        tolerance = bench.ROLL_TOLERANCE_DEG.get(stroke, 45.0)
        result["swim_metrics"] = bench.straight_line_metrics(a["track_time_s"], a["swimmer_m"], np.degrees(a["roll_rad"]),
                                                             start, direction, speed, tolerance)
    if out is not None:
        np.savez_compressed(out / "track.npz", **track.arrays())
        _write_json(out / "summary.json", result)
        _write_json(out / "config.json", {"trajectory": str(target.source), "trajectory_spec": _dump(target.spec),
                                          "stroke": stroke, "layers": layers.describe(), "current_m_s": list(current),
                                          "density_kg_m3": density, "seconds": seconds, **info})
    return result


class ScheduledGoal:
    """SWIM's intermediate goal: the on-schedule point ``lead_s`` ahead on the start-goal line."""

    def __init__(self, task: bench.GoalTask, lead_s: float):
        self.task, self.lead_s = task, lead_s

    def position(self, time_s: float) -> np.ndarray:
        return bench.intermediate_goal(self.task, time_s, self.lead_s)

    def path_points(self, n: int = 400) -> np.ndarray:
        return bench.goal_position(self.task, np.linspace(0.0, self.task.duration_s, n))


GOAL_METRICS = ("pos_m", "prog", "dev_m", "roll_deg")
GOAL_TEMPO = TempoControl(min_tempo=0.3, near_m=0.2, far_m=1.0)   # slow strokes: the goal line is slow


def goal_episode(task: bench.GoalTask, stroke: str, current=(0.0, 0.0, 0.0), layers: Layers = Layers(),
                 on_step=None) -> tuple[dict, Track]:
    """One goal-reaching episode: Pos, Prog, Dev and Roll, and the track they come from."""
    period_s = load_stroke(stroke, joint_layout(load_body())).period_s   # sets the intermediate-goal lead
    target = ScheduledGoal(task, lead_s=period_s / 2)
    track, _ = swim_toward(target, stroke, task.duration_s, layers, current, None, start_xy=tuple(task.start_m[:2]),
                           start_speed=task.speed_m_s, tempo=GOAL_TEMPO, on_step=on_step)
    a = track.arrays()
    metrics = bench.episode_metrics(task, a["track_time_s"], a["swimmer_m"], np.degrees(a["roll_rad"]),
                                    bench.ROLL_TOLERANCE_DEG.get(stroke, 45.0))
    return {"goal_m": [float(v) for v in task.goal_m], **{k: metrics[k] for k in GOAL_METRICS}}, track


def goal_run(pool_name: str, stroke: str, current=(0.0, 0.0, 0.0), layers: Layers = Layers()) -> dict:
    pool = bench.pool(pool_name)
    per_goal = [goal_episode(task, stroke, current, layers)[0] for task in bench.goal_tasks(pool)]
    mean = {k: float(np.mean([g[k] for g in per_goal])) for k in GOAL_METRICS}
    return {"pool": pool_name, "stroke": stroke, "layers": layers.describe(), "current_m_s": list(current),
            **mean, "goals": per_goal, "swim_published": bench.SWIM_PUBLISHED.get(pool_name)}


def _dump(spec):
    return spec.model_dump(mode="json") if spec is not None else None
