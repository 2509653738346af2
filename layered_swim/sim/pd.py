"""Stable PD (Tan, Liu and Turk 2011), as PyBullet's STABLE_PD_CONTROL computes it.

The torque drives each joint to its target from where the joint will be one step ahead, with the damping
made implicit through the body's mass matrix:

    tau = Kp e + Kd (qd_target - qd - dt qdd),   e = target - (q + dt qd),
    qdd = (M + dt Kd)^-1 (Kp e + Kd (qd_target - qd) - C),

then clamped to each joint's maximum torque. M and C are the whole body's (floating base
included, with zero gains), so a light hand cannot be overdriven however stiff its gains: this
is what keeps high gains stable at 480 Hz. A ball joint's error is the rotation from its
predicted orientation to the target, as an axis times angle in the child frame.
"""
from __future__ import annotations

import math

import numpy as np
from numba import njit

from layered_swim.sim.articulation import SPHERICAL, generalized_forces, ltl_factor, ltl_solve, mass_matrix_and_bias


@njit(cache=True)
def cholesky_factor(a):
    """Factor symmetric positive definite ``a`` in place: its lower triangle becomes L, a = L L^T.
    Stable PD's solve when PyBullet steps the body (the bits such swims have always had); stepping
    itself it uses the tree's own factorisation (``articulation.ltl_factor``, ~20 % quicker here)."""
    n = a.shape[0]
    for j in range(n):
        d = a[j, j]
        for k in range(j):
            d -= a[j, k] * a[j, k]
        d = math.sqrt(d)
        a[j, j] = d
        for i in range(j + 1, n):
            s = a[i, j]
            for k in range(j):
                s -= a[i, k] * a[j, k]
            a[i, j] = s / d


@njit(cache=True)
def cholesky_substitute(factor, b):
    """Solve L L^T x = b with ``factor`` from ``cholesky_factor``."""
    n = factor.shape[0]
    x = b.copy()
    for i in range(n):
        for k in range(i):
            x[i] -= factor[i, k] * x[k]
        x[i] /= factor[i, i]
    for i in range(n - 1, -1, -1):
        for k in range(i + 1, n):
            x[i] -= factor[k, i] * x[k]
        x[i] /= factor[i, i]
    return x


@njit(cache=True)
def _ball_error(q, w_rel, dt, target, out):
    """Axis-angle (child frame) from orientation q (x, y, z, w) advanced by dt at child-frame rate
    w_rel, to ``target``; nothing below a micro-radian, as in PyBullet."""
    x, y, z, w = q[0], q[1], q[2], q[3]
    wx, wy, wz = w_rel[0], w_rel[1], w_rel[2]
    px = x + 0.5 * dt * (w * wx - z * wy + y * wz)
    py = y + 0.5 * dt * (z * wx + w * wy - x * wz)
    pz = z + 0.5 * dt * (-y * wx + x * wy + w * wz)
    pw = w - 0.5 * dt * (x * wx + y * wy + z * wz)
    norm = math.sqrt(px * px + py * py + pz * pz + pw * pw)
    px, py, pz, pw = -px / norm, -py / norm, -pz / norm, pw / norm  # conjugate of the prediction
    tx, ty, tz, tw = target[0], target[1], target[2], target[3]
    dx = pw * tx + px * tw + py * tz - pz * ty
    dy = pw * ty - px * tz + py * tw + pz * tx
    dz = pw * tz + px * ty - py * tx + pz * tw
    dw = pw * tw - px * tx - py * ty - pz * tz
    dw = min(1.0, max(-1.0, dw))
    sin_half = math.sqrt(1.0 - dw * dw)
    if sin_half <= 1e-6:
        out[:] = 0.0
        return
    angle = 2.0 * math.acos(dw)
    if angle > math.pi:
        angle -= 2.0 * math.pi  # the short way round
    out[0], out[1], out[2] = angle * dx / sin_half, angle * dy / sin_half, angle * dz / sin_half


@njit(cache=True)
def stable_pd_torques(mass, bias, index, q, qd, target_q, target_qd, gains, dt, parent):
    """Generalised forces (n_dof,), zero on the base's rates. ``mass`` and ``bias`` from
    ``mass_matrix_and_bias`` (``mass`` is used up: factorised in place); ``index`` the tree's
    (parent, kind, position index, rate index) table; ``q``, ``qd`` the generalised positions and
    rates, ``target_q``, ``target_qd`` laid out alike (their base entries unused); ``gains``
    (3, n_dof): Kp, Kd and maximum torque per rate, zero on the base's. ``parent``
    (``articulation.parent_rates``) solves with the tree's own factorisation; empty, with a dense
    Cholesky (the bits every swim stepped by PyBullet has had)."""
    n = qd.shape[0]
    kp, kd, limit = gains[0], gains[1], gains[2]
    error = np.zeros(n)
    for i in range(1, index.shape[0]):
        qa, da = index[i, 2], index[i, 3]
        if index[i, 1] == SPHERICAL:
            _ball_error(q[qa:qa + 4], qd[da:da + 3], dt, target_q[qa:qa + 4], error[da:da + 3])
        else:
            error[da] = target_q[qa] - (q[qa] + dt * qd[da])
    rhs = np.empty(n)
    for k in range(n):
        mass[k, k] += dt * kd[k]
        rhs[k] = kp[k] * error[k] + kd[k] * (target_qd[k] - qd[k]) - bias[k]
    if parent.shape[0] > 0:
        ltl_factor(mass, parent)
        qdd = ltl_solve(mass, parent, rhs)
    else:
        cholesky_factor(mass)
        qdd = cholesky_substitute(mass, rhs)
    tau = np.empty(n)
    for k in range(n):
        t = kp[k] * error[k] + kd[k] * (target_qd[k] - qd[k] - dt * qdd[k])
        tau[k] = min(limit[k], max(-limit[k], t))
    return tau


@njit(cache=True)
def loads_and_pd(index, params, frames, s, rows, force, torque, at, q, qd, target_q, target_qd, gains, dt,
                 gravity_m_s2, base_wrench, tau, total, mass_out, bias_out, parent):
    """One call for a physics step's joint-space loads: the generalised forces of one wrench per
    body (``articulation.generalized_forces``), the stable PD torques (``stable_pd_torques`` on
    ``articulation.mass_matrix_and_bias``) and their sum on the joints' rates (zero on the base's,
    whose wrench PyBullet takes apart). The same arithmetic as the three calls one by one: the
    same bits, a third of the call overhead. Writes the base's wrench (moment; force) into
    ``base_wrench`` (6,), the PD torques into ``tau`` and the joints' total into ``total``
    (n_dof,): arrays a call returns cost Python more than these kernels' own arithmetic; and, where
    ``mass_out`` is not empty, the mass matrix and bias forces into ``mass_out`` and ``bias_out``."""
    load = generalized_forces(index, frames, s, rows, force, torque, at)
    mass, bias = mass_matrix_and_bias(index, params, frames, s, gravity_m_s2)
    if mass_out.shape[0] > 0:       # stepping without PyBullet (``sim/integrator.py``) needs them after PD
        mass_out[:, :] = mass
        bias_out[:] = bias
    tau[:] = stable_pd_torques(mass, bias, index, q, qd, target_q, target_qd, gains, dt, parent)
    for k in range(tau.shape[0]):
        total[k] = (load[k] if k >= 6 else 0.0) + tau[k]
    base_wrench[:] = load[0:6]
