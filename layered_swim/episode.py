"""The one loop: an episode drives the simulation, its task and the controller.

After dm_control's Physics / Task / Environment split and Gymnasium's ``reset(seed)`` / ``step``:

- ``Episode(stroke, task, ...)`` reads the stroke and body files, builds the fluid backend (by
  name), the controller (from the task's target and the layers) and the simulation, once.
- ``reset(seed, **options)`` asks the task where to start (it may move its target: a goal task
  takes ``goal=k``), resets the simulation there without rebuilding anything, and lets the task
  take its first sample. Seed 0 starts exactly where the task says; any other seed jitters that
  start (``jittered_start``, within ``jitter``), the same way every time for the same seed.
- ``step()`` runs one physics step and lets the task observe it; ``run(seconds)`` is the loop
  every command, the calibration, the experiments, the app and the bench go through, with
  ``observers`` (a recorder, a push, the app's trail) called after every step.

``stroke="auto"`` builds a layered controller for each of ``AUTO_STROKES`` and lets
``control/auto.py`` switch between them; the start is the first one's. Which controller drives
the swimmer: ``weights`` (a ``CycleChooser``, e.g. ``fixed_weights``: scripted per-cycle
weights) gives the layered controller with that chooser; otherwise a task without a target gets
the basic stroke alone, and a task with one gets the layered controller steering toward it
(``TargetChooser``; ``layers`` says which layers are on; the per-cycle layer reads the stroke's
calibration table). ``wrap`` puts another controller around that one (the RL environment's
learned residual).
"""
from __future__ import annotations

import contextlib
import math
import signal
import threading
from dataclasses import dataclass, replace
from typing import Callable, Iterable

import numpy as np

from layered_swim.body.layout import joint_layout
from layered_swim.body.model import load_body
from layered_swim.config import ConfigError, load
from layered_swim.control.auto import AUTO, AUTO_STROKES, AutoStrokeController
from layered_swim.control.basic import StrokeController
from layered_swim.control.calibration import load_table
from layered_swim.control.cycle_choice import Lead, TargetChooser, TempoControl, Water
from layered_swim.control.depth_hold import DepthHold
from layered_swim.control.layered import CycleChooser, LayeredController, Layers, fixed_weights
from layered_swim.control.lungs import LungControl
from layered_swim.control.rules import arm_indices
from layered_swim.control.steering import SteeringGains
from layered_swim.control.stroke import LEVEL_OFF, ROLL_OVER, Stroke, StrokeSpec, build_stroke, stroke_path
from layered_swim.control.targets import Target
from layered_swim.fluid import make_fluid
from layered_swim.fluid.medium import Medium
from layered_swim.sim.simulation import DEFAULT_SIM, PHYSICS_HZ, Simulation
from layered_swim.state import BodyState, JointLayout, Start, lying
from layered_swim.tasks import Task

Observer = Callable[[Simulation], None]


@dataclass(frozen=True)
class StartJitter:
    """How far a non-zero seed moves the start: uniform within +-these."""

    heading_rad: float = math.radians(5.0)
    position_m: float = 0.1
    depth_m: float = 0.03
    speed_share: float = 0.1


START_JITTER = StartJitter()
# The robustness runs (``follow --seeds``): a start a user might give, not a nudge.
WIDE_JITTER = StartJitter(heading_rad=math.radians(10.0), position_m=0.3)


class Episode:
    def __init__(self, stroke: str, task: Task | None = None, *, medium: Medium = Medium(), backend: str = "plate",
                 fluid_settings=None, lung_air_l: float | None = None, physics_hz: int = PHYSICS_HZ,
                 integrator: str = DEFAULT_SIM.integrator, tempo: float = 1.0,
                 layers: Layers = Layers(), weights: CycleChooser | None = None,
                 tempo_control: TempoControl | None = None, seed: int = 0, jitter: StartJitter = START_JITTER,
                 wrap: Callable[[object, JointLayout], object] | None = None):
        if not isinstance(seed, int) or isinstance(seed, bool) or seed < 0:
            raise ConfigError(f"seed must be a non-negative integer, got {seed!r}")
        self.task = task if task is not None else Task()     # swim the stroke; nothing asked, nothing sampled
        self.seed, self.jitter = seed, jitter
        self.body = load_body(lung_air_l=lung_air_l)
        layout = joint_layout(self.body)
        paths = {name: stroke_path(name) for name in (AUTO_STROKES if stroke == AUTO else (stroke,))}
        specs = {name: load(StrokeSpec, path) for name, path in paths.items()}    # as validated, for config.json
        # Each stroke trimmed for this water (nothing changes near the body's own density).
        strokes = {name: build_stroke(specs[name], layout, str(path)).trimmed(self.body.density_ratio(medium.rho_kg_m3))
                   for name, path in paths.items()}
        # The start and the config are the first stroke's (the one ``auto`` starts with).
        first = next(iter(paths))
        self.stroke_spec: StrokeSpec = specs[first]
        self.stroke: Stroke = strokes[first]
        config = replace(DEFAULT_SIM.at(physics_hz), integrator=integrator)
        fluid = make_fluid(backend, self.body, medium, config.gravity_m_s2, fluid_settings)
        try:
            controller = self._build_controller(stroke, strokes, layout, layers, weights, tempo, tempo_control, fluid)
            if wrap is not None:          # e.g. a learned residual on top (control/residual.py)
                controller = wrap(controller, layout)
        except BaseException:
            fluid.close()
            raise
        self.sim = Simulation(self.body, controller, fluid, config, layout, self.stroke.pd_gain_scale)
        try:
            self.reset(seed)
        except BaseException:
            self.close()
            raise

    def _build_controller(self, stroke, strokes, layout, layers, weights, tempo, tempo_control, fluid):
        def water():           # the water swum in now (the app may change it)
            return fluid.medium

        if stroke != AUTO:
            return _controller(self.stroke, self.body, layout, self.task.target, layers, weights, tempo, tempo_control,
                               water)
        if self.task.target is None or weights is not None or not layers.cycle:
            raise ConfigError("--stroke auto chooses strokes to chase a target: it needs one (follow, goal, "
                              "the app) and the per-cycle layer")
        # auto weighs what the target asks against the water swum in.
        return AutoStrokeController(
            {name: _controller(s, self.body, layout, self.task.target, layers, None, tempo, tempo_control, water)
             for name, s in strokes.items()}, self.task.target, medium=water)

    @property
    def controller(self):
        return self.sim.controller

    @property
    def time_s(self) -> float:
        return self.sim.time_s

    def reset(self, seed: int | None = None, **options) -> BodyState:
        """A new episode: the task picks the start (``options`` go to it), the simulation resets
        there, the task takes its first sample. ``seed`` restarts the episode's random generator."""
        if seed is not None:
            self.seed, self.rng = seed, np.random.default_rng(seed)
        start = self.task.reset(self, self.rng, **options)
        if self.seed:
            start = jittered_start(start, self.rng, self.jitter)
        self.sim.reset(start)
        self.task.observe(self.sim)
        return self.sim.state

    def step(self) -> BodyState:
        state = self.sim.step()
        self.task.observe(self.sim)
        return state

    def run(self, seconds: float | None = None, *, steps: int | None = None, observers: Iterable[Observer] = (),
            progress: bool = False) -> None:
        """Run ``seconds`` of simulated time (or exactly ``steps`` physics steps), calling every
        observer after every step, unless the task ends the episode first (``task.ended``);
        ``progress`` shows a bar of simulated seconds."""
        hz = self.sim.config.physics_hz
        n = int(round(seconds * hz)) if steps is None else steps
        observers = list(observers)
        if progress:
            from tqdm import tqdm

            bar = tqdm(total=math.floor(n / hz), desc="simulated seconds", unit="s", leave=False)
            observers.append(lambda sim: bar.update(1) if sim.steps % hz == 0 else None)
        try:
            sim, task = self.sim, self.task
            with _ctrl_c_between_steps() as stop:
                for _ in range(n):
                    sim.step()
                    task.observe(sim)
                    for every_step in observers:
                        every_step(sim)
                    if stop:
                        raise KeyboardInterrupt
                    if task.ended is not None:
                        break
        finally:
            if progress:
                bar.close()

    def metrics(self) -> dict:
        return self.task.metrics()

    def close(self) -> None:
        self.sim.close()


@contextlib.contextmanager
def _ctrl_c_between_steps():
    """While the loop runs, Ctrl-C (SIGINT) only asks it to stop after the current step: a
    KeyboardInterrupt raised inside a compiled (numba) kernel surfaces as a SystemError
    traceback, not as an interrupt. A second Ctrl-C interrupts at once. Yields a list that is
    non-empty once a stop is asked for. Only where Python's own handler is installed (the main
    thread, SIGINT not ignored)."""
    asked: list[bool] = []
    if threading.current_thread() is not threading.main_thread() or \
            signal.getsignal(signal.SIGINT) is not signal.default_int_handler:
        yield asked
        return

    def ask(signum, frame):
        if asked:
            raise KeyboardInterrupt
        asked.append(True)

    signal.signal(signal.SIGINT, ask)
    try:
        yield asked
    finally:
        signal.signal(signal.SIGINT, signal.default_int_handler)


def jittered_start(start: Start, rng: np.random.Generator, jitter: StartJitter = START_JITTER) -> Start:
    """``start`` moved by uniform random amounts within ``jitter``: what a non-zero seed does, so
    runs with different seeds differ and one seed repeats exactly."""
    heading, speed, depth = rng.uniform(-1.0, 1.0, 3)
    dx, dy = rng.uniform(-jitter.position_m, jitter.position_m, 2)
    return replace(start, heading_rad=start.heading_rad + heading * jitter.heading_rad,
                   speed_m_s=start.speed_m_s * (1.0 + speed * jitter.speed_share),
                   depth_m=max(0.0, start.depth_m + depth * jitter.depth_m),
                   position_xy_m=(start.position_xy_m[0] + dx, start.position_xy_m[1] + dy))


def _controller(stroke: Stroke, body, layout, target: Target | None, layers: Layers, weights: CycleChooser | None,
                tempo: float, tempo_control: TempoControl | None, water: Callable[[], Water]):
    if weights is None and target is None:
        return StrokeController(stroke, tempo)
    goal_line = tempo_control is not None
    steer = stroke.steering
    if weights is None:
        if layers.cycle:
            # A task with its own tempo control (the goal line) keeps the default aim, and steers the
            # heading only (no pitch, roll or breath): the shipped residuals were trained on that.
            pace, lead, pitch_roll = tempo_control, Lead(), (0.0, 0.0)
            if not goal_line:
                pitch_roll = (steer.pitch_fraction, steer.roll_fraction)
                pace = TempoControl(min_tempo=steer.min_tempo, far_m=steer.full_tempo_beyond_m,
                                    glide_within_m=steer.glide_within_m,
                                    glide_cycles=steer.glide_cycles, turn_tempo=steer.turn_tempo,
                                    turn_tempo_until_ahead_s=steer.turn_tempo_until_ahead_s,
                                    wide_turn_rad=math.radians(steer.wide_turn_deg),
                                    catch_up_beyond_m=steer.catch_up_beyond_m, dive_tempo=steer.dive_tempo,
                                    close_gap_s=steer.close_gap_s, close_gap_beyond_m=steer.close_gap_beyond_m,
                                    close_gap_ahead_s=steer.close_gap_ahead_s,
                                    wait_turn_tempo=steer.wait_turn_tempo,
                                    wait_pace=steer.wait_pace, weave_tempo=steer.weave_tempo)
                lead = Lead(straight_s=steer.lead_straight_s, bend_s=steer.lead_bend_s,
                            diving_straight_s=steer.lead_straight_diving_s, wait_ahead_s=steer.wait_ahead_s,
                            wait_within_m=steer.wait_within_m, wait_depth_within_m=steer.wait_depth_within_m,
                            aim_off=steer.aim_off,
                            weave_rad=None if steer.weave_deg is None else math.radians(steer.weave_deg),
                            weave_within_m=steer.weave_within_m)
            gains = SteeringGains(steer.yaw_fraction, *pitch_roll,
                                  over_weight_within_rad=math.radians(steer.over_weight_within_deg),
                                  depth_within_m=steer.depth_within_m,
                                  attitude_within_rad=math.radians(steer.attitude_within_deg),
                                  attitude_proportional=steer.attitude_proportional)
            level_off = math.radians(steer.level_off_beyond_deg) if lying(stroke.start.posture) else None
            recover = (None, None) if goal_line else tuple(
                None if deg is None else math.radians(deg)
                for deg in (steer.recover_beyond_pitch_deg, steer.recover_beyond_roll_deg))
            weights = TargetChooser(target, load_table(stroke), stroke.start.posture, gains=gains, tempo=pace,
                                    lead=lead, level_off_beyond_rad=level_off, level_off_tempo=steer.level_off_tempo,
                                    level_off_sequence=LEVEL_OFF in stroke.perturbations,
                                    roll_over_sequence=ROLL_OVER in stroke.perturbations,
                                    level_off_pitch_down_weight=(None if goal_line
                                                                 else steer.level_off_pitch_down_weight),
                                    recover_beyond_rad=recover, water=None if goal_line else water,
                                    under_water_below_m=None if goal_line else steer.under_water_below_m,
                                    under_water_level_pitch_rad=(
                                        None if goal_line or steer.under_water_level_pitch_deg is None
                                        else math.radians(steer.under_water_level_pitch_deg)),
                                    under_water_yaw_fraction=None if goal_line else steer.under_water_yaw_fraction)
        else:
            weights = fixed_weights({}, tempo=tempo)
    lungs = (LungControl(body.lung_air_l, body.max_lung_air_l, breathe_out=steer.breathe_out,
                         damping_s=steer.breathe_damping_s, deep_below_m=steer.under_water_below_m or 0.0,
                         deep_air_l=steer.under_water_air_l)
             if steer.breathe and not goal_line else None)
    depth_hold = (DepthHold(steer.under_water_pitch_per_m, steer.under_water_pitch_per_m_s,
                            steer.under_water_depth_ahead_s)
                  if steer.under_water_pitch_per_m is not None and not goal_line else None)
    return LayeredController(stroke, layout, arm_indices(body, layout), weights, layers, target, lungs, depth_hold)
