"""The SPH fluid backend (``sph``): SPlisHSPlasH's DFSPH water in a pool, two-way coupled.

Each swimmer segment is a rigid boundary box in the water, placed every physics step where
PyBullet has it; the force and torque the water puts on it go back to PyBullet through the same
``FluidWrenches`` as the thin plates'. The solver runs in a worker process (``worker.py``).

A new episode (``reset``) builds a fresh pool around the swimmer's start on the first step:
water inside the body is removed and the rest settles, damped, around the body held still
(``settle_s``, reported in ``startup``), before the swim starts.
"""
from __future__ import annotations

import math

import numpy as np

from layered_swim.body.model import Body
from layered_swim.config import ConfigError
from layered_swim.fluid.backend import FluidBackend, FluidError, FluidWrenches
from layered_swim.fluid.medium import Medium
from layered_swim.fluid.sph import conveyor
from layered_swim.fluid.sph.settings import SphSettings
from layered_swim.geometry import quat_rotate
from layered_swim.state import BodyState

MAX_WATER_SPEED_M_S = 30.0     # a particle faster than this: the fluid blew up
MAX_ESCAPED_SHARE = 0.01       # more of the water than this outside the container: the pool has failed
FLOOR_CLEARANCE_RADII = 3     # a start pose reaching below the floor is raised to clear it by this many
                              # particle radii: closer, the settling water is squeezed between body and floor
HEADROOM_M = 0.4               # container wall above the surface, so splashes stay in
DAMPING_PER_STEP = 0.95        # the settle phase's velocity scaling per step...
DAMPED_SHARE = 0.7             # ...over this share of it; the rest runs free
WINDOW_S = 0.02                # per-step SPH forces are noisy (sd ~15 %): peaks are judged on 20 ms means
FLOW_HZ = 120                  # the water velocity at the segments is sampled at the controller's rate:
                               # averaging the particles around 16 boxes every step cost 8 % of it


class SphBackend(FluidBackend):
    name = "sph"
    breathes = False     # each box displaces the water its geometry does: lung air is not modelled

    def __init__(self, body: Body, medium: Medium, gravity_m_s2: float, settings: SphSettings | None = None):
        super().__init__(body, medium, gravity_m_s2)
        self.sph_settings = settings or SphSettings()
        self._check_medium(medium)
        s = self.sph_settings
        self.boundary_half_m = boundary_boxes(body.half_extents_m, s)
        # Steps per force window and per flow sample: fixed by the step, counted against self.steps.
        self._window_steps = max(1, round(WINDOW_S / s.time_step_s))
        self._flow_steps = max(1, round(1.0 / (FLOW_HZ * s.time_step_s)))
        self._worker = None
        self._last_time_s: float | None = None
        self.startup: dict = {}
        self.pool_min_m = self.pool_max_m = None
        self.solver_s = 0.0            # seconds inside SPlisHSPlasH's step, since the start
        self.steps = 0
        self.outside_steps = 0         # steps with a segment centre outside the water box
        self._window = np.zeros(3)     # total force summed over the current window
        self._flow = np.zeros((len(body.segment_names), 3))
        self.peak_window_force_n = 0.0

    def _check_medium(self, medium: Medium) -> None:
        if medium.flow is not None:
            raise ConfigError("a water file's flow field (--water) runs on the plate backend only: an SPH pool "
                              "takes a uniform --current")
        if medium.current_m_s[2]:
            raise ConfigError("an SPH pool's current must be horizontal (its z part 0): it flows in through "
                              "one end of the pool and out through the other")

    def set_medium(self, medium: Medium) -> None:
        self._check_medium(medium)
        if self._worker is not None and medium != self.medium:
            raise FluidError("the SPH water cannot change mid-swim")
        super().set_medium(medium)

    @property
    def viscosity_m2_s(self) -> float:
        return kinematic_viscosity(self.sph_settings, self.medium)

    def settings(self) -> dict:
        s = self.sph_settings
        return {"pool_size_m": list(s.pool_size_m), "wall_gap_m": s.wall_gap_m,
                "particle_radius_m": s.particle_radius_m, "time_step_s": s.time_step_s,
                "viscosity_m2_s": self.viscosity_m2_s, "mesh_shrink_radii": s.mesh_shrink_radii,
                "settle_s": s.settle_s, "threads": s.solver_threads, "deterministic": s.deterministic}

    def reset(self) -> None:
        self.close()
        self._last_time_s = self.pool_min_m = self.pool_max_m = None
        self.startup = {}
        self.solver_s, self.steps, self.outside_steps, self.peak_window_force_n = 0.0, 0, 0, 0.0
        self._window = np.zeros(3)
        self._flow = np.zeros_like(self._flow)

    def close(self) -> None:
        if self._worker is not None:
            self._worker.close()
            self._worker = None

    # -- the pool ----------------------------------------------------------------------------
    def place_pool(self, state: BodyState) -> None:
        """An axis-aligned pool: its back wall ``wall_gap_m`` behind the body's rearmost corner
        (the swimmer heads +x), centred across the swimmer's centre of mass, surface at the medium's."""
        length, width, depth = self.sph_settings.pool_size_m
        corners = body_corners(state.pos_m, state.quat_xyzw, self.body.half_extents_m)
        back = corners[:, 0].min() - self.sph_settings.wall_gap_m
        if corners[:, 0].max() > back + length or np.ptp(corners[:, 1]) > width:
            raise ConfigError(f"the swimmer ({np.ptp(corners[:, 0]):.2f} x {np.ptp(corners[:, 1]):.2f} m) does not "
                              f"fit the {length:g} x {width:g} m SPH pool")
        centre_y = state.com_m[1]
        surface = self.medium.surface_z_m
        self.pool_min_m = np.array([back, centre_y - width / 2, surface - depth])
        self.pool_max_m = np.array([back + length, centre_y + width / 2, surface + HEADROOM_M])

    def container(self, state: BodyState) -> tuple[np.ndarray, np.ndarray, float]:
        """The pool's floor and walls (the swimmer touches them, as in a real pool: a body pushed
        through SPH's walls would squeeze the water out), and the rise that lifts a start pose
        reaching below the floor clear of it (the 0.5 m small pool is shallower than a
        breaststroke's legs at rest)."""
        self.place_pool(state)
        lowest = body_corners(state.pos_m, state.quat_xyzw, self.body.half_extents_m)[:, 2].min()
        clearance = FLOOR_CLEARANCE_RADII * self.sph_settings.particle_radius_m
        lift = max(0.0, self.pool_min_m[2] + clearance - lowest)
        self.startup = {"start_raised_m": round(float(lift), 4)}
        return self.pool_min_m, self.pool_max_m, lift

    def domain_xy_m(self, state: BodyState) -> tuple[np.ndarray, np.ndarray]:
        if self.pool_min_m is None:
            self.place_pool(state)
        return self.pool_min_m[:2], self.pool_max_m[:2]

    def _start(self, state: BodyState) -> None:
        from layered_swim.fluid.sph.worker import SphWorker

        if self.pool_min_m is None:
            self.place_pool(state)
        self._worker = SphWorker(self.sph_settings.solver_threads)
        self.startup = {**self.startup, **self._worker.request("start", start_request(
            self.sph_settings, self.medium, self.gravity_m_s2, self.pool_min_m, self.pool_max_m,
            self.boundary_half_m, state.pos_m, state.quat_xyzw))}

    def wrenches(self, state: BodyState) -> FluidWrenches:
        if self._worker is None:
            self._start(state)
        elif not math.isclose(state.time_s - self._last_time_s, self.sph_settings.time_step_s, abs_tol=1e-9):
            raise FluidError(f"the SPH step ({self.sph_settings.time_step_s:.6g} s) must equal the physics step "
                             f"({state.time_s - self._last_time_s:.6g} s)")
        self._last_time_s = state.time_s
        self._check_inside(state)
        want_flow = self.steps % self._flow_steps == 0
        force, torque, solver_s, flow, max_speed, escaped = self._worker.request(
            "step", (state.pos_m, state.quat_xyzw, state.linvel_m_s, state.angvel_rad_s, want_flow))
        if flow is not None:
            self._flow = flow
        self.solver_s += solver_s
        self.steps += 1
        self._window += force.sum(axis=0)
        if self.steps % self._window_steps == 0:
            self.peak_window_force_n = max(self.peak_window_force_n,
                                           float(np.linalg.norm(self._window)) / self._window_steps)
            self._window[:] = 0.0
        if not (max_speed < MAX_WATER_SPEED_M_S and np.isfinite(force).all() and np.isfinite(torque).all()):
            raise FluidError(f"the SPH water blew up at t = {state.time_s:.3f} s (a particle at {max_speed:.3g} m/s); "
                             "try a smaller time step or particle radius")
        if escaped > MAX_ESCAPED_SHARE:
            raise FluidError(f"{100 * escaped:.0f} % of the SPH water left the pool by t = {state.time_s:.2f} s "
                             "(pushed through a wall or the floor by the body); use a larger --pool")
        return FluidWrenches(force, torque, self._flow, None)

    def _check_inside(self, state: BodyState) -> None:
        lo, hi = self.pool_min_m, self.pool_max_m
        com = state.com_m
        if com[2] < lo[2]:
            raise FluidError(f"the swimmer sank through the floor of the {self.sph_settings.pool_size_m[2]:g} m deep "
                             f"SPH pool at t = {state.time_s:.2f} s; use --pool large or a larger --water-depth")
        if not (lo[0] < com[0] < hi[0] and lo[1] < com[1] < hi[1]):
            raise FluidError(f"the swimmer left the {hi[0] - lo[0]:g} x {hi[1] - lo[1]:g} m SPH pool at "
                             f"t = {state.time_s:.2f} s (centre of mass at x = {com[0]:.2f}, y = {com[1]:.2f} m)")
        if not (np.all(state.pos_m[:, :2] > lo[:2]) and np.all(state.pos_m[:, :2] < hi[:2])
                and np.all(state.pos_m[:, 2] > lo[2])):
            self.outside_steps += 1

    def particles(self) -> tuple[np.ndarray, np.ndarray] | None:
        """Positions (k, 3) and speeds (k,) of every water particle now; None before the first
        step builds the water."""
        if self._worker is None:
            return None
        positions, velocities = self._worker.request("particles")
        return positions, np.linalg.norm(velocities, axis=1)

    def report(self) -> dict:
        """What the run's summary says about the water."""
        return {**self.startup, "pool_min_m": _listed(self.pool_min_m), "pool_max_m": _listed(self.pool_max_m),
                "steps": self.steps, "solver_s": round(self.solver_s, 3),
                "steps_with_segment_outside_pool": self.outside_steps,
                "peak_total_force_n": self.peak_window_force_n, "window_s": WINDOW_S}


def kinematic_viscosity(settings: SphSettings, medium: Medium) -> float:
    """The settings' viscosity, or the medium's (dynamic over density)."""
    return settings.viscosity_m2_s if settings.viscosity_m2_s is not None else medium.eta_pa_s / medium.rho_kg_m3


def boundary_boxes(half_m: np.ndarray, settings: SphSettings) -> np.ndarray:
    """The boxes SPH sees: shrunk by ``mesh_shrink_radii`` particle radii per side, the correction
    for SPH's fluid-free skin, but never below half the box (thin limbs stay boxes)."""
    half = np.atleast_2d(half_m)
    return np.maximum(half - settings.mesh_shrink_radii * settings.particle_radius_m, half / 2)


def start_request(settings: SphSettings, medium: Medium, gravity_m_s2: float, pool_min_m, pool_max_m,
                  boxes_half_m, pos_m, quat_xyzw) -> dict:
    """The worker's ``start`` request: the scene (pool, water, boxes) and how to settle it. With a
    current the water reaches a buffer past each end it crosses and settles at least
    ``conveyor.SETTLE_S`` (``conveyor.py``)."""
    pos, quat = np.array(np.atleast_2d(pos_m), dtype=float), np.array(np.atleast_2d(quat_xyzw), dtype=float)
    axes = conveyor.open_axes(medium.current_m_s)
    buffer_m = conveyor.BUFFER_RADII * settings.particle_radius_m
    water_min, water_max = conveyor.water_box(pool_min_m, pool_max_m, axes, buffer_m)
    return {
        "scene": {"pool_min_m": water_min, "pool_max_m": water_max,
                  "particle_radius_m": settings.particle_radius_m, "time_step_s": settings.time_step_s,
                  "density_kg_m3": medium.rho_kg_m3, "viscosity_m2_s": kinematic_viscosity(settings, medium),
                  "gravity_m_s2": gravity_m_s2, "boxes_half_m": np.atleast_2d(boxes_half_m), "box_centres_m": pos,
                  "open_axes": axes},
        "surface_z_m": medium.surface_z_m, "pos_m": pos, "quat_xyzw": quat,
        "settle_s": max(settings.settle_s, conveyor.SETTLE_S) if any(axes) else settings.settle_s,
        "damped_share": DAMPED_SHARE, "damping_per_step": DAMPING_PER_STEP,
        "current_m_s": np.asarray(medium.current_m_s, dtype=float), "buffer_m": buffer_m,
    }


def body_corners(pos_m: np.ndarray, quat_xyzw: np.ndarray, half_m: np.ndarray) -> np.ndarray:
    """The eight corners of every segment's box, world frame, (8 n, 3)."""
    signs = np.array([[x, y, z] for x in (-1, 1) for y in (-1, 1) for z in (-1, 1)], dtype=float)
    local = signs[None, :, :] * half_m[:, None, :]                        # (n, 8, 3)
    quats = np.repeat(quat_xyzw[:, None, :], 8, axis=1)
    return (quat_rotate(quats, local) + pos_m[:, None, :]).reshape(-1, 3)


def _listed(values) -> list | None:
    return None if values is None else [round(float(v), 4) for v in values]
