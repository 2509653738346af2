"""``layered-swim bench --env``: how fast the environment runs on one core, and where the time
goes: the physics it steps (480 Hz, plate backend) against what the environment adds
(observation, reward) and the policy network's forward pass; then over all cores, as the
trainer runs it: ``workers`` processes (the training config's ``run.workers``) stepping their own
environments at once."""
from __future__ import annotations

import multiprocessing
import time

import numpy as np
import torch

from layered_swim.rl.ppo import ActorCritic, ActorSnapshot, Normaliser
from layered_swim.rl.rollouts import make_env
from layered_swim.sim.simulation import DEFAULT_SIM


def bench_env(seconds: float = 10.0, env_state: str = "SmoothFT", hidden: tuple[int, ...] = (256, 256),
              workers: int | None = None, integrator: str = DEFAULT_SIM.integrator) -> dict:
    """Environment steps over about ``seconds`` of simulated time with a fresh policy, one thread;
    then ``workers`` processes (default: the shipped training config's ``run.workers``) doing the
    same at once, each on its own core as the trainer's rollout workers run: the steps per second
    all of them make together (0 or 1 worker: none)."""
    result = _bench_one(seconds, env_state, hidden, integrator)
    if workers is None:
        from layered_swim.rl.config import load_train_spec

        workers = load_train_spec(None).run.workers
    if workers > 1:
        result.update(_bench_workers(seconds, env_state, hidden, workers, integrator))
    return result


def _bench_workers(seconds: float, env_state: str, hidden: tuple[int, ...], workers: int, integrator: str) -> dict:
    """Every worker builds its environment, waits for the others, then steps: the rate is all
    their steps over the span from the first start to the last finish."""
    context = multiprocessing.get_context("spawn")     # as the trainer's pool: PyBullet and torch do not survive fork
    barrier, results = context.Barrier(workers), context.Queue()
    procs = [context.Process(target=_worker, args=(seconds, env_state, hidden, integrator, barrier, results))
             for _ in range(workers)]
    for p in procs:
        p.start()
    try:
        runs = [results.get(timeout=600) for _ in procs]
    finally:
        for p in procs:
            p.join(timeout=60)
    span = max(r["end"] for r in runs) - min(r["start"] for r in runs)
    steps = sum(r["env_steps"] for r in runs)
    return {"workers": workers, "env_steps_per_s_all_cores": round(steps / span, 1),
            "env_steps_per_s_per_worker": [r["env_steps_per_s_per_core"] for r in runs]}


def _worker(seconds, env_state, hidden, integrator, barrier, results) -> None:
    results.put(_bench_one(seconds, env_state, tuple(hidden), integrator, barrier))


def _bench_one(seconds: float, env_state: str, hidden: tuple[int, ...], integrator: str, barrier=None) -> dict:
    torch.set_num_threads(1)
    env = make_env({"env_state": env_state, "reference": "layered", "integrator": integrator})
    actor = ActorSnapshot(ActorCritic(env.observation_space.shape[0], env.action_space.shape[0], hidden))
    normaliser = Normaliser(env.observation_space.shape[0])
    rng = np.random.default_rng(0)
    target_steps = max(1, int(round(seconds / env.dt_s)))
    steps, policy_s, episodes = 0, 0.0, 0
    try:
        # A second of steps first, off the clock: the first calls load the compiled kernels.
        env.reset(seed=0)
        for _ in range(round(1.0 / env.dt_s)):
            env.step(np.zeros(env.action_space.shape))
        obs, _ = env.reset(seed=0)
        env.timing = dict.fromkeys(env.timing, 0.0)
        if barrier is not None:
            barrier.wait()
        started = time.perf_counter()
        while steps < target_steps:
            clock = time.perf_counter()
            action, _ = actor.act(normaliser(obs), False, rng)
            policy_s += time.perf_counter() - clock
            obs, _, terminated, truncated, _ = env.step(action)
            steps += 1
            if terminated or truncated:
                episodes += 1
                obs, _ = env.reset(seed=episodes)
        ended = time.perf_counter()
        wall_s = ended - started
    finally:
        env.close()
    t = env.timing
    physics = t["physics_s"]
    env_added = t["observation_s"] + t["reward_s"]
    return {"env_steps": steps, "policy_hz": round(1.0 / env.dt_s),
            "physics_steps_per_env_step": env.physics_per_action,
            "env_steps_per_s_per_core": round(steps / wall_s, 1), "wall_s": round(wall_s, 2),
            "share_physics": round(physics / wall_s, 3), "share_observation": round(t["observation_s"] / wall_s, 3),
            "share_reward": round(t["reward_s"] / wall_s, 3), "share_policy": round(policy_s / wall_s, 3),
            "env_overhead_vs_physics": round(env_added / physics, 3),
            "policy_vs_physics": round(policy_s / physics, 3), "env_state": env_state, "hidden": list(hidden),
            "integrator": integrator,
            **({"start": started, "end": ended} if barrier is not None else {})}
