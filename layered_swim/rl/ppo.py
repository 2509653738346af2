"""PPO (Schulman et al. 2017) in PyTorch, one readable piece: a Gaussian actor and a critic,
an observation normaliser, GAE, and the clipped update against the behaviour policy's stored
log-probabilities (the buffer may hold episodes from older policies: SWIM's ProgEvict)."""
from __future__ import annotations

from typing import NamedTuple

import numpy as np
import torch
from torch import nn

from layered_swim.rl.buffer import EpisodeData
from layered_swim.rl.config import PpoSpec

OBS_CLIP = 10.0


class Normaliser:
    """Running mean and variance of the observations (parallel-merge update); part of every
    checkpoint, since a policy means nothing without the scaling it was trained on."""

    def __init__(self, size: int):
        self.mean, self.var, self.count = np.zeros(size), np.ones(size), 1e-4

    def update(self, batch: np.ndarray) -> None:
        batch = np.asarray(batch, dtype=float)
        b_mean, b_var, b_count = batch.mean(axis=0), batch.var(axis=0), len(batch)
        delta, total = b_mean - self.mean, self.count + b_count
        self.mean = self.mean + delta * b_count / total
        self.var = (self.var * self.count + b_var * b_count + delta**2 * self.count * b_count / total) / total
        self.count = total

    def __call__(self, obs: np.ndarray) -> np.ndarray:
        return np.clip((np.asarray(obs) - self.mean) / np.sqrt(self.var + 1e-8), -OBS_CLIP, OBS_CLIP).astype(np.float32)

    def state_dict(self) -> dict:
        return {"mean": self.mean.tolist(), "var": self.var.tolist(), "count": self.count}

    def load_state_dict(self, state: dict) -> None:
        self.mean, self.var, self.count = np.array(state["mean"]), np.array(state["var"]), float(state["count"])


def _mlp(n_in: int, hidden: tuple[int, ...], n_out: int) -> nn.Sequential:
    layers, width = [], n_in
    for h in hidden:
        layers += [nn.Linear(width, h), nn.Tanh()]
        width = h
    layers.append(nn.Linear(width, n_out))
    return nn.Sequential(*layers)


class ModelArgs(NamedTuple):
    """``ActorCritic``'s arguments (a policy file's ``model_args``, as a list)."""

    n_obs: int
    n_act: int
    hidden: tuple[int, ...]
    init_log_std: float


class ActorCritic(nn.Module):
    """A diagonal Gaussian policy (state-independent log std) and a value function, separate MLPs.
    The actor's last layer starts near zero: the first policy is the reference motion itself."""

    def __init__(self, n_obs: int, n_act: int, hidden: tuple[int, ...] = (256, 256), init_log_std: float = -1.0):
        super().__init__()
        self.actor, self.critic = _mlp(n_obs, hidden, n_act), _mlp(n_obs, hidden, 1)
        self.log_std = nn.Parameter(torch.full((n_act,), float(init_log_std)))
        with torch.no_grad():
            self.actor[-1].weight.mul_(0.01)
            self.actor[-1].bias.zero_()

    def distribution(self, obs: torch.Tensor) -> torch.distributions.Normal:
        return torch.distributions.Normal(self.actor(obs), self.log_std.exp().expand(obs.shape[0], -1))

    def value(self, obs: torch.Tensor) -> torch.Tensor:
        return self.critic(obs).squeeze(-1)



class ActorSnapshot:
    """The actor frozen into numpy arrays, for acting one observation at a time: a forward pass
    costs tens of microseconds this way, against torch's per-call overhead of a few hundred
    (rollouts act once per environment step)."""

    def __init__(self, model: ActorCritic):
        with torch.no_grad():
            self.layers = [(m.weight.numpy().T.astype(np.float64), m.bias.numpy().astype(np.float64))
                           for m in model.actor if isinstance(m, nn.Linear)]
            self.log_std = model.log_std.numpy().astype(np.float64)
        self.std = np.exp(self.log_std)
        self._log_norm = -self.log_std.sum() - 0.5 * len(self.log_std) * np.log(2.0 * np.pi)

    def act(self, obs: np.ndarray, deterministic: bool, rng: np.random.Generator | None = None):
        """One action for one normalised observation: (action, its log-probability)."""
        x = np.asarray(obs, dtype=np.float64)
        for weight, bias in self.layers[:-1]:
            x = np.tanh(x @ weight + bias)
        weight, bias = self.layers[-1]
        mean = x @ weight + bias
        noise = np.zeros_like(mean) if deterministic else rng.standard_normal(len(mean))
        action = mean + self.std * noise
        return action.astype(np.float32), float(self._log_norm - 0.5 * noise @ noise)


def gae(rewards: np.ndarray, values: np.ndarray, final_value: float, gamma: float, lam: float) -> np.ndarray:
    """Generalised advantage estimates of one episode; ``final_value`` is V(final_obs) for a
    truncated episode (the horizon cut it, the future was not zero) and 0 for a terminated one."""
    advantages = np.zeros(len(rewards))
    next_value, running = final_value, 0.0
    for t in range(len(rewards) - 1, -1, -1):
        delta = rewards[t] + gamma * next_value - values[t]
        running = delta + gamma * lam * running
        advantages[t] = running
        next_value = values[t]
    return advantages


def update(model: ActorCritic, optimiser: torch.optim.Optimizer, episodes: list[EpisodeData], normaliser: Normaliser,
           settings: PpoSpec, generator: torch.Generator) -> dict:
    """PPO epochs over every buffered step (``settings``: the training YAML's ``ppo`` section);
    returns the losses and the clip fraction."""
    obs = torch.as_tensor(np.concatenate([normaliser(e.obs) for e in episodes]))
    finals = torch.as_tensor(np.stack([normaliser(e.final_obs) for e in episodes]))
    with torch.no_grad():
        values, final_values = model.value(obs).numpy(), model.value(finals).numpy()
    advantages, start = [], 0
    for k, e in enumerate(episodes):
        v = values[start:start + e.steps]
        advantages.append(gae(e.rewards, v, float(final_values[k]) if e.truncated else 0.0,
                              settings.gamma, settings.lam))
        start += e.steps
    adv = np.concatenate(advantages)
    returns = torch.as_tensor(adv + values, dtype=torch.float32)
    adv_t = torch.as_tensor((adv - adv.mean()) / (adv.std() + 1e-8), dtype=torch.float32)
    actions = torch.as_tensor(np.concatenate([e.actions for e in episodes]))
    old_log_probs = torch.as_tensor(np.concatenate([e.log_probs for e in episodes]), dtype=torch.float32)
    n, stats = len(obs), {"policy_loss": 0.0, "value_loss": 0.0, "clip_fraction": 0.0, "approx_kl": 0.0}
    batches = 0
    for _ in range(settings.epochs):
        order = torch.randperm(n, generator=generator)
        for begin in range(0, n, settings.minibatch):
            idx = order[begin:begin + settings.minibatch]
            dist = model.distribution(obs[idx])
            log_prob = dist.log_prob(actions[idx]).sum(-1)
            log_ratio = log_prob - old_log_probs[idx]
            ratio = log_ratio.exp()
            policy_loss = -torch.min(ratio * adv_t[idx],
                                     ratio.clamp(1 - settings.clip, 1 + settings.clip) * adv_t[idx]).mean()
            value_loss = (model.value(obs[idx]) - returns[idx]).pow(2).mean()
            entropy = dist.entropy().sum(-1).mean()
            loss = policy_loss + settings.value_coef * value_loss - settings.entropy_coef * entropy
            optimiser.zero_grad()
            loss.backward()
            nn.utils.clip_grad_norm_(model.parameters(), settings.max_grad_norm)
            optimiser.step()
            with torch.no_grad():
                stats["policy_loss"] += float(policy_loss)
                stats["value_loss"] += float(value_loss)
                stats["clip_fraction"] += float(((ratio - 1).abs() > settings.clip).float().mean())
                stats["approx_kl"] += float(((ratio - 1) - log_ratio).mean())
            batches += 1
    return {k: v / max(1, batches) for k, v in stats.items()}
