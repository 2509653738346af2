"""The SPlisHSPlasH scene for one pool and a set of boxes, written as files (pure: no solver).

One OBJ per box: with one shared OBJ and per-body ``scale``, SPlisHSPlasH 2.19 gave every body
the container's boundary sampling. The pool's walls come first and the swimmer's boxes last. A
pool with a current (``conveyor.py``) is open at the ends the current crosses: its floor and
remaining walls are then static slabs (a container mesh with faces left out let the water fall
through its floor). Floats are written as plain numbers (its JSON reader rejects
``np.float64(...)``). World z is up, as in PyBullet.
"""
from __future__ import annotations

import json
from pathlib import Path

import numpy as np

SLAB_M = 0.1               # the open pool's floor and wall thickness
# Corners and the twelve triangles (outward, counter-clockwise) of the unit cube [-1, 1]^3.
_CORNERS = np.array([[x, y, z] for x in (-1, 1) for y in (-1, 1) for z in (-1, 1)], dtype=float)
_TRIANGLES = ((0, 3, 2), (0, 1, 3), (4, 7, 5), (4, 6, 7), (0, 5, 1), (0, 4, 5),
              (2, 7, 6), (2, 3, 7), (0, 6, 4), (0, 2, 6), (1, 7, 3), (1, 5, 7))


def box_obj(half_extents_m) -> str:
    """A closed box mesh centred on the origin, as OBJ text."""
    vertices = _CORNERS * np.asarray(half_extents_m, dtype=float)
    lines = [f"v {float(x):.9g} {float(y):.9g} {float(z):.9g}" for x, y, z in vertices]
    lines += [f"f {a + 1} {b + 1} {c + 1}" for a, b, c in _TRIANGLES]
    return "\n".join(lines) + "\n"


def write_scene(folder: Path, *, pool_min_m, pool_max_m, fill_top_z_m: float, particle_radius_m: float,
                time_step_s: float, density_kg_m3: float, viscosity_m2_s: float, gravity_m_s2: float,
                boxes_half_m, box_centres_m, open_axes: tuple[bool, bool] = (False, False)) -> Path:
    """Write the scene (pool, one block of water, one dynamic box per body) into ``folder`` and
    return the scene file. The pool is ``pool_min_m``..``pool_max_m`` (its top above the water so
    a wave stays in), open at both ends of the ``open_axes`` (x, y); the water block fills it up
    to ``fill_top_z_m``."""
    folder.mkdir(parents=True, exist_ok=True)
    lo, hi = np.asarray(pool_min_m, float), np.asarray(pool_max_m, float)
    wall = {"scale": [1.0, 1.0, 1.0], "rotationAxis": [0.0, 0.0, 1.0], "rotationAngle": 0.0, "isDynamic": False,
            "samplingMode": 1, "color": [0.1, 0.4, 0.6, 1.0]}
    if any(open_axes):
        bodies = []
        for k, (half, centre) in enumerate(pool_slabs(lo, hi, open_axes)):
            (folder / f"wall{k}.obj").write_text(box_obj(half))
            bodies.append({**wall, "geometryFile": f"wall{k}.obj", "translation": _floats(centre), "isWall": False,
                           "mapInvert": False})
    else:
        (folder / "pool.obj").write_text(box_obj((hi - lo) / 2))
        bodies = [{**wall, "geometryFile": "pool.obj", "translation": _floats((hi + lo) / 2), "isWall": True,
                   "mapInvert": True}]
    for k, (half, centre) in enumerate(zip(boxes_half_m, box_centres_m)):
        name = f"box{k:02d}.obj"
        (folder / name).write_text(box_obj(half))
        bodies.append({
            "geometryFile": name, "translation": _floats(centre), "scale": [1.0, 1.0, 1.0],
            "rotationAxis": [0.0, 0.0, 1.0], "rotationAngle": 0.0, "isDynamic": True, "isWall": False,
            "density": 1000.0, "samplingMode": 1, "color": [0.8, 0.5, 0.3, 1.0],
        })
    # The water block stops half a particle short of the walls (SPlisHSPlasH fills it on a grid).
    inset = particle_radius_m
    scene = {
        "Configuration": {
            "particleRadius": float(particle_radius_m), "timeStepSize": float(time_step_s),
            "simulationMethod": 4, "boundaryHandlingMethod": 0, "gravitation": [0.0, 0.0, -float(gravity_m_s2)],
            "cflMethod": 0, "maxIterations": 100, "maxError": 0.01, "maxIterationsV": 100, "maxErrorV": 0.1,
            "enableDivergenceSolver": True, "stopAt": -1.0, "enablePartioExport": False,
            "enableVTKExport": False, "enableRigidBodyExport": False, "enableRigidBodyVTKExport": False,
            "enableStateExport": False, "enableAsyncExport": False,
        },
        "Materials": [{
            "id": "Fluid", "density0": float(density_kg_m3), "viscosityMethod": 1 if viscosity_m2_s > 0 else 0,
            "viscosity": float(viscosity_m2_s), "surfaceTensionMethod": 0, "vorticityMethod": 0, "dragMethod": 0,
        }],
        "FluidBlocks": [{
            "denseMode": 0, "id": "Fluid",
            "start": _floats(lo + inset), "end": _floats([hi[0] - inset, hi[1] - inset, fill_top_z_m]),
        }],
        "RigidBodies": bodies,
    }
    path = folder / "scene.json"
    path.write_text(json.dumps(scene, indent=1))
    return path


def pool_slabs(lo: np.ndarray, hi: np.ndarray, open_axes: tuple[bool, bool], thickness_m: float = SLAB_M):
    """The floor and the side walls on the closed axes of an open pool, as (half extents, centre)
    of static boxes whose inner faces are the pool's; they reach past the open ends."""
    outer_lo, outer_hi = lo - thickness_m, hi + thickness_m
    slabs = [(np.array([(outer_hi[0] - outer_lo[0]) / 2, (outer_hi[1] - outer_lo[1]) / 2, thickness_m / 2]),
              np.array([(lo[0] + hi[0]) / 2, (lo[1] + hi[1]) / 2, lo[2] - thickness_m / 2]))]
    for axis, is_open in enumerate(open_axes):
        if is_open:
            continue
        half = np.array([(outer_hi[0] - outer_lo[0]) / 2, (outer_hi[1] - outer_lo[1]) / 2,
                         (hi[2] - outer_lo[2]) / 2])
        half[axis] = thickness_m / 2
        for face, sign in ((lo[axis], -1.0), (hi[axis], 1.0)):
            centre = np.array([(lo[0] + hi[0]) / 2, (lo[1] + hi[1]) / 2, (hi[2] + outer_lo[2]) / 2])
            centre[axis] = face + sign * thickness_m / 2
            slabs.append((half, centre))
    return slabs


def _floats(values) -> list[float]:
    return [float(v) for v in values]
