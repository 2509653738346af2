"""What the policy sees (SWIM 2026, section 3.2), laid out by name: ``ObservationLayout`` says
which slice of the flat vector holds what, so nothing reads a bare index.

- body kinematics: the root's height, shoulder roll, linear and angular velocity; ten tracked
  links' positions and velocities relative to the root; every joint's position (ball joints as
  quaternions, hinges as angles) and rate. Directions are in the heading frame: the world turned
  by the swimmer's heading about z (SWIM works in the x-y plane).
- the stroke's phase, encoded as sin and cos of 2 pi k phase for k = 1, 2, 4.
- four intermediate goals (eqs. 1-3), each [x, y, |yaw|] in the heading frame.
- the water's wrenches on the body, one of SWIM's variants: NoEnv (none), TotalFT (the whole
  body's force and torque about its centre of mass), RawFT (per segment), SmoothFT (per segment,
  sign(h) log(1 + |h|) smoothed exponentially with w = 0.78, eq. 4).
"""
from __future__ import annotations

import math

import numpy as np
from numba import njit

from layered_swim.config import ConfigError

TRACKED_LINKS = ("head", "thorax", "forearm_l", "forearm_r", "hand_l", "hand_r", "shank_l", "shank_r",
                 "foot_l", "foot_r")
PHASE_FREQUENCIES = (1, 2, 4)
GOALS = 4
ENV_STATES = ("NoEnv", "TotalFT", "RawFT", "SmoothFT")
SMOOTH_W = 0.78


class ObservationLayout:
    """Ordered named parts of the observation vector and their slices."""

    def __init__(self, widths: dict[str, int]):
        self.slices, start = {}, 0
        for name, width in widths.items():
            self.slices[name] = slice(start, start + width)
            start += width
        self.size = start

    def part(self, observation: np.ndarray, name: str) -> np.ndarray:
        return observation[..., self.slices[name]]

    def describe(self) -> list[dict]:
        return [{"name": name, "start": s.start, "stop": s.stop} for name, s in self.slices.items()]


def layout_for(n_joint_positions: int, n_joint_rates: int, n_segments: int, env_state: str) -> ObservationLayout:
    if env_state not in ENV_STATES:
        raise ConfigError(f"env_state must be one of {', '.join(ENV_STATES)}, got {env_state!r}")
    links = len(TRACKED_LINKS)
    widths = {"root_height": 1, "root_roll": 1, "root_linvel": 3, "root_angvel": 3, "link_pos": 3 * links,
              "link_vel": 3 * links, "joint_pos": n_joint_positions, "joint_vel": n_joint_rates,
              "phase": 2 * len(PHASE_FREQUENCIES), "goals": 3 * GOALS}
    if env_state == "TotalFT":
        widths["env"] = 6
    elif env_state in ("RawFT", "SmoothFT"):
        widths["env"] = 6 * n_segments
    return ObservationLayout(widths)


def to_heading_frame(vectors: np.ndarray, heading_rad: float) -> np.ndarray:
    """World vectors (..., 3) turned by -heading about z."""
    v = np.asarray(vectors, float)
    return _turned(v.reshape(-1, 3), math.cos(heading_rad), math.sin(heading_rad)).reshape(v.shape)


@njit(cache=True)
def _turned(v, c, s):
    """Rows of ``v`` turned: numpy's elementwise arithmetic, compiled (five numpy calls on a few
    rows cost ~5 us, four times an environment step)."""
    out = np.empty((v.shape[0], 3))
    for i in range(v.shape[0]):
        x, y = v[i, 0], v[i, 1]
        out[i, 0] = c * x + s * y
        out[i, 1] = -s * x + c * y
        out[i, 2] = v[i, 2]
    return out


def phase_encoding(phase: float) -> np.ndarray:
    angles = 2.0 * math.pi * np.array(PHASE_FREQUENCIES) * (phase % 1.0)
    return np.concatenate([np.sin(angles), np.cos(angles)])


def local_goals(goals_m: np.ndarray, root_m: np.ndarray, heading_rad: float) -> tuple[np.ndarray, np.ndarray]:
    """Goals (k, 3) in the heading frame: [x, y, |yaw|] per goal (k, 3) and the signed yaws (k,)."""
    local = to_heading_frame(np.asarray(goals_m, float) - np.asarray(root_m, float), heading_rad)
    yaws = np.arctan2(local[:, 1], local[:, 0])
    return np.column_stack([local[:, 0], local[:, 1], np.abs(yaws)]), yaws


def squash(wrench: np.ndarray) -> np.ndarray:
    """Eq. 4's sign(h) log(1 + |h|)."""
    return np.sign(wrench) * np.log1p(np.abs(wrench))


def env_features(env_state: str, force_n: np.ndarray, torque_nm: np.ndarray, pos_m: np.ndarray, com_m: np.ndarray,
                 heading_rad: float, smoothed: np.ndarray | None) -> tuple[np.ndarray, np.ndarray | None]:
    """The water's part of the observation from per-segment forces and torques (world frame,
    torques about each segment's centre), and the smoothing state to keep for next time."""
    if env_state == "NoEnv":
        return np.zeros(0), None
    if env_state == "TotalFT":
        total_torque = torque_nm.sum(axis=0) + np.cross(pos_m - com_m, force_n).sum(axis=0)
        return to_heading_frame(np.stack([force_n.sum(axis=0), total_torque]), heading_rad).ravel(), None
    raw = np.concatenate([to_heading_frame(force_n, heading_rad), to_heading_frame(torque_nm, heading_rad)],
                         axis=1).ravel()
    if env_state == "RawFT":
        return raw, None
    now = squash(raw)
    smoothed = now if smoothed is None else (1.0 - SMOOTH_W) * smoothed + SMOOTH_W * now
    return smoothed, smoothed
