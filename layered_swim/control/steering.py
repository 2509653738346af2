"""Where the swimmer points and how far it must turn: the inputs of the per-cycle layer.

All angles in radians. Heading is the yaw of the swimmer's forward axis (the pelvis long axis
for prone and supine strokes, its front for upright ones); pitch is that axis's elevation; roll
is the tilt of the shoulder line (thorax lateral axis) out of the horizontal, positive when the
left shoulder is up. Pure functions of arrays.
"""
from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from layered_swim.geometry import quat_rotate
from layered_swim.state import BodyState, lying

FORWARD_LOCAL = {"prone": np.array([0.0, 0.0, 1.0]), "supine": np.array([0.0, 0.0, 1.0]),
                 "upright": np.array([1.0, 0.0, 0.0])}
LATERAL_LOCAL = np.array([0.0, 1.0, 0.0])


def wrap_angle(a: float) -> float:
    return (a + math.pi) % (2 * math.pi) - math.pi


def bearing_error(position_m: np.ndarray, target_m: np.ndarray, heading_rad: float) -> float:
    """How far the target's bearing from ``position_m`` lies off the heading (+ to the left)."""
    return wrap_angle(math.atan2(target_m[1] - position_m[1], target_m[0] - position_m[0]) - heading_rad)


@dataclass(frozen=True)
class Attitude:
    heading_rad: float
    pitch_rad: float
    roll_rad: float


def forward_axis(pelvis_quat: np.ndarray, posture: str) -> np.ndarray:
    return quat_rotate(np.asarray(pelvis_quat, float), FORWARD_LOCAL[posture])


def shoulder_roll(thorax_quat: np.ndarray) -> float:
    lateral_z = float(quat_rotate(np.asarray(thorax_quat, float), LATERAL_LOCAL)[2])
    return math.asin(max(-1.0, min(1.0, lateral_z)))


def attitude(pelvis_quat: np.ndarray, thorax_quat: np.ndarray, posture: str) -> Attitude:
    forward = forward_axis(pelvis_quat, posture)
    return Attitude(math.atan2(forward[1], forward[0]), math.asin(max(-1.0, min(1.0, forward[2]))),
                    shoulder_roll(thorax_quat))


def attitude_of(state: BodyState, posture: str) -> Attitude:
    """The swimmer's heading, pitch and shoulder roll now."""
    return attitude(state.quat("pelvis"), state.quat("thorax"), posture)


@dataclass(frozen=True)
class SteeringGains:
    """How much of the error the layer tries to remove in one cycle, and pitch limits."""

    yaw_fraction: float = 0.7
    pitch_fraction: float = 0.5
    roll_fraction: float = 0.5
    max_glide_pitch_rad: float = math.radians(30.0)
    over_weight_within_rad: float = math.pi    # weights above 1 only for a heading turn wanted within this


def wanted_turns(att: Attitude, position_m: np.ndarray, target_m: np.ndarray,
                 posture: str, gains: SteeringGains = SteeringGains(), level_roll_rad: float = 0.0) -> dict[str, float]:
    """Signed turns wanted this cycle: yaw (+ left), pitch (+ nose up, toward the glide angle to the
    target's depth), roll (+ toward the left, i.e. left shoulder down) back to ``level_roll_rad``,
    the stroke's own mean roll when swimming straight."""
    delta = np.asarray(target_m, float) - np.asarray(position_m, float)
    horizontal = math.hypot(delta[0], delta[1])
    yaw_error = wrap_angle(math.atan2(delta[1], delta[0]) - att.heading_rad) if horizontal > 1e-6 else 0.0
    turns = {"yaw": gains.yaw_fraction * yaw_error, "pitch": 0.0,
             "roll": gains.roll_fraction * (att.roll_rad - level_roll_rad)}
    if lying(posture):
        turns["pitch"] = gains.pitch_fraction * (glide_pitch(position_m, target_m, gains) - att.pitch_rad)
    return turns


def glide_pitch(position_m: np.ndarray, target_m: np.ndarray, gains: SteeringGains = SteeringGains()) -> float:
    """The pitch (+ nose up) a lying swimmer steers toward: the angle to the target's depth,
    within +-``max_glide_pitch_rad``."""
    delta = np.asarray(target_m, float) - np.asarray(position_m, float)
    angle = math.atan2(delta[2], math.hypot(delta[0], delta[1]))
    return max(-gains.max_glide_pitch_rad, min(gains.max_glide_pitch_rad, angle))
