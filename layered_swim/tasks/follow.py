"""Following a target (a trajectory file, the mouse's point, a fixed point): the swimmer's centre
of mass against the target over time, and how far apart they were.

Beyond the distance, two measures for targets that ask something particular: a target whose depth
changes is held to its depth while it holds one (``hold_depth_error_m``, the pelvis's depth
against the target's), and a target that jumps between stations is reached and then held
(per station: seconds until within ``REACH_M``, then the farthest it drifts until the next jump).
"""
from __future__ import annotations

import numpy as np

from layered_swim.control.steering import attitude_of, bearing_error
from layered_swim.control.targets import Target
from layered_swim.geometry import unit_vector
from layered_swim.state import Start
from layered_swim.tasks import swim_benchmark as bench
from layered_swim.tasks.base import Task, moved_start

TRACK_HZ = 20      # target-tracking samples per second
REACH_M = 1.0      # a station is reached within this distance, and held while the swimmer stays within it
HOLDING_M_S = 0.01         # the target holds its depth while it moves up or down slower than this
DEPTH_CHANGE_M = 0.1       # a path whose depth varies more than this is checked for depth


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
        self._stroke = episode.stroke.name
        self._samples: dict[str, list] = {"track_time_s": [], "swimmer_m": [], "target_m": [],
                                          "pelvis_m": [], "heading_error_rad": [], "roll_rad": [], "stroke": []}
        return moved_start(episode.stroke.start_state(), self.start_xy_m, self.start_speed_m_s, self.start_heading_rad)

    def observe(self, sim) -> None:
        if sim.steps % self._every:
            return
        state = sim.state
        com = state.com_m
        goal = self.target.position(sim.time_s)
        att = attitude_of(state, sim.controller.stroke.start.posture)     # the stroke swimming now (auto switches)
        rows = self._samples
        rows["track_time_s"].append(sim.time_s)
        rows["swimmer_m"].append(com)
        rows["target_m"].append(goal)
        rows["pelvis_m"].append(state.pos("pelvis"))
        rows["heading_error_rad"].append(bearing_error(com, goal, att.heading_rad))
        rows["roll_rad"].append(att.roll_rad)
        rows["stroke"].append(sim.controller.stroke.name)

    def track(self) -> dict[str, np.ndarray]:
        """Per sample: ``track_time_s``, ``swimmer_m`` (centre of mass), ``target_m`` and ``pelvis_m``
        (n, 3), ``heading_error_rad`` (the target's bearing off the heading), ``roll_rad`` (shoulder
        roll), ``stroke`` (the stroke swimming: ``auto`` switches)."""
        return {name: np.array(rows) for name, rows in self._samples.items()}

    def metrics(self) -> dict:
        a = self.track()
        distance = np.linalg.norm(a["swimmer_m"] - a["target_m"], axis=1)
        result = {"mean_distance_m": float(distance.mean()), "max_distance_m": float(distance.max()),
                  "final_distance_m": float(distance[-1]),
                  "mean_heading_error_deg": float(np.degrees(np.abs(a["heading_error_rad"])).mean())}
        result.update(hold_depth(a["track_time_s"], a["pelvis_m"], a["target_m"]))
        result["strokes_swum"] = stroke_spells(a["track_time_s"], a["stroke"])
        if getattr(self.target, "kind", None) == "stations":
            result.update(station_metrics(a["track_time_s"], distance, [t for t, _ in self.target.stations]))
        if getattr(self.target, "kind", None) == "line":
            # A target moving along a straight line at constant speed: SWIM's metrics apply.
            start = self.target.position(0.0)
            direction = unit_vector(self.target.position(1.0) - start)
            speed = float(np.linalg.norm(self.target.position(1.0) - start))
            result["swim_metrics"] = bench.straight_line_metrics(
                a["track_time_s"], a["swimmer_m"], np.degrees(a["roll_rad"]), start, direction, speed,
                bench.ROLL_TOLERANCE_DEG.get(self._stroke, 45.0))
        return result


def stroke_spells(time_s: np.ndarray, strokes: np.ndarray) -> list[dict]:
    """Which stroke swam when: one ``{stroke, from_s, to_s}`` per unbroken spell of one stroke."""
    if not len(time_s):
        return []
    changes = [0] + [i for i in range(1, len(strokes)) if strokes[i] != strokes[i - 1]] + [len(strokes)]
    return [{"stroke": str(strokes[a]), "from_s": float(time_s[a]), "to_s": float(time_s[min(b, len(time_s) - 1)])}
            for a, b in zip(changes, changes[1:])]


def hold_depth(time_s: np.ndarray, pelvis_m: np.ndarray, target_m: np.ndarray) -> dict:
    """For a target whose depth changes: the mean and worst distance between the pelvis's depth and
    the target's while the target holds a depth, and per hold (``holds``: one per unbroken stretch
    of it) its ``target_z_m``, ``from_s``, ``to_s``, ``mean_error_m``, ``max_error_m`` and when that
    was (``max_error_at_s``), and ``mean_above_m``, how far the pelvis stayed above the target's
    depth on average (< 0: below), which tells a swimmer held short from one that overshot;
    nothing for a target at one depth."""
    if len(time_s) < 2 or np.ptp(target_m[:, 2]) <= DEPTH_CHANGE_M:
        return {}
    holding = np.abs(np.gradient(target_m[:, 2], time_s)) < HOLDING_M_S
    if not holding.any():
        return {}
    above = pelvis_m[:, 2] - target_m[:, 2]
    error = np.abs(above)
    edges = np.flatnonzero(np.diff(np.concatenate([[0], holding.astype(int), [0]])))
    holds = []
    for first, end in zip(edges[::2], edges[1::2]):
        worst = first + int(np.argmax(error[first:end]))
        holds.append({"target_z_m": float(target_m[first, 2]), "from_s": float(time_s[first]),
                      "to_s": float(time_s[end - 1]), "mean_error_m": float(error[first:end].mean()),
                      "max_error_m": float(error[worst]), "max_error_at_s": float(time_s[worst]),
                      "mean_above_m": float(above[first:end].mean())})
    return {"hold_depth_error_m": float(error[holding].mean()), "hold_depth_error_max_m": float(error[holding].max()),
            "holds": holds}


def station_metrics(time_s: np.ndarray, distance_m: np.ndarray, jumps_s: list[float]) -> dict:
    """Per station: ``reach_s``, seconds from its jump until within REACH_M (None: never), and
    ``held_within_m``, the farthest the swimmer was from it after that until the next jump."""
    ends = jumps_s[1:] + [float("inf")]
    stations = []
    for start, end in zip(jumps_s, ends):
        window = (time_s >= start) & (time_s < end)
        if not window.any():
            break                      # the run ended before this jump
        t, d = time_s[window], distance_m[window]
        inside = np.flatnonzero(d <= REACH_M)
        reached = inside[0] if len(inside) else None
        stations.append({"t_s": start, "reach_s": None if reached is None else float(t[reached] - start),
                         "held_within_m": None if reached is None else float(d[reached:].max())})
    reached_all = all(s["reach_s"] is not None for s in stations)
    return {"stations": stations, "reached_all": reached_all,
            "worst_reach_s": max(s["reach_s"] for s in stations) if reached_all else None,
            "worst_held_within_m": max(s["held_within_m"] for s in stations) if reached_all else None}
