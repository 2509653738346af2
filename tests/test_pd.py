"""Stable PD alone (no gravity, no fluid) brings the joints to a target pose."""
import numpy as np

from layered_swim.body.model import load_body
from layered_swim.control.pose import joint_layout
from layered_swim.sim.simulation import UPRIGHT_QUAT_XYZW
from layered_swim.sim.world import World

PHYSICS_HZ = 480


def test_pd_reaches_elbow_and_shoulder_targets():
    body = load_body()
    layout = joint_layout(body)
    target = layout.zeros()
    for side in ("l", "r"):
        target[layout.index(f"elbow_{side}.flexion")] = np.radians(90.0)
        target[layout.index(f"shoulder_{side}.flexion")] = np.radians(45.0)
    world = World(body, layout, PHYSICS_HZ, gravity_m_s2=0.0)
    try:
        world.reset((0.0, 0.0, 0.0), UPRIGHT_QUAT_XYZW, layout.zeros())
        world.set_targets(target, np.zeros_like(target))
        for _ in range(PHYSICS_HZ):   # 1 s
            world.drive()
            world.step()
        joints = world.joint_positions()
    finally:
        world.close()

    column = 0
    ball_quats = layout.ball_quaternions(target)
    for m, is_ball in enumerate(layout.motor_is_ball):
        name = layout.motor_joint[m]
        if is_ball:
            actual = joints[column:column + 4]
            wanted = ball_quats[layout.motor_ball[m]]
            error_deg = np.degrees(2 * np.arccos(min(1.0, abs(np.dot(wanted, actual)))))   # |q1.q2| = cos(angle/2)
            assert error_deg < 2.0, f"{name}: {error_deg:.2f} deg from target"
            column += 4
        else:
            error_deg = abs(np.degrees(joints[column] - target[layout.motor_coord[m]]))
            assert error_deg < 1.0, f"{name}: {error_deg:.2f} deg from target"
            column += 1
    assert column == len(joints)
