"""Records a simulation at a fixed log rate and writes ``log.npz`` and ``timeseries.csv``.

Pass the recorder to ``Episode.run(..., observers=[recorder])``. It is created right after the
episode's reset and takes the starting state as sample 0; sample k is the state after physics
step k * (physics_hz / log_hz). The fluid force logged with a state is the one applied during
the step that led to it (``buoyancy_force_n`` is its buoyancy part, NaN for a fluid backend that
cannot separate it); at sample 0 nothing has been applied or commanded yet, so the fluid forces
and the desired pose are NaN there.

With ``joint_work=True`` the recorder also integrates the joints' mechanical work every physics
step (torque times the mean of the joint rates before and after the step, which closes the
energy balance of the step) and logs the running total ``joint_work_j``; power over any window
is its difference over the window's duration. Power sampled at the log rate would be biased: the
PD torque jumps each time the controller sets new targets, a few physics steps apart.
"""
from __future__ import annotations

import hashlib
from pathlib import Path
from typing import Mapping

import numpy as np

from layered_swim.tasks.metrics import head_top_height_m
from layered_swim.config import ConfigError

DEFAULT_LOG_HZ = 60
# Arrays in the order the hash reads them; names come from the recorder, not the simulation.
ARRAY_NAMES = ("time_s", "root_pos_m", "root_quat_xyzw", "com_pos_m", "com_vel_m_s", "segment_pos_m",
               "segment_quat_xyzw", "joint_positions", "desired_pose_rad", "fluid_force_n", "buoyancy_force_n",
               "head_top_m")
OPTIONAL_ARRAY_NAMES = ("joint_work_j",)
CSV_COLUMNS = ("time_s", "pelvis_x_m", "pelvis_y_m", "pelvis_z_m", "com_speed_m_s", "head_top_m")


def joint_position_names(layout) -> tuple[str, ...]:
    """Column names of ``World.joint_positions()``: ball joints as quaternions, hinges as angles."""
    names = []
    for is_ball, coord, motor in zip(layout.motor_is_ball, layout.motor_coord, layout.motor_joint):
        names += [f"{motor}.q{c}" for c in "xyzw"] if is_ball else [layout.names[coord]]
    return tuple(names)


def log_hash(arrays: Mapping[str, np.ndarray]) -> str:
    """sha256 over name, dtype, shape and raw bytes of every logged array, in a fixed order."""
    digest = hashlib.sha256()
    for name in ARRAY_NAMES + tuple(n for n in OPTIONAL_ARRAY_NAMES if n in arrays):
        a = np.ascontiguousarray(arrays[name])
        digest.update(f"{name}|{a.dtype.str}|{a.shape}|".encode())
        digest.update(a.tobytes())
    return digest.hexdigest()


class Recorder:
    def __init__(self, sim, log_hz: int = DEFAULT_LOG_HZ, joint_work: bool = False):
        physics_hz = sim.config.physics_hz
        if log_hz <= 0 or physics_hz % log_hz:
            raise ConfigError(f"log rate {log_hz} Hz must divide the physics rate {physics_hz} Hz")
        self.every = physics_hz // log_hz
        self._physics_hz = physics_hz
        body = sim.body
        self.segment_names = body.segment_names
        self.joint_names = joint_position_names(sim.layout)
        self.pose_names = sim.layout.names
        self._head = body.index("head")
        self._head_half_z_m = float(body.half_extents_m[self._head, 2])
        self._rows: dict[str, list] = {name: [] for name in ARRAY_NAMES if name != "head_top_m"}
        self._work_j = None
        if joint_work:
            self._dt_s = 1.0 / physics_hz
            self._work_j, self._rates = 0.0, sim.world.joint_torques_and_rates()[1]
            self._rows["joint_work_j"] = []
        self._record(sim, fresh=True)

    def __call__(self, sim) -> None:
        if self._work_j is not None:
            torque, rates = sim.world.joint_torques_and_rates()
            self._work_j += self._dt_s * float(torque @ (0.5 * (rates + self._rates)))
            self._rates = rates
        if sim.steps % self.every == 0:
            self._record(sim, fresh=False)

    def _record(self, sim, fresh: bool) -> None:
        s, rows = sim.state, self._rows
        rows["time_s"].append(sim.steps / self._physics_hz)   # exact, unlike a running sum of dt
        rows["root_pos_m"].append(s.pos_m[0])
        rows["root_quat_xyzw"].append(s.quat_xyzw[0])
        rows["com_pos_m"].append(s.com_m)
        rows["com_vel_m_s"].append(s.com_vel_m_s)
        rows["segment_pos_m"].append(s.pos_m)
        rows["segment_quat_xyzw"].append(s.quat_xyzw)
        rows["joint_positions"].append(sim.world.joint_positions())
        rows["desired_pose_rad"].append(np.full(len(self.pose_names), np.nan) if fresh else sim.desired_pose.copy())
        fluid = sim.fluid_now
        rows["fluid_force_n"].append(np.full_like(s.pos_m, np.nan) if fresh else fluid.force_n.copy())
        buoyancy = None if fresh else fluid.buoyancy_force_n
        rows["buoyancy_force_n"].append(np.full_like(s.pos_m, np.nan) if buoyancy is None else buoyancy.copy())
        if self._work_j is not None:
            rows["joint_work_j"].append(self._work_j)

    def arrays(self) -> dict[str, np.ndarray]:
        out = {name: np.array(rows, dtype=float) for name, rows in self._rows.items()}
        out["head_top_m"] = head_top_height_m(out["segment_pos_m"][:, self._head],
                                              out["segment_quat_xyzw"][:, self._head], self._head_half_z_m)
        return {name: out[name] for name in ARRAY_NAMES + OPTIONAL_ARRAY_NAMES if name in out}

    def log_hash(self) -> str:
        return log_hash(self.arrays())

    def save(self, out_dir: str | Path) -> None:
        """Write ``log.npz`` (every array plus the name lists) and ``timeseries.csv``."""
        out_dir = Path(out_dir)
        a = self.arrays()
        np.savez_compressed(out_dir / "log.npz", **a, segment_names=np.array(self.segment_names),
                            joint_names=np.array(self.joint_names), pose_names=np.array(self.pose_names))
        table = np.column_stack([a["time_s"], a["root_pos_m"], np.linalg.norm(a["com_vel_m_s"], axis=1),
                                 a["head_top_m"]])
        np.savetxt(out_dir / "timeseries.csv", table, fmt="%.6f", delimiter=",", header=",".join(CSV_COLUMNS),
                   comments="")
