"""The thin-plate fluid backend: body state -> one force and one torque per segment.

Flow at the swimmer = uniform current + Yang's swimmer-induced flow (eq. 5) driven by the
whole-body centre-of-mass velocity and the pelvis long axis. Hydrodynamic forces come from
the per-face plate kernel, buoyancy from the exact ellipsoid kernel. All three run in one
compiled call per step: called one by one from Python, their call overheads cost as much as
their arithmetic.
"""
from __future__ import annotations

import numpy as np
from numba import njit

from layered_swim.body.model import Body
from layered_swim.fluid.buoyancy import _buoyancy_wrenches
from layered_swim.fluid.coefficients import build_coefficient_table
from layered_swim.fluid.induced_flow import _induced_flow
from layered_swim.fluid.medium import Medium
from layered_swim.fluid.plate import _plate_wrenches


@njit(cache=True)
def _flow_at_swimmer(quat, linvel, mass_fraction, current, r_min, r_max, axial):
    com_velocity = np.zeros(3)
    for i in range(linvel.shape[0]):     # a loop: np.dot wants contiguous rows, the state's are views
        for j in range(3):
            com_velocity[j] += mass_fraction[i] * linvel[i, j]
    x, y, z, w = quat[0, 0], quat[0, 1], quat[0, 2], quat[0, 3]
    # Pelvis long axis (local z) in world coordinates: third column of its rotation matrix.
    axis = np.array([2 * (x * z + y * w), 2 * (y * z - x * w), 1 - 2 * (x * x + y * y)])
    return current + _induced_flow(com_velocity - current, axis, r_min, r_max, axial)


@njit(cache=True)
def _fluid_wrenches(pos, quat, linvel, angvel, segments, medium, coefficients):
    """``segments`` (n, 8): half extents, ellipsoid semi-axes, mass fraction, volume; ``medium``:
    the current, then the scalars in the order ThinPlateFluid.__init__ packs them; ``coefficients``
    (3, k): angles, C_L, C_D. Packed so that the per-step call passes seven arguments, not twenty."""
    half, semi, mass_fraction, volume = segments[:, 0:3], segments[:, 3:6], segments[:, 6], segments[:, 7]
    current = medium[0:3]
    r_min, r_max, axial, rho, eta, surface_z, g, exact, patches = medium[3:12]
    water = _flow_at_swimmer(quat, linvel, mass_fraction, current, r_min, r_max, axial != 0.0)
    flow = np.empty((pos.shape[0], 3))
    flow[:] = water
    force, torque = _plate_wrenches(pos, quat, linvel, angvel, half, flow, rho, eta, surface_z, coefficients[0],
                                    coefficients[1], coefficients[2], int(patches))
    b_force, b_torque = _buoyancy_wrenches(pos, quat, semi, volume, rho, g, surface_z, exact != 0.0)
    return force + b_force, torque + b_torque, b_force, water


class ThinPlateFluid:
    def __init__(self, body: Body, medium: Medium):
        self.body = body
        self.medium = medium
        self.table = build_coefficient_table()
        self._mass_fraction = body.mass_fraction
        self._segments = np.ascontiguousarray(np.column_stack(
            [body.half_extents_m, body.semi_axes_m, self._mass_fraction, body.volume_m3]), dtype=np.float64)
        m = medium
        self._medium = np.array([*m.current_m_s, m.r_min, m.r_max, m.axial_induced_flow, m.rho_kg_m3,
                                 m.eta_pa_s, m.surface_z_m, abs(m.gravity_m_s2), m.exact_buoyancy,
                                 m.patches_per_edge], dtype=np.float64)
        self._coefficients = np.ascontiguousarray(np.vstack(self.table), dtype=np.float64)
        # The buoyancy part of the last ``wrenches`` force, for logs that separate it from the
        # hydrodynamic force (the part a stroke can change).
        self.buoyancy_force_n = np.zeros((len(body.segment_names), 3))
        # The water velocity near the swimmer at the last ``wrenches`` (the controller's rules read
        # it rather than computing it again); the current until the first step.
        self.flow_m_s = medium.current

    def flow_at_swimmer(self, pos_m, quat_xyzw, linvel_m_s) -> np.ndarray:
        """Water velocity near the swimmer: the current plus the flow it drags along. Only motion
        along the body drags water along by default (``Medium.axial_induced_flow``: the segments
        sit in each other's wake along the body axis, not across it), which keeps the legs'
        weathervane drag that holds the body level when it pitches or yaws."""
        m = self.medium
        return _flow_at_swimmer(np.asarray(quat_xyzw, dtype=np.float64), np.asarray(linvel_m_s, dtype=np.float64),
                                self._mass_fraction, m.current, m.r_min, m.r_max, m.axial_induced_flow)

    def wrenches(self, pos_m, quat_xyzw, linvel_m_s, angvel_rad_s) -> tuple[np.ndarray, np.ndarray]:
        force, torque, self.buoyancy_force_n, self.flow_m_s = _fluid_wrenches(
            pos_m, quat_xyzw, linvel_m_s, angvel_rad_s, self._segments, self._medium, self._coefficients)
        return force, torque
