"""glTF 2.0 binary (.glb): one named node per segment in the body's tree, its translation the
joint's offset from the parent (the pelvis: its position), its rotation the segment's relative
to the parent, animated by one animation ("swim") at the export's frame rate. Each segment node
has a child node ``<segment>_box`` at the box centre holding the segment's box, so the swim is
visible as it is. glTF's own conventions: y up (see ``axes``), metres, quaternions x, y, z, w,
times in seconds; float32 throughout, as the format has it (a micrometre at 10 m).

pygltflib assembles the file; the buffer is our arrays' bytes, laid out one view per accessor.
"""
from __future__ import annotations

from pathlib import Path

import numpy as np
import pygltflib as gl

from layered_swim.export.axes import y_up_rotations, y_up_vectors
from layered_swim.export.motion import Motion

TYPES = {1: gl.SCALAR, 3: gl.VEC3, 4: gl.VEC4}


def write_glb(motion: Motion, path: Path, generator: str) -> None:
    bones = motion.skeleton
    count = len(bones.names)
    gltf = gl.GLTF2(asset=gl.Asset(generator=generator, extras=_about(motion)), scene=0,
                    scenes=[gl.Scene(name="swimmer", nodes=[0])])
    data = bytearray()
    box_triangles = _accessor(gltf, data, _box_triangles().reshape(-1), gl.ELEMENT_ARRAY_BUFFER)
    local = y_up_rotations(motion.local_quat_xyzw).astype(np.float32)
    root_m = y_up_vectors(motion.root_pos_m).astype(np.float32)
    offsets_m = y_up_vectors(bones.offset_m)
    for i, name in enumerate(bones.names):
        gltf.nodes.append(gl.Node(name=name, translation=(root_m[0] if i == 0 else offsets_m[i]).tolist(),
                                  rotation=local[0, i].tolist(),
                                  children=[count + i] + bones.children(i)))
    for i, name in enumerate(bones.names):
        # The y-up box: our half extents with y and z swapped (a quarter turn keeps their lengths).
        half_m = np.abs(y_up_vectors(bones.half_extents_m[i]))
        corners = _accessor(gltf, data, _box_corners(half_m), gl.ARRAY_BUFFER, bounds=True)
        gltf.meshes.append(gl.Mesh(name=f"{name}_box", primitives=[
            gl.Primitive(attributes=gl.Attributes(POSITION=corners), indices=box_triangles)]))
        gltf.nodes.append(gl.Node(name=f"{name}_box", mesh=i, translation=y_up_vectors(bones.center_m[i]).tolist()))
    times = _accessor(gltf, data, np.arange(motion.frames, dtype=np.float32) / motion.fps, bounds=True)
    animation = gl.Animation(name="swim")
    outputs = [(0, "translation", root_m)] + [(i, "rotation", local[:, i]) for i in range(count)]
    for node, path_name, values in outputs:
        animation.samplers.append(gl.AnimationSampler(input=times, output=_accessor(gltf, data, values),
                                                      interpolation=gl.ANIM_LINEAR))
        animation.channels.append(gl.AnimationChannel(sampler=len(animation.samplers) - 1,
                                                      target=gl.AnimationChannelTarget(node=node, path=path_name)))
    gltf.animations.append(animation)
    gltf.buffers.append(gl.Buffer(byteLength=len(data)))
    gltf.set_binary_blob(bytes(data))
    gltf.save_binary(str(path))


def _about(motion: Motion) -> dict:
    return {"units": "metres", "up": "y", "frames_per_s": motion.fps, "frames": motion.frames,
            "run_folder": motion.source, "run_time_at_frame_0_s": motion.start_s, "partial_run": motion.partial}


def _accessor(gltf: gl.GLTF2, data: bytearray, values: np.ndarray, target: int | None = None,
              bounds: bool = False) -> int:
    """``values`` appended to the buffer in a view of their own; the new accessor's index."""
    values = np.ascontiguousarray(values, dtype=np.uint16 if values.dtype.kind == "u" else np.float32)
    gltf.bufferViews.append(gl.BufferView(buffer=0, byteOffset=len(data), byteLength=values.nbytes, target=target))
    data.extend(values.tobytes())
    data.extend(b"\0" * (-len(data) % 4))       # every view starts 4-byte aligned
    columns = 1 if values.ndim == 1 else values.shape[1]
    rows = values.reshape(len(values), columns)
    gltf.accessors.append(gl.Accessor(
        bufferView=len(gltf.bufferViews) - 1, count=len(values), type=TYPES[columns],
        componentType=gl.UNSIGNED_SHORT if values.dtype == np.uint16 else gl.FLOAT,
        min=rows.min(axis=0).tolist() if bounds else None, max=rows.max(axis=0).tolist() if bounds else None))
    return len(gltf.accessors) - 1


def _box_corners(half_m: np.ndarray) -> np.ndarray:
    """(8, 3): corner k has +half on axis a where bit a of k is set, else -half."""
    signs = np.array([[1.0 if k >> a & 1 else -1.0 for a in range(3)] for k in range(8)])
    return signs * half_m


def _box_triangles() -> np.ndarray:
    """(12, 3) corner indices, counterclockwise seen from outside (glTF's front faces)."""
    unit = _box_corners(np.ones(3))
    triangles = []
    for axis in range(3):
        u, v = (a for a in range(3) if a != axis)
        for side in (0, 1):
            # The face's corners round its edge: (u, v) bits 00, 10, 11, 01.
            quad = [side << axis | bu << u | bv << v for bu, bv in ((0, 0), (1, 0), (1, 1), (0, 1))]
            for a, b, c in ((quad[0], quad[1], quad[2]), (quad[0], quad[2], quad[3])):
                normal = np.cross(unit[b] - unit[a], unit[c] - unit[a])
                triangles.append((a, b, c) if normal @ (unit[a] + unit[b] + unit[c]) > 0 else (a, c, b))
    return np.array(triangles, dtype=np.uint16)
