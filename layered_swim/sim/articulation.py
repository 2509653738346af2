"""Kinematics and rigid-body dynamics of the swimmer's joint tree, compiled.

The tree is PyBullet's multibody: a floating base and one joint per link (spherical or revolute),
frames as PyBullet keeps them (each body's frame at its centre of mass, axes parallel to its URDF
link frame). From the base state and the joint positions and rates this computes every body's
pose and velocity (what the fluid needs) and the joint-space mass matrix and bias forces (what
stable PD needs). PyBullet's own STABLE_PD_CONTROL rebuilds a second model of the body on every
call and costs more than a third of the whole step; this does the same maths in a few
microseconds.

Coordinates, as PyBullet's joint states report them: a spherical joint's position is the child's
orientation in the parent as a quaternion (x, y, z, w), its rate the child's angular velocity
relative to the parent in the child frame; a revolute joint has an angle about its axis. The base
rate is its world angular velocity, then its centre-of-mass velocity. Spatial vectors are
(angular; linear) in world axes about the base's centre of mass (a reference point near the
body keeps the products small wherever the swimmer is).
"""
from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from numba import njit

from layered_swim.geometry import quat_product_into, quat_to_rows

FREE, SPHERICAL, REVOLUTE = 0, 1, 2

# Columns of the per-body kinematics table ``frames`` (then the joint pivot, 22:25).
POS, QUAT, LINVEL, ANGVEL, ROT = slice(0, 3), slice(3, 7), slice(7, 10), slice(10, 13), slice(13, 22)
FRAME_COLUMNS = 25

_SIZES = {FREE: (7, 6), SPHERICAL: (4, 3), REVOLUTE: (1, 1)}   # positions, rates


@njit(cache=True, inline="always")
def _rate_count(kind):
    return 6 if kind == FREE else (3 if kind == SPHERICAL else 1)


@dataclass(frozen=True)
class Tree:
    """Body 0 is the base; body i > 0 hangs from ``parent[i] < i`` by PyBullet joint i - 1.
    Generalised positions: the base's position and quaternion (7), then each joint's in body
    order; rates: the base's angular velocity and velocity (6), then each joint's."""

    parent: np.ndarray           # (n,) int
    kind: np.ndarray             # (n,) FREE, SPHERICAL or REVOLUTE
    joint_in_parent_m: np.ndarray  # (n, 3) joint pivot in the parent's centre-of-mass frame
    com_in_joint_m: np.ndarray   # (n, 3) the body's centre of mass in its joint frame
    axis: np.ndarray             # (n, 3) a revolute joint's axis (unit, joint frame)
    mass_kg: np.ndarray          # (n,)
    inertia_kg_m2: np.ndarray    # (n, 3) principal moments about the centre of mass

    def __post_init__(self):
        q_at, dof_at, q, dof = [], [], 0, 0
        for kind in self.kind:
            q_at.append(q)
            dof_at.append(dof)
            q += _SIZES[int(kind)][0]
            dof += _SIZES[int(kind)][1]
        object.__setattr__(self, "_index", np.column_stack([self.parent, self.kind, q_at, dof_at]).astype(np.int64))
        object.__setattr__(self, "_params", np.ascontiguousarray(np.column_stack(
            [self.joint_in_parent_m, self.com_in_joint_m, self.axis, self.mass_kg, self.inertia_kg_m2]),
            dtype=np.float64))
        last = len(self.kind) - 1
        object.__setattr__(self, "_n_positions", q_at[last] + _SIZES[int(self.kind[last])][0])
        object.__setattr__(self, "_n_dof", dof_at[last] + _SIZES[int(self.kind[last])][1])

    @property
    def n_bodies(self) -> int:
        return len(self.parent)

    @property
    def n_positions(self) -> int:
        return self._n_positions

    @property
    def n_dof(self) -> int:
        return self._n_dof

    def positions_of(self, body: int) -> range:
        """Where body ``body``'s joint positions sit in the generalised positions."""
        start = int(self._index[body, 2])
        return range(start, start + _SIZES[int(self.kind[body])][0])

    def rates_of(self, body: int) -> range:
        start = int(self._index[body, 3])
        return range(start, start + _SIZES[int(self.kind[body])][1])

    @property
    def index(self) -> np.ndarray:
        """(n, 4) int: parent, kind, first position index, first rate index (packed for the kernels)."""
        return self._index

    @property
    def params(self) -> np.ndarray:
        """(n, 13): pivot in parent, centre of mass in joint frame, axis, mass, inertia (packed)."""
        return self._params


@njit(cache=True)
def forward_kinematics(index, params, q, qd, frames, subspace):
    """Fill ``frames`` (n, FRAME_COLUMNS): per body its centre of mass, orientation (x, y, z, w),
    velocity, angular velocity, rotation matrix (row-major) and joint pivot, all in world
    coordinates; and ``subspace`` (n_dof, 6): each rate's unit spatial motion about the base's
    centre of mass, which the dynamics and the generalised forces share. ``q``: the base's
    position and quaternion, then the joints'; ``qd``: the base's angular velocity and velocity,
    then the joints' rates."""
    frames[0, 0:7] = q[0:7]
    frames[0, 7:10] = qd[3:6]
    frames[0, 10:13] = qd[0:3]
    quat_to_rows(frames[0, 3:7], frames[0, 13:22], False)
    frames[0, 22:25] = q[0:3]
    rel = np.empty(4)
    w_rel = np.empty(3)
    for i in range(1, index.shape[0]):
        p, kind, qa, da = index[i, 0], index[i, 1], index[i, 2], index[i, 3]
        rp = frames[p, 13:22]
        # Joint pivot: the parent's centre of mass plus its rotated offset.
        for a in range(3):
            frames[i, 22 + a] = frames[p, a] + rp[3 * a] * params[i, 0] + rp[3 * a + 1] * params[i, 1] \
                + rp[3 * a + 2] * params[i, 2]
        if kind == SPHERICAL:
            rel[:] = q[qa:qa + 4]
            w_rel[:] = qd[da:da + 3]
        else:
            s, c = np.sin(0.5 * q[qa]), np.cos(0.5 * q[qa])
            for a in range(3):
                rel[a] = params[i, 6 + a] * s
                w_rel[a] = params[i, 6 + a] * qd[da]
            rel[3] = c
        quat_product_into(frames[p, 3:7], rel, frames[i, 3:7])
        quat_to_rows(frames[i, 3:7], frames[i, 13:22], False)
        r = frames[i, 13:22]
        for a in range(3):
            d = r[3 * a] * params[i, 3] + r[3 * a + 1] * params[i, 4] + r[3 * a + 2] * params[i, 5]
            frames[i, a] = frames[i, 22 + a] + d
            frames[i, 10 + a] = frames[p, 10 + a] + r[3 * a] * w_rel[0] + r[3 * a + 1] * w_rel[1] \
                + r[3 * a + 2] * w_rel[2]
        # Velocity: the pivot moves with the parent, the centre of mass turns about the pivot.
        wp, wi = frames[p, 10:13], frames[i, 10:13]
        ex = frames[i, 22] - frames[p, 0]
        ey = frames[i, 23] - frames[p, 1]
        ez = frames[i, 24] - frames[p, 2]
        dx = frames[i, 0] - frames[i, 22]
        dy = frames[i, 1] - frames[i, 23]
        dz = frames[i, 2] - frames[i, 24]
        frames[i, 7] = frames[p, 7] + wp[1] * ez - wp[2] * ey + wi[1] * dz - wi[2] * dy
        frames[i, 8] = frames[p, 8] + wp[2] * ex - wp[0] * ez + wi[2] * dx - wi[0] * dz
        frames[i, 9] = frames[p, 9] + wp[0] * ey - wp[1] * ex + wi[0] * dy - wi[1] * dx
    _motion_subspace(index, params, frames, subspace)


@njit(cache=True, inline="always")
def _cross(a, b, out):
    out[0] = a[1] * b[2] - a[2] * b[1]
    out[1] = a[2] * b[0] - a[0] * b[2]
    out[2] = a[0] * b[1] - a[1] * b[0]


@njit(cache=True)
def _spatial_inertia(m, c, rows, inertia, out):
    """6x6 spatial inertia (angular; linear) about the reference point of a body with mass m,
    centre of mass c (relative to the point), rotation ``rows`` and principal moments."""
    for a in range(3):
        for b in range(3):
            s = 0.0
            for k in range(3):
                s += rows[3 * a + k] * inertia[k] * rows[3 * b + k]
            out[a, b] = s
    cc = c[0] * c[0] + c[1] * c[1] + c[2] * c[2]
    for a in range(3):
        out[a, a] += m * cc
        for b in range(3):
            out[a, b] -= m * c[a] * c[b]
            out[a + 3, b] = 0.0
            out[a, b + 3] = 0.0
            out[a + 3, b + 3] = m if a == b else 0.0
    # m [c]x above right, its transpose below left.
    out[0, 4], out[0, 5], out[1, 5] = -m * c[2], m * c[1], -m * c[0]
    out[1, 3], out[2, 3], out[2, 4] = m * c[2], -m * c[1], m * c[0]
    out[4, 0], out[5, 0], out[5, 1] = -m * c[2], m * c[1], -m * c[0]
    out[3, 1], out[3, 2], out[4, 2] = m * c[2], -m * c[1], m * c[0]


@njit(cache=True)
def _motion_subspace(index, params, frames, s):
    s[0:6] = 0.0
    for k in range(6):
        s[k, k] = 1.0  # base: world angular velocity, then centre-of-mass velocity
    pivot = np.empty(3)
    for i in range(1, index.shape[0]):
        kind, da = index[i, 1], index[i, 3]
        r = frames[i, 13:22]
        for a in range(3):
            pivot[a] = frames[i, 22 + a] - frames[0, a]
        for k in range(_rate_count(kind)):
            row = s[da + k]
            for a in range(3):
                if kind == SPHERICAL:
                    row[a] = r[3 * a + k]  # the child's k-th axis
                else:
                    row[a] = r[3 * a] * params[i, 6] + r[3 * a + 1] * params[i, 7] + r[3 * a + 2] * params[i, 8]
            _cross(pivot, row[0:3], row[3:6])


@njit(cache=True, inline="always")
def _motion_cross(v, w, out):
    """out = v x w for spatial motions (angular; linear)."""
    out[0] = v[1] * w[2] - v[2] * w[1]
    out[1] = v[2] * w[0] - v[0] * w[2]
    out[2] = v[0] * w[1] - v[1] * w[0]
    out[3] = v[1] * w[5] - v[2] * w[4] + v[4] * w[2] - v[5] * w[1]
    out[4] = v[2] * w[3] - v[0] * w[5] + v[5] * w[0] - v[3] * w[2]
    out[5] = v[0] * w[4] - v[1] * w[3] + v[3] * w[1] - v[4] * w[0]


@njit(cache=True, inline="always")
def _force_cross(v, f, out):
    """out += v x* f for a spatial motion v and force f (moment; force)."""
    out[0] += v[1] * f[2] - v[2] * f[1] + v[4] * f[5] - v[5] * f[4]
    out[1] += v[2] * f[0] - v[0] * f[2] + v[5] * f[3] - v[3] * f[5]
    out[2] += v[0] * f[1] - v[1] * f[0] + v[3] * f[4] - v[4] * f[3]
    out[3] += v[1] * f[5] - v[2] * f[4]
    out[4] += v[2] * f[3] - v[0] * f[5]
    out[5] += v[0] * f[4] - v[1] * f[3]


@njit(cache=True, inline="always")
def _mat6_vec(m, v, out):
    for a in range(6):
        t = 0.0
        for b in range(6):
            t += m[a, b] * v[b]
        out[a] = t


@njit(cache=True)
def mass_matrix_and_bias(index, params, frames, s, gravity_m_s2):
    """Joint-space mass matrix M (n_dof, n_dof) and bias forces C (gravity, centrifugal and
    Coriolis) such that M qdd + C = generalised forces: the composite-rigid-body algorithm and
    recursive Newton-Euler with qdd = 0, all in one frame so no spatial transforms are needed.
    ``frames`` and the motion subspace ``s`` as ``forward_kinematics`` fills them."""
    n = index.shape[0]
    n_dof = s.shape[0]
    inertia = np.empty((n, 6, 6))
    vel = np.empty((n, 6))
    acc = np.empty((n, 6))
    force = np.empty((n, 6))
    c = np.empty(3)
    rel = np.empty(6)
    tmp = np.empty(6)
    for i in range(n):
        for a in range(3):
            c[a] = frames[i, a] - frames[0, a]
        _spatial_inertia(params[i, 9], c, frames[i, 13:22], params[i, 10:13], inertia[i])
        # Spatial velocity about the reference point: the body's spin and the velocity of the
        # material point at the reference, v - w x c.
        w = frames[i, 10:13]
        vel[i, 0:3] = w
        vel[i, 3] = frames[i, 7] - (w[1] * c[2] - w[2] * c[1])
        vel[i, 4] = frames[i, 8] - (w[2] * c[0] - w[0] * c[2])
        vel[i, 5] = frames[i, 9] - (w[0] * c[1] - w[1] * c[0])
        if i == 0:
            # The base's centre-of-mass velocity is fixed, but the reference point is not on it:
            # its material acceleration is v x w. Gravity enters as the base accelerating upwards.
            acc[0, 0:3] = 0.0
            _cross(frames[0, 7:10], w, acc[0, 3:6])
            acc[0, 5] += gravity_m_s2
        else:
            p = index[i, 0]
            for a in range(6):
                rel[a] = vel[i, a] - vel[p, a]
            _motion_cross(vel[i], rel, tmp)
            for a in range(6):
                acc[i, a] = acc[p, a] + tmp[a]
        _mat6_vec(inertia[i], acc[i], force[i])
        _mat6_vec(inertia[i], vel[i], tmp)
        _force_cross(vel[i], tmp, force[i])
    bias = np.empty(n_dof)
    mass = np.zeros((n_dof, n_dof))
    f = np.empty(6)
    for i in range(n - 1, -1, -1):
        kind, da, p = index[i, 1], index[i, 3], index[i, 0]
        for k in range(_rate_count(kind)):
            col = da + k
            t = 0.0
            for a in range(6):
                t += s[col, a] * force[i, a]
            bias[col] = t
            # The composite inertia of the subtree below i couples its rates with every ancestor's.
            _mat6_vec(inertia[i], s[col], f)
            j = i
            while j >= 0:
                dj = index[j, 3]
                for r in range(dj, dj + _rate_count(index[j, 1])):
                    t = 0.0
                    for a in range(6):
                        t += s[r, a] * f[a]
                    mass[r, col] = t
                    mass[col, r] = t
                j = index[j, 0]
        if p >= 0:
            for a in range(6):
                force[p, a] += force[i, a]
                for b in range(6):
                    inertia[p, a, b] += inertia[i, a, b]
    return mass, bias


@njit(cache=True)
def generalized_forces(index, frames, s, rows, force, torque, at):
    """The generalised forces (n_dof,) of a force (applied at ``at``) and a torque on each of the
    bodies ``rows`` (world frame): each rate feels the wrench of the whole subtree it carries.
    The base's six are the total moment about its centre of mass, then the total force.
    ``frames`` and the motion subspace ``s`` as ``forward_kinematics`` fills them."""
    n = index.shape[0]
    wrench = np.zeros((n, 6))
    for r in range(rows.shape[0]):
        i = rows[r]
        lx, ly, lz = at[r, 0] - frames[0, 0], at[r, 1] - frames[0, 1], at[r, 2] - frames[0, 2]
        fx, fy, fz = force[r, 0], force[r, 1], force[r, 2]
        wrench[i, 0] += torque[r, 0] + ly * fz - lz * fy
        wrench[i, 1] += torque[r, 1] + lz * fx - lx * fz
        wrench[i, 2] += torque[r, 2] + lx * fy - ly * fx
        wrench[i, 3] += fx
        wrench[i, 4] += fy
        wrench[i, 5] += fz
    out = np.empty(s.shape[0])
    for i in range(n - 1, -1, -1):
        kind, da, p = index[i, 1], index[i, 3], index[i, 0]
        for k in range(_rate_count(kind)):
            t = 0.0
            for a in range(6):
                t += s[da + k, a] * wrench[i, a]
            out[da + k] = t
        if p >= 0:
            for a in range(6):
                wrench[p, a] += wrench[i, a]
    return out


def parent_rates(index: np.ndarray) -> np.ndarray:
    """Each rate's parent rate in the tree (-1 for the base's first): the rate before it in its own
    joint, else its parent body's last. The mass matrix couples two rates only if one is the
    other's ancestor, which ``ltl_factor`` keeps to."""
    last = {}
    parent = []
    for i in range(index.shape[0]):
        p, kind, da = int(index[i, 0]), int(index[i, 1]), int(index[i, 3])
        count = 6 if kind == FREE else (3 if kind == SPHERICAL else 1)
        parent += [last[p] if p >= 0 else -1] + list(range(da, da + count - 1))
        last[i] = da + count - 1
    return np.array(parent, dtype=np.int64)


@njit(cache=True)
def ltl_factor(h, parent):
    """Factor the mass matrix in place as L^T L, L lower triangular with M's own sparsity
    (Featherstone's LTL: leaves first, no fill-in): a third of a dense Cholesky's work on this
    tree."""
    n = h.shape[0]
    for k in range(n - 1, -1, -1):
        h[k, k] = math.sqrt(h[k, k])
        i = parent[k]
        while i >= 0:
            h[k, i] /= h[k, k]
            i = parent[i]
        i = parent[k]
        while i >= 0:
            j = i
            while j >= 0:
                h[i, j] -= h[k, i] * h[k, j]
                j = parent[j]
            i = parent[i]


@njit(cache=True)
def ltl_solve(factor, parent, b):
    """x with L^T L x = b, ``factor`` from ``ltl_factor``."""
    n = b.shape[0]
    x = b.copy()
    for k in range(n - 1, -1, -1):       # L^T z = b
        x[k] /= factor[k, k]
        j = parent[k]
        while j >= 0:
            x[j] -= factor[k, j] * x[k]
            j = parent[j]
    for k in range(n):                   # L x = z
        j = parent[k]
        while j >= 0:
            x[k] -= factor[k, j] * x[j]
            j = parent[j]
        x[k] /= factor[k, k]
    return x
