"""The training configuration: a YAML file people edit (``layered_swim/rl/front_crawl.yaml`` is
the shipped one), checked field by field, plus ``--set key=value`` overrides (dotted keys,
YAML values: ``--set ppo.learning_rate=1e-4``)."""
from __future__ import annotations

from pathlib import Path
from typing import Literal

import yaml

from layered_swim.config import ConfigError, Strict, between, load_yaml, parse
from layered_swim.rl.observation import ENV_STATES

SHIPPED_CONFIG = Path(__file__).with_name("front_crawl.yaml")


class EnvSpec(Strict):
    stroke: str = "front_crawl"
    pool: Literal["small", "large"] = "small"
    reference: Literal["basic", "layered"] = "basic"
    env_state: Literal[ENV_STATES] = "SmoothFT"
    policy_hz: int = 30
    action_scale_rad: between(0.0, 1.0, above=True) = 0.2
    start_jitter: bool = True


class RewardSpec(Strict):
    forward_per_m: between(0.0, 1000.0) = 5.0
    deviation_per_m: between(0.0, 1000.0) = 10.0
    heading_per_rad: between(0.0, 1000.0) = 2.0
    roll_per_rad: between(0.0, 1000.0) = 2.0
    accel_s2_per_rad: between(0.0, 10.0) = 0.01
    accel_weight: between(0.0, 10.0) = 0.1


class PpoSpec(Strict):
    gamma: between(0.0, 1.0) = 0.97
    lam: between(0.0, 1.0) = 0.95
    clip: between(0.0, 1.0, above=True) = 0.2
    learning_rate: between(0.0, 1.0, above=True) = 3e-4
    epochs: int = 5
    minibatch: int = 512
    value_coef: between(0.0, 100.0) = 0.5
    entropy_coef: between(0.0, 1.0) = 0.0
    max_grad_norm: between(0.0, 100.0, above=True) = 0.5
    hidden: tuple[int, ...] = (256, 256)
    init_log_std: between(-10.0, 2.0) = -1.0


class BufferSpec(Strict):
    policy: Literal["fifo", "progevict"] = "progevict"
    capacity_episodes: int = 64
    e_mid: between(-1e6, 1e6) = 30.0
    k: between(0.0, 1e6, above=True) = 5.0
    w_age: between(0.0, 1.0) = 0.5
    w_reward: between(0.0, 1.0) = 0.5
    sigma: between(0.0, 10.0, above=True) = 0.5


class RunSpec(Strict):
    samples: int = 1_000_000         # environment steps in all
    episodes_per_epoch: int = 32
    eval_every: int = 5              # epochs between evaluations on the goal task
    checkpoint_every: int = 1        # epochs between checkpoints
    seed: int = 0
    workers: int = 2


class TrainSpec(Strict):
    env: EnvSpec = EnvSpec()
    reward: RewardSpec = RewardSpec()
    ppo: PpoSpec = PpoSpec()
    buffer: BufferSpec = BufferSpec()
    run: RunSpec = RunSpec()

    def model_post_init(self, _context) -> None:
        for name, value, low in (("env.policy_hz", self.env.policy_hz, 1), ("ppo.epochs", self.ppo.epochs, 1),
                                 ("ppo.minibatch", self.ppo.minibatch, 1),
                                 ("buffer.capacity_episodes", self.buffer.capacity_episodes, 1),
                                 ("run.samples", self.run.samples, 1), ("run.episodes_per_epoch", self.run.episodes_per_epoch, 1),
                                 ("run.eval_every", self.run.eval_every, 1), ("run.checkpoint_every", self.run.checkpoint_every, 1),
                                 ("run.seed", self.run.seed, 0), ("run.workers", self.run.workers, 1)):
            if value < low:
                raise ValueError(f"{name} must be at least {low}, got {value}")
        if not self.ppo.hidden or min(self.ppo.hidden) < 1:
            raise ValueError(f"ppo.hidden must list positive layer widths, got {list(self.ppo.hidden)}")


def load_train_spec(path: str | Path | None, overrides: list[str] = ()) -> TrainSpec:
    """The file (the shipped one when None) with ``key=value`` overrides applied."""
    source = Path(path) if path is not None else SHIPPED_CONFIG
    data = load_yaml(source) or {}
    if not isinstance(data, dict):
        raise ConfigError(f"{source}: expected a mapping at the top level, got {type(data).__name__}")
    for item in overrides:
        key, sep, text = item.partition("=")
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
    try:
        return parse(TrainSpec, data, f"{source}{' with --set' if overrides else ''}")
    except ValueError as err:      # model_post_init's checks
        if isinstance(err, ConfigError):
            raise
        raise ConfigError(f"{source}: {str(err).splitlines()[-1] if str(err) else err}") from None
