"""BVH (Biovision hierarchy): the joint tree with the body's real offsets, then one line per frame.

Y up (see ``axes``), metres, angles in degrees; BVH has no place for units (a comment line breaks
Blender's importer and bvhio), so docs/export.md says it. The pelvis (root) has six channels,
its position then its rotation; every other joint three rotations in the order the body file
composes its axes, so a channel reads as the joint's anatomical angle where it can. Positions
are the link frames', at the joints; a leaf's End Site lies as far past its box centre as the
joint lies before it. The root's OFFSET is zero and its position channels absolute, so readers
that add the offset and readers that replace it agree.

Written here as text: bvhio, the kept BVH library, turns rotations into Euler angles in float32,
each angle on its own, and lost whole rotations near a middle angle of 90 deg in our check;
scipy's conversion keeps them to 1e-7 rad.
"""
from __future__ import annotations

import warnings
from pathlib import Path

import numpy as np
from scipy.spatial.transform import Rotation

from layered_swim.export.axes import Y_UP_AXIS_NAMES, y_up_rotations, y_up_vectors
from layered_swim.export.motion import Motion

NUMBER = "%.6f"      # micrometres and microdegrees


def write_bvh(motion: Motion, path: Path) -> None:
    bones = motion.skeleton
    orders = ["".join(Y_UP_AXIS_NAMES[a] for a in axes) for axes in bones.euler_axes]
    local = y_up_rotations(motion.local_quat_xyzw)
    lines, columns = ["HIERARCHY"], []

    def joint(i: int, depth: int) -> None:
        pad, root = "\t" * depth, bones.parents[i] < 0
        channels = ["Xposition", "Yposition", "Zposition"] * root + [f"{axis}rotation" for axis in orders[i]]
        lines.extend([f"{pad}{'ROOT' if root else 'JOINT'} {bones.names[i]}", pad + "{",
                      f"{pad}\tOFFSET {_vector(y_up_vectors(bones.offset_m[i]))}",
                      f"{pad}\tCHANNELS {len(channels)} {' '.join(channels)}"])
        if root:
            columns.append(y_up_vectors(motion.root_pos_m))
        columns.append(_euler_deg(local[:, i], orders[i]))
        children = bones.children(i)
        for child in children:
            joint(child, depth + 1)
        if not children:
            lines.extend([f"{pad}\tEnd Site", f"{pad}\t{{",
                          f"{pad}\t\tOFFSET {_vector(y_up_vectors(2 * bones.center_m[i]))}", f"{pad}\t}}"])
        lines.append(pad + "}")

    joint(0, 0)
    lines.extend(["MOTION", f"Frames: {motion.frames}", f"Frame Time: {1 / motion.fps:.10f}"])
    with open(path, "w") as f:
        f.write("\n".join(lines) + "\n")
        np.savetxt(f, np.hstack(columns), fmt=NUMBER)


def _vector(v: np.ndarray) -> str:
    return " ".join(NUMBER % (x + 0.0) for x in v)     # + 0.0: no "-0.000000" from a turned zero


def _euler_deg(quat_xyzw: np.ndarray, order: str) -> np.ndarray:
    """(F, 3) intrinsic angles in ``order`` (BVH's: the first channel's axis turns first, in the
    parent frame), unwrapped over time so an importer's interpolation never spins a joint round."""
    with warnings.catch_warnings():
        # At gimbal lock scipy says so and puts the whole turn in the first angle: still exact.
        warnings.simplefilter("ignore", UserWarning)
        angles = Rotation.from_quat(quat_xyzw).as_euler(order, degrees=True)
    return np.unwrap(angles, period=360.0, axis=0)
