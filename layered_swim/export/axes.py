"""Our world is z up; BVH and glTF are y up. One rotation (-90 deg about x) takes ours to
theirs: x stays (the swimmer's start heading), z becomes y and y becomes -z. It is the exact
inverse of what Blender's BVH and glTF importers do with their default axes (forward -Z, up Y),
so an import lands in our frame again."""
from __future__ import annotations

import numpy as np
from scipy.spatial.transform import Rotation

Y_UP = Rotation.from_euler("x", -90.0, degrees=True)
Y_UP_AXIS_NAMES = "XZY"      # the y-up axis each of our x, y, z becomes (y: its negative)


def y_up_vectors(v: np.ndarray) -> np.ndarray:
    """Vectors (..., 3) in our frame, in the y-up one."""
    v = np.asarray(v, dtype=float)
    return Y_UP.apply(v.reshape(-1, 3)).reshape(v.shape)


def y_up_rotations(quat_xyzw: np.ndarray) -> np.ndarray:
    """Rotations (..., 4) between frames of ours, as the same rotations between y-up frames."""
    q = np.asarray(quat_xyzw, dtype=float)
    return (Y_UP * Rotation.from_quat(q.reshape(-1, 4)) * Y_UP.inv()).as_quat().reshape(q.shape)
