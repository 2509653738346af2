"""A trained residual policy as a file: the actor, its observation normaliser and the
environment it was trained in (``policy.pt``, small, loadable without the trainer's state);
running it on SWIM's goal task (``evaluate_goals``) and inside any other episode
(``ResidualDriver``: trajectories, the app's mouse point)."""
from __future__ import annotations

from pathlib import Path

import numpy as np
import torch

from layered_swim.config import ConfigError
from layered_swim.rl.ppo import ActorCritic, ActorSnapshot, Normaliser
from layered_swim.rl.reward import RewardWeights
from layered_swim.tasks.goal import GOAL_METRICS
from layered_swim.tasks.swim_benchmark import goal_leads_s

POLICY_FORMAT = 1


class Policy:
    def __init__(self, model: ActorCritic, normaliser: Normaliser, env: dict, reward: dict, model_args: tuple):
        self.model, self.normaliser, self.env, self.reward, self.model_args = model, normaliser, env, reward, model_args

    def to_file(self) -> dict:
        return {"format": POLICY_FORMAT, "model_args": list(self.model_args), "model": self.model.state_dict(),
                "normaliser": self.normaliser.state_dict(), "env": self.env, "reward": self.reward}

    @classmethod
    def load(cls, path: str | Path) -> "Policy":
        try:
            data = torch.load(path, map_location="cpu", weights_only=True)
        except FileNotFoundError:
            raise ConfigError(f"{path}: no such policy file") from None
        except Exception as err:      # noqa: BLE001  a damaged or foreign file: one line
            raise ConfigError(f"{path}: not a layered-swim policy file ({type(err).__name__})") from None
        if not isinstance(data, dict) or data.get("format") != POLICY_FORMAT:
            raise ConfigError(f"{path}: not a layered-swim policy file (format {POLICY_FORMAT})")
        n_obs, n_act, hidden, log_std = data["model_args"]
        model_args = (int(n_obs), int(n_act), tuple(int(h) for h in hidden), float(log_std))
        model = ActorCritic(*model_args)
        model.load_state_dict(data["model"])
        normaliser = Normaliser(model_args[0])
        normaliser.load_state_dict(data["normaliser"])
        return cls(model, normaliser, dict(data["env"]), dict(data["reward"]), model_args)

    def env_kwargs(self, **changes) -> dict:
        """The training environment's arguments, with ``changes`` (backend, pool, current...)."""
        return env_arguments(self.env, self.reward, **changes)


def follow_steering(policy_path: str | Path, stroke: str):
    """The layers and ``follow_run`` arguments that put the residual in ``policy_path`` in charge
    of a follow swim: its own reference controller, driven by ``ResidualDriver``."""
    from layered_swim.control.layered import Layers
    from layered_swim.control.residual import ResidualController
    from layered_swim.rl.env import REFERENCES

    policy = Policy.load(policy_path)
    if stroke != policy.env["stroke"]:
        raise ConfigError(f"{policy_path} was trained for {policy.env['stroke']}; add --stroke {policy.env['stroke']}")
    return Layers.parse(REFERENCES[policy.env["reference"]]), {
        "wrap": ResidualController, "driver": lambda episode: ResidualDriver(policy, episode),
        "extra": {"policy": str(policy_path), "reference": policy.env["reference"]}}


def env_arguments(env: dict, reward: dict, **changes) -> dict:
    """``SwimGoalEnv``'s keyword arguments from a config's ``env`` and ``reward`` sections."""
    return {**env, "reward_weights": RewardWeights(**reward), **changes}


def evaluate_goals(policy: Policy, seeds: int = 5, goals: list[int] | None = None, **env_changes) -> dict:
    """The policy, deterministic, on each of ``goals`` (default: all the pool's) from ``seeds``
    starts (seed 0: SWIM's fixed start; the others jittered): Pos, Prog, Dev and Roll per run
    and their means."""
    from layered_swim.rl.rollouts import make_env, play

    env = make_env(policy.env_kwargs(**{"start_jitter": False, **env_changes}))
    runs = []
    try:
        goals = range(len(env.episode.task.goals)) if goals is None else goals
        options = [{"goal": g, "start_seed": s} for g in goals for s in range(seeds)]
        episodes = play(env, ActorSnapshot(policy.model), policy.normaliser, list(range(len(options))), True, options)
        for option, episode in zip(options, episodes):
            metrics = episode.info.get("metrics", {})
            runs.append({**option, **metrics, "steps": episode.steps, "return": episode.episode_return,
                         "termination": episode.info.get("termination")})
    finally:
        env.close()
    complete = [r for r in runs if all(k in r for k in GOAL_METRICS)]
    mean = {k: float(np.mean([r[k] for r in complete])) if complete else None for k in GOAL_METRICS}
    return {**mean, "runs": runs, "terminated": sum(r["termination"] is not None for r in runs)}


class ResidualDriver:
    """Drives ``episode`` (built with ``wrap=ResidualController`` around the policy's reference)
    with ``policy``: an observer called after every physics step that, every 1/policy_hz, reads
    the episode's state, the water's mean wrenches since its last action and four goals on the
    task's target ahead (SWIM eq. 2's leads along the target's own path), and sets the residual."""

    def __init__(self, policy: Policy, episode):
        from layered_swim.rl.env import PolicyInput

        self.policy, self.episode = policy, episode
        self.actor = ActorSnapshot(policy.model)
        self.input = PolicyInput(episode, policy.env["env_state"])
        if self.input.layout.size != policy.model_args[0]:
            raise ConfigError(f"the policy expects {policy.model_args[0]} observations, this episode gives "
                              f"{self.input.layout.size}")
        sim = episode.sim
        self.every = sim.config.physics_hz // int(policy.env["policy_hz"])
        self.scale = float(policy.env["action_scale_rad"])
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
