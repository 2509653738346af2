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
from numba import njit

from layered_swim.body.model import Body
from layered_swim.control.stroke import RulesSpec
from layered_swim.geometry import _cross_rows, _rotate_by_one, _rotate_one
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


class Arms(tuple):
    """Both arms' ``ArmIndices`` (left, right), also packed for the compiled kernel: ``index``
    (2, 5) hand, forearm, the two wrist coordinates, elbow; ``wrist_axes`` (2, 2, 3)."""

    def __new__(cls, arms):
        self = super().__new__(cls, arms)
        self.index = np.array([[a.hand, a.forearm, *a.palm_coords, a.elbow_coord] for a in self], dtype=np.int64)
        self.wrist_axes = np.ascontiguousarray([a.wrist_axes for a in self], dtype=np.float64)
        return self


def arm_indices(body: Body, layout: JointLayout) -> Arms:
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
    return Arms(arms)


RULE_MEMORY_S = 0.25   # offsets fade with this time constant once the flow stops asking for them


def rule_offsets(previous: np.ndarray, arms: Arms, rules: RulesSpec, quat_xyzw: np.ndarray,
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
    return _rule_offsets(previous, arms.index, arms.wrist_axes, rules.palm.gain, math.radians(rules.palm.max_deg),
                         rules.reach.gain, math.radians(rules.reach.max_deg), palm, rules.palm.hindering, reach,
                         rules.reach.hindering, quat_xyzw, linvel_m_s, flow_m_s, desired_dir, dt_s, engagement)


@njit(cache=True)
def _dot3(a, b):
    return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]   # left to right, the same bits on every machine


@njit(cache=True)
def _clip(x, lo, hi):
    """``np.clip``'s comparisons in its order (NaN passes; at equal values the bound wins)."""
    x = x if (math.isnan(x) or x > lo) else lo
    return x if (math.isnan(x) or x < hi) else hi


@njit(cache=True)
def _rule_offsets(previous, index, wrist_axes, palm_gain, palm_limit, reach_gain, reach_limit, palm, palm_hindering,
                  reach, reach_hindering, quat, linvel, flow_m_s, desired, dt_s, engagement):
    """``rule_offsets`` compiled (it runs every control step; numpy on 3-vectors cost ~40 us): the
    same operations in the same order as numpy's vector expressions with 3-vector dot products
    summed left to right (the test's reference), so the same bits; the limits in rad."""
    n = previous.shape[0]
    pull = np.zeros(n)
    limit = np.zeros(n)
    flow_dir = np.empty(3)
    for a in range(index.shape[0]):
        hand, forearm = index[a, 0], index[a, 1]
        flow = np.empty(3)
        for c in range(3):
            flow[c] = flow_m_s[hand, c] - linvel[hand, c]
        speed = math.sqrt(_dot3(flow, flow))
        if speed < MIN_FLOW_M_S:
            continue
        for c in range(3):
            flow_dir[c] = flow[c] / speed
        helpfulness = _dot3(flow_dir, desired)      # > 0: the drag on the hand pushes where we want to go
        strength = min(speed, 1.0)
        if palm and (helpfulness > 0.0 or palm_hindering):
            normal = _rotate_one(quat[hand], PALM_NORMAL_LOCAL)
            axes = _rotate_by_one(quat[forearm], wrist_axes[a])
            turning = _cross_rows(axes, normal)     # d(normal)/d(angle), one row per axis
            facing, along = _dot3(normal, flow_dir), _dot3(normal, desired)
            # A flat plate's pressure force lies along its normal, ~ facing*|facing|; its useful part is
            # that times the normal's component along the desired direction. Climb that thrust: the palm
            # faces the flow when the push helps and slices through it when it hinders.
            for k in range(2):
                # Summed here, not by BLAS (np.dot): its kernel, and so the last bit, depends on the CPU.
                toward_flow, toward_desired = _dot3(turning[k], flow_dir), _dot3(turning[k], desired)
                gradient = 2.0 * abs(facing) * along * toward_flow + facing * abs(facing) * toward_desired
                pull[index[a, 2 + k]] = palm_gain * strength * gradient
                limit[index[a, 2 + k]] = palm_limit
        if reach and (helpfulness > 0.0 or reach_hindering):
            pull[index[a, 4]] = -reach_gain * helpfulness * strength
            limit[index[a, 4]] = reach_limit
    fade = 1.0 - dt_s / RULE_MEMORY_S
    out = np.empty(n)
    for k in range(n):
        out[k] = _clip(previous[k] * fade + engagement * pull[k] * dt_s, -limit[k], limit[k])
    return out
