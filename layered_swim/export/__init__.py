"""A run folder's swim written for other tools (Blender, game engines, USD): BVH, glTF binary or
USD ascii, chosen by the file's suffix. ``motion`` derives the joint tree and parent-relative
rotations from the log and resamples them; one module per format writes them in its conventions
(docs/export.md). The writers' libraries are the ``[export]`` extra, imported only when used."""
from __future__ import annotations

from pathlib import Path

from layered_swim.export.motion import Motion, load_motion
from layered_swim.export.target import ExportTarget, check_target
from layered_swim.outputs import atomic_path
from layered_swim.runs import package_version

__all__ = ["ExportTarget", "check_target", "export_run"]


def export_run(run_dir: str | Path, target: ExportTarget, fps: int) -> Motion:
    """Write the swim of ``run_dir`` (its log, or a stopped run's chunks) to ``target`` at
    ``fps``, whole or not at all; returns what was written."""
    motion = load_motion(run_dir, fps)
    target = check_target(target.path, target.overwrite)     # again: a run may have taken minutes since
    generator = f"layered-swim {package_version()}"
    with atomic_path(target.path) as tmp:
        if target.suffix == ".bvh":
            from layered_swim.export.bvh import write_bvh
            write_bvh(motion, tmp)
        elif target.suffix == ".glb":
            from layered_swim.export.gltf import write_glb
            write_glb(motion, tmp, generator)
        else:
            from layered_swim.export.usd import write_usda
            write_usda(motion, tmp, generator)
    return motion
