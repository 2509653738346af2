"""SWIM benchmark: pools, goals, the schedule and each metric on hand-made swims."""
import numpy as np
import pytest

from layered_swim.config import ConfigError
from layered_swim.tasks.swim_benchmark import (
    ROLL_TOLERANCE_DEG,
    START_DEPTH_M,
    SWIM_PUBLISHED,
    episode_metrics,
    goal_position,
    goal_tasks,
    intermediate_goal,
    intermediate_goals,
    pool,
    straight_line_metrics,
)

LOG_HZ = 60
SMALL = pool("small")


def timeline(seconds=4.0):
    return np.arange(round(seconds * LOG_HZ) + 1) / LOG_HZ       # 0 .. 4 s, mean 2 s


def metrics(task, positions, roll=None, t=None, **kw):
    t = timeline() if t is None else t
    roll = np.zeros(len(t)) if roll is None else roll
    return episode_metrics(task, t, positions, roll, ROLL_TOLERANCE_DEG["front_crawl"], **kw)


def test_pools_follow_the_paper():
    small, large = pool("small"), pool("large")
    assert (small.length_m, small.width_m, small.depth_m, small.horizon_s) == (3.0, 1.5, 0.5, 4.0)
    assert (large.length_m, large.width_m, large.depth_m, large.horizon_s) == (5.0, 2.0, 0.7, 8.0)
    assert large.goal_distance_m == 2 * small.goal_distance_m            # 2x distance, 2x duration
    assert goal_tasks(small)[0].speed_m_s == pytest.approx(0.375)        # SWIM's target speed


def test_unknown_pool_is_a_config_error():
    with pytest.raises(ConfigError, match="olympic"):
        pool("olympic")


@pytest.mark.parametrize("name", ["small", "large"])
def test_three_goals_inside_the_pool_on_the_far_side(name):
    p = pool(name)
    tasks = goal_tasks(p)
    assert len(tasks) == 3 and len({t.goal_m for t in tasks}) == 3
    x_min, x_max = p.x_range_m
    for task in tasks:
        assert task.start_m == (0.0, 0.0, -START_DEPTH_M) and task.duration_s == p.horizon_s
        x, y, z = task.goal_m
        assert (x_min + x_max) / 2 < x < x_max and abs(y) < p.width_m / 2 and -p.depth_m < z < 0
        assert x_min < 0.0                                              # the start is inside too


def test_goal_position_runs_the_line_on_schedule_and_holds_at_the_goal():
    task = goal_tasks(SMALL)[1]                                         # the left goal
    np.testing.assert_allclose(goal_position(task, 0.0), task.start_m)
    np.testing.assert_allclose(goal_position(task, 2.0), np.add(task.start_m, task.goal_m) / 2)
    np.testing.assert_allclose(goal_position(task, [4.0, 9.0]), [task.goal_m, task.goal_m])


def test_intermediate_goal_is_dt_times_speed_ahead_capped_at_the_goal():
    task = goal_tasks(SMALL)[2]
    ahead = intermediate_goal(task, 1.0, 0.2) - goal_position(task, 1.0)
    np.testing.assert_allclose(ahead, 0.2 * task.speed_m_s * task.direction, atol=1e-12)
    np.testing.assert_allclose(intermediate_goal(task, 3.9, 0.2), task.goal_m)
    four = intermediate_goals(task, 1.0, cycle_s=1.6)
    np.testing.assert_allclose(four, goal_position(task, [1.1, 1.2, 1.8, 2.6]))


@pytest.mark.parametrize("goal", [0, 1, 2])
def test_on_schedule_swimmer_scores_perfectly(goal):
    task = goal_tasks(SMALL)[goal]
    m = metrics(task, goal_position(task, timeline()))
    assert m["pos_m"] == pytest.approx(0, abs=1e-12) and m["dev_m"] == pytest.approx(0, abs=1e-12)
    assert m["prog"] == pytest.approx(1.0) and m["roll_deg"] == 0.0 and m["vel"] is None


def test_half_speed_swimmer():
    task = goal_tasks(SMALL)[0]
    t = timeline()
    m = metrics(task, goal_position(task, t / 2))
    # At time t it is 0.375 t / 2 behind the schedule: Pos = 0.1875 * mean(t) = 0.1875 * 2 s.
    assert m["prog"] == pytest.approx(0.5)
    assert m["pos_m"] == pytest.approx(0.375)
    assert m["dev_m"] == pytest.approx(0.0, abs=1e-12)


def test_backwards_swimmer_has_negative_progress():
    task = goal_tasks(SMALL)[0]
    t = timeline()
    positions = np.column_stack([-0.375 * t, np.zeros_like(t), np.full_like(t, -0.05)])
    assert metrics(task, positions)["prog"] == pytest.approx(-1.0)


def test_constant_lateral_offset_and_bobbing():
    task = goal_tasks(SMALL)[1]
    t = timeline()
    left_of_line = np.array([-task.direction[1], task.direction[0], 0.0])
    positions = goal_position(task, t) + 0.1 * left_of_line
    positions[:, 2] += 0.2 * np.sin(3 * t)                  # depth is not part of the task
    m = metrics(task, positions)
    assert m["dev_m"] == pytest.approx(0.1)
    assert m["pos_m"] == pytest.approx(0.1)
    assert m["prog"] == pytest.approx(1.0)


def test_roll_counts_only_the_excess_over_the_tolerance():
    task = goal_tasks(SMALL)[0]
    t = timeline(0.05)                                      # 4 samples
    on_line = goal_position(task, t)
    assert metrics(task, on_line, roll=[10.0, -30.0, 44.0, -45.0], t=t)["roll_deg"] == 0.0
    # 45 deg tolerance: excesses 0, 5, 0, 15 -> mean 5.
    excess = metrics(task, on_line, roll=[10.0, 50.0, -30.0, -60.0], t=t)["roll_deg"]
    assert excess == pytest.approx(5.0)


def test_vel_is_the_mean_absolute_joint_velocity_difference():
    task = goal_tasks(SMALL)[0]
    t = timeline(0.05)
    joint_vel = np.array([[1.0, -2.0], [0.0, 0.5], [3.0, 3.0], [0.0, 0.0]])
    ref = np.array([[0.0, 0.0], [0.0, -0.5], [1.0, 3.0], [0.0, -1.0]])
    m = metrics(task, goal_position(task, t), t=t, joint_vel=joint_vel, ref_joint_vel=ref)
    assert m["vel"] == pytest.approx((1 + 2 + 0 + 1 + 2 + 0 + 0 + 1) / 8)
    with pytest.raises(ValueError):
        metrics(task, goal_position(task, t), t=t, joint_vel=joint_vel)


def test_goal_metrics_are_the_straight_line_metrics_over_the_horizon():
    task = goal_tasks(pool("large"))[2]
    t = timeline(10.0)                                      # logged past the 8 s horizon
    rng = np.random.default_rng(0)
    positions = goal_position(task, t) + rng.normal(0.0, 0.05, (len(t), 3))
    roll = rng.normal(0.0, 40.0, len(t))
    within = t <= 8.0
    expected = straight_line_metrics(t[within], positions[within], roll[within], task.start_m,
                                     task.direction, task.speed_m_s, 45.0)
    assert metrics(task, positions, roll=roll, t=t) == expected


def test_published_numbers():
    assert SWIM_PUBLISHED["small"]["SWIM"] == {"pos_m": (0.126, 0.030), "prog": (0.712, 0.028),
                                               "dev_m": (0.037, 0.006)}
    assert SWIM_PUBLISHED["small"]["M-PPO-3"]["pos_m"][0] == 0.177
    large = SWIM_PUBLISHED["large"]["SWIM"]
    assert [large[k][0] for k in ("pos_m", "prog", "dev_m")] == [0.217, 0.880, 0.144]


def test_the_pool_ends_a_swim_past_its_walls_or_on_its_floor():
    x0, x1 = SMALL.x_range_m                                  # -0.75 .. 2.25 m
    assert SMALL.ending([0.0, 0.0, -0.2]) is None
    assert "left the small pool" in SMALL.ending([x1 + 0.01, 0.0, -0.2])
    assert "left the small pool" in SMALL.ending([0.5, -0.76, -0.2])     # 1.5 m wide
    assert "sank to the floor of the 0.5 m" in SMALL.ending([0.5, 0.0, -0.51])


def test_a_pool_holding_a_goal_off_its_three_is_widened_to_keep_it_inside():
    wide = pool("large").holding(-1.25)
    assert wide.goal_offsets_m == (-1.25,) and wide.width_m == pytest.approx(2 * (1.25 + 0.5))
    assert pool("large").holding(0.3).width_m == pool("large").width_m       # already fits
    assert goal_tasks(wide)[0].goal_m[1] == -1.25


def test_an_episode_that_ended_early_is_held_where_it_stopped_to_the_horizon():
    task = goal_tasks(SMALL)[0]                               # 1.5 m along +x in 4 s
    t = timeline(1.0)
    positions = goal_position(task, t) + [0.0, 0.2, 0.0]       # on schedule, 0.2 m to the left, for 1 s
    got = metrics(task, positions, t=t, ended_s=1.0, step_s=0.05)
    # Held at x = 0.375 m from t = 1 to 4 s: behind the schedule by 0.375 (t - 1) m.
    held_t = np.arange(1.05, 4.0 + 1e-9, 0.05)
    lag = 0.375 * (held_t - 1.0)
    expected_pos = (np.sum(np.full(len(t), 0.2)) + np.sum(np.hypot(lag, 0.2))) / (len(t) + len(held_t))
    assert got["pos_m"] == pytest.approx(expected_pos)
    assert got["prog"] == pytest.approx(0.375 / 1.5)          # a quarter of the way when the horizon ends
    assert got["dev_m"] == pytest.approx(0.2)
    # Not ended: the same samples are scored over what was swum.
    assert metrics(task, positions, t=t)["prog"] == pytest.approx(1.0)


def test_table_3_has_all_four_columns():
    from layered_swim.tasks.swim_benchmark import SWIM_PUBLISHED_TABLE3

    assert list(SWIM_PUBLISHED_TABLE3) == ["3 m static", "3 m dynamic", "5 m static", "5 m dynamic"]
    assert SWIM_PUBLISHED_TABLE3["3 m dynamic"]["SWIM"]["pos_m"] == (0.254, 0.104)
    assert SWIM_PUBLISHED_TABLE3["5 m dynamic"]["SWIM"]["dev_m"][0] == 0.169
    assert SWIM_PUBLISHED_TABLE3["5 m static"] == SWIM_PUBLISHED["large"]
