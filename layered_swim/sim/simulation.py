"""The physics step: fixed physics rate, controller at a whole divisor of it.

One step, one way through: body state -> fluid backend -> one wrench per segment; the controller
(at control rate) reads the state and the water velocity the fluid found -> desired pose ->
stable PD -> PyBullet step. The episode runner (``layered_swim/episode.py``) is the only loop
that calls ``step``.
"""
from __future__ import annotations

import math
from dataclasses import dataclass, replace
from typing import NamedTuple, Protocol

import numpy as np
from numba import njit

from layered_swim.body.layout import joint_layout
from layered_swim.body.model import Body
from layered_swim.config import ConfigError
from layered_swim.fluid.backend import FluidBackend, FluidWrenches
from layered_swim.geometry import quat_multiply
from layered_swim.sim.world import INTEGRATORS, World
from layered_swim.state import BodyState, JointLayout, Start

PRONE_QUAT_XYZW = (0.0, math.sqrt(0.5), 0.0, math.sqrt(0.5))  # standing frame pitched 90 deg: head +x, face down
SUPINE_QUAT_XYZW = (math.sqrt(0.5), 0.0, math.sqrt(0.5), 0.0)  # prone turned half about the long axis: face up
UPRIGHT_QUAT_XYZW = (0.0, 0.0, 0.0, 1.0)
BASE_QUAT_XYZW = {"prone": PRONE_QUAT_XYZW, "supine": SUPINE_QUAT_XYZW, "upright": UPRIGHT_QUAT_XYZW}
MAX_SPEED_M_S = 50.0     # any segment faster than this means the integration blew up


@njit(cache=True)
def _all_within(values, limit):
    """Every |value| < limit (False for NaN): a compiled loop, a tenth of numpy's abs-max per step."""
    for v in values.flat:
        if not abs(v) < limit:
            return False
    return True


class Pool(NamedTuple):
    """The walls a fluid backend's water has (``FluidBackend.container``): the box's lower and upper
    corner and how far the start must rise for its lowest point to clear the floor."""

    min_m: np.ndarray
    max_m: np.ndarray
    lift_m: float


class SimulationDiverged(RuntimeError):
    """The physics blew up (NaN or absurd velocities); reported, never silently continued."""


class Controller(Protocol):
    def desired(self, time_s: float, state: BodyState | None,
                flow_m_s: np.ndarray | None) -> tuple[np.ndarray, np.ndarray]:
        """Desired pose (rad) and its rate (rad/s) at ``time_s``, given the water velocity at each
        segment (``state`` and ``flow_m_s`` are None at reset)."""

    def reset(self) -> None:
        """Forget any state (cycle clock, weights) before a new run."""


@dataclass(frozen=True)
class SimConfig:
    physics_hz: int
    control_hz: int
    gravity_m_s2: float
    integrator: str = "own"     # who steps the body: our own (sim/integrator.py), or PyBullet

    def __post_init__(self):
        if self.physics_hz < 120 or self.physics_hz > 5000:
            raise ConfigError(f"physics rate must be in 120..5000 Hz, got {self.physics_hz}")
        if self.control_hz <= 0 or self.physics_hz % self.control_hz:
            raise ConfigError(f"control rate {self.control_hz} Hz must divide the physics rate {self.physics_hz} Hz")
        if not (math.isfinite(self.gravity_m_s2) and 0.0 <= self.gravity_m_s2 <= 100.0):
            raise ConfigError(f"gravity must be in 0..100 m/s^2, got {self.gravity_m_s2}")
        if self.integrator not in INTEGRATORS:
            raise ConfigError(f"integrator must be one of {', '.join(INTEGRATORS)}, got {self.integrator!r}")

    def at(self, physics_hz: int) -> "SimConfig":
        return replace(self, physics_hz=physics_hz)


# The rates and gravity of every swim unless it asks otherwise: written here only.
DEFAULT_SIM = SimConfig(physics_hz=480, control_hz=120, gravity_m_s2=9.81)
PHYSICS_HZ, GRAVITY_M_S2 = DEFAULT_SIM.physics_hz, DEFAULT_SIM.gravity_m_s2


class Simulation:
    def __init__(self, body: Body, controller: Controller, fluid: FluidBackend, config: SimConfig = DEFAULT_SIM,
                 layout: JointLayout | None = None, pd_gain_scale: dict[str, float] | None = None):
        self.body = body
        self.layout = layout or joint_layout(body)
        self.controller = controller
        self.fluid = fluid
        self.config = config
        self.world = World(body, self.layout, config.physics_hz, config.gravity_m_s2, pd_gain_scale, config.integrator)
        self.control_every = config.physics_hz // config.control_hz
        self.steps = 0
        self.state: BodyState | None = None
        self.fluid_now = _still(len(body.segment_names))   # what the water did in the last step
        # Pushes from outside the water (experiments' impulses), per segment at its centre of
        # mass, world frame; None until the first ``push``, so a plain swim does no extra work.
        self.external_force_n: np.ndarray | None = None
        self.desired_pose = self.desired_rate = None

    @property
    def time_s(self) -> float:
        return self.world.time_s

    @property
    def fluid_force_n(self) -> np.ndarray:
        return self.fluid_now.force_n

    def reset(self, start: Start) -> None:
        base = BASE_QUAT_XYZW[start.posture]
        heading = start.heading_rad
        yaw = (0.0, 0.0, math.sin(heading / 2), math.cos(heading / 2))
        quat = quat_multiply(np.array(yaw), np.array(base))
        velocity = (start.speed_m_s * math.cos(heading), start.speed_m_s * math.sin(heading), 0.0)
        self.controller.reset()
        self.fluid.reset()
        self._breathe(self.body.lung_air_l)
        pose, _ = self.controller.desired(0.0, None, None)  # the stroke's pose at phase 0 needs no state
        root_m = np.array([*start.position_xy_m, -start.depth_m])
        self.world.reset(root_m, quat, pose, velocity)
        walls = self.fluid.container(self.world.read_state())
        pool = Pool(*walls) if walls is not None else None
        if pool is not None and pool.lift_m > 0.0:
            self.world.reset(root_m + [0.0, 0.0, pool.lift_m], quat, pose, velocity)
        self.world.set_pool(*((pool.min_m, pool.max_m) if pool is not None else (None, None)))
        self.steps = 0
        self.external_force_n = None
        self.fluid_now = _still(len(self.body.segment_names))
        self.state = self.world.read_state()

    @property
    def lung_air_l(self) -> float:
        """The air the swimmer holds now, as the fluid sees it."""
        return self.fluid.body.lung_air_l

    def _breathe(self, air_l: float) -> None:
        if air_l != self.lung_air_l and self.fluid.breathes:
            self.fluid.breathe(air_l)

    def push(self, force_n, segment: str = "pelvis") -> None:
        """Push ``segment`` with ``force_n`` (world frame, at its centre of mass) on every step
        from now until changed; zero stops it."""
        if self.external_force_n is None:
            self.external_force_n = np.zeros((len(self.body.segment_names), 3))
        self.external_force_n[self.body.index(segment)] = force_n

    def step(self) -> BodyState:
        state = self.state
        # The fluid first: the controller's rules read the water velocity it found for this state.
        fluid = self.fluid_now = self.fluid.wrenches(state)
        if self.steps % self.control_every == 0:
            self.desired_pose, self.desired_rate = self.controller.desired(self.world.time_s, state, fluid.flow_m_s)
            self.world.set_targets(self.desired_pose, self.desired_rate)
            air = getattr(self.controller, "lung_air_l", None)    # a stroke that breathes to steer
            if air is not None:
                self._breathe(air)
        force = fluid.force_n if self.external_force_n is None else fluid.force_n + self.external_force_n
        self.world.drive_and_step(force, fluid.torque_nm, state.pos_m)
        self.steps += 1
        self.state = self.world.read_state()
        if not _all_within(self.state.linvel_m_s, MAX_SPEED_M_S):
            raise SimulationDiverged(
                f"simulation diverged at t = {self.world.time_s:.3f} s (non-finite or > {MAX_SPEED_M_S} m/s "
                f"segment velocity); try a higher physics rate or lower PD gains")
        return self.state

    def close(self) -> None:
        self.fluid.close()
        self.world.close()


def _still(n_segments: int) -> FluidWrenches:
    zeros = np.zeros((n_segments, 3))
    return FluidWrenches(zeros, zeros, zeros, zeros)
