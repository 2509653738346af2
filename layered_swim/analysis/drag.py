"""Passive drag of the rigid body towed in a streamlined glide, against real swimmers.

The body is posed (arms overhead, legs together, toes pointed), placed prone just under the
surface and given a uniform velocity along +x; the fluid backend's force along the tow is read
off directly, with no time stepping, so the numbers are exact for the model (buoyancy pushes
straight up and adds nothing along x). Reference: Narita et al. 2017, passive drag D = 23.5 v^2 N.
"""
from __future__ import annotations

import numpy as np

from layered_swim.body.layout import joint_layout
from layered_swim.fluid.backend import FluidBackend
from layered_swim.sim.simulation import GRAVITY_M_S2, PHYSICS_HZ, PRONE_QUAT_XYZW
from layered_swim.sim.world import World
from layered_swim.state import BodyState

REFERENCE_PASSIVE_DRAG_N_S2_M2 = 23.5      # Narita et al. 2017
GLIDE_POSE_DEG = {
    "shoulder_l.flexion": 180.0, "shoulder_r.flexion": 180.0,
    "shoulder_l.abduction": -10.0, "shoulder_r.abduction": -10.0,
    "ankle_l.plantarflexion": 45.0, "ankle_r.plantarflexion": 45.0,
}
GLIDE_DEPTH_M = 0.2                          # pelvis centre below the surface: fully submerged
SPEEDS_M_S = (0.5, 1.0, 1.5, 2.0, 2.5)


def glide_state(body) -> BodyState:
    """The body at rest in the streamlined glide, prone, pelvis GLIDE_DEPTH_M under the surface."""
    layout = joint_layout(body)
    pose = layout.zeros()
    for name, deg in GLIDE_POSE_DEG.items():
        pose[layout.index(name)] = np.radians(deg)
    world = World(body, layout, PHYSICS_HZ, GRAVITY_M_S2)
    try:
        world.reset((0.0, 0.0, -GLIDE_DEPTH_M), PRONE_QUAT_XYZW, pose)
        return world.read_state()
    finally:
        world.close()


def towed_drag(fluid: FluidBackend, speeds_m_s=SPEEDS_M_S) -> list[dict]:
    """Drag of ``fluid``'s body towed through its water at each speed (one evaluation, no time:
    a model without memory, like the plates)."""
    body = fluid.body
    glide = glide_state(body)
    rows = []
    for v in speeds_m_s:
        velocity = np.tile([v, 0.0, 0.0], (len(body.segment_names), 1))
        towed = BodyState(0.0, glide.pos_m, glide.quat_xyzw, velocity, np.zeros_like(velocity), glide.segments)
        drag = float(-fluid.wrenches(towed).force_n[:, 0].sum())
        reference = REFERENCE_PASSIVE_DRAG_N_S2_M2 * v**2
        rows.append({"speed_m_s": v, "drag_n": drag, "reference_n": reference, "ratio": drag / reference})
    return rows
