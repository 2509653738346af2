"""An episode-level replay buffer with SWIM's progressive eviction, ProgEvict (SWIM 2026, section
3.6, eqs. 16-20), or plain FIFO.

When the buffer is over capacity, episodes are evicted one at a time, each drawn with

    P_evict(i) = T(e) P_FIFO(i) + (1 - T(e)) P_heuristic(i)                    (16)
    T(e) = 1 / (1 + exp((e - e_mid) / k))                                      (17)
    P_heuristic(i) = w_age P_age(i) + w_reward P_reward(i)                     (18)
    P_age(i) ~ (e_current - e_i + 1)^2                                         (19)
    P_reward(i) ~ exp(-z_i^2 / (2 sigma^2)),  z_i = 2 rank(R_i) / (N - 1) - 1  (20)

P_FIFO is 1 for the oldest episode; P_age and P_reward are normalised over the buffer. Early on
(T near 1) the oldest goes; later, old and middling-return episodes go, keeping the best and the
worst, which teach the most. The settings (``e_mid``, ``k``, ``w_age``, ``w_reward``, ``sigma``)
and the rule (``eviction``: ``fifo`` or ``progevict``) are the training YAML's ``buffer`` section,
a ``BufferSpec``.
"""
from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from layered_swim.rl.config import BufferSpec


@dataclass
class EpisodeData:
    """One episode as the behaviour policy played it: per step the (raw) observation, the action,
    its log-probability then and the reward; ``final_obs`` follows the last step; ``truncated``:
    the horizon ended it (bootstrapped), else it terminated (no future)."""

    obs: np.ndarray            # (T, n_obs) float32
    actions: np.ndarray        # (T, n_act) float32
    log_probs: np.ndarray      # (T,)
    rewards: np.ndarray        # (T,)
    final_obs: np.ndarray      # (n_obs,)
    truncated: bool
    epoch: int = 0             # the training epoch that collected it
    info: dict = field(default_factory=dict)

    @property
    def steps(self) -> int:
        return len(self.rewards)

    @property
    def episode_return(self) -> float:
        return float(self.rewards.sum())


def transition(epoch: float, s: BufferSpec) -> float:
    """Eq. 17: T(e), near 1 early (FIFO), near 0 late (the heuristic)."""
    x = (epoch - s.e_mid) / s.k
    return 0.0 if x > 700 else 1.0 / (1.0 + math.exp(x))


def eviction_probabilities(collected_epochs, returns, current_epoch: int, s: BufferSpec) -> np.ndarray:
    """Eqs. 16-20 for every episode in the buffer (they sum to 1)."""
    epochs = np.asarray(collected_epochs, dtype=float)
    n = len(epochs)
    fifo = np.zeros(n)
    fifo[int(np.argmin(epochs))] = 1.0          # the oldest (the first of equals: inserted earliest)
    age = (current_epoch - epochs + 1.0) ** 2
    age /= age.sum()
    ranks = np.argsort(np.argsort(np.asarray(returns, dtype=float), kind="stable"), kind="stable")
    z = 2.0 * ranks / (n - 1) - 1.0 if n > 1 else np.zeros(n)
    reward = np.exp(-z**2 / (2.0 * s.sigma**2))
    reward /= reward.sum()
    heuristic = (s.w_age * age + s.w_reward * reward) / (s.w_age + s.w_reward)
    t = transition(current_epoch, s)
    return t * fifo + (1.0 - t) * heuristic


class EpisodeBuffer:
    """Up to ``spec.capacity_episodes`` episodes; ``add`` inserts new ones and evicts by
    ``spec.eviction`` (``fifo`` or ``progevict``) with ``rng``."""

    def __init__(self, spec: BufferSpec = BufferSpec()):
        self.spec, self.capacity = spec, spec.capacity_episodes
        self.episodes: list[EpisodeData] = []

    def add(self, episodes: list[EpisodeData], epoch: int, rng: np.random.Generator) -> int:
        """Insert ``episodes`` (collected at ``epoch``) and evict down to capacity; returns how
        many were evicted."""
        for episode in episodes:
            episode.epoch = epoch
        self.episodes.extend(episodes)
        evicted = 0
        while len(self.episodes) > self.capacity:
            if self.spec.eviction == "fifo":
                victim = 0
            else:
                p = eviction_probabilities([e.epoch for e in self.episodes],
                                           [e.episode_return for e in self.episodes], epoch, self.spec)
                victim = int(rng.choice(len(p), p=p))
            del self.episodes[victim]
            evicted += 1
        return evicted

    @property
    def steps(self) -> int:
        return sum(e.steps for e in self.episodes)
