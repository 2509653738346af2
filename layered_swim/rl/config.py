"""The training configuration: a YAML file people edit (``layered_swim/rl/front_crawl.yaml`` is
the shipped one), checked field by field, plus ``--set key=value`` overrides (dotted keys,
YAML values: ``--set ppo.learning_rate=1e-4``).

Each section's type is the one the code uses, validated once here: ``EnvSpec`` (a policy file's
``env`` too, ``ResidualPolicy.env``), ``RewardSpec`` (the reward's weights, ``reward.py``),
``PpoSpec`` (``ppo.update``) and ``BufferSpec`` (``EpisodeBuffer``)."""
from __future__ import annotations

from pathlib import Path
from typing import Annotated, Literal

import yaml
from pydantic import Field, field_validator, model_validator

from layered_swim.config import ConfigError, Strict, between, load_yaml, parse
from layered_swim.rl.observation import ENV_STATES

SHIPPED_CONFIG = Path(__file__).with_name("front_crawl.yaml")
CONTROL_HZ = 120        # the simulation's control rate (SimConfig.control_hz): an action spans whole control steps
MAX_HIDDEN_WIDTH, MAX_HIDDEN_LAYERS = 4096, 8


def count(low: int, high: int):
    """An integer people edit with both bounds: a typo like 5000 workers or a 10^5-wide layer is
    an error before anything is built, not a run that eats the machine."""
    return Annotated[int, Field(ge=low, le=high)]


Hidden = Annotated[tuple[count(1, MAX_HIDDEN_WIDTH), ...], Field(min_length=1, max_length=MAX_HIDDEN_LAYERS)]


class Range(Strict):
    """A value drawn uniformly from ``min`` to ``max`` (equal: that value)."""

    min: between(-1e6, 1e6)
    max: between(-1e6, 1e6)

    @model_validator(mode="after")
    def _ordered(self) -> "Range":
        if self.min > self.max:
            raise ValueError(f"min {self.min:g} is above max {self.max:g}")
        return self

    def draw(self, rng) -> float:
        return float(rng.uniform(self.min, self.max)) if self.max > self.min else float(self.min)


class DrawsSpec(Strict):
    """What every training episode draws (domain randomisation). A reset that names its goal
    (evaluation on SWIM's fixed goals, ``evaluate_goals``) draws nothing."""

    pools: tuple[Literal["small", "large"], ...] = Field(("small",), min_length=1)
    # 0: one of the pool's three goals; above: a goal anywhere within this bearing either side of
    # straight ahead (SWIM trains within 14 deg; its Fig. 4 tests out to 30), the pool widened to hold it.
    goal_bearing_deg: between(0.0, 60.0) = 0.0
    current_m_s: Range = Range(min=0.0, max=0.0)      # speed, from a direction drawn over the whole circle
    density_kg_m3: Range | None = None                # None: the environment's own water
    push_chance: between(0.0, 1.0) = 0.0              # the share of episodes pushed once, at a random moment
    push_body_weights: Range = Range(min=1.0, max=3.0)
    push_s: Range = Range(min=0.05, max=0.2)

    @model_validator(mode="after")
    def _physical(self) -> "DrawsSpec":
        if self.current_m_s.min < 0 or self.current_m_s.max > 3.0:
            raise ValueError("current_m_s must lie within 0-3 m/s (a speed; its direction is drawn)")
        density = self.density_kg_m3
        if density is not None and not (300.0 <= density.min and density.max <= 3000.0):
            raise ValueError("density_kg_m3 must lie within 300-3000 kg/m^3")
        if self.push_body_weights.min < 0 or self.push_body_weights.max > 10:
            raise ValueError("push_body_weights must lie within 0-10")
        if self.push_s.min <= 0 or self.push_s.max > 2.0:
            raise ValueError("push_s must lie within 0-2 s and above 0")
        return self


class EnvSpec(Strict):
    """The environment a residual trains in (``SwimGoalEnv``'s arguments but the reward's weights
    and what a run changes: backend, current)."""

    stroke: str = "front_crawl"
    pool: Literal["small", "large"] = "small"
    reference: Literal["basic", "layered"] = "basic"
    env_state: Literal[ENV_STATES] = "SmoothFT"
    policy_hz: count(1, CONTROL_HZ) = 30
    action_scale_rad: between(0.0, 1.0, above=True) = 0.2
    start_jitter: bool = True
    draws: DrawsSpec | None = None        # None: SWIM's setting, the pool's three goals in its own water

    @field_validator("policy_hz")
    @classmethod
    def _whole_control_steps(cls, value: int) -> int:
        if CONTROL_HZ % value:
            raise ValueError(f"must divide the control rate {CONTROL_HZ} Hz")
        return value


class RewardSpec(Strict):
    """The reward's weights (SWIM eqs. 9-15, ``reward.py``)."""

    forward_per_m: between(0.0, 1000.0) = 5.0           # a_p
    deviation_per_m: between(0.0, 1000.0) = 10.0        # a_a
    heading_per_rad: between(0.0, 1000.0) = 2.0         # a_h
    roll_per_rad: between(0.0, 1000.0) = 2.0            # a_r
    accel_s2_per_rad: between(0.0, 10.0) = 0.01         # a_s
    accel_weight: between(0.0, 10.0) = 0.1              # w_accel


class PpoSpec(Strict):
    """PPO's settings (``ppo.update``) and the network's shape (``hidden``, ``init_log_std``)."""

    gamma: between(0.0, 1.0) = 0.97                     # 4 s horizon at 30 Hz: rewards ~1 s ahead still count
    lam: between(0.0, 1.0) = 0.95
    clip: between(0.0, 1.0, above=True) = 0.2
    learning_rate: between(0.0, 1.0, above=True) = 3e-4
    epochs: count(1, 1000) = 5                          # passes over the buffer per update
    minibatch: count(1, 1_000_000) = 512
    value_coef: between(0.0, 100.0) = 0.5
    entropy_coef: between(0.0, 1.0) = 0.0
    max_grad_norm: between(0.0, 100.0, above=True) = 0.5
    hidden: Hidden = (256, 256)
    init_log_std: between(-10.0, 2.0) = -1.0


EVICTIONS = ("fifo", "progevict")


class BufferSpec(Strict):
    """The episode buffer (``EpisodeBuffer``): its size, its eviction rule and ProgEvict's settings
    (SWIM eqs. 16-20; ``fifo`` uses none of them)."""

    eviction: Literal[EVICTIONS] = "progevict"
    capacity_episodes: count(1, 100_000) = 64
    e_mid: between(-1e6, 1e6) = 30.0                    # the epoch where FIFO and the heuristic weigh the same
    k: between(0.0, 1e6, above=True) = 5.0              # how many epochs the hand-over takes (its scale)
    w_age: between(0.0, 1.0) = 0.5
    w_reward: between(0.0, 1.0) = 0.5
    sigma: between(0.0, 10.0, above=True) = 0.5

    @model_validator(mode="before")
    @classmethod
    def _renamed(cls, data):
        if isinstance(data, dict) and "policy" in data:
            raise ValueError(f"policy is now called eviction ({' or '.join(EVICTIONS)})")
        return data

    @model_validator(mode="after")
    def _some_weight(self) -> "BufferSpec":
        if self.w_age + self.w_reward <= 0:
            raise ValueError("w_age and w_reward must not both be 0 (eq. 18 would weigh nothing)")
        return self


class RunSpec(Strict):
    samples: count(1, 10**10) = 1_000_000       # environment steps in all
    episodes_per_epoch: count(1, 10_000) = 32
    eval_every: count(1, 1_000_000) = 5          # epochs between evaluations on the goal task
    checkpoint_every: count(1, 1_000_000) = 1    # epochs between checkpoints
    seed: count(0, 2**31 - 1) = 0
    workers: count(1, 64) = 2
    # A policy file whose network and normaliser the training starts from (a curriculum's next
    # stage), relative to the configuration file; None: a fresh network.
    start_from: str | None = None


class TrainSpec(Strict):
    env: EnvSpec = EnvSpec()
    reward: RewardSpec = RewardSpec()
    ppo: PpoSpec = PpoSpec()
    buffer: BufferSpec = BufferSpec()
    run: RunSpec = RunSpec()


def load_train_spec(path: str | Path | None, overrides: list[str] = ()) -> TrainSpec:
    """The file (the shipped one when None) with ``key=value`` overrides applied."""
    source = Path(path) if path is not None else SHIPPED_CONFIG
    data = load_yaml(source) or {}
    if not isinstance(data, dict):
        raise ConfigError(f"{source}: expected a mapping at the top level, got {type(data).__name__}")
    typed = False           # run.start_from given with --set
    for item in overrides:
        key, sep, text = item.partition("=")
        typed = typed or key == "run.start_from"
        if not sep or not key:
            raise ConfigError(f"--set expects key=value, got {item!r}")
        parts, node = key.split("."), data
        for part in parts[:-1]:
            node = node.setdefault(part, {})
            if not isinstance(node, dict):
                raise ConfigError(f"--set {key}: {part} is not a section")
        try:
            node[parts[-1]] = yaml.safe_load(text)
        except yaml.YAMLError:
            raise ConfigError(f"--set {key}: cannot read the value {text!r}") from None
    spec = parse(TrainSpec, data, f"{source}{' with --set' if overrides else ''}")
    if spec.run.start_from is not None:
        # A file's path is read from the file's folder, one typed with --set from the working folder;
        # an absolute one stays as it is.
        start = (Path.cwd() if typed else source.parent) / spec.run.start_from
        if not start.is_file():
            where = "--set run.start_from" if typed else f"{source}: run.start_from"
            raise ConfigError(f"{where}: no policy file {start}")
        spec = spec.model_copy(update={"run": spec.run.model_copy(update={"start_from": str(start.resolve())})})
    return spec
