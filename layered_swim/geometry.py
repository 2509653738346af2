"""Quaternions and vectors: the one place for rotation maths, numpy and compiled.

Quaternions are (x, y, z, w) throughout, as PyBullet reports them. The compiled routines write
into caller-owned arrays so the physics step's kernels (forward kinematics, plates, buoyancy,
ball-joint targets) allocate nothing per call.
"""
from __future__ import annotations

import math

import numpy as np
from numba import njit


def quat_multiply(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Hamilton product a * b of quaternions (..., 4)."""
    ax, ay, az, aw = np.moveaxis(a, -1, 0)
    bx, by, bz, bw = np.moveaxis(b, -1, 0)
    return np.stack([
        aw * bx + ax * bw + ay * bz - az * by,
        aw * by - ax * bz + ay * bw + az * bx,
        aw * bz + ax * by - ay * bx + az * bw,
        aw * bw - ax * bx - ay * by - az * bz,
    ], axis=-1)


def quat_rotate(q: np.ndarray, v: np.ndarray) -> np.ndarray:
    """Rotate vectors v (..., 3) by unit quaternions q (..., 4)."""
    if type(q) is np.ndarray and type(v) is np.ndarray and q.shape == (4,) and q.dtype == _F8 \
            and v.dtype == _F8 and v.ndim <= 2 and v.shape[-1] == 3:
        # One quaternion (the controller's per-step calls): compiled scalar maths, the same
        # operations in the same order as the general path below, so the same bits.
        return _rotate_by_one(q, v) if v.ndim == 2 else _rotate_one(q, v)
    u, w = q[..., :3], q[..., 3:4]
    t = 2.0 * np.cross(u, v)
    return v + w * t + np.cross(u, t)


def cross(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """``np.cross`` of 3-vectors (..., 3), bit for bit; compiled for a (3,) or (m, 3) ``a`` with a
    (3,) ``b`` in float64, where numpy's general routine costs tens of microseconds."""
    if type(a) is np.ndarray and type(b) is np.ndarray and b.shape == (3,) and a.dtype == _F8 \
            and b.dtype == _F8 and a.ndim <= 2 and a.shape[-1] == 3:
        return _cross_rows(a, b) if a.ndim == 2 else _cross_one(a, b)
    return np.cross(a, b)


_F8 = np.dtype(np.float64)


@njit(cache=True, inline="always")
def _rotate_into(q, v0, v1, v2, out):
    """out = (v0, v1, v2) rotated by unit quaternion q: ``quat_rotate``'s numpy expression
    (t = 2 u x v; v + w t + u x t) one operation at a time, each cross term a product minus a
    product as ``np.cross`` computes it."""
    ux, uy, uz, w = q[0], q[1], q[2], q[3]
    tx = 2.0 * (uy * v2 - uz * v1)
    ty = 2.0 * (uz * v0 - ux * v2)
    tz = 2.0 * (ux * v1 - uy * v0)
    out[0] = v0 + w * tx + (uy * tz - uz * ty)
    out[1] = v1 + w * ty + (uz * tx - ux * tz)
    out[2] = v2 + w * tz + (ux * ty - uy * tx)


@njit(cache=True)
def _rotate_one(q, v):
    out = np.empty(3)
    _rotate_into(q, v[0], v[1], v[2], out)
    return out


@njit(cache=True)
def _rotate_by_one(q, v):
    out = np.empty((v.shape[0], 3))
    for i in range(v.shape[0]):
        _rotate_into(q, v[i, 0], v[i, 1], v[i, 2], out[i])
    return out


@njit(cache=True)
def _cross_one(a, b):
    out = np.empty(3)
    out[0] = a[1] * b[2] - a[2] * b[1]
    out[1] = a[2] * b[0] - a[0] * b[2]
    out[2] = a[0] * b[1] - a[1] * b[0]
    return out


@njit(cache=True)
def _cross_rows(a, b):
    out = np.empty((a.shape[0], 3))
    for i in range(a.shape[0]):
        out[i, 0] = a[i, 1] * b[2] - a[i, 2] * b[1]
        out[i, 1] = a[i, 2] * b[0] - a[i, 0] * b[2]
        out[i, 2] = a[i, 0] * b[1] - a[i, 1] * b[0]
    return out


def ease(progress: float) -> float:
    """0 to 1 as ``progress`` goes 0 to 1, flat at both ends (smoothstep): a blend with no kink."""
    return progress * progress * (3.0 - 2.0 * progress)


def unit_vector(v: np.ndarray) -> np.ndarray:
    """``v`` scaled to length 1 (zero stays zero)."""
    # A float64 vector: np.linalg.norm's own sum (sqrt of v . v) without its checks.
    norm = math.sqrt(v.dot(v)) if type(v) is np.ndarray and v.ndim == 1 and v.dtype == _F8 \
        else float(np.linalg.norm(v))
    return v / norm if norm > 1e-9 else np.zeros_like(v)


@njit(cache=True, inline="always")
def quat_product_into(a, b, out):
    """out = a * b (Hamilton product), compiled, no temporaries."""
    out[0] = a[3] * b[0] + a[0] * b[3] + a[1] * b[2] - a[2] * b[1]
    out[1] = a[3] * b[1] - a[0] * b[2] + a[1] * b[3] + a[2] * b[0]
    out[2] = a[3] * b[2] + a[0] * b[1] - a[1] * b[0] + a[2] * b[3]
    out[3] = a[3] * b[3] - a[0] * b[0] - a[1] * b[1] - a[2] * b[2]


@njit(cache=True, inline="always")
def quat_to_rows(q, out, normalise):
    """Rotation matrix of quaternion q, row-major into out[0:9] (row r, column c at 3 r + c; the
    columns are the body axes in world coordinates). With ``normalise`` q need not be unit
    (the fluid kernels take quaternions from anywhere); without it q must be unit (the
    kinematics builds its own, a division less per body)."""
    x, y, z, w = q[0], q[1], q[2], q[3]
    s = 2.0 / (x * x + y * y + z * z + w * w) if normalise else 2.0
    out[0] = 1.0 - s * (y * y + z * z)
    out[1] = s * (x * y - z * w)
    out[2] = s * (x * z + y * w)
    out[3] = s * (x * y + z * w)
    out[4] = 1.0 - s * (x * x + z * z)
    out[5] = s * (y * z - x * w)
    out[6] = s * (x * z - y * w)
    out[7] = s * (y * z + x * w)
    out[8] = 1.0 - s * (x * x + y * y)


@njit(cache=True, inline="always")
def add_rotated_inverse(q, v0, v1, v2, out):
    """out += v rotated by the conjugate of unit quaternion q (no temporaries: this runs per joint
    per control step)."""
    ux, uy, uz, w = -q[0], -q[1], -q[2], q[3]
    tx = 2.0 * (uy * v2 - uz * v1)
    ty = 2.0 * (uz * v0 - ux * v2)
    tz = 2.0 * (ux * v1 - uy * v0)
    out[0] += v0 + w * tx + uy * tz - uz * ty
    out[1] += v1 + w * ty + uz * tx - ux * tz
    out[2] += v2 + w * tz + ux * ty - uy * tx
