"""The per-cycle weight policy that steers toward a target (Yang 4.3 + section 5).

At each cycle start: where is the target relative to the swimmer (heading error, depth, and the
shoulder roll averaged over the last cycle against the stroke's own), how much of that to correct
this cycle, and which
weights the calibration table says produce those turns. The cycle's tempo slows the stroke near
the target so the swimmer does not overshoot a slow target.
"""
from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from layered_swim.control.calibration import CalibrationTable
from layered_swim.control.layered import CycleChoice
from layered_swim.control.steering import Attitude, SteeringGains, attitude, wanted_turns, wrap_angle
from layered_swim.control.targets import Target
from layered_swim.sim.world import BodyState


@dataclass(frozen=True)
class TempoControl:
    """Full tempo beyond ``far_m`` from the target, ``min_tempo`` within ``near_m``; also
    ``min_tempo`` while the target is more than ``wide_turn_rad`` off the heading (swimming slower
    tightens the turn: speed falls faster than the turn rate)."""

    min_tempo: float = 0.5
    glide_within_m: float = 0.0
    near_m: float = 0.2
    far_m: float = 0.6
    easy_turn_rad: float = math.radians(30.0)
    wide_turn_rad: float = math.radians(90.0)

    def tempo(self, distance_m: float, heading_error_rad: float = 0.0) -> float:
        near = (distance_m - self.near_m) / (self.far_m - self.near_m)
        straight = (self.wide_turn_rad - abs(heading_error_rad)) / (self.wide_turn_rad - self.easy_turn_rad)
        x = min(1.0, max(0.0, min(near, straight)))
        return float(self.min_tempo + (1.0 - self.min_tempo) * x)


class TargetPolicy:
    def __init__(self, target: Target, table: CalibrationTable, posture: str, mass_fraction: np.ndarray,
                 gains: SteeringGains = SteeringGains(), tempo: TempoControl = TempoControl(), lead_s: float = 2.0):
        self.target, self.table, self.posture, self.lead_s = target, table, posture, lead_s
        self.mass_fraction, self.gains, self.tempo_control = mass_fraction, gains, tempo
        self.last_wanted: dict[str, float] = {}

    def __call__(self, cycle: int, state: BodyState, mean_roll_rad: float | None) -> CycleChoice:
        position = self.mass_fraction @ state.pos_m
        # Steer for where a moving target will be a little later: turning takes cycles.
        target = self.target.position(state.time_s + self.lead_s)
        now = attitude(state.quat_xyzw[0], state.quat_xyzw[2], self.posture)
        # Heading and pitch as the cycle starts (the same phase every cycle, and current); roll
        # averaged over the last cycle (a crawl rolls +-30 deg within it).
        att = Attitude(now.heading_rad, now.pitch_rad, now.roll_rad if mean_roll_rad is None else mean_roll_rad)
        heading_error = wrap_angle(math.atan2(target[1] - position[1], target[0] - position[0]) - att.heading_rad)
        distance = float(np.linalg.norm(self.target.position(state.time_s) - position))
        tempo = self.tempo_control.tempo(distance, heading_error)
        self.last_wanted = wanted_turns(att, position, target, self.posture, self.gains, self.table.roll_at(tempo))
        glide = distance < self.tempo_control.glide_within_m and abs(heading_error) < self.tempo_control.easy_turn_rad
        return CycleChoice({} if glide else self.table.weights_for(self.last_wanted, tempo), tempo, glide)
