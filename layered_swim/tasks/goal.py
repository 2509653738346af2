"""SWIM's goal reaching (SWIM 2026, section 4): swim from the start to one of the pool's three
goals on schedule. The target is the intermediate goal half a stroke cycle ahead on the
start-goal line; the metrics are Pos, Prog, Dev and Roll (``swim_benchmark.py``)."""
from __future__ import annotations

import numpy as np

from layered_swim.state import Start
from layered_swim.tasks import swim_benchmark as bench
from layered_swim.tasks.base import moved_start
from layered_swim.tasks.follow import FollowTarget

GOAL_METRICS = ("pos_m", "prog", "dev_m", "roll_deg")


class ScheduledGoal:
    """SWIM's intermediate goal: the on-schedule point ``lead_s`` ahead on the start-goal line.
    One object for the task's life: a reset points it at another goal."""

    def __init__(self, goal: bench.GoalTask, lead_s: float = 0.0):
        self.goal, self.lead_s = goal, lead_s

    def position(self, time_s: float) -> np.ndarray:
        return bench.intermediate_goal(self.goal, time_s, self.lead_s)

    def path_points(self, n: int = 400) -> np.ndarray:
        return bench.goal_position(self.goal, np.linspace(0.0, self.goal.duration_s, n))


class GoalReaching(FollowTarget):
    """One of ``pool``'s goals per episode: ``reset(goal=k)`` picks goal k, else the episode's
    random generator draws one. The episode lasts the pool's horizon (``duration_s``)."""

    name = "goal"

    def __init__(self, pool: bench.Pool):
        self.pool = pool
        self.goals = bench.goal_tasks(pool)
        super().__init__(ScheduledGoal(self.goals[0]))

    @property
    def goal(self) -> bench.GoalTask:
        return self.target.goal

    @property
    def duration_s(self) -> float:
        return self.pool.horizon_s

    def reset(self, episode, rng, goal: int | None = None, **options) -> Start:
        index = int(rng.integers(len(self.goals))) if goal is None else goal
        if not 0 <= index < len(self.goals):
            raise ValueError(f"goal must be in 0..{len(self.goals) - 1}, got {goal}")
        self.target.goal = self.goals[index]
        self.target.lead_s = episode.stroke.period_s / 2
        super().reset(episode, rng)
        return moved_start(episode.stroke.start_state(), self.goal.start_m[:2], self.goal.speed_m_s)

    def metrics(self) -> dict:
        a = self.track()
        scores = bench.episode_metrics(self.goal, a["track_time_s"], a["swimmer_m"], np.degrees(a["roll_rad"]),
                                       bench.ROLL_TOLERANCE_DEG.get(self._stroke, 45.0))
        return {"goal_m": [float(v) for v in self.goal.goal_m], **{k: scores[k] for k in GOAL_METRICS}}
