"""Depth by breath: a swimmer exhales to sink and breathes in to rise.

Each control step the air wanted is the resting breath less ``gain_l_per_m`` for every metre
the target lies deeper than the pelvis, between empty lungs (the residual volume stays; for a
stroke that only breathes in, the resting breath) and a full breath; the lungs move toward it
at no more than ``rate_l_per_s`` (a forced exhale of the vital capacity takes about a second and
a half). Three litres are ~30 N of buoyancy: enough to take the body down a few metres and back,
not to make light water carry it.
"""
from __future__ import annotations

from dataclasses import dataclass


@dataclass(frozen=True)
class LungControl:
    rest_air_l: float
    max_air_l: float
    gain_l_per_m: float = 6.0
    rate_l_per_s: float = 3.0
    breathe_out: bool = True        # False: never below the resting breath (breathing in only, to rise)

    def next_air_l(self, air_l: float, pelvis_depth_m: float, target_depth_m: float, dt_s: float) -> float:
        wanted = self.rest_air_l - self.gain_l_per_m * (target_depth_m - pelvis_depth_m)
        wanted = min(self.max_air_l, max(0.0 if self.breathe_out else self.rest_air_l, wanted))
        step = self.rate_l_per_s * dt_s
        return air_l + min(step, max(-step, wanted - air_l))
