"""A trained residual policy (``ResidualPolicy``) as a file: the actor, its observation
normaliser and the environment it was trained in (``policy.pt``, small, loadable without the
trainer's state; its ``env`` and ``reward`` sections are an ``EnvSpec`` and a ``RewardSpec`` in
memory); running it on SWIM's goal task (``evaluate_goals``) and inside any other episode
(``ResidualDriver``: trajectories, the app's mouse point)."""
from __future__ import annotations

from pathlib import Path
from typing import Callable, NamedTuple

import numpy as np
import torch

from layered_swim.config import ConfigError, parse
from layered_swim.rl.checks import check_keys, check_normaliser, check_tensors, is_count, is_number, read_weights
from layered_swim.rl.config import MAX_HIDDEN_LAYERS, MAX_HIDDEN_WIDTH, EnvSpec, RewardSpec
from layered_swim.rl.ppo import ActorCritic, ActorSnapshot, ModelArgs, Normaliser
from layered_swim.tasks.goal import GOAL_METRICS
from layered_swim.tasks.swim_benchmark import goal_leads_s

POLICY_FORMAT = 1
POLICY_KEYS = ("format", "model_args", "model", "normaliser", "env", "reward")
MAX_POLICY_BYTES = 256 * 2**20      # the shipped policy is 1 MB; hidden [4096, 4096] about 140 MB
MAX_IO_SIZE = 10_000                # observations or actions (the body gives 255 and 33)


class Steering(NamedTuple):
    """A learned residual in charge of an episode (``ResidualPolicy.steering``)."""

    layers: object          # the reference controller's layers (control.layered.Layers)
    wrap: Callable          # Episode's wrap: the residual's controller around the reference
    driver: Callable        # episode -> the observer that sets the residual every policy step
    summary: dict           # what a run's summary says of it


class ResidualPolicy:
    """The trained residual: the actor (``model``) and its observation ``normaliser``, and the
    environment (``env``) and reward weights (``reward``) it was trained with."""

    def __init__(self, model: ActorCritic, normaliser: Normaliser, env: EnvSpec, reward: RewardSpec,
                 model_args: ModelArgs | tuple, source: str = "the policy"):
        self.model, self.normaliser, self.env, self.reward = model, normaliser, env, reward
        self.model_args = ModelArgs(*model_args)
        self.source = source          # what error messages call it: the file it came from

    def to_file(self) -> dict:
        """The file's content: plain data and tensors (torch's safe unpickler reads it), the
        specs as their sections' dicts."""
        return {"format": POLICY_FORMAT, "model_args": list(self.model_args), "model": self.model.state_dict(),
                "normaliser": self.normaliser.state_dict(), "env": self.env.model_dump(),
                "reward": self.reward.model_dump()}

    @classmethod
    def load(cls, path: str | Path) -> "ResidualPolicy":
        """A policy file, every part checked before use: a damaged or foreign one is one
        ConfigError naming it, never a traceback or a network of someone else's size."""
        if not Path(path).exists():
            raise ConfigError(f"{path}: no such policy file")
        data = read_weights(path, MAX_POLICY_BYTES, "not a layered-swim policy file ({kind})")
        if not (isinstance(data, dict) and type(data.get("format")) is int and data["format"] == POLICY_FORMAT):
            raise ConfigError(f"{path}: not a layered-swim policy file (format {POLICY_FORMAT})")
        check_keys(data, POLICY_KEYS, "policy file", path)
        model_args = model_arguments(data["model_args"], path)
        env, reward = section(EnvSpec, data["env"], "env", path), section(RewardSpec, data["reward"], "reward", path)
        like = network_like(model_args)
        size = sum(t.numel() * t.element_size() for t in like.values())
        if size > MAX_POLICY_BYTES:      # before allocating it: the file's shapes must match these
            raise ConfigError(f"{path}: model_args describe a {size}-byte network, more than a policy file may hold")
        weights = check_tensors(data["model"], like, "model", path)
        scaling = check_normaliser(data["normaliser"], model_args.n_obs, path)
        model = ActorCritic(*model_args)
        model.load_state_dict(weights)
        normaliser = Normaliser(model_args.n_obs)
        normaliser.load_state_dict(scaling)
        return cls(model, normaliser, env, reward, model_args, str(path))

    def check_stroke(self, stroke: str | None) -> None:
        """Refuse, in one line, to swim ``stroke`` (None: whichever it was trained for) with a
        policy trained for another."""
        trained = self.env.stroke
        if stroke is not None and stroke != trained:
            raise ConfigError(f"{self.source} was trained for {trained}, not {stroke}; add --stroke {trained}")

    def check_sizes(self, n_obs: int, n_act: int, where: str) -> None:
        """Refuse an episode whose observation or action differs from the network's (another body
        or observation variant): it would fail deep in a matrix product."""
        if (n_obs, n_act) != (self.model_args.n_obs, self.model_args.n_act):
            raise ConfigError(f"{self.source} expects {self.model_args.n_obs} observations and {self.model_args.n_act} "
                              f"actions, {where} has {n_obs} and {n_act}")

    def steering(self, stroke: str | None = None) -> "Steering":
        """How this residual takes charge of an episode of ``stroke`` (None: its own; another is
        refused): build the episode with ``layers`` (its reference controller) and ``wrap``
        around it, then observe it with ``driver(episode)``."""
        from layered_swim.control.layered import Layers
        from layered_swim.control.residual import ResidualController
        from layered_swim.rl.env import REFERENCES

        self.check_stroke(stroke)
        reference = self.env.reference
        return Steering(Layers.parse(REFERENCES[reference]), ResidualController,
                        lambda episode: ResidualDriver(self, episode), {"policy": self.source, "reference": reference})

    def env_kwargs(self, **changes) -> dict:
        """The training environment's arguments, with ``changes`` (backend, pool, current...)."""
        return env_arguments(self.env, self.reward, **changes)


def model_arguments(value, source) -> ModelArgs:
    """``ActorCritic``'s arguments (observations, actions, hidden widths, initial log std)
    within the training configuration's bounds."""
    if not (isinstance(value, (list, tuple)) and len(value) == 4):
        raise ConfigError(f"{source}: model_args must be [observations, actions, hidden widths, log std]")
    n_obs, n_act, hidden, log_std = value
    if not (is_count(n_obs, 1, MAX_IO_SIZE) and is_count(n_act, 1, MAX_IO_SIZE)):
        raise ConfigError(f"{source}: model_args observations and actions must be integers in 1..{MAX_IO_SIZE}")
    if not (isinstance(hidden, (list, tuple)) and 1 <= len(hidden) <= MAX_HIDDEN_LAYERS
            and all(is_count(h, 1, MAX_HIDDEN_WIDTH) for h in hidden)):
        raise ConfigError(f"{source}: model_args hidden widths must be 1 to {MAX_HIDDEN_LAYERS} integers "
                          f"in 1..{MAX_HIDDEN_WIDTH}")
    if not is_number(log_std):
        raise ConfigError(f"{source}: model_args log std must be a finite number")
    return ModelArgs(n_obs, n_act, tuple(hidden), float(log_std))


# Fields added after policies were shipped, whose default is what every earlier file trained with.
LATER_FIELDS = {"draws": None}


def section(spec, data, name: str, source):
    """A file's ``env`` or ``reward`` section as the training configuration's ``spec`` (EnvSpec,
    RewardSpec), complete (a default filled in would change what the policy was trained for),
    but for ``LATER_FIELDS``, which a file written before them lacks."""
    if isinstance(data, dict):
        data = {**{k: v for k, v in LATER_FIELDS.items() if k in spec.model_fields}, **data}
    check_keys(data, spec.model_fields, name, source)
    return parse(spec, data, f"{source}: {name}")


def network_like(model_args: ModelArgs) -> dict[str, torch.Tensor]:
    """The state of ``ActorCritic(*model_args)``: names, shapes and dtypes, nothing allocated."""
    with torch.device("meta"):
        return ActorCritic(*model_args).state_dict()


def env_arguments(env: EnvSpec, reward: RewardSpec, **changes) -> dict:
    """``SwimGoalEnv``'s keyword arguments from a config's ``env`` and ``reward`` sections."""
    return {**env.model_dump(), "reward_weights": reward, **changes}


def evaluate_goals(policy: ResidualPolicy, seeds: int = 5, goals: list[int] | None = None, **env_changes) -> dict:
    """The policy, deterministic, on each of ``goals`` (default: all the pool's) from ``seeds``
    starts (seed 0: SWIM's fixed start; the others jittered): Pos, Prog, Dev and Roll per run
    (over the whole horizon, an episode that ended early held where it stopped), their means and
    the share of runs that swam to the end."""
    from layered_swim.rl.rollouts import make_env, play

    env = make_env(policy.env_kwargs(**{"start_jitter": False, **env_changes}))
    runs = []
    try:
        policy.check_sizes(env.observation_space.shape[0], env.action_space.shape[0], "the goal task")
        goals = range(len(env.episode.task.goals)) if goals is None else goals
        options = [{"goal": g, "start_seed": s} for g in goals for s in range(seeds)]
        episodes = play(env, ActorSnapshot(policy.model), policy.normaliser, list(range(len(options))), True, options)
        for option, episode in zip(options, episodes):
            metrics = episode.info.get("metrics", {})
            runs.append({**option, **metrics, "steps": episode.steps, "return": episode.episode_return,
                         "termination": episode.info.get("termination")})
    finally:
        env.close()
    mean = {k: float(np.mean([r[k] for r in runs])) for k in GOAL_METRICS}    # every run scored to its horizon
    return {**mean, "success_rate": float(np.mean([r["success"] for r in runs])), "runs": runs,
            "terminated": sum(r["termination"] is not None for r in runs)}


class ResidualDriver:
    """Drives ``episode`` (built with ``wrap=ResidualController`` around the policy's reference)
    with ``policy``: an observer called after every physics step that, every 1/policy_hz, reads
    the episode's state, the water's mean wrenches since its last action and four goals on the
    task's target ahead (SWIM eq. 2's leads along the target's own path), and sets the residual."""

    def __init__(self, policy: ResidualPolicy, episode):
        from layered_swim.rl.env import PolicyInput

        self.policy, self.episode = policy, episode
        self.actor = ActorSnapshot(policy.model)
        self.input = PolicyInput(episode, policy.env.env_state)
        sim = episode.sim
        policy.check_sizes(self.input.layout.size, len(sim.layout.names), "this episode")
        self.every = sim.config.physics_hz // policy.env.policy_hz
        self.scale = float(policy.env.action_scale_rad)
        self.leads_s = goal_leads_s(episode.stroke.period_s)
        self._force = np.zeros_like(sim.fluid_now.force_n)
        self._torque = np.zeros_like(sim.fluid_now.torque_nm)
        self.input.reset()
        self._act(1)

    def _act(self, steps: int) -> None:
        sim, target = self.episode.sim, self.episode.task.target
        goals = np.array([target.position(sim.time_s + lead) for lead in self.leads_s])
        observation = self.input(self._force / steps, self._torque / steps, goals)
        action, _ = self.actor.act(self.policy.normaliser(observation), True)
        sim.controller.set_residual(self.scale * np.clip(action, -1.0, 1.0))
        self._force[:] = 0.0
        self._torque[:] = 0.0

    def __call__(self, sim) -> None:
        self._force += sim.fluid_now.force_n
        self._torque += sim.fluid_now.torque_nm
        if sim.steps % self.every == 0:
            self._act(self.every)
