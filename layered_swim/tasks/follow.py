"""Following a target (a trajectory file, the mouse's point, a fixed point): the swimmer's centre
of mass against the target over time, and how far apart they were."""
from __future__ import annotations

import math

import numpy as np

from layered_swim.control.steering import attitude_of, wrap_angle
from layered_swim.control.targets import Target
from layered_swim.geometry import unit_vector
from layered_swim.state import Start
from layered_swim.tasks import swim_benchmark as bench
from layered_swim.tasks.base import Task, moved_start

TRACK_HZ = 20      # target-tracking samples per second


class FollowTarget(Task):
    """Chase ``target`` from the stroke's start (moved to ``start_xy_m``, launched at
    ``start_speed_m_s``, heading ``start_heading_rad``, where given); the track is sampled at
    TRACK_HZ."""

    name = "follow"

    def __init__(self, target: Target, start_xy_m=None, start_speed_m_s: float | None = None,
                 start_heading_rad: float | None = None):
        self.target = target
        self.start_xy_m, self.start_speed_m_s, self.start_heading_rad = start_xy_m, start_speed_m_s, start_heading_rad

    def reset(self, episode, rng, **options) -> Start:
        self._every = episode.sim.config.physics_hz // TRACK_HZ
        self._posture = episode.stroke.start.posture
        self._stroke = episode.stroke.name
        self._samples: dict[str, list] = {"track_time_s": [], "swimmer_m": [], "target_m": [],
                                          "heading_error_rad": [], "roll_rad": []}
        return moved_start(episode.stroke.start_state(), self.start_xy_m, self.start_speed_m_s, self.start_heading_rad)

    def observe(self, sim) -> None:
        if sim.steps % self._every:
            return
        state = sim.state
        com = state.com_m
        goal = self.target.position(sim.time_s)
        att = attitude_of(state, self._posture)
        rows = self._samples
        rows["track_time_s"].append(sim.time_s)
        rows["swimmer_m"].append(com)
        rows["target_m"].append(goal)
        rows["heading_error_rad"].append(wrap_angle(math.atan2(goal[1] - com[1], goal[0] - com[0]) - att.heading_rad))
        rows["roll_rad"].append(att.roll_rad)

    def track(self) -> dict[str, np.ndarray]:
        """Per sample: ``track_time_s``, ``swimmer_m`` and ``target_m`` (n, 3), ``heading_error_rad``
        (the target's bearing off the heading), ``roll_rad`` (shoulder roll)."""
        return {name: np.array(rows) for name, rows in self._samples.items()}

    def metrics(self) -> dict:
        a = self.track()
        distance = np.linalg.norm(a["swimmer_m"] - a["target_m"], axis=1)
        result = {"mean_distance_m": float(distance.mean()), "max_distance_m": float(distance.max()),
                  "final_distance_m": float(distance[-1]),
                  "mean_heading_error_deg": float(np.degrees(np.abs(a["heading_error_rad"])).mean())}
        if getattr(self.target, "kind", None) == "line":
            # A target moving along a straight line at constant speed: SWIM's metrics apply.
            start = self.target.position(0.0)
            direction = unit_vector(self.target.position(1.0) - start)
            speed = float(np.linalg.norm(self.target.position(1.0) - start))
            result["swim_metrics"] = bench.straight_line_metrics(
                a["track_time_s"], a["swimmer_m"], np.degrees(a["roll_rad"]), start, direction, speed,
                bench.ROLL_TOLERANCE_DEG.get(self._stroke, 45.0))
        return result
