"""Poses as flat vectors of named joint-axis angles, and their conversion to PD targets.

A pose is one angle (rad) per joint axis, in the body's joint order: ``shoulder_l.flexion``,
``shoulder_l.abduction``, ... Layers add offsets to this vector; ``clamp`` keeps it inside the
ranges of motion. Ball joints turn into quaternions (intrinsic composition of their axes, in
file order), hinges and the two hinges of a two-axis joint stay angles.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numba import njit

from layered_swim.body.model import Body


def quat_multiply(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    ax, ay, az, aw = np.moveaxis(a, -1, 0)
    bx, by, bz, bw = np.moveaxis(b, -1, 0)
    return np.stack([
        aw * bx + ax * bw + ay * bz - az * by,
        aw * by - ax * bz + ay * bw + az * bx,
        aw * bz + ax * by - ay * bx + az * bw,
        aw * bw - ax * bx - ay * by - az * bz,
    ], axis=-1)


def unit_vector(v: np.ndarray) -> np.ndarray:
    """``v`` scaled to length 1 (zero stays zero)."""
    norm = float(np.linalg.norm(v))
    return v / norm if norm > 1e-9 else np.zeros_like(v)


def quat_rotate(q: np.ndarray, v: np.ndarray) -> np.ndarray:
    """Rotate vectors v (..., 3) by unit quaternions q (..., 4)."""
    u, w = q[..., :3], q[..., 3:4]
    t = 2.0 * np.cross(u, v)
    return v + w * t + np.cross(u, t)


@dataclass(frozen=True)
class JointLayout:
    """Where each joint's angles sit in a pose vector, and their ranges."""

    names: tuple[str, ...]           # "joint.axis" per coordinate
    lower_rad: np.ndarray
    upper_rad: np.ndarray
    ball_slices: tuple[slice, ...]   # three coordinates each
    ball_axes: np.ndarray            # (n_ball, 3, 3)
    ball_coords: np.ndarray          # (n_ball, 3) pose indices of each ball joint's angles
    motor_is_ball: tuple[bool, ...]  # one entry per PyBullet motor (ball joint or hinge)
    motor_coord: tuple[int, ...]     # first pose coordinate of each motor
    motor_ball: tuple[int, ...]      # index into the ball arrays, -1 for hinges
    motor_joint: tuple[str, ...]     # PyBullet joint name of each motor

    @property
    def size(self) -> int:
        return len(self.names)

    def index(self, name: str) -> int:
        try:
            return self.names.index(name)
        except ValueError:
            raise KeyError(name) from None

    def zeros(self) -> np.ndarray:
        return np.zeros(self.size)

    def clamp(self, pose: np.ndarray) -> np.ndarray:
        return np.clip(pose, self.lower_rad, self.upper_rad)

    def ball_targets(self, pose: np.ndarray, rates: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Ball joints' child-in-parent quaternions (n_ball, 4) and child-frame angular
        velocities (n_ball, 3) for a pose and its rates."""
        return _ball_targets(pose, rates, self.ball_coords, self.ball_axes)

    def ball_quaternions(self, pose: np.ndarray) -> np.ndarray:
        return self.ball_targets(pose, np.zeros_like(pose))[0]


@njit(cache=True, inline="always")
def _quat_mul(a, b, out):
    out[0] = a[3] * b[0] + a[0] * b[3] + a[1] * b[2] - a[2] * b[1]
    out[1] = a[3] * b[1] - a[0] * b[2] + a[1] * b[3] + a[2] * b[0]
    out[2] = a[3] * b[2] + a[0] * b[1] - a[1] * b[0] + a[2] * b[3]
    out[3] = a[3] * b[3] - a[0] * b[0] - a[1] * b[1] - a[2] * b[2]


@njit(cache=True, inline="always")
def _add_rotated_inverse(q, v0, v1, v2, out):
    """out += v rotated by the conjugate of unit quaternion q (no temporaries: this runs per joint
    per control step)."""
    ux, uy, uz, w = -q[0], -q[1], -q[2], q[3]
    tx = 2.0 * (uy * v2 - uz * v1)
    ty = 2.0 * (uz * v0 - ux * v2)
    tz = 2.0 * (ux * v1 - uy * v0)
    out[0] += v0 + w * tx + uy * tz - uz * ty
    out[1] += v1 + w * ty + uz * tx - ux * tz
    out[2] += v2 + w * tz + ux * ty - uy * tx


@njit(cache=True)
def _ball_targets(pose, rates, coords, axes):
    n = coords.shape[0]
    quats = np.empty((n, 4))
    omegas = np.zeros((n, 3))
    parts = np.empty((3, 4))
    r23 = np.empty(4)
    for j in range(n):
        for k in range(3):
            h = 0.5 * pose[coords[j, k]]
            sin_h = np.sin(h)
            for i in range(3):
                parts[k, i] = axes[j, k, i] * sin_h
            parts[k, 3] = np.cos(h)
        _quat_mul(parts[1], parts[2], r23)
        _quat_mul(parts[0], r23, quats[j])
        # Intrinsic chain R1 R2 R3: in the child frame axis k is seen through the later rotations.
        r0, r1, r2 = rates[coords[j, 0]], rates[coords[j, 1]], rates[coords[j, 2]]
        for i in range(3):
            omegas[j, i] = axes[j, 2, i] * r2
        _add_rotated_inverse(parts[2], axes[j, 1, 0] * r1, axes[j, 1, 1] * r1, axes[j, 1, 2] * r1, omegas[j])
        _add_rotated_inverse(r23, axes[j, 0, 0] * r0, axes[j, 0, 1] * r0, axes[j, 0, 2] * r0, omegas[j])
    return quats, omegas


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
