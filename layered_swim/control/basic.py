"""The basic stroke layer alone: the stroke's key poses at the current phase, nothing steered."""
from __future__ import annotations

import math

import numpy as np

from layered_swim.config import ConfigError
from layered_swim.control.stroke import Stroke
from layered_swim.state import BodyState


class StrokeController:
    def __init__(self, stroke: Stroke, tempo: float = 1.0):
        if not (math.isfinite(tempo) and 0.1 <= tempo <= 5.0):
            raise ConfigError(f"tempo must be between 0.1 and 5, got {tempo}")
        self.stroke = stroke
        self.cycles_per_s = tempo / stroke.period_s

    def phase(self, time_s: float) -> float:
        return time_s * self.cycles_per_s

    def reset(self) -> None:
        """Stateless: the phase is a function of time."""

    def desired(self, time_s: float, state: BodyState | None,
                flow_m_s: np.ndarray | None) -> tuple[np.ndarray, np.ndarray]:
        pose, rate = self.stroke.pose(self.phase(time_s))
        return pose, rate * self.cycles_per_s
