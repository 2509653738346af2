"""Passive drag of the rigid body towed in a streamlined glide, against real swimmers.

The body is posed (arms overhead, legs together, toes pointed), placed prone just under the
surface and given a uniform velocity along +x; the thin-plate model's hydrodynamic force
(buoyancy excluded) is read off directly, with no time stepping, so the numbers are exact for
the model. Reference: Narita et al. 2017, passive drag D = 23.5 v^2 N.
"""
from __future__ import annotations

import numpy as np

from layered_swim.body.model import Body
from layered_swim.control.pose import joint_layout
from layered_swim.fluid.medium import Medium
from layered_swim.fluid.plate import plate_wrenches
from layered_swim.fluid.thin_plate import ThinPlateFluid
from layered_swim.sim.simulation import PRONE_QUAT_XYZW
from layered_swim.sim.world import World

REFERENCE_PASSIVE_DRAG_N_S2_M2 = 23.5      # Narita et al. 2017
GLIDE_POSE_DEG = {
    "shoulder_l.flexion": 180.0, "shoulder_r.flexion": 180.0,
    "shoulder_l.abduction": -10.0, "shoulder_r.abduction": -10.0,
    "ankle_l.plantarflexion": 45.0, "ankle_r.plantarflexion": 45.0,
}
GLIDE_DEPTH_M = 0.2                          # pelvis centre below the surface: fully submerged
SPEEDS_M_S = (0.5, 1.0, 1.5, 2.0, 2.5)


def towed_drag(body: Body, medium: Medium, speeds_m_s=SPEEDS_M_S) -> list[dict]:
    layout = joint_layout(body)
    pose = layout.zeros()
    for name, deg in GLIDE_POSE_DEG.items():
        pose[layout.index(name)] = np.radians(deg)
    world = World(body, layout, physics_hz=480)
    try:
        world.reset((0.0, 0.0, -GLIDE_DEPTH_M), PRONE_QUAT_XYZW, pose)
        state = world.read_state()
    finally:
        world.close()
    fluid = ThinPlateFluid(body, medium)
    rows = []
    for v in speeds_m_s:
        velocity = np.tile([v, 0.0, 0.0], (len(body.segment_names), 1))
        flow = np.tile(fluid.flow_at_swimmer(state.pos_m, state.quat_xyzw, velocity), (len(body.segment_names), 1))
        force, _ = plate_wrenches(state.pos_m, state.quat_xyzw, velocity, np.zeros_like(velocity),
                                  body.half_extents_m, flow, medium.rho_kg_m3, medium.eta_pa_s,
                                  medium.surface_z_m, fluid.table, medium.patches_per_edge)
        reference = REFERENCE_PASSIVE_DRAG_N_S2_M2 * v**2
        drag = float(-force[:, 0].sum())
        rows.append({"speed_m_s": v, "drag_n": drag, "reference_n": reference,
                     "ratio": drag / reference})
    return rows
