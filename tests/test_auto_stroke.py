"""`--stroke auto`: which stroke the rule picks, that a switch never jumps the pose, and that it
holds a target that stays put by treading water."""
import math

import numpy as np
import pytest

from layered_swim.config import ConfigError
from layered_swim.control.auto import HOLD, SPRINT, TURN, Ability, Ask, StrokeChoice, ability_of
from layered_swim.control.calibration import load_table
from layered_swim.control.targets import (
    FixedTarget,
    StationTarget,
    load_trajectory,
    target_speed_m_s,
    target_velocity_m_s,
)
from layered_swim.episode import Episode
from layered_swim.fluid.medium import Medium
from layered_swim.tasks import FollowTarget

RULE = StrokeChoice()
AHEAD, BEHIND = 0.0, math.radians(150.0)


@pytest.mark.parametrize("active, distance, speed, error, expected", [
    (TURN, 0.8, 0.0, BEHIND, HOLD),       # a still target close by is held, wherever it is
    (TURN, 0.8, 0.5, AHEAD, TURN),        # a moving one is followed
    (HOLD, 1.5, 0.0, BEHIND, HOLD),       # treading goes on until the target is hold_leave_m away...
    (TURN, 1.5, 0.0, AHEAD, TURN),        # ...but does not start until within hold_within_m
    (HOLD, 2.5, 0.0, AHEAD, TURN),
    (HOLD, 1.5, 0.5, AHEAD, TURN),        # or until it moves
    (TURN, 13.0, 0.5, AHEAD, SPRINT),     # far ahead: sprint
    (TURN, 8.0, 0.5, BEHIND, TURN),       # far behind: turn first
    (SPRINT, 4.0, 0.5, math.radians(45.0), SPRINT),   # a sprint keeps on to sprint_until_m...
    (TURN, 4.0, 0.5, AHEAD, TURN),        # ...which a turn does not start from
    (SPRINT, 2.0, 0.5, AHEAD, TURN),
    (SPRINT, 8.0, 0.5, math.radians(70.0), TURN),
])
def test_the_rule_picks_the_stroke_for_what_the_target_asks(active, distance, speed, error, expected):
    assert RULE.choose(active, Ask(distance, speed, error)) == expected


# Made-up strokes: the breaststroke's full pace 0.8 m/s, so a target asking over 0.68 m/s (0.85 of it)
# is kept up with, and left below 0.6 (0.75 of it); "tight" turns most per metre but is fast enough
# (0.85 of its pace) only up to 0.85 m/s, the crawl up to 1.02.
ABILITIES = {TURN: Ability(0.8, 0.4), "tight": Ability(1.0, 0.5), SPRINT: Ability(1.2, 0.3), "fast": Ability(1.5, 0.1)}


@pytest.mark.parametrize("active, asked, expected", [
    (TURN, 0.6, TURN),           # within what the breaststroke swims comfortably
    (TURN, 0.7, "tight"),        # beyond it: the tightest turner fast enough
    (TURN, 0.95, SPRINT),        # too fast for "tight": the crawl
    (TURN, 1.2, "fast"),
    (TURN, 2.0, "fast"),         # faster than any: the fastest
    ("tight", 0.62, "tight"),    # keeps up down to 0.6 m/s...
    ("tight", 0.55, TURN),
    (TURN, 0.65, TURN),          # ...which does not start it
])
def test_a_target_asking_more_pace_than_the_breaststroke_gets_the_tightest_turner_fast_enough(active, asked, expected):
    assert RULE.choose(active, Ask(5.0, asked, AHEAD, asked), ABILITIES) == expected


def test_hold_dive_and_sprint_come_before_keeping_up():
    assert RULE.choose(TURN, Ask(0.5, 0.0, AHEAD, 1.0), ABILITIES) == HOLD      # a still target in a current
    assert RULE.choose(TURN, Ask(13.0, 1.0, AHEAD, 1.0), ABILITIES) == SPRINT
    # A deep target, however fast or far: the breaststroke, which holds a depth.
    for distance in (5.0, 13.0):
        assert RULE.choose("tight", Ask(distance, 1.0, AHEAD, 1.0, depth_m=1.5), ABILITIES) == TURN
    assert RULE.choose(TURN, Ask(5.0, 1.0, AHEAD, 1.0, depth_m=0.5), ABILITIES) == SPRINT


# Made-up strokes for reaching: "fast" is the quickest but turns widely, "back" swims on its back.
REACHERS = ABILITIES | {"back": Ability(2.0, 0.5, face_down=False)}
GOING = 0.6      # m/s: already swimming


@pytest.mark.parametrize("active, distance, error_deg, speed, expected", [
    # 8 m straight ahead: TURN 8/0.8 = 10 s (no change), "tight" 8/1.0 + 2 = 10, the crawl 8.7, "fast"
    # 7.3 s; "back" (6 s) does not face where it goes.
    (TURN, 8.0, 0.0, GOING, "fast"),
    # 30 deg off: "fast" would circle round it (8 m x 0.1 rad/m < 2 sin 30 deg); the crawl 10.1 s,
    # "tight" 11.0, TURN 11.6.
    (TURN, 8.0, 30.0, GOING, SPRINT),
    # 90 deg off: "fast" would circle, the crawl 13.0 s, "tight" 13.1, TURN 14.9.
    (TURN, 8.0, 90.0, GOING, SPRINT),
    (TURN, 8.0, 0.0, 0.1, TURN),            # from a standstill the breaststroke sets off first
    (TURN, 3.5, 0.0, GOING, TURN),          # not far: no change of stroke
    ("fast", 3.5, 0.0, 0.1, "fast"),        # one under way goes on until reach_until_m...
    ("fast", 1.5, 0.0, GOING, TURN),
])
def test_a_far_still_target_is_reached_with_the_stroke_that_gets_there_soonest(active, distance, error_deg,
                                                                               speed, expected):
    ask = Ask(distance, 0.0, math.radians(error_deg), speed_m_s=speed)
    assert RULE.choose(active, ask, REACHERS) == expected
    assert RULE.choose(active, ask._replace(target_speed_m_s=0.5), REACHERS) == TURN     # a moving one: not


def test_arriving_fast_the_hold_starts_where_coasting_takes_the_swimmer_near():
    """Treading water from 1.2 m/s it coasts on 2 m (and overshot stations by 3-4 m)."""
    assert not RULE.holds(TURN, 2.5, 0.0, closing_m_s=0.0)
    assert not RULE.holds(TURN, 2.5, 0.0, closing_m_s=1.0)          # coasts to 1.0 m: not yet
    assert RULE.holds(TURN, 2.5, 0.0, closing_m_s=1.5)              # coasts to 0.25 m
    assert RULE.holds(TURN, 0.9, 0.0, closing_m_s=-0.5)             # within hold_within_m, whatever its speed
    assert not RULE.holds(TURN, 2.5, 0.5, closing_m_s=1.5)          # a moving target is followed


def test_a_strokes_ability_is_read_off_its_calibration():
    episode = Episode("auto", FollowTarget(FixedTarget([2.5, 0.0, -0.3])))
    try:
        butterfly = episode.controller.controllers["butterfly"]
        abilities = episode.controller.abilities
    finally:
        episode.close()
    table = load_table(butterfly.stroke)
    top = table.pace.speed_at(1.0)
    turn = min(table.turn_at("yaw_left", 1.0)[-1], table.turn_at("yaw_right", 1.0)[-1])
    assert ability_of(butterfly) == Ability(top, pytest.approx(turn / (top * butterfly.stroke.period_s)))
    assert set(abilities) == {TURN, SPRINT, "butterfly", "backstroke"}       # treading water keeps up with nothing


@pytest.mark.parametrize("depth_m", [0.3, 1.5])
def test_a_current_to_fight_is_swum_with_a_faster_stroke_and_logged(depth_m):
    """A target 6 m ahead in a 0.8 m/s current against the way to it asks more than the
    breaststroke's comfortable pace: at its first cycle's end auto takes the stroke the rule picks,
    unless the target is deep (the breaststroke holds a depth)."""
    episode = Episode("auto", FollowTarget(FixedTarget([6.0, 0.0, -depth_m])),
                      medium=Medium(current_m_s=(-0.8, 0.0, 0.0)))
    try:
        expected = episode.controller.choice_rule.keeping_up(0.8, episode.controller.abilities)
        episode.run(2.0)
        switches = episode.controller.switches
    finally:
        episode.close()
    assert expected != TURN
    assert [s.stroke for s in switches] == ([expected] if depth_m < RULE.dive_beyond_m else [])


def test_a_jump_asks_no_pace_but_a_current_does():
    jump = StationTarget(np.array([[0.0, 0.0, -0.3], [8.0, 0.0, -0.3]]), np.array([0.0, 10.0]))
    assert np.linalg.norm(target_velocity_m_s(jump, 10.5)) > RULE.jumped_beyond_m_s
    for current, asked in [((0.0, 0.0, 0.0), 0.0), ((0.3, -0.4, 0.1), 0.5)]:
        episode = Episode("auto", FollowTarget(jump), medium=Medium(current_m_s=current))
        try:
            assert episode.controller._asked_m_s(10.5, np.array([1.0, 2.0, -0.3])) == pytest.approx(asked)
        finally:
            episode.close()


def test_target_speed_looks_ahead_only_where_the_path_is_known():
    line = load_trajectory("straight_line")
    assert target_speed_m_s(line, 5.0) == pytest.approx(float(np.linalg.norm(line.position(6.0) - line.position(5.0))))
    jump = StationTarget(np.array([[0.0, 0.0, -0.3], [4.0, 3.0, -0.3]]), np.array([0.0, 10.0]))
    assert target_speed_m_s(jump, 9.5) == 0.0                  # the jump is not seen coming
    assert target_speed_m_s(jump, 10.5) == pytest.approx(5.0)   # it moved 5 m within the last second
    assert target_speed_m_s(jump, 12.0) == 0.0


def test_auto_holds_a_still_target_by_treading_water_and_never_jumps_the_pose():
    episode = Episode("auto", FollowTarget(FixedTarget([2.5, 0.0, -0.3])))
    poses = []
    try:
        episode.run(14.0, observers=[lambda sim: poses.append(sim.desired_pose.copy())])
        controller, state = episode.controller, episode.sim.state
    finally:
        episode.close()
    # Held: one switch, to treading water, which drifts (backwards, 0.19 m/s on its own) but stays
    # within the distance at which auto would swim again.
    assert [switch.stroke for switch in controller.switches] == [HOLD] and controller.active == HOLD
    assert np.linalg.norm(state.com_m[:2] - [2.5, 0.0]) < RULE.hold_leave_m
    steps = np.abs(np.diff(np.array(poses), axis=0)).max(axis=1)
    hz = episode.sim.config.physics_hz
    switch = int(round(controller.switches[0].time_s * hz))
    # Across the switch the pose moves no faster than the strokes themselves move it.
    assert steps[switch - 5:switch + 5].max() <= 1.5 * np.percentile(steps, 99.9)


def test_auto_needs_a_target():
    with pytest.raises(ConfigError, match="auto"):
        Episode("auto")


def test_auto_starts_holding_a_still_target_as_soon_as_it_is_in_reach():
    """Not at the next cycle end: a breaststroke turning tightly round the target may be in reach
    only between its cycle ends (in reach: within hold_within_m, or coasting to it)."""
    goal = np.array([2.5, 0.0, -0.3])
    episode = Episode("auto", FollowTarget(FixedTarget(goal)))

    def seen(sim):
        away = goal[:2] - sim.state.com_m[:2]
        closing = float(sim.state.com_vel_m_s[:2] @ away / np.linalg.norm(away))
        return (sim.time_s, episode.controller.controllers[TURN].cycle_start_s,
                episode.controller.controllers[TURN].cycles_per_s, float(np.linalg.norm(away)), closing)
    try:
        switched = []
        episode.run(8.0, observers=[lambda sim: switched or not episode.controller.switches or switched.append(
            seen(sim))])
        controller = episode.controller
    finally:
        episode.close()
    assert controller.switches[0].stroke == HOLD
    time_s, cycle_start_s, cycles_per_s, distance_m, closing_m_s = switched[0]
    assert (time_s - cycle_start_s) * cycles_per_s < 0.95      # mid-cycle
    assert distance_m - RULE.hold_coast_s * closing_m_s < RULE.hold_coast_to_m + 0.05


def test_auto_leaves_a_held_target_the_moment_it_jumps_away():
    """Not at the treading cycle's end: every second standing there is a second later at the jump."""
    jump = StationTarget(np.array([[2.5, 0.0, -0.3], [2.5, 8.0, -0.3]]), np.array([0.0, 9.0]))
    episode = Episode("auto", FollowTarget(jump))
    seen = []
    try:
        episode.run(10.0, observers=[lambda sim: seen.append(
            (sim.time_s, len(episode.controller.switches), episode.controller.controllers[HOLD].cycle_start_s,
             episode.controller.controllers[HOLD].cycles_per_s))])
        switches = episode.controller.switches
    finally:
        episode.close()
    held = [t for t, name in switches if name == HOLD]
    assert held and held[0] < 9.0 and switches[-1].stroke == TURN
    left_s = switches[-1].time_s
    assert 9.0 <= left_s < 9.05
    _, _, cycle_start_s, cycles_per_s = next(row for row in seen if row[0] >= left_s - 1e-9)
    assert (left_s - cycle_start_s) * cycles_per_s < 0.95      # mid-cycle


def test_after_treading_water_auto_gets_away_and_reaches_a_far_jump_with_the_soonest_stroke():
    """Standing after a hold, the breaststroke lays the body down and gets it going; then the stroke
    that gets there soonest (the butterfly, by the shipped calibrations) swims the rest, and it
    treads water again where it coasts to the target: 8 m reached within 12 s."""
    goal = np.array([10.5, 0.0, -0.3])
    jump = StationTarget(np.array([[2.5, 0.0, -0.3], goal]), np.array([0.0, 9.0]))
    episode = Episode("auto", FollowTarget(jump))
    try:
        soonest = RULE.soonest(TURN, Ask(8.0, 0.0, 0.0), episode.controller.abilities)
        reached = []
        episode.run(21.0, observers=[lambda sim: reached or np.linalg.norm(sim.state.com_m - goal) > 1.0
                                     or reached.append(sim.time_s)])
        switches = [s.stroke for s in episode.controller.switches if s.time_s >= 9.0]
    finally:
        episode.close()
    assert soonest == "butterfly"
    assert switches == [TURN, soonest, HOLD]
    assert reached and reached[0] - 9.0 < 12.0
