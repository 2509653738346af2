"""Stable PD: alone (no gravity, no fluid) it brings the joints to a target pose; it computes
what PyBullet's STABLE_PD_CONTROL computes."""
import numpy as np
import pybullet
import pytest

from layered_swim.body.layout import joint_layout
from layered_swim.body.model import load_body
from layered_swim.episode import Episode
from layered_swim.geometry import quat_multiply
from layered_swim.sim.pd import _ball_error
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


def test_ball_error_is_the_short_rotation_in_the_child_frame():
    error = np.empty(3)
    quarter_z = np.array([0.0, 0.0, np.sin(np.pi / 4), np.cos(np.pi / 4)])
    _ball_error(np.array([0.0, 0.0, 0.0, 1.0]), np.zeros(3), 1.0 / PHYSICS_HZ, quarter_z, error)
    np.testing.assert_allclose(error, [0.0, 0.0, np.pi / 2], atol=1e-12)
    _ball_error(quarter_z, np.zeros(3), 1.0 / PHYSICS_HZ, -quarter_z, error)   # the same orientation
    np.testing.assert_allclose(error, 0.0, atol=1e-12)
    # Tipped 90 deg about x first, the same world turn about z is about the child's y.
    tipped = np.array([np.sin(np.pi / 4), 0.0, 0.0, np.cos(np.pi / 4)])
    _ball_error(tipped, np.zeros(3), 1.0 / PHYSICS_HZ, quat_multiply(quarter_z, tipped), error)
    np.testing.assert_allclose(error, [0.0, np.pi / 2, 0.0], atol=1e-12)
    # Spinning toward the target at 1 rad/s, one step of the error is already gone.
    _ball_error(np.array([0.0, 0.0, 0.0, 1.0]), np.array([0.0, 0.0, 1.0]), 1.0 / PHYSICS_HZ, quarter_z, error)
    assert error[2] == pytest.approx(np.pi / 2 - 1.0 / PHYSICS_HZ, abs=1e-9)


def test_stable_pd_matches_pybullets():
    """Our stable PD drives the swimming body as PyBullet's STABLE_PD_CONTROL would, to a few
    parts in a million of one step's change in the joint rates."""
    episode = Episode("front_crawl", integrator="bullet")   # checked against PyBullet's own step
    sim = episode.sim
    try:
        episode.run(1.3)
        world, tree = sim.world, sim.world.tree
        before = world.kinematics()[1].copy()
        target_q, target_qd, gains = world._target_q, world._target_qd, world._gains
        positions, rates, kp, kd, limit = [], [], [], [], []
        for j in world._joints:
            at, rate = tree.positions_of(j + 1), tree.rates_of(j + 1)
            positions.append(target_q[at].tolist())
            rates.append(target_qd[rate].tolist())
            kp.append(gains[0, rate.start])
            kd.append(gains[1, rate.start])
            limit.append(gains[2, rate].tolist())
        saved = world.client.saveState()
        world.drive()
        world.step()
        ours = world.kinematics()[1].copy()
        world.client.restoreState(saved)
        world.read_state()
        pybullet.setJointMotorControlMultiDofArray(
            world.uid, world._joints, pybullet.STABLE_PD_CONTROL, targetPositions=positions, targetVelocities=rates,
            positionGains=kp, velocityGains=kd, forces=limit, physicsClientId=world._cid)
        world.step()
        theirs = world.kinematics()[1].copy()
    finally:
        sim.close()
    change = np.abs(theirs - before).max()
    assert change > 0.1
    assert np.abs(ours - theirs).max() < 1e-5 * change
