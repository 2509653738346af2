"""A run folder's swim as every exporter sees it: the body's joint tree and, frame by frame at
the export's rate, the pelvis's position and each segment's rotation relative to its parent.

Frames are the body's link frames (as in its URDF): each sits at the joint to its parent, with
axes parallel to the world's at the zero ("standing") pose, so a joint's offset is the body
file's ``joint_at_m`` and a segment's box (its centre of mass) sits at ``center_m`` in it. The log
holds world poses of the centres of mass; the link frames and parent-relative rotations are
derived here, and the log is checked to agree with the body file first.
"""
from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import numpy as np
from scipy.spatial.transform import Rotation, Slerp

from layered_swim.body.model import Body, load_body
from layered_swim.config import ConfigError, load_json
from layered_swim.recorder import read_log

MATCH_TOLERANCE_M = 1e-4     # the log's joints may sit this far from where the body file puts them


@dataclass(frozen=True)
class Skeleton:
    names: tuple[str, ...]          # parents before children, the root first
    parents: tuple[int, ...]        # each segment's parent index, -1 for the root
    offset_m: np.ndarray            # (S, 3) the joint in the parent's link frame (the root's: zero)
    center_m: np.ndarray            # (S, 3) the box centre (centre of mass) in the segment's link frame
    half_extents_m: np.ndarray      # (S, 3) the box
    euler_axes: np.ndarray          # (S, 3) link-frame axes (0 x, 1 y, 2 z) in the order the joint turns

    def children(self, segment: int) -> list[int]:
        return [i for i, parent in enumerate(self.parents) if parent == segment]


@dataclass(frozen=True)
class Motion:
    skeleton: Skeleton
    fps: int
    start_s: float                  # the run's time at frame 0 (its first log sample)
    root_pos_m: np.ndarray          # (F, 3) the pelvis link frame's origin, world frame (z up)
    local_quat_xyzw: np.ndarray     # (F, S, 4) each segment relative to its parent (the root: to the world)
    source: str                     # the run folder
    partial: bool                   # from the chunks of a run that was stopped

    @property
    def frames(self) -> int:
        return len(self.root_pos_m)


# The root turns freely: heading (z) first, then x, then y, whose lock (y vertical: lying on one
# side) a swimmer reaches more rarely than prone, supine or upright.
ROOT_EULER_AXES = (2, 0, 1)


def skeleton(body: Body) -> Skeleton:
    names = body.segment_names
    offsets, axes = np.zeros((len(names), 3)), np.tile(ROOT_EULER_AXES, (len(names), 1))
    for joint in body.joints:
        i = names.index(joint.child)
        offsets[i] = joint.joint_at_m
        # The joint's own axes first (its anatomical order), the rest after.
        own = list(dict.fromkeys(int(np.argmax(np.abs(a))) for a in joint.axes))
        axes[i] = own + [a for a in range(3) if a not in own]
    return Skeleton(names, tuple(-1 if p is None else names.index(p) for p in body.parents), offsets,
                    body.center_m.copy(), body.half_extents_m.copy(), axes)


def load_motion(run_dir: str | Path, fps: int) -> Motion:
    """The run folder's swim (``log.npz``, or a stopped run's ``log.partial/``) at ``fps``."""
    log = read_log(run_dir)
    body = _body(Path(run_dir))
    if tuple(log["segment_names"]) != body.segment_names:
        raise ConfigError(f"{run_dir}: the log's segments are not those of its body file {body.source}")
    bones = skeleton(body)
    world = Rotation.from_quat(log["segment_quat_xyzw"].reshape(-1, 4))
    shape = log["segment_quat_xyzw"].shape
    origin_m = log["segment_pos_m"] - world.apply(np.tile(bones.center_m, (shape[0], 1))).reshape(shape[:2] + (3,))
    world_quat = world.as_quat().reshape(shape)
    _check_joints(bones, origin_m, world_quat, run_dir, body.source)
    local = world_quat.copy()
    for i, parent in enumerate(bones.parents):
        if parent >= 0:
            turn = Rotation.from_quat(world_quat[:, parent]).inv() * Rotation.from_quat(world_quat[:, i])
            local[:, i] = turn.as_quat()
    times_s = _frame_times(log["time_s"], fps)
    return Motion(bones, fps, float(log["time_s"][0]), _lerp(log["time_s"], origin_m[:, 0], times_s),
                  _slerp(log["time_s"], local, times_s), str(run_dir), bool(log["partial"]))


def _body(run_dir: Path) -> Body:
    """The body the run swam: its config.json's ``body_file``, else (no config.json, or a file
    since moved: another install) the packaged one; ``_check_joints`` tells if it is not."""
    config = run_dir / "config.json"
    data = load_json(config) if config.exists() else {}
    body_file = data.get("body_file") if isinstance(data, dict) else None
    return load_body(body_file if isinstance(body_file, str) and Path(body_file).is_file() else None)


def _check_joints(bones: Skeleton, origin_m: np.ndarray, world_quat: np.ndarray, run_dir, body_file: str) -> None:
    """Every logged child frame at its joint on its parent, as the body file says: else the
    exported lengths would not be the swim's."""
    for i, parent in enumerate(bones.parents):
        if parent < 0:
            continue
        joint_m = origin_m[:, parent] + Rotation.from_quat(world_quat[:, parent]).apply(bones.offset_m[i])
        off_m = float(np.linalg.norm(joint_m - origin_m[:, i], axis=1).max())
        if off_m > MATCH_TOLERANCE_M:
            raise ConfigError(f"{run_dir}: segment '{bones.names[i]}' sits {off_m * 1000:.1f} mm off its joint in "
                              f"the body file {body_file}; not the body this run swam")


def _frame_times(log_times_s: np.ndarray, fps: int) -> np.ndarray:
    """From the first log sample to the last at 1/fps (a last partial interval is left out)."""
    count = int(np.floor((log_times_s[-1] - log_times_s[0]) * fps + 1e-6)) + 1
    return np.minimum(log_times_s[0] + np.arange(count) / fps, log_times_s[-1])


def _lerp(times_s: np.ndarray, values: np.ndarray, at_s: np.ndarray) -> np.ndarray:
    return np.stack([np.interp(at_s, times_s, values[:, k]) for k in range(values.shape[1])], axis=1)


def _slerp(times_s: np.ndarray, quat_xyzw: np.ndarray, at_s: np.ndarray) -> np.ndarray:
    """(F, S, 4) rotations at ``at_s``, each segment's slerped between log samples."""
    if len(times_s) == 1:           # a run stopped within its second log interval: one frame
        return quat_xyzw[:1].copy()
    quat = np.stack([Slerp(times_s, Rotation.from_quat(quat_xyzw[:, s]))(at_s).as_quat()
                     for s in range(quat_xyzw.shape[1])], axis=1)
    return _continuous(quat)


def _continuous(quat_xyzw: np.ndarray) -> np.ndarray:
    """q and -q are one rotation: each frame's sign picked to agree with the frame before, so a
    reader that interpolates quaternions component-wise takes the short way."""
    flips = np.sum(quat_xyzw[1:] * quat_xyzw[:-1], axis=-1) < 0
    signs = np.concatenate([np.ones((1, quat_xyzw.shape[1])), np.cumprod(np.where(flips, -1.0, 1.0), axis=0)])
    return quat_xyzw * signs[..., None]
