"""The interactive swim behind the app's window, without any OpenGL: the simulation, its target
(the mouse's point or a trajectory), the switches a user flips, the fixed-step clock and the
figures the HUD shows. The window (``window.py``) and headless rendering (``render.py``) drive it.
"""
from __future__ import annotations

import math
import time
from collections import deque
from dataclasses import dataclass, replace

import numpy as np

from layered_swim.control.auto import AUTO
from layered_swim.control.calibration import CalibrationError
from layered_swim.control.layered import Layers
from layered_swim.control.steering import attitude_of
from layered_swim.control.stroke import available_strokes, stroke_path
from layered_swim.control.targets import MovableTarget, TrajectoryTarget, load_trajectory
from layered_swim.episode import Episode
from layered_swim.fluid.flow_field import load_water
from layered_swim.fluid.medium import PRESETS_KG_M3_PA_S, water
from layered_swim.render.scene import Scene
from layered_swim.sim.simulation import PHYSICS_HZ, SimulationDiverged
from layered_swim.tasks import FollowTarget

CURRENT_PRESETS_M_S = (("none", (0.0, 0.0, 0.0)), ("0.3 m/s cross", (0.0, 0.3, 0.0)),
                       ("0.5 m/s head-on", (-0.5, 0.0, 0.0)))
DENSITY_PRESETS_KG_M3 = (("fresh water", PRESETS_KG_M3_PA_S["fresh_water"][0]),
                         ("seawater", PRESETS_KG_M3_PA_S["seawater"][0]), ("light fluid", 800.0),
                         ("dense fluid", 1500.0))
SLOW_MOTION = 0.25
MAX_LAG_S = 0.1            # simulated time a frame may owe; beyond it the sim slows instead of spiralling
TRAIL_EVERY_S = 0.1
TRAIL_POINTS = 600         # one minute of trail
DEFAULT_TARGET_AHEAD_M = 8.0
DEFAULT_TARGET_DEPTH_M = 0.3
MAX_TARGET_DEPTH_M = 3.0
SPEED_TIME_CONSTANT_S = 1.0
RATE_WINDOW_S = 1.0        # real-time factor over about the last second of wall time


@dataclass(frozen=True)
class Choice:
    """A named preset: what the HUD prints and the value behind it."""

    label: str
    value: object


def _presets(presets, given, label) -> tuple[list[Choice], int]:
    """The presets, with a value given on the command line first when it is not one of them."""
    choices = [Choice(name, value) for name, value in presets]
    for i, choice in enumerate(choices):
        if np.allclose(choice.value, given):
            return choices, i
    return [Choice(label, given)] + choices, 0


class ActiveTarget:
    """The target the controller steers to: the scripted trajectory until the user clicks, then
    the mouse's point. One object for the session: the controller is built with it and keeps it
    through every switch."""

    def __init__(self, mouse: MovableTarget, trajectory: TrajectoryTarget | None):
        self.mouse, self.trajectory = mouse, trajectory
        self.scripted = trajectory is not None

    def position(self, time_s: float) -> np.ndarray:
        return self.trajectory.position(time_s) if self.scripted else self.mouse.position(time_s)

    def path_points(self, n: int = 400) -> np.ndarray:
        return self.trajectory.path_points(n) if self.scripted else self.mouse.path_points(n)


class SwimSession:
    def __init__(self, stroke: str = "breaststroke", layers: Layers = Layers(), current_m_s=(0.0, 0.0, 0.0),
                 density_kg_m3: float | None = None, trajectory: str | None = None, physics_hz: int = PHYSICS_HZ,
                 backend: str = "plate", fluid_settings=None, policy=None, water: str | None = None):
        """``water``: a water file (name or path) whose flow field is added to the current."""
        self.strokes = available_strokes() + [AUTO]
        if stroke != AUTO:
            stroke_path(stroke)                      # unknown stroke: one-line error before anything opens
        if stroke not in self.strokes:
            self.strokes.append(stroke)              # a stroke file given by path
        # A learned residual (rl.policy.ResidualPolicy) drives its own stroke on its own reference controller.
        self.policy = policy
        if policy is not None:
            policy.check_stroke(stroke)
            self.strokes = [stroke]
        self.currents, self.current_index = _presets(CURRENT_PRESETS_M_S, tuple(current_m_s), "custom current")
        self.flow = load_water(water) if water else None
        density = DENSITY_PRESETS_KG_M3[0][1] if density_kg_m3 is None else float(density_kg_m3)
        self.densities, self.density_index = _presets(DENSITY_PRESETS_KG_M3, density, f"{density:g} kg/m3")
        trajectory_target = load_trajectory(trajectory) if trajectory else None
        self.trajectory_path_m = trajectory_target.path_points(600) if trajectory_target else None
        self.target_depth_m = DEFAULT_TARGET_DEPTH_M
        self.mouse_target = MovableTarget((DEFAULT_TARGET_AHEAD_M, 0.0, -self.target_depth_m))
        self.target = ActiveTarget(self.mouse_target, trajectory_target)
        self.layers = layers
        self.physics_hz = physics_hz
        self.backend, self.fluid_settings = backend, fluid_settings
        self._speed_blend = 1.0 - math.exp(-1.0 / (physics_hz * SPEED_TIME_CONSTANT_S))   # per-step speed smoothing
        self.paused = False
        self.slow_motion = False
        self.message = ""
        self.stroke = stroke
        self._build(stroke, position_xy_m=(0.0, 0.0), heading_rad=0.0, use_start_speed=True)

    # --- building ----------------------------------------------------------------------
    def _medium(self):
        return water(density_kg_m3=self.densities[self.density_index].value,
                     current_m_s=self.currents[self.current_index].value, flow=self.flow)

    def _build(self, stroke: str, position_xy_m, heading_rad: float, use_start_speed: bool) -> None:
        old = getattr(self, "episode", None)
        task = FollowTarget(self.target, position_xy_m, None if use_start_speed else 0.0, heading_rad)
        self._driver = None
        if self.policy is not None:
            episode = self._policy_episode(stroke, task)
        else:
            episode = self._episode(stroke, task)
        if old is not None:
            old.close()
        self.episode, self.sim, self.stroke = episode, episode.sim, stroke
        self._apply_layers()
        self.trail: deque = deque(maxlen=TRAIL_POINTS)
        self._next_trail_s = 0.0
        self._accumulator_s = 0.0
        self.diverged = False
        self.divergence = ""            # what blew up, for a caller with no R key (headless render)
        self.speed_m_s = float(np.hypot(*self.sim.state.com_vel_m_s[:2]))
        self._rate_samples: deque = deque()
        self.realtime_factor = 0.0
        self.falling_behind = False
        self._record_trail()

    def _policy_episode(self, stroke: str, task) -> Episode:
        steering = self.policy.steering(stroke)
        self.cycle_available = True
        episode = Episode(stroke, task, medium=self._medium(), physics_hz=self.physics_hz, layers=steering.layers,
                          backend=self.backend, fluid_settings=self.fluid_settings, wrap=steering.wrap)
        self._driver = steering.driver(episode)
        return episode

    def _episode(self, stroke: str, task) -> Episode:
        try:
            self.cycle_available = True
            episode = Episode(stroke, task, medium=self._medium(), physics_hz=self.physics_hz, layers=Layers(),
                              backend=self.backend, fluid_settings=self.fluid_settings)
        except CalibrationError as err:
            # A stroke without a usable table still swims, with the rules but no steering.
            self.cycle_available = False
            self.message = f"per-cycle steering off: {err}"
            episode = Episode(stroke, task, medium=self._medium(), physics_hz=self.physics_hz,
                              layers=Layers(cycle=False), backend=self.backend, fluid_settings=self.fluid_settings)
        return episode

    def _apply_layers(self) -> None:
        if self.policy is None:       # a policy's reference keeps the layers it was trained on
            self.sim.controller.layers = self.layers if self.cycle_available else replace(self.layers, cycle=False)

    # --- what the user does ------------------------------------------------------------
    def reset(self) -> None:
        self.message = ""
        self._build(self.stroke, (0.0, 0.0), 0.0, use_start_speed=True)

    def set_stroke(self, stroke: str) -> None:
        """Switch stroke where the swimmer is, facing where it faces."""
        com = self.com_m
        heading = self.heading_rad
        self.message = ""
        self._build(stroke, (float(com[0]), float(com[1])), heading, use_start_speed=False)

    def next_stroke(self, step: int = 1) -> None:
        self.set_stroke(self.strokes[(self.strokes.index(self.stroke) + step) % len(self.strokes)])

    def toggle_layer(self, name: str) -> None:
        if self.policy is not None:
            self.message = "the policy's reference controller keeps the layers it was trained with"
            return
        self.layers = replace(self.layers, **{name: not getattr(self.layers, name)})
        self._apply_layers()
        if name == "cycle" and not self.cycle_available:
            self.message = f"{self.stroke} has no calibration table: per-cycle steering unavailable"

    def next_current(self) -> None:
        self.current_index = (self.current_index + 1) % len(self.currents)
        self.sim.fluid.set_medium(self._medium())

    def next_density(self) -> None:
        trim = self._trim_weight()
        self.density_index = (self.density_index + 1) % len(self.densities)
        if self._trim_weight() != trim:
            self.set_stroke(self.stroke)      # strokes are trimmed for the water they are built in
            self.message = f"{self.stroke} trimmed for {self.densities[self.density_index].label}"
        else:
            self.sim.fluid.set_medium(self._medium())

    def _trim_weight(self) -> float:
        stroke = self.episode.stroke
        return stroke.trim_spec.weight(self.episode.body.density_ratio(self._medium().rho_kg_m3))

    def set_target(self, point_xy_m) -> None:
        """Put the mouse target at a point on the water, at the current target depth."""
        self.mouse_target.set((float(point_xy_m[0]), float(point_xy_m[1]), -self.target_depth_m))
        self.target.scripted = False

    def change_target_depth(self, delta_m: float) -> None:
        self.target_depth_m = min(MAX_TARGET_DEPTH_M, max(0.0, self.target_depth_m + delta_m))
        p = self.mouse_target.position(0.0)
        self.mouse_target.set((p[0], p[1], -self.target_depth_m))

    # --- time --------------------------------------------------------------------------
    @property
    def time_scale(self) -> float:
        return SLOW_MOTION if self.slow_motion else 1.0

    def advance(self, wall_dt_s: float) -> int:
        """Run the physics on its own fixed step for ``wall_dt_s`` of wall time (scaled in slow
        motion). Time the machine could not simulate is dropped, not owed: the swim slows down
        and ``falling_behind`` says so. Returns the physics steps taken."""
        now = time.perf_counter()
        steps = 0
        if not (self.paused or self.diverged):
            dt_s = 1.0 / self.physics_hz
            self._accumulator_s += max(0.0, wall_dt_s) * self.time_scale
            dropped = self._accumulator_s > MAX_LAG_S
            self._accumulator_s = min(self._accumulator_s, MAX_LAG_S)
            steps = int(self._accumulator_s / dt_s + 1e-9)
            self._accumulator_s -= steps * dt_s
            self.step(steps)
            self._measure_rate(now, steps * dt_s, dropped)
        return steps

    def _measure_rate(self, now_s: float, simulated_s: float, dropped: bool) -> None:
        self._rate_samples.append((now_s, simulated_s))
        while len(self._rate_samples) > 2 and now_s - self._rate_samples[0][0] > RATE_WINDOW_S:
            self._rate_samples.popleft()
        span_s = now_s - self._rate_samples[0][0]
        if span_s > 0:
            self.realtime_factor = sum(s for _, s in list(self._rate_samples)[1:]) / span_s
        self.falling_behind = dropped or (span_s > 0.5 and self.realtime_factor < 0.9 * self.time_scale)

    def step(self, steps: int) -> None:
        """Exactly ``steps`` physics steps (single-stepping, headless rendering)."""
        if self.diverged:
            return
        try:
            self.episode.run(steps=steps,
                             observers=[self._driver, self._after_step] if self._driver else [self._after_step])
        except SimulationDiverged as err:
            self.diverged, self.divergence = True, str(err)
            self.message = f"{err}; press R to reset"

    def _after_step(self, sim) -> None:
        if sim.time_s >= self._next_trail_s:
            self._record_trail()
        velocity = sim.state.com_vel_m_s
        self.speed_m_s += self._speed_blend * (math.hypot(velocity[0], velocity[1]) - self.speed_m_s)

    def _record_trail(self) -> None:
        self.trail.append(self.com_m)
        self._next_trail_s = self.sim.time_s + TRAIL_EVERY_S

    # --- what the HUD and the renderer read --------------------------------------------
    @property
    def com_m(self) -> np.ndarray:
        return self.sim.state.com_m

    @property
    def heading_rad(self) -> float:
        return attitude_of(self.sim.state, self.swimming.start.posture).heading_rad

    @property
    def swimming(self):
        """The stroke swimming now (``auto`` switches between several)."""
        return self.sim.controller.stroke

    @property
    def target_m(self) -> np.ndarray:
        return self.target.position(self.sim.time_s)

    @property
    def distance_to_target_m(self) -> float:
        return float(np.linalg.norm(self.target_m - self.com_m))

    @property
    def stroke_rate_cpm(self) -> float:
        return 60.0 * self.sim.controller.cycles_per_s

    @property
    def cycle_phase(self) -> float:
        return self.sim.controller.phase(self.sim.time_s) % 1.0

    @property
    def weights(self) -> dict[str, float]:
        return {k: v for k, v in self.sim.controller.choice.weights.items() if v > 0.005}

    @property
    def current_m_s(self) -> np.ndarray:
        return np.asarray(self.currents[self.current_index].value, float)

    def scene(self) -> Scene:
        state, body = self.sim.state, self.sim.body
        water = self.sim.fluid.particles()
        return Scene(body.segment_names, body.half_extents_m, state.pos_m, state.quat_xyzw, self.target_m,
                     self.trajectory_path_m if self.target.scripted else None, np.array(self.trail),
                     self.sim.fluid_force_n, self.current_m_s, *(water or (None, None)),
                     flow_m_s=self.sim.fluid_now.flow_m_s, water_at=self._water_at if self.flow else None)

    def _water_at(self, points_m: np.ndarray) -> np.ndarray:
        return self.sim.fluid.medium.current_at(points_m, self.sim.time_s)

    def close(self) -> None:
        self.episode.close()
