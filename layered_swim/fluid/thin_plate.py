"""The thin-plate fluid backend: body state -> one force and one torque per segment.

Flow at the swimmer = uniform current + Yang's swimmer-induced flow (eq. 5) driven by the
whole-body centre-of-mass velocity and the pelvis long axis. Hydrodynamic forces come from
the per-face plate kernel, buoyancy from the exact ellipsoid kernel; both are compiled.
"""
from __future__ import annotations

import numpy as np

from layered_swim.body.model import Body
from layered_swim.fluid.buoyancy import buoyancy_wrenches
from layered_swim.fluid.coefficients import build_coefficient_table
from layered_swim.fluid.induced_flow import induced_flow
from layered_swim.fluid.medium import Medium
from layered_swim.fluid.plate import plate_wrenches

PELVIS_LONG_AXIS_LOCAL = np.array([0.0, 0.0, 1.0])


class ThinPlateFluid:
    def __init__(self, body: Body, medium: Medium):
        self.body = body
        self.medium = medium
        self.table = build_coefficient_table()
        self._mass_fraction = body.mass_kg / body.mass_kg.sum()
        self._half = np.ascontiguousarray(body.half_extents_m)
        self._flow = np.zeros((len(body.segment_names), 3))
        # The buoyancy part of the last ``wrenches`` force, for logs that separate it from the
        # hydrodynamic force (the part a stroke can change).
        self.buoyancy_force_n = np.zeros((len(body.segment_names), 3))

    def flow_at_swimmer(self, pos_m, quat_xyzw, linvel_m_s) -> np.ndarray:
        m = self.medium
        com_velocity = self._mass_fraction @ linvel_m_s
        x, y, z, w = quat_xyzw[0]
        # Pelvis long axis (local z) in world coordinates: third column of its rotation matrix.
        axis = np.array([2 * (x * z + y * w), 2 * (y * z - x * w), 1 - 2 * (x * x + y * y)])
        entrained = induced_flow(com_velocity - m.current, axis, m.r_min, m.r_max)
        if m.axial_induced_flow:
            # Only motion along the body drags water along (the segments sit in each other's wake
            # along the body axis, not across it); keeps the legs' weathervane drag that holds the
            # body level when it pitches or yaws.
            entrained = (entrained @ axis) * axis
        return m.current + entrained

    def wrenches(self, pos_m, quat_xyzw, linvel_m_s, angvel_rad_s) -> tuple[np.ndarray, np.ndarray]:
        m = self.medium
        self._flow[:] = self.flow_at_swimmer(pos_m, quat_xyzw, linvel_m_s)
        force, torque = plate_wrenches(pos_m, quat_xyzw, linvel_m_s, angvel_rad_s, self._half, self._flow,
                                       m.rho_kg_m3, m.eta_pa_s, m.surface_z_m, self.table, m.patches_per_edge)
        b_force, b_torque = buoyancy_wrenches(pos_m, quat_xyzw, self.body.semi_axes_m, self.body.volume_m3,
                                              m.rho_kg_m3, m.gravity_m_s2, m.surface_z_m, m.exact_buoyancy)
        self.buoyancy_force_n = b_force
        return force + b_force, torque + b_torque
