"""The continuous perturbation layer (Yang 4.4): two rules applied every control step.

* Palm orientation: when the water pushing on a hand helps toward the desired direction, turn
  the palm to face the relative flow (more force); when it hinders, turn the palm to slice
  through it (less force). Both are the gradient of one quantity, the hand's flat-plate thrust
  along the desired direction, followed by the wrist's two axes. (Turning the shoulder too
  swings the whole bent arm, which costs more than the palm gains.)
* Arm reach: reach further (extend the elbow) while the hand's drag helps, keep the arm closer
  (flex the elbow) while it hinders.

A stroke whose hands recover through the air keeps a rule to the helping phase (``hindering:
false`` in its file). Pure functions of the body state, the water velocity at the hands and the
desired direction.
"""
from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from layered_swim.body.model import Body
from layered_swim.control.stroke import RulesSpec
from layered_swim.geometry import cross, quat_rotate
from layered_swim.state import JointLayout

PALM_NORMAL_LOCAL = np.array([0.0, 1.0, 0.0])   # the hand box's thin axis
MIN_FLOW_M_S = 0.05                             # below this the hand feels no useful force


@dataclass(frozen=True)
class ArmIndices:
    hand: int
    forearm: int
    wrist_axes: np.ndarray        # (2, 3) in the forearm frame
    palm_coords: tuple[int, int]        # wrist flexion, wrist deviation
    elbow_coord: int


def arm_indices(body: Body, layout: JointLayout) -> list[ArmIndices]:
    arms = []
    for side in ("l", "r"):
        wrist = body.joint(f"wrist_{side}")
        arms.append(ArmIndices(
            hand=body.index(f"hand_{side}"), forearm=body.index(f"forearm_{side}"),
            wrist_axes=wrist.axes,
            palm_coords=(layout.index(f"wrist_{side}.{wrist.axis_names[0]}"),
                         layout.index(f"wrist_{side}.{wrist.axis_names[1]}")),
            elbow_coord=layout.index(f"elbow_{side}.flexion"),
        ))
    return arms


RULE_MEMORY_S = 0.25   # offsets fade with this time constant once the flow stops asking for them


def rule_offsets(previous: np.ndarray, arms: list[ArmIndices], rules: RulesSpec, quat_xyzw: np.ndarray,
                 linvel_m_s: np.ndarray, flow_m_s: np.ndarray, desired_dir: np.ndarray, dt_s: float,
                 palm: bool = True, reach: bool = True, engagement: float = 1.0) -> np.ndarray:
    """The rules' pose offsets (rad) after one control step of ``dt_s``: each offset moves along its
    rule's gradient at ``engagement * gain`` rad/s per unit gradient, fades with RULE_MEMORY_S and
    stays within ``max_deg``; zero where a rule is off. ``flow_m_s`` (n, 3): the water velocity at
    each segment, as the fluid backend found it."""
    palm = palm and rules.palm.enabled
    reach = reach and rules.reach.enabled
    if not (palm or reach):
        return np.zeros_like(previous)
    pull = np.zeros_like(previous)
    limit = np.zeros_like(previous)
    for arm in arms:
        flow = flow_m_s[arm.hand] - linvel_m_s[arm.hand]
        speed = math.sqrt(flow.dot(flow))      # np.linalg.norm's own sum for a vector, without its checks
        if speed < MIN_FLOW_M_S:
            continue
        flow_dir = flow / speed
        helpfulness = float(flow_dir @ desired_dir)   # > 0: the drag on the hand pushes where we want to go
        strength = min(speed, 1.0)
        if palm and (helpfulness > 0.0 or rules.palm.hindering):
            normal = quat_rotate(quat_xyzw[arm.hand], PALM_NORMAL_LOCAL)
            axes = quat_rotate(quat_xyzw[arm.forearm], arm.wrist_axes)
            turning = cross(axes, normal)                       # d(normal)/d(angle), one row per axis
            facing, along = float(normal @ flow_dir), float(normal @ desired_dir)
            # A flat plate's pressure force lies along its normal, ~ facing*|facing|; its useful part is
            # that times the normal's component along the desired direction. Climb that thrust: the palm
            # faces the flow when the push helps and slices through it when it hinders.
            gradient = 2.0 * abs(facing) * along * (turning @ flow_dir) + facing * abs(facing) * (turning @ desired_dir)
            pull[list(arm.palm_coords)] = rules.palm.gain * strength * gradient
            limit[list(arm.palm_coords)] = np.radians(rules.palm.max_deg)
        if reach and (helpfulness > 0.0 or rules.reach.hindering):
            pull[arm.elbow_coord] = -rules.reach.gain * helpfulness * strength
            limit[arm.elbow_coord] = np.radians(rules.reach.max_deg)
    faded = previous * (1.0 - dt_s / RULE_MEMORY_S)
    return np.clip(faded + engagement * pull * dt_s, -limit, limit)
