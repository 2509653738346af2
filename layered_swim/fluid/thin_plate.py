"""The thin-plate fluid backend (``plate``): body state -> one force and one torque per segment.

Flow at each segment = the water's own motion there (a uniform current, plus a flow field's) +
Yang's swimmer-induced flow (eq. 5) driven by the whole-body centre-of-mass velocity through the
water at the centre of mass and the pelvis long axis. Hydrodynamic forces come from
the per-face plate kernel, buoyancy from the exact ellipsoid kernel. All three run in one
compiled call per step: called one by one from Python, their call overheads cost as much as
their arithmetic. With ``added_mass`` (on by default) each segment also carries the water it
accelerates (``added_mass.py``), with one step of memory, in the same compiled call.
"""
from __future__ import annotations

import math
from dataclasses import asdict, dataclass

import numpy as np
from numba import njit

from layered_swim.body.model import Body
from layered_swim.config import ConfigError
from layered_swim.fluid.added_mass import AddedMass, added_mass_step
from layered_swim.fluid.backend import FluidBackend, FluidWrenches
from layered_swim.fluid.buoyancy import _buoyancy_wrenches
from layered_swim.fluid.coefficients import build_coefficient_table
from layered_swim.fluid.induced_flow import _induced_flow
from layered_swim.fluid.medium import Medium
from layered_swim.fluid.plate import _plate_wrenches
from layered_swim.geometry import quat_to_rows
from layered_swim.state import BodyState

# Yang eq. 5 ratios (docs/fluid.md). Along the body the boxes sit in each other's
# wake, which the per-face model cannot see, so the nearby water moves with the swimmer at r_min
# of its speed: calibrated so a towed streamlined body matches Narita et al. 2017's passive drag
# 23.5 v^2 N. Broadside every face meets undisturbed water and the plate model alone gives a
# realistic bluff-body drag (C_D ~1.2 on ~0.55 m^2), so r_max = 0.
DEFAULT_R_MIN = 0.68
DEFAULT_R_MAX = 0.0


@dataclass(frozen=True)
class PlateSettings:
    """The thin-plate model's own knobs (what the water is lives in ``Medium``)."""

    r_min: float = DEFAULT_R_MIN
    r_max: float = DEFAULT_R_MAX
    # Only motion along the body drags water along (the segments sit in each other's wake along
    # the body axis, not across it), which keeps the legs' weathervane drag that holds the body
    # level when it pitches or yaws. False: Yang's eq. 5 entrains the whole velocity.
    axial_induced_flow: bool = True
    exact_buoyancy: bool = True
    patches_per_edge: int = 1      # >= 2 resolves a spinning segment's rotational drag (plate.py)
    # Each segment's added mass and inertia (its ellipsoid's, Lamb), opposing its acceleration,
    # semi-implicit (added_mass.py): the unsteady force SWUM includes and Yang's plates lack.
    added_mass: bool = True

    def __post_init__(self):
        for name in ("r_min", "r_max"):
            value = getattr(self, name)
            if not (math.isfinite(value) and 0.0 <= value <= 0.99):
                raise ConfigError(f"{name} must be a number in [0, 0.99], got {value}")
        if not 1 <= self.patches_per_edge <= 8:
            raise ConfigError(f"patches_per_edge must be in 1..8, got {self.patches_per_edge}")
        if not isinstance(self.added_mass, bool):
            raise ConfigError(f"added_mass must be true or false, got {self.added_mass!r}")


@njit(cache=True)
def _induced_at_swimmer(quat, linvel, mass_fraction, current, r_min, r_max, axial):
    com_velocity = np.zeros(3)
    for i in range(linvel.shape[0]):     # a loop: np.dot wants contiguous rows, the state's are views
        for j in range(3):
            com_velocity[j] += mass_fraction[i] * linvel[i, j]
    rows = np.empty(9)
    quat_to_rows(quat[0], rows, False)
    axis = np.array([rows[2], rows[5], rows[8]])   # the pelvis long axis (local z) in world coordinates
    return _induced_flow(com_velocity - current, axis, r_min, r_max, axial)


@njit(cache=True)
def _fluid_wrenches(pos, quat, linvel, angvel, segments, medium, coefficients, segment_current):
    """``segments`` (n, 8): half extents, ellipsoid semi-axes, mass fraction, volume; ``medium``:
    the water's velocity at the centre of mass, then the scalars in the order PlateFluid.set_medium
    packs them; ``coefficients`` (3, k): angles, C_L, C_D; ``segment_current`` (n, 3): the water's
    own velocity at each segment. Packed so that the per-step call passes eight arguments, not twenty."""
    half, semi, mass_fraction, volume = segments[:, 0:3], segments[:, 3:6], segments[:, 6], segments[:, 7]
    current = medium[0:3]
    r_min, r_max, axial, rho, eta, surface_z, g, exact, patches = medium[3:12]
    induced = _induced_at_swimmer(quat, linvel, mass_fraction, current, r_min, r_max, axial != 0.0)
    flow = np.empty((pos.shape[0], 3))
    for i in range(pos.shape[0]):
        for j in range(3):
            flow[i, j] = segment_current[i, j] + induced[j]
    force, torque = _plate_wrenches(pos, quat, linvel, angvel, half, flow, rho, eta, surface_z, coefficients[0],
                                    coefficients[1], coefficients[2], int(patches))
    b_force, b_torque = _buoyancy_wrenches(pos, quat, semi, volume, rho, g, surface_z, exact != 0.0)
    return force + b_force, torque + b_torque, flow, b_force


@njit(cache=True)
def _fluid_and_added_mass(pos, quat, linvel, angvel, segments, medium, coefficients, segment_current, memory,
                          added_force, added_torque, inv_dt, own, added, semi, explicit):
    """``_fluid_wrenches`` and the added mass's step (``added_mass.added_mass_step``, in place) in
    one call, their wrenches summed: the same sums as added one by one in numpy."""
    force, torque, flow, b_force = _fluid_wrenches(pos, quat, linvel, angvel, segments, medium, coefficients,
                                                   segment_current)
    added_mass_step(pos, quat, linvel, angvel, memory, added_force, added_torque, inv_dt, own, added, semi,
                    medium[8], explicit)
    for i in range(force.shape[0]):
        for c in range(3):
            force[i, c] = force[i, c] + added_force[i, c]
            torque[i, c] = torque[i, c] + added_torque[i, c]
    return force, torque, flow, b_force


class PlateFluid(FluidBackend):
    """Thin plates on every box face, ellipsoid buoyancy and the swimmer-induced flow."""

    name = "plate"

    def __init__(self, body: Body, medium: Medium, gravity_m_s2: float, settings: PlateSettings | None = None):
        super().__init__(body, medium, gravity_m_s2)
        self.plate_settings = settings or PlateSettings()
        self.table = build_coefficient_table()
        self._segments = np.ascontiguousarray(np.column_stack(
            [body.half_extents_m, body.semi_axes_m, body.mass_fraction, body.volume_m3]), dtype=np.float64)
        self._coefficients = np.ascontiguousarray(np.vstack(self.table), dtype=np.float64)
        self.added_mass = AddedMass(body, medium.rho_kg_m3) if self.plate_settings.added_mass else None
        self.set_medium(medium)

    def breathe(self, air_l: float) -> None:
        super().breathe(air_l)
        # Only the lung segment's volume and ellipsoid change; this runs every control step while
        # the lungs fill or empty, so the rest of the table stays.
        i = self.body.index(self.body.lung_segment)
        self._segments[i, 3:6] = self.body.semi_axes_m[i]
        self._segments[i, 7] = self.body.volume_m3[i]
        if self.added_mass is not None:
            self.added_mass.reshape(i, self.body.semi_axes_m[i])

    def set_medium(self, medium: Medium) -> None:
        super().set_medium(medium)
        m, s = medium, self.plate_settings
        self._medium = np.array([*m.current_m_s, s.r_min, s.r_max, s.axial_induced_flow, m.rho_kg_m3,
                                 m.eta_pa_s, m.surface_z_m, abs(self.gravity_m_s2), s.exact_buoyancy,
                                 s.patches_per_edge], dtype=np.float64)
        self._segment_current = np.ascontiguousarray(np.tile(m.current, (len(self._segments), 1)))
        if self.added_mass is not None:
            self.added_mass.set_density(m.rho_kg_m3)

    def settings(self) -> dict:
        return asdict(self.plate_settings)

    def reset(self) -> None:
        if self.added_mass is not None:
            self.added_mass.reset()

    def wrenches(self, state: BodyState) -> FluidWrenches:
        # The kernel returns the four arrays in FluidWrenches' order; wrapping the tuple as it is
        # skips the named constructor's argument handling (this runs every physics step).
        if self.medium.flow is not None:      # the water moves differently at every segment, and in time
            water = self.medium.current_at(np.vstack([state.pos_m, state.com_m]), state.time_s)
            self._segment_current, self._medium[0:3] = water[:-1], water[-1]
        water = self.added_mass
        inv_dt = None if water is None else water.inverse_step_s(state.time_s)
        if inv_dt is None:        # no added mass, or asked again at the same time: it stands
            out = _fluid_wrenches(state.pos_m, state.quat_xyzw, state.linvel_m_s, state.angvel_rad_s, self._segments,
                                  self._medium, self._coefficients, self._segment_current)
            if water is None:
                return tuple.__new__(FluidWrenches, out)
            force, torque, flow, buoyancy = out
            return FluidWrenches(force + water.force_n, torque + water.torque_nm, flow, buoyancy)
        return tuple.__new__(FluidWrenches, _fluid_and_added_mass(
            state.pos_m, state.quat_xyzw, state.linvel_m_s, state.angvel_rad_s, self._segments, self._medium,
            self._coefficients, self._segment_current, water.memory, water.force_n, water.torque_nm, inv_dt, water.own,
            water.added, water.semi, water.explicit))
