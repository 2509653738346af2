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
# The side of a lying body that faces the floor: the belly prone, the back supine.
DOWN_LOCAL = {"prone": np.array([1.0, 0.0, 0.0]), "supine": np.array([-1.0, 0.0, 0.0])}
# Nose up beyond this (standing up from treading water), a lying body's heading can be read off
# where it would lie down.
STEEP_PITCH_RAD = math.radians(60.0)
# A target this close to dead behind keeps the turn going the way it went.
KEEP_TURNING_RAD = math.radians(45.0)


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


def turned_over(thorax_quat: np.ndarray, posture: str) -> bool:
    """Whether a lying body's chest faces the other way than its posture's (a supine one face
    down): its shoulder roll (the shoulder line's tilt) reads the same either way."""
    return lying(posture) and float(quat_rotate(np.asarray(thorax_quat, float), DOWN_LOCAL[posture])[2]) > 0.0


def elevation(forward: np.ndarray) -> float:
    """How far a unit axis points up (rad): the forward axis's is the body's pitch (+ nose up)."""
    return math.asin(max(-1.0, min(1.0, float(forward[2]))))


def attitude(pelvis_quat: np.ndarray, thorax_quat: np.ndarray, posture: str, facing: bool = False) -> Attitude:
    """``facing``: a lying body pitched up beyond ``STEEP_PITCH_RAD`` heads where it would lie down
    (for a stroke setting off standing; swimming, the butterfly and a breaststroke climbing to
    the surface pitch up that far for a moment and keep their heading)."""
    forward = forward_axis(pelvis_quat, posture)
    pitch = elevation(forward)
    along = forward
    if facing and lying(posture) and pitch > STEEP_PITCH_RAD:
        # Nearly upright, the long axis points up and its heading is noise (it flipped 180 deg in a
        # second as the breaststroke set off from treading water, which then turned the long way
        # round); such a body lies down toward the side facing the floor: the long axis rotated
        # level through it.
        down = quat_rotate(np.asarray(pelvis_quat, float), DOWN_LOCAL[posture])
        along = forward * math.cos(pitch) + down * math.sin(pitch)
    return Attitude(math.atan2(along[1], along[0]), pitch, shoulder_roll(thorax_quat))


def attitude_of(state: BodyState, posture: str, facing: bool = False) -> Attitude:
    """The swimmer's heading, pitch and shoulder roll now."""
    return attitude(state.quat("pelvis"), state.quat("thorax"), posture, facing)


@dataclass(frozen=True)
class SteeringGains:
    """How much of the error the layer tries to remove in one cycle, and pitch limits. The heading
    turns as long as a yaw sequence works; pitch and roll settle at an offset a sequence holds, so
    their fractions are integral gains: each cycle the held offset moves by that share of the
    remaining error; ``attitude_proportional`` of the error is added at once on top (a PI control)."""

    yaw_fraction: float = 0.7
    pitch_fraction: float = 0.5
    roll_fraction: float = 0.5
    max_glide_pitch_rad: float = math.radians(30.0)
    over_weight_within_rad: float = math.pi    # weights above 1 only for a heading turn wanted within this
    depth_within_m: float = 0.0                # the target's depth counts as reached within this
    attitude_within_rad: float = 0.0           # pitch and roll errors within this are left alone
    attitude_proportional: float = 0.0         # share of the error (beyond that) added at once to the held offset


@dataclass(frozen=True)
class MeanAttitude:
    """The body pitch and shoulder roll averaged over a stroke cycle (a crawl rolls +-30 deg within one)."""

    pitch_rad: float
    roll_rad: float


def turn_error(att: Attitude, position_m: np.ndarray, target_m: np.ndarray, last_error_rad: float = 0.0) -> float:
    """The signed heading error to turn away this cycle (+ left). ``last_error_rad``: the last
    cycle's, as steered; a target that was and still is within ``KEEP_TURNING_RAD`` of dead behind
    is turned to the same side as then, not the side the last degree of error now says (flipping
    each cycle, the breaststroke swam 10 s straight away from a jump behind it)."""
    delta = np.asarray(target_m, float) - np.asarray(position_m, float)
    if math.hypot(delta[0], delta[1]) <= 1e-6:
        return 0.0
    error = bearing_error(position_m, target_m, att.heading_rad)
    behind = math.pi - KEEP_TURNING_RAD
    if last_error_rad * error < 0.0 and abs(last_error_rad) > behind and abs(error) > behind:
        error -= math.copysign(2.0 * math.pi, error)
    return error


def attitude_errors(mean: MeanAttitude, position_m: np.ndarray, target_m: np.ndarray, posture: str,
                    level: MeanAttitude, gains: SteeringGains = SteeringGains()) -> dict[str, float]:
    """How far the cycle's mean attitude is from the wanted one (+: more nose up, more left shoulder
    up is wanted): roll back to ``level`` (the unperturbed stroke's own), and for a lying stroke the
    pitch of ``level`` plus the glide angle toward the target's depth."""
    errors = {"roll": level.roll_rad - mean.roll_rad}
    if lying(posture):
        errors["pitch"] = level.pitch_rad + glide_pitch(position_m, target_m, gains) - mean.pitch_rad
    return errors


def beyond(error_rad: float, within_rad: float) -> float:
    """The part of an error beyond +-``within_rad`` (0 inside)."""
    return math.copysign(max(0.0, abs(error_rad) - within_rad), error_rad)


def held_offset(offset_rad: float, error_rad: float, fraction: float, low_rad: float, high_rad: float,
                within_rad: float = 0.0) -> float:
    """Next cycle's held attitude offset: this one moved by ``fraction`` of the error beyond
    ``within_rad``, within what the sequences can hold (an integral that cannot wind up beyond
    them); an error within ``within_rad`` is the stroke's own attitude, and the offset eases back
    toward none by the same fraction."""
    excess = beyond(error_rad, within_rad)
    step = excess if excess else -offset_rad
    return min(high_rad, max(low_rad, offset_rad + fraction * step))


def glide_pitch(position_m: np.ndarray, target_m: np.ndarray, gains: SteeringGains = SteeringGains()) -> float:
    """The pitch (+ nose up) a lying swimmer steers toward: the angle to the target's depth (less
    ``depth_within_m``), within +-``max_glide_pitch_rad``."""
    delta = np.asarray(target_m, float) - np.asarray(position_m, float)
    angle = math.atan2(beyond(delta[2], gains.depth_within_m), math.hypot(delta[0], delta[1]))
    return max(-gains.max_glide_pitch_rad, min(gains.max_glide_pitch_rad, angle))
