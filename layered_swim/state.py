"""Plain data every room shares: the body's state and the pose vector's layout. No PyBullet.

``BodyState`` is what one physics step reads (per-segment centre-of-mass pose and velocity);
``Segments`` names the segments and weighs them, so code asks for ``state.quat("thorax")`` and
``state.com_m`` instead of counting rows. ``JointLayout`` says where each joint's angles sit in
a pose vector (one angle per joint axis, ``shoulder_l.flexion`` ...) and turns a pose into the
ball joints' quaternion targets.
"""
from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
from numba import njit

from layered_swim.geometry import add_rotated_inverse, quat_product_into


@dataclass(frozen=True)
class Segments:
    """The body's segments by name (root first) and each one's share of the boxes' mass."""

    names: tuple[str, ...]
    mass_fraction: np.ndarray
    rows: dict[str, int] = field(init=False, repr=False, compare=False)

    def __post_init__(self):
        object.__setattr__(self, "rows", {name: i for i, name in enumerate(self.names)})

    def index(self, name: str) -> int:
        try:
            return self.rows[name]
        except KeyError:
            raise KeyError(f"no segment named {name!r}") from None

    def centre_of_mass(self, per_segment: np.ndarray) -> np.ndarray:
        """The mass-weighted mean of per-segment vectors (n, 3) or a log of them (t, n, 3):
        the whole body's centre-of-mass position or velocity."""
        return self.mass_fraction @ per_segment


@dataclass(slots=True)
class BodyState:
    """Per-segment centre-of-mass state, in the segment order of ``segments`` (root first)."""

    time_s: float
    pos_m: np.ndarray          # (n, 3)
    quat_xyzw: np.ndarray      # (n, 4)
    linvel_m_s: np.ndarray     # (n, 3)
    angvel_rad_s: np.ndarray   # (n, 3)
    segments: Segments
    # The centre of mass, worked out on first asking (the controller, observation and reward each
    # ask it every control step); a state is a snapshot, its arrays never change after it is made.
    _com_m: np.ndarray | None = field(default=None, init=False, repr=False, compare=False)

    def pos(self, segment: str) -> np.ndarray:
        return self.pos_m[self.segments.rows[segment]]

    def quat(self, segment: str) -> np.ndarray:
        return self.quat_xyzw[self.segments.rows[segment]]

    @property
    def com_m(self) -> np.ndarray:
        if self._com_m is None:
            self._com_m = self.segments.centre_of_mass(self.pos_m)
        return self._com_m

    @property
    def com_vel_m_s(self) -> np.ndarray:
        return self.segments.centre_of_mass(self.linvel_m_s)


def lying(posture: str) -> bool:
    """Prone and supine strokes swim along the body's long axis; upright ones do not travel."""
    return posture != "upright"


@dataclass(frozen=True)
class Start:
    """Where and how a swim starts: posture (``prone`` lies face down heading +x, ``supine`` face
    up heading +x, ``upright`` stands), pelvis depth, forward speed, heading (rad, from +x toward
    +y) and position."""

    posture: str = "prone"
    depth_m: float = 0.1
    speed_m_s: float = 0.0
    heading_rad: float = 0.0
    position_xy_m: tuple[float, float] = (0.0, 0.0)


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
        return _clipped(pose, self.lower_rad, self.upper_rad)

    def ball_targets(self, pose: np.ndarray, rates: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Ball joints' child-in-parent quaternions (n_ball, 4) and child-frame angular
        velocities (n_ball, 3) for a pose and its rates."""
        return _ball_targets(pose, rates, self.ball_coords, self.ball_axes)

    def ball_quaternions(self, pose: np.ndarray) -> np.ndarray:
        return self.ball_targets(pose, np.zeros_like(pose))[0]


@njit(cache=True)
def _clipped(x, low, high):
    """``np.clip(x, low, high)`` for (n,) float arrays, compiled (twice a control step): numpy's own
    rule, a NaN kept and a tie going to the bound, so the same bits."""
    out = np.empty(x.shape[0])
    for k in range(x.shape[0]):
        v = x[k] if (x[k] > low[k] or x[k] != x[k]) else low[k]
        out[k] = v if (v < high[k] or v != v) else high[k]
    return out


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
        quat_product_into(parts[1], parts[2], r23)
        quat_product_into(parts[0], r23, quats[j])
        # Intrinsic chain R1 R2 R3: in the child frame axis k is seen through the later rotations.
        r0, r1, r2 = rates[coords[j, 0]], rates[coords[j, 1]], rates[coords[j, 2]]
        for i in range(3):
            omegas[j, i] = axes[j, 2, i] * r2
        add_rotated_inverse(parts[2], axes[j, 1, 0] * r1, axes[j, 1, 1] * r1, axes[j, 1, 2] * r1, omegas[j])
        add_rotated_inverse(r23, axes[j, 0, 0] * r0, axes[j, 0, 1] * r0, axes[j, 0, 2] * r0, omegas[j])
    return quats, omegas
