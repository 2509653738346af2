"""The episode runner: reset(seed, options) / step / run, tasks that observe and score, and a
task that moves its target on reset without anything being rebuilt."""
import numpy as np
import pytest

from layered_swim.control.layered import Layers, fixed_weights
from layered_swim.control.targets import FixedTarget
from layered_swim.episode import Episode
from layered_swim.runs import goal_episode, reach_goal
from layered_swim.spec import GoalTask, SwimSpec
from layered_swim.tasks import FollowTarget
from layered_swim.tasks.follow import TRACK_HZ


def _goal(stroke: str) -> SwimSpec:
    return SwimSpec(stroke=stroke, task=GoalTask(pool="small"))


def test_goal_task_moves_its_target_on_reset_without_rebuilding_the_world():
    episode = goal_episode(_goal("front_crawl"))
    fresh = goal_episode(_goal("front_crawl"))
    try:
        world = episode.sim.world
        far = reach_goal(episode, 1)
        again = reach_goal(episode, 0)
        assert episode.sim.world is world                          # the same PyBullet body all along
        assert far["goal_m"] != again["goal_m"]
        assert again == reach_goal(fresh, 0)                       # a reused world swims bit for bit the same
    finally:
        episode.close()
        fresh.close()


def test_goal_task_draws_its_goal_from_the_seed():
    episode = goal_episode(_goal("breaststroke"))
    try:
        drawn = []
        for seed in (3, 3, 4, 5, 6):
            episode.reset(seed=seed)
            drawn.append(tuple(episode.task.goal.goal_m))
        assert drawn[0] == drawn[1] and len(set(drawn)) > 1
        with pytest.raises(ValueError, match="goal must be in 0..2"):
            episode.reset(goal=3)
    finally:
        episode.close()


def test_reset_replays_the_same_swim():
    episode = Episode("breaststroke")
    try:
        runs = []
        for _ in range(2):
            episode.reset()
            episode.run(0.5)
            runs.append(episode.sim.state.pos_m.copy())
        np.testing.assert_array_equal(runs[0], runs[1])
    finally:
        episode.close()


def test_a_task_samples_the_swim_at_its_own_rate():
    target = FixedTarget((5.0, 0.0, -0.2))
    episode = Episode("breaststroke", FollowTarget(target))
    try:
        episode.run(1.0)
    finally:
        episode.close()
    track = episode.task.track()
    assert len(track["track_time_s"]) == TRACK_HZ + 1                          # reset plus one per 1/20 s
    np.testing.assert_allclose(track["target_m"], np.tile(target.position(0.0), (TRACK_HZ + 1, 1)))
    assert episode.metrics()["final_distance_m"] < episode.metrics()["max_distance_m"]


def test_scripted_weights_with_the_rules_on_swim_straight_ahead():
    """A fixed-weights policy and no target used to leave the rules without a direction (a crash);
    they now push toward where the swimmer faces."""
    episode = Episode("breaststroke", weights=fixed_weights({}), layers=Layers())
    try:
        episode.run(1.0)
        assert np.abs(episode.controller.rule_offsets).max() > 0.0
    finally:
        episode.close()


@pytest.mark.parametrize("rho_kg_m3, min_tempo, kicks", [(997.05, 0.8, True), (1023.3, 0.8, True), (900.0, 0.8, True),
                                                      (1100.0, 0.5, False), (1500.0, 0.5, False)])
def test_the_crawl_slows_down_and_glides_still_in_dense_water(rho_kg_m3, min_tempo, kicks):
    from layered_swim.control.targets import FixedTarget
    from layered_swim.fluid.medium import water
    from layered_swim.tasks import FollowTarget

    episode = Episode("front_crawl", FollowTarget(FixedTarget([5.0, 0.0, -0.3])), medium=water(density_kg_m3=rho_kg_m3))
    try:
        assert episode.controller.chooser.tempo_control.min_tempo == pytest.approx(min_tempo)
        assert episode.controller.stroke.glide_moving.any() == kicks
    finally:
        episode.close()


@pytest.mark.parametrize("rho_kg_m3, hip_deg", [(997.05, 0.0), (1023.3, 0.0), (900.0, 30.0), (1300.0, 30.0),
                                               (2500.0, 30.0)])
def test_the_breaststroke_is_trimmed_only_in_water_far_from_the_body_density(rho_kg_m3, hip_deg):
    from layered_swim.fluid.medium import water

    fresh, other = Episode("breaststroke"), Episode("breaststroke", medium=water(density_kg_m3=rho_kg_m3))
    try:
        names = other.sim.layout.names
        moved = np.degrees(other.stroke.pose(0.4)[0] - fresh.stroke.pose(0.4)[0])
        expected = np.zeros(len(names))
        expected[[names.index("hip_l.flexion"), names.index("hip_r.flexion")]] = hip_deg
        np.testing.assert_allclose(moved, expected, atol=1e-9)
    finally:
        fresh.close()
        other.close()
