"""The simulation loop: fixed physics step, controller at a whole divisor of it.

One step, one way through: controller (at control rate) -> desired pose -> stable PD;
body state -> fluid backend -> one wrench per segment -> PyBullet step.
"""
from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Callable, Protocol

import numpy as np
from numba import njit

from layered_swim.body.model import Body
from layered_swim.config import ConfigError
from layered_swim.control.pose import JointLayout, joint_layout, quat_multiply
from layered_swim.control.stroke import Stroke
from layered_swim.fluid.medium import Medium
from layered_swim.fluid.thin_plate import ThinPlateFluid
from layered_swim.sim.world import BodyState, World

PRONE_QUAT_XYZW = (0.0, math.sqrt(0.5), 0.0, math.sqrt(0.5))  # standing frame pitched 90 deg: head +x, face down
UPRIGHT_QUAT_XYZW = (0.0, 0.0, 0.0, 1.0)
MAX_SPEED_M_S = 50.0     # any segment faster than this means the integration blew up


@njit(cache=True)
def _all_within(values, limit):
    """Every |value| < limit (False for NaN): a compiled loop, a tenth of numpy's abs-max per step."""
    for v in values.flat:
        if not abs(v) < limit:
            return False
    return True


class SimulationDiverged(RuntimeError):
    """The physics blew up (NaN or absurd velocities); reported, never silently continued."""


class Controller(Protocol):
    def desired(self, time_s: float, state: BodyState | None) -> tuple[np.ndarray, np.ndarray]:
        """Desired pose (rad) and its rate (rad/s) at ``time_s`` (``state`` is None at reset)."""

    def reset(self) -> None:
        """Forget any state (cycle clock, weights) before a new run."""


class StrokeController:
    """The basic stroke layer alone: the stroke's pose at the current phase."""

    def __init__(self, stroke: Stroke, tempo: float = 1.0):
        if not (math.isfinite(tempo) and 0.1 <= tempo <= 5.0):
            raise ConfigError(f"tempo must be between 0.1 and 5, got {tempo}")
        self.stroke = stroke
        self.cycles_per_s = tempo / stroke.period_s

    def phase(self, time_s: float) -> float:
        return time_s * self.cycles_per_s

    def reset(self) -> None:
        """Stateless: the phase is a function of time."""

    def desired(self, time_s: float, state: BodyState) -> tuple[np.ndarray, np.ndarray]:
        pose, rate = self.stroke.pose(self.phase(time_s))
        return pose, rate * self.cycles_per_s


@dataclass(frozen=True)
class SimConfig:
    physics_hz: int = 480
    control_hz: int = 120

    def __post_init__(self):
        if self.physics_hz < 120 or self.physics_hz > 5000:
            raise ConfigError(f"physics rate must be in 120..5000 Hz, got {self.physics_hz}")
        if self.control_hz <= 0 or self.physics_hz % self.control_hz:
            raise ConfigError(f"control rate {self.control_hz} Hz must divide the physics rate {self.physics_hz} Hz")


class Simulation:
    def __init__(self, body: Body, controller: Controller, medium: Medium, config: SimConfig = SimConfig(),
                 layout: JointLayout | None = None, pd_gain_scale: dict[str, float] | None = None):
        self.body = body
        self.layout = layout or joint_layout(body)
        self.controller = controller
        self.medium = medium
        self.config = config
        self.fluid = ThinPlateFluid(body, medium)
        self.world = World(body, self.layout, config.physics_hz, medium.gravity_m_s2, pd_gain_scale)
        self.control_every = config.physics_hz // config.control_hz
        self.steps = 0
        self.state: BodyState | None = None
        self.fluid_force_n = np.zeros((len(body.segment_names), 3))
        # Pushes from outside the water (experiments' impulses), per segment at its centre of
        # mass, world frame; None until the first ``push``, so a plain swim does no extra work.
        self.external_force_n: np.ndarray | None = None
        self.desired_pose = self.desired_rate = None

    @property
    def time_s(self) -> float:
        return self.world.time_s

    def set_medium(self, medium: Medium) -> None:
        """Change the fluid (density, current) mid-run: the swimmer carries on in the new water."""
        self.medium = medium
        self.fluid = ThinPlateFluid(self.body, medium)

    def reset(self, posture: str = "prone", depth_m: float = 0.1, speed_m_s: float = 0.0,
              heading_rad: float = 0.0, position_xy_m: tuple[float, float] = (0.0, 0.0)) -> None:
        base = PRONE_QUAT_XYZW if posture == "prone" else UPRIGHT_QUAT_XYZW
        yaw = (0.0, 0.0, math.sin(heading_rad / 2), math.cos(heading_rad / 2))
        quat = quat_multiply(np.array(yaw), np.array(base))
        velocity = (speed_m_s * math.cos(heading_rad), speed_m_s * math.sin(heading_rad), 0.0)
        self.controller.reset()
        pose, _ = self.controller.desired(0.0, None)  # the stroke's pose at phase 0 needs no state
        self.world.reset((*position_xy_m, -depth_m), quat, pose, velocity)
        self.steps = 0
        self.external_force_n = None
        self.state = self.world.read_state()

    def push(self, force_n, segment: int = 0) -> None:
        """Push ``segment`` (default the pelvis) with ``force_n`` (world frame, at its centre of
        mass) on every step from now until changed; zero stops it."""
        if self.external_force_n is None:
            self.external_force_n = np.zeros((len(self.body.segment_names), 3))
        self.external_force_n[segment] = force_n

    def step(self) -> BodyState:
        state = self.state if self.state is not None else self.world.read_state()
        # The fluid first: the controller's rules read the water velocity it found for this state.
        force, torque = self.fluid.wrenches(state.pos_m, state.quat_xyzw, state.linvel_m_s, state.angvel_rad_s)
        self.fluid_force_n = force
        if self.steps % self.control_every == 0:
            self.desired_pose, self.desired_rate = self.controller.desired(self.world.time_s, state)
            self.world.set_targets(self.desired_pose, self.desired_rate)
        if self.external_force_n is not None:
            force = force + self.external_force_n
        self.world.apply_wrenches(force, torque, state.pos_m)
        self.world.drive()
        self.world.step()
        self.steps += 1
        self.state = self.world.read_state()
        if not _all_within(self.state.linvel_m_s, MAX_SPEED_M_S):
            raise SimulationDiverged(
                f"simulation diverged at t = {self.world.time_s:.3f} s (non-finite or > {MAX_SPEED_M_S} m/s "
                f"segment velocity); try a higher physics rate or lower PD gains")
        return self.state

    def run(self, seconds: float, every_step: Callable[["Simulation"], None] | None = None) -> None:
        for _ in range(int(round(seconds * self.config.physics_hz))):
            self.step()
            if every_step is not None:
                every_step(self)

    def close(self) -> None:
        self.world.close()
