"""The one place that talks to PyBullet: one client per World, batched reads and writes.

A World owns the swimmer's multibody. Each physics step the simulation loop reads a
``BodyState`` (per-segment centre-of-mass pose and velocity), applies one external force and
torque per segment, sets the stable-PD targets and steps.

The per-step calls go to the ``pybullet`` functions with the World's own client id rather than
through ``BulletClient``: its attribute lookup builds a new partial per call, which cost about as
much as the 32 force calls themselves.
"""
from __future__ import annotations

import contextlib
import operator
import os
import sys
import tempfile
from dataclasses import dataclass
from itertools import chain
from pathlib import Path

import numpy as np

from layered_swim.body.model import Body
from layered_swim.body.urdf import write_urdf
from layered_swim.control.pose import JointLayout


@contextlib.contextmanager
def _pybullet_quiet():
    """PyBullet prints its build time and importer notes from C onto fds 1 and 2; keep them off a
    terminal. (A piped stdout buffers them in C until exit: the CLI guards that case itself.)"""
    sys.stdout.flush()
    sys.stderr.flush()
    saved = {fd: os.dup(fd) for fd in (1, 2)}
    with open(os.devnull, "w") as devnull:
        for fd in saved:
            os.dup2(devnull.fileno(), fd)
        try:
            yield
        finally:
            for fd, copy in saved.items():
                os.dup2(copy, fd)
                os.close(copy)


with _pybullet_quiet():
    import pybullet
    from pybullet_utils.bullet_client import BulletClient


# getLinkStates' fields: centre-of-mass position and orientation, world velocity and spin.
_COM_STATE = operator.itemgetter(0, 1, 6, 7)
_flatten = chain.from_iterable


@dataclass
class BodyState:
    """Per-segment centre-of-mass state, segment order of the Body (root first)."""

    time_s: float
    pos_m: np.ndarray          # (n, 3)
    quat_xyzw: np.ndarray      # (n, 4)
    linvel_m_s: np.ndarray     # (n, 3)
    angvel_rad_s: np.ndarray   # (n, 3)


class World:
    def __init__(self, body: Body, layout: JointLayout, physics_hz: float, gravity_m_s2: float = 9.81,
                 pd_gain_scale: dict[str, float] | None = None):
        self.body = body
        self.layout = layout
        self.dt_s = 1.0 / physics_hz
        self.steps = 0
        self.gravity_m_s2 = gravity_m_s2
        with _pybullet_quiet():
            self.client = BulletClient(connection_mode=pybullet.DIRECT)
            self.client.setGravity(0, 0, -gravity_m_s2)
            self.client.setTimeStep(self.dt_s)
            with tempfile.TemporaryDirectory() as tmp:
                urdf = write_urdf(body, Path(tmp) / f"{body.name}.urdf")
                self.uid = self.client.loadURDF(str(urdf), flags=pybullet.URDF_USE_INERTIA_FROM_FILE)
        self._cid = self.client._client
        c = self.client
        names = {c.getJointInfo(self.uid, j)[12].decode(): j for j in range(c.getNumJoints(self.uid))}
        joint_index = {c.getJointInfo(self.uid, j)[1].decode(): j for j in range(c.getNumJoints(self.uid))}
        self.segment_links = [-1] + [names[s] for s in body.segment_names[1:]]
        self._child_links = self.segment_links[1:]
        self._state_size = 13 * len(self.segment_links)
        for link in [-1, *range(c.getNumJoints(self.uid))]:
            # Open water: no contacts at all (collision shapes exist only for stable PD's sake).
            c.setCollisionFilterGroupMask(self.uid, link, 0, 0)
        for j in range(c.getNumJoints(self.uid)):
            if c.getJointInfo(self.uid, j)[2] == pybullet.JOINT_SPHERICAL:
                c.setJointMotorControlMultiDof(self.uid, j, pybullet.POSITION_CONTROL, targetPosition=[0, 0, 0, 1],
                                               targetVelocity=[0, 0, 0], force=[0, 0, 0])
            else:
                c.setJointMotorControl2(self.uid, j, pybullet.VELOCITY_CONTROL, force=0)

        self.motor_indices = [joint_index[name] for name in layout.motor_joint]
        scale = pd_gain_scale or {}
        kp, kd, force = [], [], []
        for motor_name, is_ball in zip(layout.motor_joint, layout.motor_is_ball):
            joint = next(j for j in body.joints if motor_name == j.name or motor_name.startswith(j.name + "_"))
            s = scale.get(joint.name, 1.0)
            kp.append(joint.kp * s)
            kd.append(joint.kd * s)
            force.append([joint.max_torque_nm] * (3 if is_ball else 1))
        self._kp, self._kd, self._force = kp, kd, force
        n_ball = len(layout.ball_slices)
        self._position_cuts = [(4 * b, 4 * b + 4) if b >= 0 else (4 * n_ball + k, 4 * n_ball + k + 1)
                               for b, k in zip(layout.motor_ball, layout.motor_coord)]
        self._velocity_cuts = [(3 * b, 3 * b + 3) if b >= 0 else (3 * n_ball + k, 3 * n_ball + k + 1)
                               for b, k in zip(layout.motor_ball, layout.motor_coord)]

    # --- state -------------------------------------------------------------------------
    def reset(self, root_pos_m, root_quat_xyzw, pose: np.ndarray, root_linvel_m_s=(0.0, 0.0, 0.0)) -> None:
        c = self.client
        c.resetBasePositionAndOrientation(self.uid, list(root_pos_m), list(root_quat_xyzw))
        c.resetBaseVelocity(self.uid, list(root_linvel_m_s), [0.0, 0.0, 0.0])
        quats = self.layout.ball_quaternions(pose)
        for m, joint in enumerate(self.motor_indices):
            if self.layout.motor_is_ball[m]:
                c.resetJointStateMultiDof(self.uid, joint, list(quats[self.layout.motor_ball[m]]), [0.0, 0.0, 0.0])
            else:
                c.resetJointState(self.uid, joint, float(pose[self.layout.motor_coord[m]]), 0.0)
        self.steps = 0

    @property
    def time_s(self) -> float:
        return self.steps * self.dt_s  # a product, not a running sum: no drift over long runs

    def read_state(self) -> BodyState:
        uid, cid = self.uid, self._cid
        base_pos, base_quat = pybullet.getBasePositionAndOrientation(uid, cid)
        base_lin, base_ang = pybullet.getBaseVelocity(uid, cid)
        # With velocities, and the kinematics recomputed: the cached link frames are stale after a step.
        links = pybullet.getLinkStates(uid, self._child_links, 1, 1, cid)
        # One flat pass into one array: per segment position, quaternion, velocity, spin.
        flat = chain(base_pos, base_quat, base_lin, base_ang, _flatten(_flatten(map(_COM_STATE, links))))
        table = np.fromiter(flat, np.float64, self._state_size).reshape(-1, 13)
        return BodyState(self.time_s, table[:, 0:3], table[:, 3:7], table[:, 7:10], table[:, 10:13])

    def joint_positions(self) -> np.ndarray:
        """Current pose as PyBullet reports it: ball joints as quaternions, hinges as angles,
        flattened motor by motor."""
        states = self.client.getJointStatesMultiDof(self.uid, self.motor_indices)
        return np.concatenate([s[0] for s in states])

    def enable_joint_torque_sensors(self) -> None:
        """Have every step compute the wrench each motor joint transmits (``joint_torques_and_rates``).
        Off by default: it costs a few per cent of the step."""
        c = self.client
        for joint in self.motor_indices:
            c.enableJointForceTorqueSensor(self.uid, joint, True)
        # The transmitted wrench comes about the child's centre of mass; the joint pivot is the
        # child link's origin. A hinge's torque is the wrench's part along its axis.
        com_m = np.array([c.getDynamicsInfo(self.uid, j)[3] for j in self.motor_indices])
        rows = []
        for m, (joint, is_ball) in enumerate(zip(self.motor_indices, self.layout.motor_is_ball)):
            axes = np.eye(3) if is_ball else np.array([c.getJointInfo(self.uid, joint)[13]])
            for axis in axes:
                row = np.zeros((len(self.motor_indices), 3))
                row[m] = axis
                rows.append(row.ravel())
        self._torque_com_m, self._torque_rows = com_m, np.array(rows)

    def joint_torques_and_rates(self) -> tuple[np.ndarray, np.ndarray]:
        """Torque each motor applied during the last step (N m) and the joint rates now (rad/s),
        flattened motor by motor as in ``joint_positions``: a ball joint's three components in the
        child frame, one value per hinge; their dot product is the joints' mechanical power.
        PyBullet reports no applied torque under STABLE_PD_CONTROL, so the torque is read from the
        joint's transmitted wrench (``enable_joint_torque_sensors`` first): a ball joint passes no
        torque but the motor's, and a hinge none about its axis but the motor's."""
        states = self.client.getJointStatesMultiDof(self.uid, self.motor_indices)
        wrench = np.array([s[2] for s in states])
        about_pivot = wrench[:, 3:] + np.cross(self._torque_com_m, wrench[:, :3])
        return self._torque_rows @ about_pivot.ravel(), np.concatenate([s[1] for s in states])

    # --- actions -----------------------------------------------------------------------
    def apply_wrenches(self, force_n: np.ndarray, torque_nm: np.ndarray, at_m: np.ndarray) -> None:
        """One force (at each segment's centre of mass ``at_m``) and one torque per segment, world frame."""
        uid, cid, frame = self.uid, self._cid, pybullet.WORLD_FRAME
        force, torque = pybullet.applyExternalForce, pybullet.applyExternalTorque
        # Positional arguments: PyBullet parses a keyword argument at a third of the call's cost.
        for link, f, t, p in zip(self.segment_links, force_n.tolist(), torque_nm.tolist(), at_m.tolist()):
            force(uid, link, f, p, frame, cid)
            torque(uid, link, t, frame, cid)

    def set_targets(self, pose: np.ndarray, rates: np.ndarray) -> None:
        """Convert a desired pose and its rates into PyBullet's per-motor targets (at control rate)."""
        quats, omegas = self.layout.ball_targets(pose, rates)
        # One list per kind, cut motor by motor (ball joints first in it, then every pose angle).
        positions = quats.ravel().tolist() + pose.tolist()
        velocities = omegas.ravel().tolist() + rates.tolist()
        self._targets = [positions[a:b] for a, b in self._position_cuts]
        self._velocities = [velocities[a:b] for a, b in self._velocity_cuts]

    def drive(self) -> None:
        """Stable PD toward the last targets. PyBullet computes the torque once per call and holds
        it, so this must be called before every physics step."""
        pybullet.setJointMotorControlMultiDofArray(
            self.uid, self.motor_indices, pybullet.STABLE_PD_CONTROL, targetPositions=self._targets,
            targetVelocities=self._velocities, positionGains=self._kp, velocityGains=self._kd, forces=self._force,
            physicsClientId=self._cid)

    def step(self) -> None:
        pybullet.stepSimulation(physicsClientId=self._cid)
        self.steps += 1

    def close(self) -> None:
        with contextlib.suppress(Exception):
            self.client.disconnect()
