"""The RL environment: Gymnasium's checker, an outside trainer (stable-baselines3), the reward
parts against hand-computed values, the observation's layout, the residual, and how episodes end."""
import math
import warnings

import gymnasium as gym
import numpy as np
import pytest

import layered_swim.rl  # noqa: F401  (registers the ids)
from layered_swim.config import ConfigError
from layered_swim.rl import observation as obs
from layered_swim.rl.config import RewardSpec
from layered_swim.rl.env import SwimGoalEnv
from layered_swim.rl.reward import deviation_m, forward_distance_m, reward_parts, yaw_error_rad
from layered_swim.tasks import swim_benchmark as bench


@pytest.fixture(scope="module")
def env():
    e = SwimGoalEnv(reference="layered")
    yield e
    e.close()


def test_gymnasium_env_checker_passes():
    from gymnasium.utils.env_checker import check_env

    e = gym.make("layered_swim/FrontCrawlGoal-v0")
    with warnings.catch_warnings():
        warnings.filterwarnings("ignore", message=".*infinity.*")     # unbounded kinematics and forces
        check_env(e.unwrapped)
    e.close()


def test_stable_baselines3_ppo_trains_on_it_unmodified(tmp_path, monkeypatch):
    from stable_baselines3 import PPO

    monkeypatch.setenv("SB3_LOGDIR", str(tmp_path))    # its logger's folder, else a new one in /tmp each run
    e = gym.make("layered_swim/BreaststrokeGoal-v0", env_state="TotalFT")
    model = PPO("MlpPolicy", e, n_steps=256, batch_size=64, n_epochs=1, seed=0, device="cpu")
    model.learn(total_timesteps=1024)
    assert model.num_timesteps >= 1024
    action, _ = model.predict(e.reset(seed=0)[0], deterministic=True)
    assert e.action_space.contains(action)
    e.close()


def test_reward_parts_against_hand_computed_values():
    w = RewardSpec()
    # On schedule at (1, 0); root at (0.8, 0.1); line along +x from the origin.
    assert forward_distance_m([1.0, 0.0, 0.0], [0.8, 0.1, -0.2], [1.0, 0.0, 0.0]) == pytest.approx(0.2)
    assert deviation_m([0.5, -0.3, 0.0], [0.0, 0.0, 0.0], [1.0, 0.0, 0.0]) == pytest.approx(0.3)
    d = np.array([1.0, 1.0, 0.0]) / math.sqrt(2)
    assert deviation_m([1.0, 0.0, 0.0], [0.0, 0.0, 0.0], d) == pytest.approx(1 / math.sqrt(2))
    assert yaw_error_rad([-0.1, 0.2, 0.3, 0.1]) == 0.0          # goals on both sides: no error
    assert yaw_error_rad([0.2, 0.3, 0.25, 0.4]) == pytest.approx(0.2)   # all left: the nearest
    assert yaw_error_rad([-0.5, -0.3, -0.6, -0.4]) == pytest.approx(0.3)
    parts = reward_parts([1.0, 0.0, 0.0], [0.8, 0.1, 0.0], [0.8, 0.1, 0.0], [0.0, 0.0, 0.0], [1.0, 0.0, 0.0],
                         [0.2, 0.3, 0.25, 0.4], roll_rad=-1.0, roll_tolerance_rad=0.8,
                         joint_accel_rad_s2=[10.0, -30.0], w=w)
    forward, deviation, heading = math.exp(-5.0 * 0.2), math.exp(-10.0 * 0.1), math.exp(-2.0 * 0.2)
    stability, smoothness = math.exp(-2.0 * 0.2), math.exp(-0.01 * 20.0)
    assert parts["forward"] == pytest.approx(forward) and parts["deviation"] == pytest.approx(deviation)
    assert parts["heading"] == pytest.approx(heading) and parts["stability"] == pytest.approx(stability)
    assert parts["smoothness"] == pytest.approx(smoothness)
    assert parts["total"] == pytest.approx(forward * deviation * heading * stability + 0.1 * smoothness)


def test_bad_reward_weights_and_settings_are_one_line():
    with pytest.raises(ConfigError, match="forward_per_m"):
        SwimGoalEnv(reward_weights={"forward_per_m": float("nan")})
    with pytest.raises(ConfigError, match="env_state"):
        obs.layout_for(10, 10, 16, "Nothing")
    with pytest.raises(ConfigError, match="reference"):
        SwimGoalEnv(reference="magic")


def test_smoothed_wrenches_follow_eq_4():
    force, torque = np.zeros((2, 3)), np.zeros((2, 3))
    force[0, 0] = math.e - 1.0              # squashes to exactly 1
    pos, com = np.zeros((2, 3)), np.zeros(3)
    first, state = obs.env_features("SmoothFT", force, torque, pos, com, 0.0, None)
    assert first[0] == pytest.approx(1.0)
    force[0, 0] = 0.0
    second, _ = obs.env_features("SmoothFT", force, torque, pos, com, 0.0, state)
    assert second[0] == pytest.approx(1.0 - obs.SMOOTH_W)
    total, _ = obs.env_features("TotalFT", np.array([[1.0, 0, 0], [0, 0, 0]]), torque,
                                np.array([[0, 1.0, 0], [0, 0, 0]]), com, math.pi / 2, None)
    # 1 N along world x, one metre to the left of the centre: torque -1 N m about z; in the
    # frame turned 90 deg, world x is the swimmer's -y.
    assert total == pytest.approx([0.0, -1.0, 0.0, 0.0, 0.0, -1.0])


def test_the_layout_names_every_slice_once(env):
    slices = list(env.layout.slices.values())
    assert slices[0].start == 0 and slices[-1].stop == env.layout.size == env.observation_space.shape[0]
    assert all(a.stop == b.start for a, b in zip(slices, slices[1:]))
    observation, _ = env.reset(seed=0, options={"goal": 0})
    goals = env.layout.part(observation, "goals").reshape(4, 3)
    assert np.all(np.diff(goals[:, 0]) > 0) and np.all(goals[:, 2] >= 0)   # further ahead, |yaw|
    assert env.layout.part(observation, "root_height")[0] < 0              # under water


def test_the_action_is_a_residual_on_the_reference_pose(env):
    env.reset(seed=0, options={"goal": 0})
    action = np.zeros(env.action_space.shape, np.float32)
    k = env.action_names.index("elbow_l.flexion")
    action[k] = 0.5
    env.step(action)
    residual = env.episode.sim.controller.residual_rad
    assert residual[k] == pytest.approx(0.5 * env.action_scale_rad) and np.count_nonzero(residual) == 1


def test_the_residual_controller_adds_and_clamps():
    from layered_swim.control.residual import ResidualController

    class Reference:
        def desired(self, time_s, state, flow):
            return np.array([0.1, 0.2]), np.array([1.0, 2.0])

        def reset(self):
            pass

        def phase(self, time_s):
            return 0.25

    class Layout:
        def zeros(self):
            return np.zeros(2)

        def clamp(self, pose):
            return np.clip(pose, -0.3, 0.3)

    c = ResidualController(Reference(), Layout())
    c.set_residual([0.15, -0.1])
    pose, rate = c.desired(0.0, None, None)
    assert pose == pytest.approx([0.25, 0.1]) and rate == pytest.approx([1.0, 2.0]) and c.phase(1.0) == 0.25
    c.set_residual([0.5, 0.0])
    assert c.desired(0.0, None, None)[0][0] == pytest.approx(0.3)          # inside the joint's range
    c.reset()
    assert not c.residual_rad.any()


def test_the_horizon_truncates_and_reports_the_metrics(env):
    env.reset(seed=0, options={"goal": 1})
    steps, done = 0, False
    while not done:
        _, reward, terminated, truncated, info = env.step(np.zeros(env.action_space.shape, np.float32))
        steps, done = steps + 1, terminated or truncated
        assert 0.0 <= reward <= 1.1 and set(info["reward"]) >= {"task", "stability", "smoothness", "total"}
    assert truncated and not terminated and steps == 120          # 4 s at 30 Hz
    assert set(info["metrics"]) >= {"pos_m", "prog", "dev_m", "roll_deg"}


def test_leaving_the_pool_terminates_with_a_reason():
    # the full-tempo crawl carried by a current along the line outswims the 4 s schedule
    e = SwimGoalEnv(reference="basic", goal=0, current_m_s=(0.5, 0.0, 0.0))
    e.reset(seed=0)
    for _ in range(120):
        _, _, terminated, truncated, info = e.step(np.zeros(e.action_space.shape, np.float32))
        if terminated or truncated:
            break
    e.close()
    assert terminated and "left the small pool" in info["termination"] and "metrics" in info


def test_same_seed_same_episode():
    def rollout(seed):
        e = SwimGoalEnv(env_state="RawFT")
        o, _ = e.reset(seed=seed)
        rng = np.random.default_rng(7)
        for _ in range(10):
            o, r, *_ = e.step(rng.uniform(-1, 1, e.action_space.shape).astype(np.float32))
        e.close()
        return o, r
    (a, ra), (b, rb) = rollout(3), rollout(3)
    assert np.array_equal(a, b) and ra == rb


def test_the_heuristic_ends_at_the_same_walls_and_is_scored_to_the_horizon():
    from layered_swim.runs import goal_episode, reach_goal
    from layered_swim.spec import SwimSpec

    spec = SwimSpec.of("test", stroke="front_crawl", task={"kind": "goal", "pool": "small"},
                       medium={"current_m_s": (2.0, 0.0, 0.0)}, layers="basic,cycle,rules")
    episode = goal_episode(spec)
    try:
        got = reach_goal(episode, 0)
        assert not got["success"] and "left the small pool" in got["ended"]
        assert got["ended_s"] < 4.0 and episode.time_s == pytest.approx(got["ended_s"], abs=0.06)   # it stopped there
        assert got["prog"] > 1.0          # carried past the goal, and held there to the horizon
        episode.task.ends_at_walls = False                  # boundless water: the whole horizon is swum
        assert reach_goal(episode, 0)["success"] and episode.time_s == pytest.approx(4.0)
    finally:
        episode.close()


def test_draws_pick_the_pool_goal_water_and_push_and_a_named_goal_draws_nothing():
    from layered_swim.rl.env import TRAINING_SEEDS

    draws = {"pools": ["large"], "goal_bearing_deg": 30.0, "current_m_s": {"min": 0.5, "max": 0.5},
             "density_kg_m3": {"min": 1200.0, "max": 1200.0}, "push_chance": 1.0,
             "push_body_weights": {"min": 1.0, "max": 1.0}, "push_s": {"min": 0.1, "max": 0.1}}
    e = SwimGoalEnv(reference="basic", env_state="NoEnv", start_jitter=True, draws=draws)
    try:
        fresh = e.episode.sim.fluid.medium.rho_kg_m3
        laterals = set()
        for seed in range(4):
            e.reset(seed=seed)
            task, medium = e.episode.task, e.episode.sim.fluid.medium
            assert task.duration_s == 8.0 and task.goal.goal_m[0] == 3.0          # the large pool's goal line
            lateral = task.goal.goal_m[1]
            laterals.add(round(lateral, 6))
            assert abs(lateral) <= 3.0 * math.tan(math.radians(30.0)) + 1e-9
            assert task.goal.pool.width_m >= 2 * (abs(lateral) + 0.5) - 1e-9
            assert medium.rho_kg_m3 == 1200.0 and np.linalg.norm(medium.current_m_s) == pytest.approx(0.5)
            assert e.push is not None and e.push.to_s - e.push.from_s == pytest.approx(0.1)
            assert np.linalg.norm(e.push.force_n) == pytest.approx(e.weight_n)
            assert e.episode.seed >= TRAINING_SEEDS                # evaluation's seeds are never drawn
        assert len(laterals) == 4
        # The push acts while its window is open.
        e.reset(seed=0)
        push, sim = e.push, e.episode.sim
        while sim.time_s < push.from_s + 0.05:
            e.step(np.zeros(e.action_space.shape, np.float32))
        assert np.array_equal(sim.external_force_n[e.episode.body.index("pelvis")], push.force_n)
        # A reset that names its goal is SWIM's: its pool, the environment's own water, no push.
        e.reset(seed=0, options={"goal": 0, "start_seed": 0})
        assert e.episode.task.duration_s == 4.0 and e.episode.task.goal == bench.goal_tasks(bench.pool("small"))[0]
        assert e.episode.sim.fluid.medium.rho_kg_m3 == fresh and not any(e.episode.sim.fluid.medium.current_m_s)
        assert e.push is None
    finally:
        e.close()


def test_bad_draws_are_one_line():
    from layered_swim.rl.config import load_train_spec

    with pytest.raises(ConfigError, match="current_m_s"):
        load_train_spec(None, ["env.draws.current_m_s={min: 0.5, max: 0.1}"])
    with pytest.raises(ConfigError, match="density_kg_m3"):
        load_train_spec(None, ["env.draws.density_kg_m3={min: 10, max: 100}"])
    with pytest.raises(ConfigError, match="pools"):
        load_train_spec(None, ["env.draws.pools=[ocean]"])
