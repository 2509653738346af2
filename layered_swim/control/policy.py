"""The per-cycle weight policy that steers toward a target (Yang 4.3 + section 5).

At each cycle start: where is the target relative to the swimmer (heading error, depth, and the
shoulder roll averaged over the last cycle), how much of that to correct this cycle, and which
weights the calibration table says produce those turns. The cycle's tempo slows the stroke near
the target so the swimmer does not overshoot a slow target.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from layered_swim.control.calibration import CalibrationTable
from layered_swim.control.layered import CycleChoice
from layered_swim.control.steering import SteeringGains, attitude, wanted_turns
from layered_swim.control.targets import Target
from layered_swim.sim.world import BodyState


@dataclass(frozen=True)
class TempoControl:
    """Full tempo beyond ``far_m`` from the target, ``min_tempo`` within ``near_m``."""

    min_tempo: float = 0.7
    near_m: float = 0.2
    far_m: float = 0.6

    def tempo(self, distance_m: float) -> float:
        x = (distance_m - self.near_m) / (self.far_m - self.near_m)
        return float(self.min_tempo + (1.0 - self.min_tempo) * min(1.0, max(0.0, x)))


class TargetPolicy:
    def __init__(self, target: Target, table: CalibrationTable, posture: str, mass_fraction: np.ndarray,
                 gains: SteeringGains = SteeringGains(), tempo: TempoControl = TempoControl()):
        self.target, self.table, self.posture = target, table, posture
        self.mass_fraction, self.gains, self.tempo_control = mass_fraction, gains, tempo
        self.last_wanted: dict[str, float] = {}

    def centre_of_mass(self, state: BodyState) -> np.ndarray:
        return self.mass_fraction @ state.pos_m

    def direction(self, state: BodyState) -> np.ndarray:
        """Unit vector from the swimmer to the target (the continuous rules' desired direction)."""
        delta = self.target.position(state.time_s) - self.centre_of_mass(state)
        norm = float(np.linalg.norm(delta))
        return delta / norm if norm > 1e-9 else np.zeros(3)

    def __call__(self, cycle: int, state: BodyState, mean_roll_rad: float) -> CycleChoice:
        position = self.centre_of_mass(state)
        target = self.target.position(state.time_s)
        att = attitude(state.quat_xyzw[0], state.quat_xyzw[2], self.posture)
        self.last_wanted = wanted_turns(att, mean_roll_rad, position, target, self.posture, self.gains)
        tempo = self.tempo_control.tempo(float(np.linalg.norm(target - position)))
        return CycleChoice(self.table.weights_for(self.last_wanted, tempo), tempo)
