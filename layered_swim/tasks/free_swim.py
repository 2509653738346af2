"""Free swimming: the stroke on its own, no target; scored by the run's headline numbers."""
from __future__ import annotations

from layered_swim.state import Start
from layered_swim.tasks.base import SampleLog, Task, moved_start
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
        self._samples = SampleLog({"time_s": 1, "com_m": 3, "pelvis_m": 3, "thorax_quat": 4, "head_top_m": 1})
        return moved_start(episode.stroke.start_state(), speed_m_s=self.speed_m_s)

    def observe(self, sim) -> None:
        if sim.steps % self._every:
            return
        s = sim.state
        self._samples.append(time_s=sim.steps / sim.config.physics_hz,   # exact, unlike a running sum of dt
                             com_m=s.com_m, pelvis_m=s.pos("pelvis"), thorax_quat=s.quat("thorax"),
                             head_top_m=head_top_height_m(s.pos("head"), s.quat("head"), self._head_half_z_m))

    def metrics(self) -> dict:
        a = self._samples.arrays()
        return summary(a["time_s"], a["com_m"], a["pelvis_m"], a["thorax_quat"], a["head_top_m"],
                       self._controller.cycles_per_s, self._stroke)
