"""SWIM's goal reaching (SWIM 2026, section 4): swim from the start to one of the pool's three
goals on schedule. The target is the intermediate goal half a stroke cycle ahead on the
start-goal line; the metrics are Pos, Prog, Dev and Roll (``swim_benchmark.py``)."""
from __future__ import annotations

import numpy as np

from layered_swim.state import Start
from layered_swim.tasks import swim_benchmark as bench
from layered_swim.tasks.base import moved_start
from layered_swim.tasks.follow import TRACK_HZ, FollowTarget

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
    """One of ``pool``'s goals per episode: ``reset(goal=k)`` picks goal k, ``reset(goal_task=t)``
    swims ``t`` (a goal of another pool: a training draw, a sweep's), else the episode's random
    generator draws one of the pool's. The episode lasts the goal's horizon (``duration_s``).

    The pool's walls and floor end an episode (``ended``: why, ``ended_s``: when) for every
    controller alike, unless ``ends_at_walls`` is off (a sweep in boundless water). The metrics
    score the whole horizon either way: an episode that ended early is held where it stopped
    (``bench.held_to``), and only one that swam the horizon counts as a ``success``."""

    name = "goal"
    ends_at_walls = True

    def __init__(self, pool: bench.Pool):
        self.pool = pool
        self.goals = bench.goal_tasks(pool)
        self.ended = self.ended_s = None
        super().__init__(ScheduledGoal(self.goals[0]))

    @property
    def goal(self) -> bench.GoalTask:
        return self.target.goal

    @property
    def duration_s(self) -> float:
        return self.goal.duration_s

    def reset(self, episode, rng, goal: int | None = None, goal_task: bench.GoalTask | None = None,
              **options) -> Start:
        if goal_task is None:
            index = int(rng.integers(len(self.goals))) if goal is None else goal
            if not 0 <= index < len(self.goals):
                raise ValueError(f"goal must be in 0..{len(self.goals) - 1}, got {goal}")
            goal_task = self.goals[index]
        self.target.goal = goal_task
        self.target.lead_s = episode.stroke.period_s / 2
        self.ended = self.ended_s = None
        super().reset(episode, rng)
        return moved_start(episode.stroke.start_state(), self.goal.start_m[:2], self.goal.speed_m_s)

    def observe(self, sim) -> None:
        if sim.steps % self._every:
            return
        super().observe(sim)
        if self.ended is None and self.ends_at_walls:
            reason = self.goal.pool.ending(self._samples["swimmer_m"][-1])
            if reason is not None:
                self.end(reason, sim.time_s)

    def end(self, reason: str, time_s: float) -> None:
        """The episode ends here (the pool's walls, a simulation that blew up): ``Episode.run`` stops."""
        if self.ended is None:
            self.ended, self.ended_s = reason, time_s

    def metrics(self) -> dict:
        a = self.track()
        scores = bench.episode_metrics(self.goal, a["track_time_s"], a["swimmer_m"], np.degrees(a["roll_rad"]),
                                       bench.ROLL_TOLERANCE_DEG.get(self._stroke, 45.0), ended_s=self.ended_s,
                                       step_s=1.0 / TRACK_HZ)
        return {"goal_m": [float(v) for v in self.goal.goal_m], **{k: scores[k] for k in GOAL_METRICS},
                "success": self.ended is None, "ended": self.ended, "ended_s": self.ended_s}
