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
    # While the target lies deeper than deep_below_m: the depth error taken damping_s ahead at the
    # rate it closes (air is slow to move the body, and on the error alone it sank past a held
    # depth), and deep_air_l (None: the resting breath) held at the target's depth (the air that
    # holds a body level under water is well below its resting breath: on that, the breaststroke
    # sat 0.2-0.4 m above a held depth). Not near the surface: a breaststroke bobs ~0.15 m/s each
    # cycle there, and breathing with the bob cost it 0.03 m on the figure-eight.
    damping_s: float = 0.0
    deep_below_m: float = 0.0
    deep_air_l: float | None = None

    def next_air_l(self, air_l: float, pelvis_depth_m: float, target_depth_m: float, dt_s: float,
                   closing_m_s: float = 0.0) -> float:
        """``closing_m_s``: how fast the pelvis's depth moves toward the target's (the pelvis's rate
        of sinking less the target's)."""
        deep = target_depth_m > self.deep_below_m
        error_m = target_depth_m - pelvis_depth_m - (self.damping_s * closing_m_s if deep else 0.0)
        level_l = self.deep_air_l if deep and self.deep_air_l is not None else self.rest_air_l
        wanted = level_l - self.gain_l_per_m * error_m
        wanted = min(self.max_air_l, max(0.0 if self.breathe_out else self.rest_air_l, wanted))
        step = self.rate_l_per_s * dt_s
        return air_l + min(step, max(-step, wanted - air_l))
