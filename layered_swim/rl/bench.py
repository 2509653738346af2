"""``layered-swim bench --env``: how fast the environment runs on one core, and where the time
goes: the physics it steps (480 Hz, plate backend) against what the environment adds
(observation, reward) and the policy network's forward pass."""
from __future__ import annotations

import time

import numpy as np
import torch

from layered_swim.rl.ppo import ActorCritic, ActorSnapshot, Normaliser
from layered_swim.rl.rollouts import make_env


def bench_env(seconds: float = 10.0, env_state: str = "SmoothFT", hidden: tuple[int, ...] = (256, 256)) -> dict:
    """Environment steps over about ``seconds`` of simulated time with a fresh policy, one thread."""
    torch.set_num_threads(1)
    env = make_env({"env_state": env_state, "reference": "layered"})
    actor = ActorSnapshot(ActorCritic(env.observation_space.shape[0], env.action_space.shape[0], hidden))
    normaliser = Normaliser(env.observation_space.shape[0])
    rng = np.random.default_rng(0)
    target_steps = max(1, int(round(seconds / env.dt_s)))
    steps, policy_s, episodes = 0, 0.0, 0
    try:
        obs, _ = env.reset(seed=0)
        env.timing = dict.fromkeys(env.timing, 0.0)
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
        wall_s = time.perf_counter() - started
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
            "policy_vs_physics": round(policy_s / physics, 3), "env_state": env_state, "hidden": list(hidden)}
