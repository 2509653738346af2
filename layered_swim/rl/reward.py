"""SWIM's reward (SWIM 2026, section 3.5), as pure functions of plain arrays:

    r = r_task * r_stab + w_accel * r_accel                                    (eq. 9)
    r_task = exp(-a_p d_forward) exp(-a_a d_deviation) exp(-a_h e_yaw)         (eqs. 10-13)
    r_stab = exp(-a_r max(|roll| - roll_tol, 0))                               (eq. 14)
    r_accel = exp(-a_s mean |q''|)                                             (eq. 15)

Distances are horizontal (SWIM's goals live in the x-y plane). The paper gives no values for the
a's; ours are chosen so that each factor halves at an error a swimmer would call clearly off:
0.14 m behind or ahead of schedule, 0.07 m off the line, 20 deg of heading, 20 deg of roll
beyond the tolerance, a mean joint acceleration of 70 rad/s^2. The a's and w_accel are the training
YAML's ``reward`` section, a ``RewardSpec``.
"""
from __future__ import annotations

import math

import numpy as np

from layered_swim.rl.config import RewardSpec

BODY_POINT_WEIGHTS = {"pelvis": 0.5, "thorax": 0.3, "head": 0.2}   # SWIM's p_body: root, chest, head


def forward_distance_m(on_schedule_m, root_m, direction) -> float:
    """Eq. 11: |(p_traj - p_root) . d|, how far ahead or behind schedule along the line."""
    d = np.asarray(direction, float)[:2]
    return abs(float((np.asarray(on_schedule_m, float)[:2] - np.asarray(root_m, float)[:2]) @ d))


def deviation_m(body_point_m, start_m, direction) -> float:
    """Eq. 12: the body point's horizontal distance to the start-goal line."""
    d = np.asarray(direction, float)[:2]
    rel = np.asarray(body_point_m, float)[:2] - np.asarray(start_m, float)[:2]
    return abs(float(d[0] * rel[1] - d[1] * rel[0]))


def yaw_error_rad(goal_yaws_rad) -> float:
    """Eq. 13: max(0, psi_min, -psi_max): zero while the intermediate goals lie on both sides of
    the heading, else the smallest turn that would put one of them ahead."""
    yaws = np.asarray(goal_yaws_rad, float)
    return max(0.0, float(yaws.min()), float(-yaws.max()))


def reward_parts(on_schedule_m, root_m, body_point_m, start_m, direction, goal_yaws_rad, roll_rad: float,
                 roll_tolerance_rad: float, joint_accel_rad_s2, w: RewardSpec = RewardSpec()) -> dict:
    """Every factor of eq. 9 and the total, as floats."""
    forward = math.exp(-w.forward_per_m * forward_distance_m(on_schedule_m, root_m, direction))
    deviation = math.exp(-w.deviation_per_m * deviation_m(body_point_m, start_m, direction))
    heading = math.exp(-w.heading_per_rad * yaw_error_rad(goal_yaws_rad))
    task = forward * deviation * heading
    stability = math.exp(-w.roll_per_rad * max(abs(roll_rad) - roll_tolerance_rad, 0.0))
    smoothness = math.exp(-w.accel_s2_per_rad * float(np.mean(np.abs(joint_accel_rad_s2))))
    return {"forward": forward, "deviation": deviation, "heading": heading, "task": task, "stability": stability,
            "smoothness": smoothness, "total": task * stability + w.accel_weight * smoothness}
