"""Free swimming: the stroke on its own, no target; scored by the run's headline numbers."""
from __future__ import annotations

import numpy as np

from layered_swim.state import Start
from layered_swim.tasks.base import Task, moved_start
from layered_swim.tasks.metrics import head_top_height_m, summary

DEFAULT_SAMPLE_HZ = 60


class FreeSwim(Task):
    """Swim from the stroke's start (or from ``speed_m_s``, e.g. 0 for a start from rest);
    samples the centre of mass, pelvis, thorax and head at ``sample_hz`` for ``metrics``."""

    name = "free_swim"

    def __init__(self, speed_m_s: float | None = None, sample_hz: int = DEFAULT_SAMPLE_HZ):
        self.speed_m_s, self.sample_hz = speed_m_s, sample_hz

    def reset(self, episode, rng, **options) -> Start:
        self._every = episode.sim.config.physics_hz // self.sample_hz
        self._stroke, self._controller = episode.stroke.name, episode.sim.controller
        body = episode.body
        self._head_half_z_m = float(body.half_extents_m[body.index("head"), 2])
        self._samples: dict[str, list] = {"time_s": [], "com_m": [], "pelvis_m": [], "thorax_quat": [], "head_pos_m": [],
                                          "head_quat": []}
        return moved_start(episode.stroke.start_state(), speed_m_s=self.speed_m_s)

    def observe(self, sim) -> None:
        if sim.steps % self._every:
            return
        s, rows = sim.state, self._samples
        rows["time_s"].append(sim.steps / sim.config.physics_hz)   # exact, unlike a running sum of dt
        rows["com_m"].append(s.com_m)
        rows["pelvis_m"].append(s.pos("pelvis"))
        rows["thorax_quat"].append(s.quat("thorax"))
        rows["head_pos_m"].append(s.pos("head"))
        rows["head_quat"].append(s.quat("head"))

    def metrics(self) -> dict:
        a = {name: np.array(rows, dtype=float) for name, rows in self._samples.items()}
        head_top = head_top_height_m(a["head_pos_m"], a["head_quat"], self._head_half_z_m)
        return summary(a["time_s"], a["com_m"], a["pelvis_m"], a["thorax_quat"], head_top,
                       self._controller.cycles_per_s, self._stroke)
