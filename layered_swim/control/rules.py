"""The continuous perturbation layer (Yang 4.4): two rules applied every control step.

* Palm orientation: when the water pushing on a hand helps toward the desired direction, turn
  the palm to face the relative flow (more force); when it hinders, turn the palm to slice
  through it (less force). The wrist's two axes and the shoulder's internal rotation each move
  along the gradient of how squarely the palm faces the flow.
* Arm reach: reach further (extend the elbow) while the hand's drag helps, keep the arm closer
  (flex the elbow) while it hinders.

Pure functions of the body state, the water velocity and the desired direction.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from layered_swim.body.model import Body
from layered_swim.control.pose import JointLayout, quat_rotate
from layered_swim.control.stroke import RulesSpec

PALM_NORMAL_LOCAL = np.array([0.0, 1.0, 0.0])   # the hand box's thin axis
MIN_FLOW_M_S = 0.05                             # below this the hand feels no useful force


@dataclass(frozen=True)
class ArmIndices:
    hand: int
    forearm: int
    upper_arm: int
    wrist_axes: np.ndarray        # (2, 3) in the forearm frame
    shoulder_rotation_axis: np.ndarray
    palm_coords: tuple[int, int, int]   # wrist flexion, wrist deviation, shoulder internal rotation
    elbow_coord: int


def arm_indices(body: Body, layout: JointLayout) -> list[ArmIndices]:
    arms = []
    for side in ("l", "r"):
        wrist, shoulder = body.joint(f"wrist_{side}"), body.joint(f"shoulder_{side}")
        arms.append(ArmIndices(
            hand=body.index(f"hand_{side}"), forearm=body.index(f"forearm_{side}"),
            upper_arm=body.index(f"upper_arm_{side}"),
            wrist_axes=wrist.axes, shoulder_rotation_axis=shoulder.axes[2],
            palm_coords=(layout.index(f"wrist_{side}.{wrist.axis_names[0]}"),
                         layout.index(f"wrist_{side}.{wrist.axis_names[1]}"),
                         layout.index(f"shoulder_{side}.{shoulder.axis_names[2]}")),
            elbow_coord=layout.index(f"elbow_{side}.flexion"),
        ))
    return arms


def rule_offsets(arms: list[ArmIndices], rules: RulesSpec, quat_xyzw: np.ndarray, linvel_m_s: np.ndarray,
                 water_m_s: np.ndarray, desired_dir: np.ndarray, size: int,
                 palm: bool = True, reach: bool = True) -> np.ndarray:
    """Pose offsets (rad) from the enabled rules; zero where a rule is off."""
    offsets = np.zeros(size)
    palm = palm and rules.palm.enabled
    reach = reach and rules.reach.enabled
    if not (palm or reach):
        return offsets
    for arm in arms:
        flow = water_m_s - linvel_m_s[arm.hand]
        speed = float(np.linalg.norm(flow))
        if speed < MIN_FLOW_M_S:
            continue
        flow_dir = flow / speed
        helpfulness = float(flow_dir @ desired_dir)   # > 0: the drag on the hand pushes where we want to go
        strength = min(speed, 1.0)
        if palm:
            normal = quat_rotate(quat_xyzw[arm.hand], PALM_NORMAL_LOCAL)
            axes = np.vstack([quat_rotate(quat_xyzw[arm.forearm], arm.wrist_axes),
                              quat_rotate(quat_xyzw[arm.upper_arm], arm.shoulder_rotation_axis)[None]])
            facing = float(normal @ flow_dir)
            turning = np.cross(axes, normal) @ flow_dir                     # d(facing)/d(angle) per axis
            # More force: climb |facing| (its slope is not zero even when slicing edge-on);
            # less force: descend facing^2, which settles smoothly at edge-on.
            gradient = (1.0 if facing >= 0 else -1.0) * turning if helpfulness > 0 else 2.0 * facing * turning
            step = rules.palm.gain * helpfulness * strength * gradient
            offsets[list(arm.palm_coords)] = np.clip(step, -np.radians(rules.palm.max_deg), np.radians(rules.palm.max_deg))
        if reach:
            step = -rules.reach.gain * helpfulness * strength
            offsets[arm.elbow_coord] = np.clip(step, -np.radians(rules.reach.max_deg), np.radians(rules.reach.max_deg))
    return offsets
