"""The physics step without PyBullet: the same integration its multibody does, compiled.

PyBullet's step of a floating multibody with no contacts is: the accelerations of the applied
generalised forces, ``M qdd = Q - C``; the rates moved on by ``dt qdd``; each revolute joint at or
past a limit pushed back by an impulse through the mass matrix (its joint-limit constraint: a row
only while the limit is passed, whose rate is driven to ``erp`` of the excess a step, or only
stopped past Bullet's split-impulse depth; projected Gauss-Seidel); then the positions moved on by
the new rates (semi-implicit Euler), orientations by the exponential map. ``articulation`` already
gives ``M`` and ``C`` (stable PD needs them), so a step here costs one factorisation of ``M`` (the
tree's own, ``ltl_factor``) and a solve: a few microseconds against PyBullet's ~15 plus its state
reads and torque writes. From the same state it lands on PyBullet's next state to rounding, and to
~1e-6 where a joint sits on its limit (``tests/test_integrator.py``); over seconds the two drift
apart as chaotic swims do, without changing how the swimmer swims.

What it does not do: contacts (an SPH pool's walls), so a World with walls steps in PyBullet.
"""
from __future__ import annotations

import math

import numpy as np
from numba import njit

from layered_swim.geometry import quat_product_into
from layered_swim.sim.articulation import SPHERICAL, forward_kinematics, ltl_factor, ltl_solve
from layered_swim.sim.pd import loads_and_pd

LIMIT_ERP = 0.2             # PyBullet's error reduction for joint limits (its default erp)
LIMIT_ITERATIONS = 50       # its solver's iterations (numSolverIterations)
SPLIT_DEPTH = 0.04          # its split impulse's penetration threshold (m_splitImpulsePenetrationThreshold)
_MAX_TURN_RAD = 0.25 * math.pi   # most a body may turn in one step (Bullet's ANGULAR_MOTION_THRESHOLD)


@njit(cache=True, inline="always")
def _turn(omega0, omega1, omega2, dt, out):
    """The unit quaternion (x, y, z, w) of turning at ``omega`` for ``dt`` (Bullet's exponential
    map: a Taylor series near zero, the turn capped)."""
    angle = math.sqrt(omega0 * omega0 + omega1 * omega1 + omega2 * omega2)
    if angle * dt > _MAX_TURN_RAD:
        angle = _MAX_TURN_RAD / dt
    if angle < 0.001:
        scale = 0.5 * dt - dt * dt * dt * 0.020833333333 * angle * angle
    else:
        scale = math.sin(0.5 * angle * dt) / angle
    out[0], out[1], out[2], out[3] = omega0 * scale, omega1 * scale, omega2 * scale, math.cos(0.5 * angle * dt)


@njit(cache=True, inline="always")
def _turned_by(a, b, out):
    """out = a * b (``geometry.quat_product_into``), scaled back to unit length."""
    quat_product_into(a, b, out)
    norm = math.sqrt(out[0] * out[0] + out[1] * out[1] + out[2] * out[2] + out[3] * out[3])
    for k in range(4):
        out[k] = out[k] / norm


@njit(cache=True)
def _push_back_limits(factor, parent, q, qd, dt, limits, erp):
    """Impulses on the joints past a limit (``limits`` rows: rate index, position index, lower,
    upper), each at least zero, that bring each one's rate to ``erp`` of its excess per step
    back inside; they act through the whole body's inverse mass matrix."""
    n_rows = 0
    for r in range(limits.shape[0]):
        p = q[int(limits[r, 1])]
        if p <= limits[r, 2] or p >= limits[r, 3]:
            n_rows += 1
    if n_rows == 0:
        return
    rate = np.empty(n_rows, np.int64)
    sign = np.empty(n_rows)
    wanted = np.empty(n_rows)
    columns = np.empty((n_rows, qd.shape[0]))
    k = 0
    for r in range(limits.shape[0]):
        p = q[int(limits[r, 1])]
        if p <= limits[r, 2] or p >= limits[r, 3]:
            rate[k] = int(limits[r, 0])
            sign[k] = 1.0 if p <= limits[r, 2] else -1.0
            excess = limits[r, 2] - p if p <= limits[r, 2] else p - limits[r, 3]
            # Past its split-impulse depth Bullet corrects the position apart from the rate: the
            # rate is only stopped.
            wanted[k] = erp * excess / dt if excess < SPLIT_DEPTH else 0.0
            unit = np.zeros(qd.shape[0])
            unit[rate[k]] = 1.0
            columns[k] = ltl_solve(factor, parent, unit)
            k += 1
    impulse = np.zeros(n_rows)
    for _ in range(LIMIT_ITERATIONS):
        moved = False
        for k in range(n_rows):
            j = rate[k]
            step = (wanted[k] - sign[k] * qd[j]) / columns[k, j]
            new = max(0.0, impulse[k] + step)
            if new != impulse[k]:
                change = sign[k] * (new - impulse[k])
                for a in range(qd.shape[0]):
                    qd[a] += columns[k, a] * change
                impulse[k] = new
                moved = True
        if not moved:
            break


@njit(cache=True)
def advance(index, parent, mass, bias, load, q, qd, dt, limits, erp):
    """One step on, in place: ``q``, ``qd`` the generalised positions and rates (``articulation.Tree``'s
    layout), ``mass`` and ``bias`` (used up) from ``articulation.mass_matrix_and_bias`` at this
    state, ``load`` the generalised forces (the base's wrench, then the joints' torques);
    ``parent`` from ``parent_rates``."""
    n = qd.shape[0]
    rhs = np.empty(n)
    for k in range(n):
        rhs[k] = load[k] - bias[k]
    ltl_factor(mass, parent)
    qdd = ltl_solve(mass, parent, rhs)
    for k in range(n):
        qd[k] += dt * qdd[k]
    _push_back_limits(mass, parent, q, qd, dt, limits, erp)
    turn = np.empty(4)
    for a in range(3):
        q[a] += dt * qd[3 + a]
    _turn(qd[0], qd[1], qd[2], dt, turn)     # the base's rate is its world angular velocity: turned first
    _turned_by(turn, q[3:7].copy(), q[3:7])
    for i in range(1, index.shape[0]):
        qa, da = index[i, 2], index[i, 3]
        if index[i, 1] == SPHERICAL:          # the child's rate in its own frame: turned last
            _turn(qd[da], qd[da + 1], qd[da + 2], dt, turn)
            _turned_by(q[qa:qa + 4].copy(), turn, q[qa:qa + 4])
        else:
            q[qa] += dt * qd[da]


@njit(cache=True)
def drive_and_advance(index, parent, params, frames, s, rows, force, torque, at, q, qd, target_q, target_qd, gains, dt,
                      gravity_m_s2, base_wrench, tau, total, mass, bias, limits, erp):
    """A whole physics step in one call: the loads and stable PD (``pd.loads_and_pd``, its arguments
    and outputs), the step on (``advance``) and the new state's kinematics into ``frames`` and
    ``s`` (``articulation.forward_kinematics``)."""
    loads_and_pd(index, params, frames, s, rows, force, torque, at, q, qd, target_q, target_qd, gains, dt,
                 gravity_m_s2, base_wrench, tau, total, mass, bias, parent)
    total[0:6] = base_wrench
    advance(index, parent, mass, bias, total, q, qd, dt, limits, erp)
    forward_kinematics(index, params, q, qd, frames, s)
