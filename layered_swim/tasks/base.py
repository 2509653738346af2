"""What a task is: what the swimmer is asked to do, and how well it does it.

A task owns its target (None: swim the stroke, go nowhere in particular), says where an episode
starts (``reset``, which may move the target without anything being rebuilt), observes the
swim after every physics step (sampling what it scores at its own rate) and turns what it saw
into metrics. The episode runner (``layered_swim/episode.py``) calls these; nothing else does.
"""
from __future__ import annotations

from dataclasses import replace

import numpy as np

from layered_swim.control.targets import Target
from layered_swim.state import Start


class SampleLog:
    """Fixed-width samples appended into one growing array: no object per sample, so memory grows
    by the numbers alone (a slice of the state kept per sample would keep that step's whole frame
    array alive: 1 GB over an hour at 60 Hz)."""

    def __init__(self, widths: dict[str, int]):
        self._slices, start = {}, 0
        for name, width in widths.items():
            self._slices[name] = slice(start, start + width)
            start += width
        self._data = np.empty((1024, start))
        self.n = 0

    def append(self, **values) -> None:
        if self.n == len(self._data):
            self._data = np.concatenate([self._data, np.empty_like(self._data)])
        row = self._data[self.n]
        for name, where in self._slices.items():
            row[where] = values[name]
        self.n += 1

    def arrays(self) -> dict[str, np.ndarray]:
        """Per name an (n, width) array, (n,) for width 1."""
        return {name: self._data[:self.n, where] if where.stop - where.start > 1 else self._data[:self.n, where.start]
                for name, where in self._slices.items()}


class Task:
    name = "task"
    target: Target | None = None
    ended: str | None = None       # why the task ended the episode early (the goal task's pool walls)

    def reset(self, episode, rng: np.random.Generator, **options) -> Start:
        """Prepare a new episode of ``episode`` (its stroke, body and controller are built);
        returns where the swimmer starts. The default: the stroke file's own start."""
        return episode.stroke.start_state()

    def observe(self, sim) -> None:
        """Called after reset and after every physics step; cheap unless it is time to sample."""

    def metrics(self) -> dict:
        return {}


def moved_start(start: Start, position_xy_m=None, speed_m_s: float | None = None,
                heading_rad: float | None = None) -> Start:
    """``start`` placed at ``position_xy_m``, launched at ``speed_m_s`` and turned to
    ``heading_rad``, each where given (None: as it was)."""
    changes = {}
    if position_xy_m is not None:
        changes["position_xy_m"] = (float(position_xy_m[0]), float(position_xy_m[1]))
    if speed_m_s is not None:
        changes["speed_m_s"] = float(speed_m_s)
    if heading_rad is not None:
        changes["heading_rad"] = float(heading_rad)
    return replace(start, **changes)
