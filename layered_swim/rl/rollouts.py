"""Collecting episodes with the current policy: in this process, in local worker processes (one
per core by default), or on a Ray cluster (``--ray ADDRESS``, the ``[ray]`` extra). Each episode
has its own seed, so a run is the same however many workers ran it, wherever."""
from __future__ import annotations

import multiprocessing
import signal
import sys
from concurrent.futures import ProcessPoolExecutor

import numpy as np
import torch

from layered_swim.analysis.sweep import ray_runtime
from layered_swim.rl.buffer import EpisodeData
from layered_swim.rl.ppo import ActorCritic, ActorSnapshot, ModelArgs, Normaliser


def make_env(env_kwargs: dict):
    from layered_swim.rl.env import SwimGoalEnv

    return SwimGoalEnv(**env_kwargs)


def play(env, actor: ActorSnapshot, normaliser: Normaliser, seeds: list[int], deterministic: bool = False,
         options: list[dict] | None = None) -> list[EpisodeData]:
    """One episode of ``actor`` in ``env`` per seed (which seeds the reset and the action noise;
    ``options[i]`` goes to reset i, where given)."""
    episodes = []
    for i, seed in enumerate(seeds):
        rng = np.random.default_rng(int(seed))
        obs, _ = env.reset(seed=int(seed), options=options[i] if options else None)
        rows: dict[str, list] = {"obs": [], "actions": [], "log_probs": [], "rewards": []}
        while True:
            action, log_prob = actor.act(normaliser(obs), deterministic, rng)
            next_obs, reward, terminated, truncated, info = env.step(action)
            for name, value in zip(rows, (obs, action, log_prob, reward)):
                rows[name].append(value)
            obs = next_obs
            if terminated or truncated:
                break
        episodes.append(EpisodeData(np.array(rows["obs"], np.float32), np.array(rows["actions"], np.float32),
                                    np.array(rows["log_probs"]), np.array(rows["rewards"]), obs.astype(np.float32),
                                    bool(truncated),
                                    info={k: info[k] for k in ("metrics", "termination") if k in info}))
    return episodes


# -- one chunk, wherever it runs: the env is built once per worker and kept ----------------
_ENV = None


def _set_env(env_kwargs: dict) -> None:
    global _ENV
    _ENV = make_env(env_kwargs)


def _worker_init(env_kwargs: dict) -> None:
    """A worker process's start (never the trainer's own process: it would die with its shell)."""
    _die_with_parent()
    torch.set_num_threads(1)          # one core each: the workers are the parallelism
    _set_env(env_kwargs)


def _die_with_parent() -> None:
    """A trainer killed outright (SIGKILL, OOM) would leave its pool's workers polling forever:
    on Linux the kernel ends them with it."""
    if sys.platform.startswith("linux"):
        import ctypes

        PR_SET_PDEATHSIG = 1
        ctypes.CDLL(None, use_errno=True).prctl(PR_SET_PDEATHSIG, signal.SIGTERM)


def _chunk(model_args: ModelArgs, model_state: dict, normaliser_state: dict, seeds: list[int]):
    model = ActorCritic(*model_args)
    model.load_state_dict(model_state)
    normaliser = Normaliser(model_args.n_obs)
    normaliser.load_state_dict(normaliser_state)
    return play(_ENV, ActorSnapshot(model), normaliser, seeds)


class Rollouts:
    """``collect(model, model_args, normaliser, seeds)``: one episode per seed, spread over
    ``workers`` (every ``workers``-th seed to each); ``ray_address`` sends the chunks to a Ray
    cluster instead ("local" starts one on this machine)."""

    def __init__(self, env_kwargs: dict, workers: int, ray_address: str | None = None):
        self.workers, self._pool, self._ray = workers, None, None
        if ray_address:
            ray = ray_runtime(ray_address, workers)
            actor = ray.remote(num_cpus=1)(_RayWorker)
            self._ray = [actor.remote(env_kwargs) for _ in range(workers)]
        elif workers > 1:
            context = multiprocessing.get_context("spawn")     # PyBullet and torch threads do not survive fork
            self._pool = ProcessPoolExecutor(workers, mp_context=context, initializer=_worker_init,
                                             initargs=(env_kwargs,))
        else:
            _set_env(env_kwargs)

    def collect(self, model: ActorCritic, model_args: ModelArgs, normaliser: Normaliser,
                seeds: list[int]) -> list[EpisodeData]:
        """One episode per seed, in the seeds' order."""
        state = {k: v.detach().clone() for k, v in model.state_dict().items()}
        chunks = [seeds[k::self.workers] for k in range(self.workers)]
        args = [(model_args, state, normaliser.state_dict(), chunk) for chunk in chunks if chunk]
        if self._ray is not None:
            import ray

            results = ray.get([w.chunk.remote(*a) for w, a in zip(self._ray, args)])
        elif self._pool is not None:
            results = list(self._pool.map(_chunk, *zip(*args)))
        else:
            results = [_chunk(*a) for a in args]
        ordered: list = [None] * len(seeds)
        for k, episodes in enumerate(results):     # chunk k holds seeds k, k + workers, ...
            ordered[k::self.workers] = episodes
        return ordered

    def close(self) -> None:
        if self._pool is not None:
            self._pool.shutdown(cancel_futures=True)
        if self._ray is not None:
            import ray

            for worker in self._ray:
                ray.kill(worker)


class _RayWorker:
    def __init__(self, env_kwargs: dict):
        _worker_init(env_kwargs)

    def chunk(self, *args):
        return _chunk(*args)
