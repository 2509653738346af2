"""A trained residual policy as a file: the actor, its observation normaliser and the
environment it was trained in (``policy.pt``, small, loadable without the trainer's state), and
running it on SWIM's goal task."""
from __future__ import annotations

from pathlib import Path

import numpy as np
import torch

from layered_swim.config import ConfigError
from layered_swim.rl.ppo import ActorCritic, ActorSnapshot, Normaliser
from layered_swim.rl.reward import RewardWeights
from layered_swim.tasks.goal import GOAL_METRICS

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
        env = {k: v for k, v in self.env.items()}
        env["reward_weights"] = RewardWeights(**self.reward)
        env.update(changes)
        return env


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
