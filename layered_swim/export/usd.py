"""USD ascii (.usda): xform animation. ``/swimmer`` holds one Xform per segment, nested as the
body's tree (``/swimmer/pelvis/abdomen/thorax/...``); each has a translate op (the joint's offset
from its parent; the pelvis's is its position, sampled every frame) and an orient op (its
rotation relative to its parent, sampled every frame, double precision), and a child Cube
``<segment>_box`` (unique names: Blender's objects need them) moved to the box centre and scaled
to the segment's box. The stage says its own
conventions: z up (ours, no conversion), metres per unit 1, time codes = frames at the export's
rate from 0.
"""
from __future__ import annotations

from pathlib import Path

from pxr import Gf, Sdf, Usd, UsdGeom

from layered_swim.export.motion import Motion


def write_usda(motion: Motion, path: Path, generator: str) -> None:
    bones = motion.skeleton
    stage = Usd.Stage.CreateInMemory()     # not CreateNew: no layer of that name left open in this process
    UsdGeom.SetStageUpAxis(stage, UsdGeom.Tokens.z)
    UsdGeom.SetStageMetersPerUnit(stage, UsdGeom.LinearUnits.meters)
    stage.SetTimeCodesPerSecond(motion.fps)
    stage.SetFramesPerSecond(motion.fps)
    stage.SetStartTimeCode(0)
    stage.SetEndTimeCode(motion.frames - 1)
    stage.GetRootLayer().documentation = (
        f"{generator}: the swim of {motion.source}{' (a stopped run, partial)' if motion.partial else ''}, "
        f"{motion.frames} frames at {motion.fps} fps from its t = {motion.start_s:.6f} s; metres, z up")
    swimmer = UsdGeom.Xform.Define(stage, "/swimmer")
    stage.SetDefaultPrim(swimmer.GetPrim())
    paths: list[Sdf.Path] = []
    for i, name in enumerate(bones.names):
        parent = bones.parents[i]
        paths.append((swimmer.GetPath() if parent < 0 else paths[parent]).AppendChild(name))
        segment = UsdGeom.Xform.Define(stage, paths[i])
        translate = segment.AddTranslateOp(UsdGeom.XformOp.PrecisionDouble)
        orient = segment.AddOrientOp(UsdGeom.XformOp.PrecisionDouble)
        if parent < 0:
            for frame, at_m in enumerate(motion.root_pos_m):
                translate.Set(Gf.Vec3d(*at_m), frame)
        else:
            translate.Set(Gf.Vec3d(*bones.offset_m[i]))
        for frame, (x, y, z, w) in enumerate(motion.local_quat_xyzw[:, i]):
            orient.Set(Gf.Quatd(w, x, y, z), frame)
        box = UsdGeom.Cube.Define(stage, paths[i].AppendChild(f"{name}_box"))    # size 2: scaled by the half extents
        box.AddTranslateOp(UsdGeom.XformOp.PrecisionDouble).Set(Gf.Vec3d(*bones.center_m[i]))
        box.AddScaleOp(UsdGeom.XformOp.PrecisionDouble).Set(Gf.Vec3d(*bones.half_extents_m[i]))
    if not stage.GetRootLayer().Export(str(path)):
        raise OSError(f"{path}: USD could not write it")
