"""SWIM's goal reaching as a Gymnasium environment: a thin layer over the goal task and the
episode runner. The policy acts at ``policy_hz`` (30) over the 480 Hz physics: each action is a
residual added to the reference controller's joint targets (SWIM eq. 5) and held for the
physics steps until the next one.

- ``reference="basic"``: the stroke's key poses alone, SWIM's setting; ``"layered"``: the whole
  layered controller (steering, rules) underneath.
- ``reset(options={"goal": k, "start_seed": s})`` picks the goal (else drawn) and the start:
  seed 0 is SWIM's fixed start, others jitter it (``episode.jittered_start``); with
  ``start_jitter`` every reset draws a jittered start, from seeds at ``TRAINING_SEEDS`` and up
  (the ones below are evaluation's). With ``draws`` (``DrawsSpec``) a reset that names no goal
  draws the episode's pool, goal, current, density and push; one that names it draws nothing.
- Observation: ``observation.py`` (``env.layout`` names its slices). Action: one value in
  [-1, 1] per pose coordinate (``env.action_names``), times ``action_scale_rad``.
- Reward: SWIM's task x stability + smoothness (``reward.py``), every part in ``info["reward"]``.
- The goal's horizon ends an episode by truncation. Leaving the pool, sinking to its floor (the
  goal task's ``ended``, as for every controller) or a simulation that blows up terminates it,
  with the reason in ``info["termination"]``. The last step's ``info["metrics"]`` holds the
  task's Pos, Prog, Dev and Roll over the whole horizon, and whether it was a success.
"""
from __future__ import annotations

import math
import time
from typing import Any, NamedTuple

import gymnasium as gym
import numpy as np
from numba import njit

from layered_swim.config import ConfigError, parse
from layered_swim.control.residual import ResidualController
from layered_swim.control.steering import attitude_of
from layered_swim.fluid import FluidError
from layered_swim.rl import observation as obs
from layered_swim.rl.config import DrawsSpec, RewardSpec
from layered_swim.rl.reward import BODY_POINT_WEIGHTS, reward_parts
from layered_swim.runs import goal_episode
from layered_swim.sim.simulation import DEFAULT_SIM, SimulationDiverged
from layered_swim.spec import SwimSpec, sph_fields
from layered_swim.state import BodyState
from layered_swim.tasks import swim_benchmark as bench

REFERENCES = {"basic": "basic", "layered": "basic,cycle,rules"}
TRAINING_SEEDS = 1000       # jittered starts drawn in training start here; evaluation uses the seeds below


@njit(cache=True)
def _add_into(force, torque, more_force, more_torque):
    """``force += more_force; torque += more_torque`` in one call (every physics step)."""
    for i in range(force.shape[0]):
        for c in range(3):
            force[i, c] += more_force[i, c]
            torque[i, c] += more_torque[i, c]


class Push(NamedTuple):
    force_n: np.ndarray         # world frame, on the pelvis
    from_s: float
    to_s: float


class Observed(NamedTuple):
    """What ``PolicyInput`` read at its last observation that the reward needs."""

    state: BodyState
    roll_rad: float                 # the shoulder roll
    goal_yaws_rad: np.ndarray       # the intermediate goals' bearings off the heading
    joint_rates: np.ndarray         # every joint's rate (a copy)


class PolicyInput:
    """The observation of an episode now, for any task: the environment gives it the goal
    task's intermediate goals, a policy driving another task (``policy.ResidualDriver``) the
    target's positions ahead. Keeps what the reward needs (``now``, an ``Observed``)."""

    def __init__(self, episode, env_state: str):
        sim = episode.sim
        self.episode, self.env_state = episode, env_state
        positions = sim.world.joint_positions()
        _, rates = sim.world.joint_torques_and_rates()
        self.layout = obs.layout_for(len(positions), len(rates), len(episode.body.segment_names), env_state)
        self._links = [episode.body.index(name) for name in obs.TRACKED_LINKS]
        self._smoothed = None
        self.now: Observed | None = None

    def reset(self) -> None:
        self._smoothed = None

    def __call__(self, force_n: np.ndarray, torque_nm: np.ndarray, goals_m: np.ndarray) -> np.ndarray:
        """The vector from the episode's state, the water's mean wrenches since the last call and
        the four intermediate goals (4, 3), world frame."""
        sim, layout = self.episode.sim, self.layout
        state = sim.state
        att = attitude_of(state, self.episode.stroke.start.posture)
        heading = att.heading_rad
        root = state.pos_m[0]
        goals, yaws = obs.local_goals(goals_m, root, heading)
        env, self._smoothed = obs.env_features(self.env_state, force_n, torque_nm, state.pos_m, state.com_m, heading,
                                               self._smoothed)
        _, rates = sim.world.joint_torques_and_rates()
        links = obs.to_heading_frame(np.concatenate([state.pos_m[self._links] - root,
                                                     state.linvel_m_s[self._links] - state.linvel_m_s[0],
                                                     state.linvel_m_s[:1], state.angvel_rad_s[:1]]), heading)
        n = len(self._links)
        parts = {
            "root_height": root[2], "root_roll": att.roll_rad, "root_linvel": links[2 * n],
            "root_angvel": links[2 * n + 1],
            "link_pos": links[:n].ravel(), "link_vel": links[n:2 * n].ravel(),
            "joint_pos": sim.world.joint_positions(), "joint_vel": rates,
            "phase": obs.phase_encoding(sim.controller.phase(sim.time_s)), "goals": goals.ravel(), "env": env,
        }
        vector = np.empty(layout.size, np.float32)
        for name, where in layout.slices.items():
            vector[where] = parts[name]
        self.now = Observed(state, att.roll_rad, yaws, rates.copy())
        return vector


class SwimGoalEnv(gym.Env):
    metadata = {"render_modes": []}

    def __init__(self, stroke: str = "front_crawl", pool: str = "small", reference: str = "basic",
                 env_state: str = "SmoothFT", policy_hz: int = 30, action_scale_rad: float = 0.2,
                 reward_weights: RewardSpec | dict = RewardSpec(), backend: str = "plate", fluid_settings=None,
                 current_m_s: tuple[float, float, float] = (0.0, 0.0, 0.0), goal: int | None = None,
                 start_jitter: bool = False, density_kg_m3: float | None = None,
                 draws: DrawsSpec | dict | None = None, integrator: str = DEFAULT_SIM.integrator):
        if isinstance(reward_weights, dict):     # gym.make's keyword arguments: checked like the YAML's reward section
            reward_weights = parse(RewardSpec, reward_weights, "the environment's reward_weights")
        if isinstance(draws, dict):
            draws = parse(DrawsSpec, draws, "the environment's draws")
        if reference not in REFERENCES:
            raise ConfigError(f"reference must be one of {', '.join(REFERENCES)}, got {reference!r}")
        if not (isinstance(action_scale_rad, (int, float)) and 0.0 < action_scale_rad <= 1.0):
            raise ConfigError(f"action_scale_rad must be in (0, 1] rad, got {action_scale_rad!r}")
        self.reference, self.env_state, self.action_scale_rad = reference, env_state, float(action_scale_rad)
        self.draws = draws
        self.reward_weights, self.fixed_goal, self.start_jitter = reward_weights, goal, start_jitter
        spec = SwimSpec.of("the environment", stroke=stroke, task={"kind": "goal", "pool": pool},
                           medium={"current_m_s": current_m_s, "density_kg_m3": density_kg_m3},
                           layers=REFERENCES[reference], backend=backend, integrator=integrator,
                           sph=sph_fields(fluid_settings))
        self.episode = goal_episode(spec, wrap=ResidualController)
        sim = self.episode.sim
        if not (isinstance(policy_hz, int) and policy_hz > 0 and sim.config.physics_hz % policy_hz == 0
                and (sim.config.physics_hz // policy_hz) % sim.control_every == 0):
            raise ConfigError(f"policy_hz must divide the control rate {sim.config.control_hz} Hz, got {policy_hz!r}")
        self.water = sim.fluid.medium        # the water a reset that draws nothing swims in
        self.weight_n = self.episode.body.total_mass_kg * abs(sim.config.gravity_m_s2)
        self.push: Push | None = None
        self.physics_per_action = sim.config.physics_hz // policy_hz
        self.dt_s = 1.0 / policy_hz
        self.roll_tolerance_rad = math.radians(bench.ROLL_TOLERANCE_DEG.get(self.episode.stroke.name, 45.0))
        self.input = PolicyInput(self.episode, env_state)
        self.layout = self.input.layout
        self.action_names = tuple(sim.layout.names)
        self.observation_space = gym.spaces.Box(-np.inf, np.inf, (self.layout.size,), np.float32)
        self.action_space = gym.spaces.Box(-1.0, 1.0, (len(self.action_names),), np.float32)
        self._body_point = {self.episode.body.index(name): w for name, w in BODY_POINT_WEIGHTS.items()}
        self._last_obs = np.zeros(self.layout.size, np.float32)
        # Seconds spent stepping the physics and building observations and rewards, since
        # construction (``bench --env`` reads them; four clock reads a step cost nothing).
        self.timing = {"physics_s": 0.0, "observation_s": 0.0, "reward_s": 0.0}

    # -- Gymnasium ------------------------------------------------------------------------
    def reset(self, *, seed: int | None = None, options: dict[str, Any] | None = None):
        super().reset(seed=seed)
        options = options or {}
        goal = options.get("goal", self.fixed_goal)
        drawn = self.draws is not None and goal is None
        if drawn:
            aim = {"goal_task": self._draw_goal()}
        else:
            if goal is None:
                goal = int(self.np_random.integers(len(self.episode.task.goals)))
            aim = {"goal": goal}
        start_seed = options.get("start_seed", int(self.np_random.integers(TRAINING_SEEDS, 2**31))
                                 if self.start_jitter else 0)
        sim = self.episode.sim
        if self.draws is not None:      # before the reset, whose first wrenches are this water's
            sim.fluid.set_medium(self._draw_water() if drawn else self.water)
        self.episode.reset(seed=start_seed, **aim)      # seed 0: exactly SWIM's start; others jitter it
        self.input.reset()
        self.push = self._draw_push() if drawn else None
        self._last_obs = self._observe(sim.fluid_now.force_n, sim.fluid_now.torque_nm)
        self._rates = self.input.now.joint_rates
        return self._last_obs.copy(), {"goal": goal, "goal_m": list(self.episode.task.goal.goal_m)}

    def step(self, action):
        action = np.clip(np.asarray(action, dtype=float), -1.0, 1.0)
        if action.shape != self.action_space.shape or not np.isfinite(action).all():
            raise ValueError(f"action must be {self.action_space.shape} finite values, got shape {action.shape}")
        episode, sim = self.episode, self.episode.sim
        sim.controller.set_residual(self.action_scale_rad * action)
        force, torque = np.zeros_like(sim.fluid_now.force_n), np.zeros_like(sim.fluid_now.torque_nm)
        clock = time.perf_counter()
        push = self.push
        try:
            for _ in range(self.physics_per_action):
                if push is not None:
                    sim.push(push.force_n if push.from_s <= sim.time_s < push.to_s else 0.0)
                episode.step()
                _add_into(force, torque, sim.fluid_now.force_n, sim.fluid_now.torque_nm)
        except (SimulationDiverged, FluidError) as err:
            episode.task.end(f"diverged: {err}", sim.time_s)
            return self._last_obs.copy(), 0.0, True, False, {"termination": episode.task.ended,
                                                              "metrics": episode.metrics()}
        observed = time.perf_counter()
        force /= self.physics_per_action
        torque /= self.physics_per_action
        self._last_obs = observation = self._observe(force, torque)
        rewarded = time.perf_counter()
        rates = self.input.now.joint_rates
        parts = self._reward((rates - self._rates) / self.dt_s)
        self._rates = rates
        done = time.perf_counter()
        self.timing["physics_s"] += observed - clock
        self.timing["observation_s"] += rewarded - observed
        self.timing["reward_s"] += done - rewarded
        info: dict[str, Any] = {"reward": parts, "time_s": sim.time_s}
        reason = episode.task.ended
        truncated = reason is None and sim.time_s >= episode.task.duration_s - 1e-9
        if reason is not None:
            info["termination"] = reason
        if reason is not None or truncated:
            info["metrics"] = episode.metrics()
        return observation.copy(), parts["total"], reason is not None, truncated, info

    def close(self) -> None:
        self.episode.close()

    # -- parts --------------------------------------------------------------------------
    def _observe(self, force_n: np.ndarray, torque_nm: np.ndarray) -> np.ndarray:
        goals = bench.intermediate_goals(self.episode.task.goal, self.episode.sim.time_s, self.episode.stroke.period_s)
        return self.input(force_n, torque_nm, goals)

    def _reward(self, joint_accel: np.ndarray) -> dict:
        now = self.input.now
        state = now.state
        task = self.episode.task.goal
        body_point = sum(w * state.pos_m[k] for k, w in self._body_point.items())
        return reward_parts(bench.goal_position(task, state.time_s), state.pos_m[0], body_point, task.start_m,
                            task.direction, now.goal_yaws_rad, now.roll_rad, self.roll_tolerance_rad, joint_accel,
                            self.reward_weights)

    # -- draws (training only) --------------------------------------------------------------
    def _draw_goal(self) -> bench.GoalTask:
        rng, draws = self.np_random, self.draws
        pool = bench.pool(draws.pools[int(rng.integers(len(draws.pools)))])
        if draws.goal_bearing_deg == 0.0:
            goals = bench.goal_tasks(pool)
            return goals[int(rng.integers(len(goals)))]
        bearing = math.radians(rng.uniform(-draws.goal_bearing_deg, draws.goal_bearing_deg))
        return bench.goal_tasks(pool.holding(pool.goal_distance_m * math.tan(bearing)))[0]

    def _draw_water(self):
        rng, draws = self.np_random, self.draws
        speed, towards = draws.current_m_s.draw(rng), rng.uniform(0.0, 2.0 * math.pi)
        water = self.water.with_(current_m_s=(speed * math.cos(towards), speed * math.sin(towards), 0.0))
        return water if draws.density_kg_m3 is None else water.with_(rho_kg_m3=draws.density_kg_m3.draw(rng))

    def _draw_push(self) -> Push | None:
        rng, draws = self.np_random, self.draws
        if rng.uniform() >= draws.push_chance:
            return None
        direction = rng.normal(size=3)
        force = draws.push_body_weights.draw(rng) * self.weight_n * direction / np.linalg.norm(direction)
        length_s = draws.push_s.draw(rng)
        start_s = rng.uniform(0.5, max(0.5, self.episode.task.duration_s - length_s - 0.5))
        return Push(force, start_s, start_s + length_s)
