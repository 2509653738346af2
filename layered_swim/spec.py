"""One description of a swim: ``SwimSpec``, frozen and validated, from which every command builds
its ``Episode`` (``SwimSpec.episode``). Its dump is the ``swim`` field of every run folder's
``config.json``, so ``layered-swim run --config FOLDER/config.json`` swims the same swim again,
bit for bit.

What it holds: the stroke, the task (free swimming, a trajectory to follow, SWIM's goal
reaching), the water (preset, density, current), the fluid backend and its settings, the rates,
the layers, the seed and how far a seed moves the start, and a learned residual's file.
"""
from __future__ import annotations

from dataclasses import asdict
from typing import Annotated, Literal, Union

from pydantic import Field

from layered_swim.config import ConfigError, Strict, between, parse
from layered_swim.control.cycle_choice import TempoControl
from layered_swim.control.layered import Layers
from layered_swim.episode import START_JITTER, WIDE_JITTER, Episode
from layered_swim.fluid.flow_field import FlowField, WaterSpec
from layered_swim.fluid.medium import Medium, water
from layered_swim.recorder import DEFAULT_LOG_HZ
from layered_swim.sim.simulation import DEFAULT_SIM, PHYSICS_HZ

MAX_SECONDS = 24 * 3600.0     # a day: soak's longest; the log streams to disk, memory stays flat
MIN_SECONDS = 0.1             # a few log samples, so the metrics have a time span
JITTERS = {"start": START_JITTER, "wide": WIDE_JITTER}
# The goal line is slow (0.375 m/s), but its schedule is not a pace to keep: keeping the calibrated
# pace of the goal's speed (steady, straight) brought the crawl there far too early (Prog 1.16).
# Below 0.6 of its tempo the crawl stalls and sinks: at 0.25 it fell behind in the large pool's
# 8 s (Prog 0.51, half its swims on the 0.7 m floor); at 0.6 it keeps the schedule there (1.01)
# and in the small pool (Prog 0.72 -> 0.90; 3 goals x 2 starts each).
GOAL_TEMPO = TempoControl(min_tempo=0.6, near_m=0.3, far_m=1.0, keep_pace=False)

Speed_m_s = between(-5.0, 5.0)


class MediumSpec(Strict):
    """The water: a preset (its density and viscosity), optionally another density, a current, and
    a flow field (a ``water`` file's content, kept whole so the run replays without the file)."""

    fluid: Literal["fresh_water", "seawater"] = "fresh_water"
    density_kg_m3: between(1.0, 20000.0) | None = None
    current_m_s: tuple[Speed_m_s, Speed_m_s, Speed_m_s] = (0.0, 0.0, 0.0)
    flow: WaterSpec | None = None

    def medium(self) -> Medium:
        return water(self.fluid, self.density_kg_m3, self.current_m_s,
                     FlowField(self.flow) if self.flow is not None else None)


class FreeSwimTask(Strict):
    kind: Literal["free"] = "free"


class FollowTask(Strict):
    kind: Literal["follow"] = "follow"
    trajectory: str = Field(min_length=1)       # a name (trajectories/) or a path to a .yaml


class GoalTask(Strict):
    kind: Literal["goal"] = "goal"
    pool: Literal["small", "large"] = "small"


TaskSpec = Annotated[Union[FreeSwimTask, FollowTask, GoalTask], Field(discriminator="kind")]


class SwimSpec(Strict):
    stroke: str = Field(min_length=1)           # a name (strokes/), a path to a .yaml, or auto
    task: TaskSpec = FreeSwimTask()
    seconds: between(MIN_SECONDS, MAX_SECONDS) = 30.0   # goal: each goal's horizon is the pool's
    medium: MediumSpec = MediumSpec()
    backend: str = "plate"
    sph: dict | None = None                     # the SPH settings' fields (backend sph)
    plate: dict | None = None                   # the thin plates' settings' fields (backend plate), e.g. added_mass
    physics_hz: int = Field(PHYSICS_HZ, ge=120, le=5000)
    integrator: Literal["own", "bullet"] = DEFAULT_SIM.integrator    # who steps the body: ours, or PyBullet
    log_hz: int = Field(DEFAULT_LOG_HZ, ge=1, le=5000)
    tempo: between(0.1, 5.0) = 1.0
    lung_air_l: between(0.0, 8.0) | None = None
    layers: str = Layers().describe()
    seed: int = Field(0, ge=0, le=2**31 - 1)    # 0: the task's exact start; others jitter it
    jitter: Literal["start", "wide"] = "start"  # how far a seed moves the start
    policy: str | None = None                   # a learned residual's file (policy.pt) on its reference

    def model_post_init(self, _context) -> None:
        Layers.parse(self.layers)                # one line if malformed
        if self.sph is not None and self.backend != "sph":
            raise ConfigError(f"sph settings are for backend sph, not {self.backend}")
        if self.plate is not None and self.backend != "plate":
            raise ConfigError(f"plate settings are for backend plate, not {self.backend}")
        if self.plate is not None:
            self.fluid_settings()                # one line if a setting is unknown or out of range

    @property
    def layer_set(self) -> Layers:
        return Layers.parse(self.layers)

    def fluid_settings(self):
        """The backend's settings object: SPH's from ``sph``, the plates' from ``plate``; None (its
        defaults) otherwise."""
        if self.plate is not None:
            from layered_swim.fluid.thin_plate import PlateSettings

            try:
                return PlateSettings(**self.plate)
            except TypeError as err:
                raise ConfigError(f"plate settings: {err}") from None
        if self.sph is None:
            return None
        from layered_swim.fluid.sph import SphSettings

        fields = {**self.sph, "pool_size_m": tuple(self.sph.get("pool_size_m", SphSettings().pool_size_m))}
        try:
            return SphSettings(**fields)
        except TypeError as err:
            raise ConfigError(f"sph settings: {err}") from None

    def episode(self, wrap=None, layers: Layers | None = None) -> Episode:
        """The episode this spec describes (``wrap``/``layers``: a learned residual's controller
        around its reference layers, see ``rl.policy.ResidualPolicy.steering``)."""
        from layered_swim.tasks import FollowTarget, FreeSwim, GoalReaching

        task = self.task
        if isinstance(task, FollowTask):
            from layered_swim.control.targets import load_trajectory

            built = FollowTarget(load_trajectory(task.trajectory))
        elif isinstance(task, GoalTask):
            from layered_swim.tasks import swim_benchmark

            built = GoalReaching(swim_benchmark.pool(task.pool))
        else:
            built = FreeSwim(sample_hz=self.log_hz)
        return Episode(self.stroke, built, medium=self.medium.medium(), backend=self.backend,
                       fluid_settings=self.fluid_settings(), lung_air_l=self.lung_air_l, physics_hz=self.physics_hz,
                       integrator=self.integrator,
                       tempo=self.tempo, layers=layers or self.layer_set,
                       tempo_control=GOAL_TEMPO if isinstance(task, GoalTask) else None, seed=self.seed,
                       jitter=JITTERS[self.jitter], wrap=wrap)

    @classmethod
    def of(cls, source: str, **fields) -> "SwimSpec":
        """A spec from ``fields`` (None: the default); a bad one is one ConfigError line naming
        ``source`` and the field."""
        return parse(cls, {k: v for k, v in fields.items() if v is not None}, source)

    def with_(self, **changes) -> "SwimSpec":
        return type(self).of("the changed swim", **{**self.model_dump(), **changes})


def sph_fields(settings) -> dict | None:
    """An SPH settings object as ``SwimSpec.sph`` holds it."""
    return None if settings is None else asdict(settings)
