"""The pose vector's layout for a body: one angle per joint axis, in the body's joint order.

Ball joints turn into quaternions (intrinsic composition of their axes, in file order), hinges and
the two hinges of a two-axis joint stay angles; ``JointLayout`` (``layered_swim/state.py``) keeps
where each sits and what PyBullet motor drives it.
"""
from __future__ import annotations

import numpy as np

from layered_swim.body.model import Body
from layered_swim.state import JointLayout


def joint_layout(body: Body) -> JointLayout:
    from layered_swim.body.urdf import axis_joint_name  # the URDF names PyBullet reports

    names, lower, upper = [], [], []
    ball_slices, ball_axes = [], []
    motor_is_ball, motor_coord, motor_ball, motor_joint = [], [], [], []
    for joint in body.joints:
        start = len(names)
        names += [f"{joint.name}.{axis}" for axis in joint.axis_names]
        lower += list(joint.lower_rad)
        upper += list(joint.upper_rad)
        if joint.type == "ball":
            motor_is_ball.append(True)
            motor_coord.append(start)
            motor_ball.append(len(ball_slices))
            motor_joint.append(joint.name)
            ball_slices.append(slice(start, start + 3))
            ball_axes.append(joint.axes)
        elif joint.type == "hinge":
            motor_is_ball.append(False)
            motor_coord.append(start)
            motor_ball.append(-1)
            motor_joint.append(joint.name)
        else:
            for k, axis in enumerate(joint.axis_names):
                motor_is_ball.append(False)
                motor_coord.append(start + k)
                motor_ball.append(-1)
                motor_joint.append(axis_joint_name(joint.name, axis))
    return JointLayout(
        names=tuple(names), lower_rad=np.array(lower), upper_rad=np.array(upper),
        ball_slices=tuple(ball_slices), ball_axes=np.array(ball_axes),
        ball_coords=np.array([[s.start, s.start + 1, s.start + 2] for s in ball_slices], dtype=np.int64),
        motor_is_ball=tuple(motor_is_ball), motor_coord=tuple(motor_coord),
        motor_ball=tuple(motor_ball), motor_joint=tuple(motor_joint),
    )
