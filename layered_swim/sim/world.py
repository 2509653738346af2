"""The one place that talks to PyBullet: one client per World, batched reads and writes.

A World owns the swimmer's multibody. Each physics step the simulation loop reads a
``BodyState`` (per-segment centre-of-mass pose and velocity), applies one external force and
torque per segment, drives the joints with stable PD and steps.

The state is read as joint positions and rates (one batched call) and turned into segment poses
by our own compiled forward kinematics, which also gives the mass matrix that stable PD needs.
PyBullet's STABLE_PD_CONTROL builds a second model of the body and solves it on every call, more
than a third of the whole step; ``layered_swim.sim.pd`` computes the same torques (tested
against it) and PyBullet only applies them.

With ``integrator="own"`` the World steps the body itself (``layered_swim.sim.integrator``: the
same integration as PyBullet's, from the mass matrix stable PD already has) and PyBullet only
loads and places the body: no state reads, torque writes or PyBullet steps per step.

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
from itertools import chain
from pathlib import Path

import numpy as np
from numba import njit

from layered_swim.body.model import Body
from layered_swim.body.urdf import write_urdf
from layered_swim.sim.articulation import (
    ANGVEL,
    FRAME_COLUMNS,
    FREE,
    LINVEL,
    POS,
    QUAT,
    REVOLUTE,
    SPHERICAL,
    Tree,
    forward_kinematics,
    generalized_forces,
    mass_matrix_and_bias,
    parent_rates,
)
from layered_swim.sim.integrator import LIMIT_ERP, advance, drive_and_advance
from layered_swim.sim.pd import loads_and_pd, stable_pd_torques
from layered_swim.state import BodyState, JointLayout


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


# getJointStatesMultiDof's fields: position, rate.
_JOINT_POSITION, _JOINT_RATE = operator.itemgetter(0), operator.itemgetter(1)
_flatten = chain.from_iterable


def _tree(client, uid: int) -> Tree:
    """PyBullet's own view of the loaded body: joint frames, axes, masses and inertias."""
    parent, kind, pivot, com, axis = [-1], [FREE], [(0.0, 0.0, 0.0)], [(0.0, 0.0, 0.0)], [(0.0, 0.0, 0.0)]
    base = client.getDynamicsInfo(uid, -1)
    mass, inertia, frames = [base[0]], [base[2]], [base[4]]
    for j in range(client.getNumJoints(uid)):
        info, dynamics = client.getJointInfo(uid, j), client.getDynamicsInfo(uid, j)
        parent.append(info[16] + 1)
        kind.append(SPHERICAL if info[2] == pybullet.JOINT_SPHERICAL else REVOLUTE)
        pivot.append(info[14])
        axis.append(info[13])
        com.append(dynamics[3])
        mass.append(dynamics[0])
        inertia.append(dynamics[2])
        frames += [info[15], dynamics[4]]
    # The URDF never turns a joint or inertial frame (see body/urdf.py); the kinematics relies on it.
    if not np.allclose(frames, (0.0, 0.0, 0.0, 1.0)):
        raise ValueError("the body's URDF turns a joint or inertial frame; forward kinematics assumes it does not")
    return Tree(np.array(parent), np.array(kind), np.array(pivot, dtype=float), np.array(com, dtype=float),
                np.array(axis, dtype=float), np.array(mass, dtype=float), np.array(inertia, dtype=float))


INTEGRATORS = ("bullet", "own")


@njit(cache=True)
def _scatter(into, at, source, first, then):
    """``into[at] = concatenate([first, then])[source]``, without building the concatenation
    (at control rate)."""
    n_first = first.shape[0]
    for m in range(at.shape[0]):
        k = source[m]
        into[at[m]] = first[k] if k < n_first else then[k - n_first]


class World:
    def __init__(self, body: Body, layout: JointLayout, physics_hz: float, gravity_m_s2: float,
                 pd_gain_scale: dict[str, float] | None = None, integrator: str = "bullet"):
        """``integrator``: ``bullet`` (PyBullet steps the body) or ``own`` (``sim/integrator.py``;
        it has no contacts, so while a pool's walls stand PyBullet steps the body anyway)."""
        if integrator not in INTEGRATORS:
            raise ValueError(f"integrator must be one of {', '.join(INTEGRATORS)}, got {integrator!r}")
        self.integrator = integrator
        self.own = integrator == "own"      # stepping itself now (not while walls stand)
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
        n_joints = c.getNumJoints(self.uid)
        names = {c.getJointInfo(self.uid, j)[12].decode(): j for j in range(n_joints)}
        joint_index = {c.getJointInfo(self.uid, j)[1].decode(): j for j in range(n_joints)}
        self.segments = body.segments
        self.segment_links = [-1] + [names[s] for s in body.segment_names[1:]]
        for link in [-1, *range(n_joints)]:
            c.setCollisionFilterGroupMask(self.uid, link, 0, 0)   # open water: no contacts at all
            # PyBullet damps every link's velocity over the ground (0.04 by default): a drag the water
            # does not exert, which also made a uniform current change the speed through the water.
            c.changeDynamics(self.uid, link, linearDamping=0.0, angularDamping=0.0)
        # PyBullet's default joint motors would fight the PD torques: switch them off.
        for j in range(n_joints):
            if c.getJointInfo(self.uid, j)[2] == pybullet.JOINT_SPHERICAL:
                c.setJointMotorControlMultiDof(self.uid, j, pybullet.POSITION_CONTROL, targetPosition=[0, 0, 0, 1],
                                               targetVelocity=[0, 0, 0], force=[0, 0, 0])
            else:
                c.setJointMotorControl2(self.uid, j, pybullet.VELOCITY_CONTROL, force=0)

        self.tree = _tree(c, self.uid)
        tree = self.tree
        self._joints = list(range(n_joints))   # tree body j + 1 hangs from joint j
        self._segment_rows = np.array(self.segment_links) + 1
        self._frames = np.zeros((tree.n_bodies, FRAME_COLUMNS))
        self._subspace = np.zeros((tree.n_dof, 6))
        self._state_size = tree.n_positions + tree.n_dof
        self._fresh = False
        # Where each joint's positions and rates sit in the generalised vectors, and per motor
        # where its targets sit in the flat lists ``set_targets`` builds (ball joints first, then
        # every pose angle: see JointLayout).
        joint_q = [tree.positions_of(j + 1) for j in self._joints]
        joint_qd = [tree.rates_of(j + 1) for j in self._joints]
        self._torque_cuts = [(r.start, r.stop) for r in joint_qd]
        n_ball = len(layout.ball_slices)
        scale = pd_gain_scale or {}
        gains = np.zeros((3, tree.n_dof))
        q_at, q_from, qd_at, qd_from = [], [], [], []
        self.motor_indices = [joint_index[name] for name in layout.motor_joint]
        for m, (motor_name, index) in enumerate(zip(layout.motor_joint, self.motor_indices)):
            joint = next(j for j in body.joints if motor_name == j.name or motor_name.startswith(j.name + "_"))
            s = scale.get(joint.name, 1.0)
            b, k = layout.motor_ball[m], layout.motor_coord[m]
            q_at += joint_q[index]
            q_from += range(4 * b, 4 * b + 4) if b >= 0 else [4 * n_ball + k]
            qd_at += joint_qd[index]
            qd_from += range(3 * b, 3 * b + 3) if b >= 0 else [3 * n_ball + k]
            gains[:, joint_qd[index]] = np.array([[joint.kp * s], [joint.kd * s], [joint.max_torque_nm]])
        self._gains = gains
        self._q_at, self._q_from = np.array(q_at), np.array(q_from)
        self._qd_at, self._qd_from = np.array(qd_at), np.array(qd_from)
        self._target_q = np.zeros(tree.n_positions)
        self._target_qd = np.zeros(tree.n_dof)
        self._torque = np.zeros(tree.n_dof)      # the PD torques of the last step
        self._total = np.zeros(tree.n_dof)       # the step's joint loads, written in place each step
        self._base_wrench = np.zeros(6)
        self._pending: np.ndarray | None = None   # generalised forces for the next step: PD and wrenches
        # Stepping itself: the mass matrix and bias forces that stable PD computed for this state
        # (kept, since PD uses its copy up), and each revolute joint's limits (rate index, position
        # index, lower, upper) as PyBullet's URDF importer makes them (lower <= upper).
        self._dynamics_fresh = False
        self._mass, self._bias = np.zeros((tree.n_dof, tree.n_dof)), np.zeros(tree.n_dof)
        self._no_mass, self._no_bias = np.zeros((0, 0)), np.zeros(0)     # stepped by PyBullet: not kept
        self._no_parent = np.zeros(0, dtype=np.int64)     # stepped by PyBullet: stable PD's dense solve, its old bits
        limits = []
        for j in self._joints:
            info = c.getJointInfo(self.uid, j)
            if info[2] == pybullet.JOINT_REVOLUTE and info[8] <= info[9]:
                limits.append((tree.rates_of(j + 1).start, tree.positions_of(j + 1).start, info[8], info[9]))
        self._limits = np.array(limits, dtype=np.float64).reshape(-1, 4)
        self._parent_rates = parent_rates(tree.index)
        self._walls: list[int] = []                # static bodies of a pool the swimmer touches

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
        self._torque[:] = 0.0
        self._pending = None
        self._fresh = False
        self._dynamics_fresh = False
        if self.own:      # from here on the World holds the coordinates itself
            self._hold_coordinates()

    def set_pool(self, min_m, max_m, thickness_m: float = 0.1) -> None:
        """A floor and four walls on the faces of the box ``[min_m, max_m]`` that the swimmer
        touches (an SPH pool: water the body pushed through them would leave it); open water
        again when ``min_m`` is None."""
        c = self.client
        for uid in self._walls:
            c.removeBody(uid)
        self._walls = []
        touching = min_m is not None
        own = self.integrator == "own" and not touching
        if own and not self.own:        # on from PyBullet's state
            self._hold_coordinates()
        elif self.own and not own:      # PyBullet on from ours
            self._write_coordinates()
        self.own, self._fresh = own, False
        for link in [-1, *self._joints]:
            c.setCollisionFilterGroupMask(self.uid, link, int(touching), 2 * int(touching))
        if not touching:
            return
        lo, hi = np.asarray(min_m, float), np.asarray(max_m, float)
        centre, half = (lo + hi) / 2, (hi - lo) / 2
        slabs = [(centre - [0, 0, half[2] + thickness_m / 2], [half[0] + thickness_m, half[1] + thickness_m,
                                                               thickness_m / 2])]
        for axis in (0, 1):
            for side in (-1, 1):
                offset, extent = np.zeros(3), half + thickness_m
                offset[axis] = side * (half[axis] + thickness_m / 2)
                extent[axis] = thickness_m / 2
                slabs.append((centre + offset, extent))
        for at, extent in slabs:
            shape = c.createCollisionShape(pybullet.GEOM_BOX, halfExtents=list(extent))
            uid = c.createMultiBody(baseMass=0.0, baseCollisionShapeIndex=shape, basePosition=list(at))
            c.setCollisionFilterGroupMask(uid, -1, 2, 1)
            self._walls.append(uid)

    @property
    def time_s(self) -> float:
        return self.steps * self.dt_s  # a product, not a running sum: no drift over long runs

    def _read_coordinates(self) -> None:
        uid, cid, tree = self.uid, self._cid, self.tree
        base_pos, base_quat = pybullet.getBasePositionAndOrientation(uid, cid)
        base_lin, base_ang = pybullet.getBaseVelocity(uid, cid)
        joints = pybullet.getJointStatesMultiDof(uid, self._joints, cid)
        # One flat pass into the generalised positions, then rates (see articulation.Tree).
        flat = np.fromiter(chain(base_pos, base_quat, _flatten(map(_JOINT_POSITION, joints)), base_ang, base_lin,
                                 _flatten(map(_JOINT_RATE, joints))), np.float64, self._state_size)
        self._q, self._qd = flat[:tree.n_positions], flat[tree.n_positions:]

    def _hold_coordinates(self) -> None:
        """PyBullet's state as the World's own arrays, and the step's arguments around them (the
        per-step call passes them as they are)."""
        self._read_coordinates()
        self._q, self._qd = self._q.copy(), self._qd.copy()
        tree = self.tree
        self._step_head = (tree.index, self._parent_rates, tree.params, self._frames, self._subspace,
                           self._segment_rows)
        self._step_tail = (self._q, self._qd, self._target_q, self._target_qd, self._gains, self.dt_s,
                           self.gravity_m_s2, self._base_wrench, self._torque, self._total, self._mass, self._bias,
                           self._limits, LIMIT_ERP)

    def _write_coordinates(self) -> None:
        uid, cid, q, qd = self.uid, self._cid, self._q, self._qd
        pybullet.resetBasePositionAndOrientation(uid, q[0:3].tolist(), q[3:7].tolist(), cid)
        pybullet.resetBaseVelocity(uid, qd[3:6].tolist(), qd[0:3].tolist(), cid)
        for j in self._joints:
            at, rates = self.tree.positions_of(j + 1), self.tree.rates_of(j + 1)
            pybullet.resetJointStateMultiDof(uid, j, q[at.start:at.stop].tolist(), qd[rates.start:rates.stop].tolist(),
                                             physicsClientId=cid)

    def read_state(self) -> BodyState:
        tree = self.tree
        if not self.own:
            self._read_coordinates()
        if not (self.own and self._fresh):      # stepping itself, the step left the kinematics fresh
            forward_kinematics(tree.index, tree.params, self._q, self._qd, self._frames, self._subspace)
        self._fresh = True
        segments = self._frames[self._segment_rows]
        return BodyState(self.time_s, segments[:, POS], segments[:, QUAT], segments[:, LINVEL], segments[:, ANGVEL],
                         self.segments)

    def _ensure_fresh(self) -> None:
        if not self._fresh:
            self.read_state()

    def kinematics(self) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
        """The generalised positions and rates now (see ``articulation.Tree``), every body's frame
        and the rates' motion subspace (``articulation.forward_kinematics``); valid until the next step."""
        self._ensure_fresh()
        return self._q, self._qd, self._frames, self._subspace

    def joint_positions(self) -> np.ndarray:
        """Current pose as PyBullet reports it: ball joints as quaternions, hinges as angles,
        flattened motor by motor."""
        self._ensure_fresh()
        return self._q[self._q_at]

    def joint_torques_and_rates(self) -> tuple[np.ndarray, np.ndarray]:
        """Torque each motor applied during the last step (N m) and the joint rates now (rad/s),
        flattened motor by motor as in ``joint_positions``: a ball joint's three components in the
        child frame, one value per hinge; their dot product is the joints' mechanical power."""
        self._ensure_fresh()
        return self._torque[self._qd_at], self._qd[self._qd_at]

    # --- actions -----------------------------------------------------------------------
    def apply_wrenches(self, force_n: np.ndarray, torque_nm: np.ndarray, at_m: np.ndarray) -> None:
        """One force (at ``at_m``, each segment's centre of mass) and one torque per segment, world
        frame, for the next step. They go in as the generalised forces they make: the base's as a
        base wrench, the joints' added to the motor torques. (PyBullet's per-link external force
        would take its lever arm from link frames it updates only when asked, at a cost.)"""
        self._ensure_fresh()
        load = generalized_forces(self.tree.index, self._frames, self._subspace, self._segment_rows, force_n,
                                  torque_nm, at_m)
        if self.own:
            self._add_pending(load)
            return
        uid, cid, frame = self.uid, self._cid, pybullet.WORLD_FRAME
        pybullet.applyExternalForce(uid, -1, load[3:6].tolist(), self._q[0:3].tolist(), frame, cid)
        pybullet.applyExternalTorque(uid, -1, load[0:3].tolist(), frame, cid)
        load[0:6] = 0.0
        self._add_pending(load)

    def drive_with_wrenches(self, force_n: np.ndarray, torque_nm: np.ndarray, at_m: np.ndarray) -> None:
        """``apply_wrenches`` then ``drive``, in one compiled call (the simulation's every step):
        the same loads to the same bits."""
        self._ensure_fresh()
        tree = self.tree
        base, total = self._base_wrench, self._total
        loads_and_pd(tree.index, tree.params, self._frames, self._subspace, self._segment_rows, force_n, torque_nm,
                     at_m, self._q, self._qd, self._target_q, self._target_qd, self._gains, self.dt_s,
                     self.gravity_m_s2, base, self._torque, total,
                     *((self._mass, self._bias, self._parent_rates) if self.own else
                       (self._no_mass, self._no_bias, self._no_parent)))
        if self.own:
            self._dynamics_fresh = True
            total[0:6] = base
            self._add_pending(total)
            return
        uid, cid, frame = self.uid, self._cid, pybullet.WORLD_FRAME
        wrench = base.tolist()
        pybullet.applyExternalForce(uid, -1, wrench[3:6], self._q[0:3].tolist(), frame, cid)
        pybullet.applyExternalTorque(uid, -1, wrench[0:3], frame, cid)
        self._add_pending(total)

    def drive_and_step(self, force_n: np.ndarray, torque_nm: np.ndarray, at_m: np.ndarray) -> None:
        """``drive_with_wrenches`` then ``step``: with the own integrator, one compiled call that
        also leaves the new state's kinematics ready for ``read_state``."""
        if not self.own or self._pending is not None:
            self.drive_with_wrenches(force_n, torque_nm, at_m)
            self.step()
            return
        self._ensure_fresh()
        drive_and_advance(*self._step_head, force_n, torque_nm, at_m, *self._step_tail)
        self.steps += 1
        self._fresh, self._dynamics_fresh = True, False

    def set_targets(self, pose: np.ndarray, rates: np.ndarray) -> None:
        """Convert a desired pose and its rates into the joints' targets (at control rate)."""
        quats, omegas = self.layout.ball_targets(pose, rates)
        _scatter(self._target_q, self._q_at, self._q_from, quats.ravel(), pose)
        _scatter(self._target_qd, self._qd_at, self._qd_from, omegas.ravel(), rates)

    def drive(self) -> None:
        """Stable PD toward the last targets from the current state: the torques hold for the
        next step only, so this must be called before every physics step."""
        self._ensure_fresh()
        tree = self.tree
        mass, bias = mass_matrix_and_bias(tree.index, tree.params, self._frames, self._subspace, self.gravity_m_s2)
        if self.own:
            self._mass[:], self._bias[:] = mass, bias
            self._dynamics_fresh = True
        self._torque[:] = stable_pd_torques(mass, bias, tree.index, self._q, self._qd, self._target_q, self._target_qd,
                                            self._gains, self.dt_s, self._parent_rates if self.own else self._no_parent)
        self._add_pending(self._torque)

    def _add_pending(self, generalised: np.ndarray) -> None:
        self._pending = generalised if self._pending is None else self._pending + generalised

    def step(self) -> None:
        if self.own:
            self._step_own()
            return
        if self._pending is not None:
            # All joint torques in one call; PyBullet clears them after the step.
            flat = self._pending.tolist()
            pybullet.setJointMotorControlMultiDofArray(self.uid, self._joints, pybullet.TORQUE_CONTROL,
                                                       forces=[flat[a:b] for a, b in self._torque_cuts],
                                                       physicsClientId=self._cid)
            self._pending = None
        pybullet.stepSimulation(physicsClientId=self._cid)
        self.steps += 1
        self._fresh = False

    def _step_own(self) -> None:
        self._ensure_fresh()
        tree = self.tree
        if not self._dynamics_fresh:
            self._mass[:], self._bias[:] = mass_matrix_and_bias(tree.index, tree.params, self._frames, self._subspace,
                                                                self.gravity_m_s2)
        load = self._pending if self._pending is not None else np.zeros(tree.n_dof)
        advance(tree.index, self._parent_rates, self._mass, self._bias, load, self._q, self._qd, self.dt_s,
                self._limits, LIMIT_ERP)
        self._pending = None
        self.steps += 1
        self._fresh = self._dynamics_fresh = False

    def step_bullet(self) -> None:
        """PyBullet's own step of the body and nothing else: the floor ``bench`` measures against
        (stepping itself, the World's state stays where it was; a ``reset`` puts both together)."""
        pybullet.stepSimulation(physicsClientId=self._cid)
        self._fresh = self._fresh and self.own

    def close(self) -> None:
        with contextlib.suppress(Exception):
            self.client.disconnect()
