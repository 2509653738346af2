"""A learned residual on top of a reference controller (SWIM 2026, eq. 5):
q_target = q_ref + a, with ``a`` set from outside (the RL environment) and held until changed."""
from __future__ import annotations

import numpy as np

from layered_swim.state import BodyState, JointLayout


class ResidualController:
    """``reference``'s desired pose plus ``residual_rad`` (one angle per pose coordinate), kept
    inside the joints' ranges; the reference's rates pass through. Everything else the episode
    asks of a controller (its phase, its cycle clock) is the reference's."""

    def __init__(self, reference, layout: JointLayout):
        self.reference = reference
        self.layout = layout
        self.residual_rad = layout.zeros()

    def __getattr__(self, name: str):
        return getattr(self.reference, name)

    def set_residual(self, residual_rad: np.ndarray) -> None:
        self.residual_rad[:] = residual_rad

    def reset(self) -> None:
        self.reference.reset()
        self.residual_rad[:] = 0.0

    def desired(self, time_s: float, state: BodyState | None,
                flow_m_s: np.ndarray | None) -> tuple[np.ndarray, np.ndarray]:
        pose, rate = self.reference.desired(time_s, state, flow_m_s)
        return self.layout.clamp(pose + self.residual_rad), rate
