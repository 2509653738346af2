"""The per-cycle layer (weights, blending, calibration inversion), the rules and a short follow."""
import dataclasses
import math

import numpy as np
import pytest

from layered_swim.analysis.calibrate import calibration_swim, weight_grid
from layered_swim.body.layout import joint_layout
from layered_swim.body.model import load_body
from layered_swim.config import ConfigError, load
from layered_swim.control.calibration import CalibrationTable, Pace, load_table
from layered_swim.control.cycle_choice import (
    Drift,
    InWater,
    Lead,
    TargetChooser,
    TempoControl,
    behind_along_m,
    gain_along_m_s,
    stays_at_surface,
    weave_aim,
)
from layered_swim.control.layered import CycleChoice, LayeredController, Layers, fixed_weights
from layered_swim.control.rules import arm_indices, rule_offsets
from layered_swim.control.steering import (
    Attitude,
    MeanAttitude,
    SteeringGains,
    attitude,
    attitude_errors,
    attitude_of,
    glide_pitch,
    held_offset,
    turn_error,
    turned_over,
)
from layered_swim.control.stroke import (
    LEVEL_OFF,
    ROLL_OVER,
    UNCALIBRATED_SEQUENCES,
    UNDER_WATER,
    JointKeys,
    PerturbationSpec,
    RulesSpec,
    StrokeSpec,
    build_stroke,
    load_stroke,
    mirrored_keys,
    stroke_path,
)
from layered_swim.control.targets import FixedTarget, TrajectoryTarget, load_trajectory
from layered_swim.episode import Episode
from layered_swim.fluid.medium import Medium
from layered_swim.geometry import quat_multiply
from layered_swim.runs import swim
from layered_swim.sim.simulation import PRONE_QUAT_XYZW, SUPINE_QUAT_XYZW
from layered_swim.spec import GOAL_TEMPO, SwimSpec
from layered_swim.state import BodyState, Segments
from layered_swim.tasks import FollowTarget

BODY = load_body()
LAYOUT = joint_layout(BODY)


def still_state(mass_fraction=None) -> BodyState:
    """All 16 segments at the origin, prone, at rest."""
    segments = BODY.segments if mass_fraction is None else Segments(BODY.segment_names, mass_fraction)
    return BodyState(0.0, np.zeros((16, 3)), np.tile(PRONE_QUAT_XYZW, (16, 1)), np.zeros((16, 3)), np.zeros((16, 3)),
                     segments)


def table(yaw_turns_deg=(0.0, 2.0, 4.0, 6.0, 8.0), weights=(0.0, 0.25, 0.5, 0.75, 1.0)) -> CalibrationTable:
    turns = np.radians([yaw_turns_deg])
    pace = Pace((0.5, 1.0), (0.4, 0.8), (0.0, 0.0), (0.0, 0.0), (0.2, 0.2))
    return CalibrationTable("t", "x", weights, (1.0,), pace, {"yaw_left": turns, "yaw_right": turns / 2})


def test_table_inversion():
    t = table()
    assert t.weight_for("yaw_left", math.radians(3.0), 1.0) == pytest.approx(0.375)
    assert t.weight_for("yaw_left", math.radians(20.0), 1.0) == 1.0      # capped at the grid's end
    assert t.weight_for("yaw_left", 0.0, 1.0) == 0.0
    # A dip in the measured turns is read as saturation, never as a smaller weight.
    dip = table((0.0, 2.0, 5.0, 4.0, 6.0))
    assert dip.weight_for("yaw_left", math.radians(5.0), 1.0) == pytest.approx(0.5)


def test_weights_pick_the_sequence_that_turns_the_right_way():
    t = table()
    left = t.weights_for(math.radians(4.0), 1.0)
    assert left == {"yaw_left": pytest.approx(0.5)}
    right = t.weights_for(-math.radians(2.0), 1.0)
    assert right == {"yaw_right": pytest.approx(0.5)}


def attitude_table() -> CalibrationTable:
    """Pitch sequences holding +10 / -20 deg at full weight; roll sequences the other way round from
    their names (roll_left lifts the left shoulder by 8 deg)."""
    t = table()
    ramp = np.radians([[0.0, 2.5, 5.0, 7.5, 10.0]])
    t.attitude_rad.update({"pitch_up": ramp, "pitch_down": -2.0 * ramp, "roll_left": 0.8 * ramp,
                           "roll_right": -0.8 * ramp})
    return t


def test_attitude_weights_invert_the_held_offsets_whichever_way_a_sequence_goes():
    t = attitude_table()
    assert t.attitude_range("pitch", 1.0) == pytest.approx((math.radians(-20.0), math.radians(10.0)))
    assert t.attitude_weights("pitch", math.radians(5.0), 1.0) == {"pitch_up": pytest.approx(0.5)}
    assert t.attitude_weights("pitch", math.radians(-5.0), 1.0) == {"pitch_down": pytest.approx(0.25)}
    assert t.attitude_weights("pitch", math.radians(40.0), 1.0) == {"pitch_up": 1.0}      # at most all of it
    assert t.attitude_weights("pitch", 0.0, 1.0) == {}
    # Left shoulder up wanted: the sequence that lifts it, whatever it is called.
    assert t.attitude_weights("roll", math.radians(4.0), 1.0) == {"roll_left": pytest.approx(0.5)}
    assert t.attitude_weights("roll", math.radians(-4.0), 1.0) == {"roll_right": pytest.approx(0.5)}
    assert table().attitude_weights("pitch", 0.1, 1.0) == {} and table().attitude_range("roll", 1.0) == (0.0, 0.0)


def test_held_offset_integrates_the_error_within_what_the_sequences_hold():
    assert held_offset(0.1, 0.2, 0.5, -0.3, 0.3) == pytest.approx(0.2)
    assert held_offset(0.25, 0.4, 0.5, -0.3, 0.3) == 0.3          # no winding up beyond the sequences
    assert held_offset(-0.25, -0.4, 0.5, -0.3, 0.3) == -0.3
    # With a band: only the error beyond it counts; within it, the offset eases back toward none.
    assert held_offset(0.1, 0.3, 0.5, -0.5, 0.5, within_rad=0.2) == pytest.approx(0.15)
    assert held_offset(0.1, -0.3, 0.5, -0.5, 0.5, within_rad=0.2) == pytest.approx(0.05)
    assert held_offset(0.1, 0.15, 0.5, -0.5, 0.5, within_rad=0.2) == pytest.approx(0.05)
    # Against a static plant (the attitude is the stroke's own plus the held offset), the error
    # shrinks by the fraction each cycle and never changes sign: no oscillation, no steady error.
    offset, own, wanted, errors = 0.0, 0.15, -0.05, []
    for _ in range(12):
        errors.append(wanted - (own + offset))
        offset = held_offset(offset, errors[-1], 0.5, -0.5, 0.5)
    assert all(e < 0 for e in errors) and abs(errors[-1]) < 1e-3 * abs(errors[0])


def test_turn_error_and_attitude_errors_from_target_position():
    facing_x = Attitude(heading_rad=0.0, pitch_rad=0.0, roll_rad=0.0)
    assert turn_error(facing_x, np.zeros(3), np.array([0.0, 5.0, 0.0])) > 0        # target on the left: turn left
    assert turn_error(facing_x, np.zeros(3), np.array([0.0, -5.0, 0.0])) < 0
    level = MeanAttitude(math.radians(8.0), 0.0)
    flat = attitude_errors(MeanAttitude(math.radians(8.0), 0.0), np.zeros(3), np.array([5.0, 0, 0]), "prone", level)
    assert flat == pytest.approx({"roll": 0.0, "pitch": 0.0})          # the stroke's own attitude at the target's depth
    deeper = attitude_errors(level, np.zeros(3), np.array([3.0, 0.0, -3.0]), "prone", level)
    assert deeper["pitch"] == pytest.approx(-math.radians(30.0))      # below: nose down, at most the glide limit
    left_up = attitude_errors(MeanAttitude(math.radians(8.0), 0.1), np.zeros(3), np.array([5.0, 0, 0]), "prone", level)
    assert left_up["roll"] == pytest.approx(-0.1)                     # left up: bring it down
    assert "pitch" not in attitude_errors(level, np.zeros(3), np.array([3.0, 0.0, -3.0]), "upright", level)
    # A target's depth within depth_within_m counts as reached; beyond it, only the rest is steered for.
    surface = SteeringGains(depth_within_m=0.2)
    assert glide_pitch(np.zeros(3), np.array([2.0, 0.0, -0.15]), surface) == 0.0
    assert glide_pitch(np.zeros(3), np.array([5.0, 0.0, -2.2]), surface) == pytest.approx(-math.atan2(2.0, 5.0))


def test_a_target_dead_behind_is_turned_to_the_side_the_turn_already_goes():
    """Noise of a degree either side of dead behind flips the shorter side; a turn under way keeps
    its side there, but a target newly behind (a jump) is turned to the shorter side."""
    facing_x = Attitude(heading_rad=0.0, pitch_rad=0.0, roll_rad=0.0)
    behind_right = np.array([-5.0, -0.2, 0.0])          # 177.7 deg to the right
    error = -math.pi + math.atan2(0.2, 5.0)
    assert turn_error(facing_x, np.zeros(3), behind_right) == pytest.approx(error)
    assert turn_error(facing_x, np.zeros(3), behind_right, last_error_rad=math.radians(170.0)) == (
        pytest.approx(error + 2 * math.pi))          # was turning left round to it: on left
    for last_deg in (20.0, -170.0):                        # not behind then, or already on the right
        assert turn_error(facing_x, np.zeros(3), behind_right,
                          last_error_rad=math.radians(last_deg)) == pytest.approx(error)


def _pitched_up(base_quat, pitch_deg: float, heading_deg: float) -> np.ndarray:
    """A lying body's base orientation pitched nose up about its own left, then turned to heading."""
    half_p, half_h = math.radians(pitch_deg) / 2, math.radians(heading_deg) / 2
    nose_up = np.array([0.0, -math.sin(half_p), 0.0, math.cos(half_p)])      # about world -y: +x tilts up
    turn = np.array([0.0, 0.0, math.sin(half_h), math.cos(half_h)])
    return quat_multiply(turn, quat_multiply(nose_up, np.asarray(base_quat, float)))


@pytest.mark.parametrize("posture, base", [("prone", PRONE_QUAT_XYZW), ("supine", SUPINE_QUAT_XYZW)])
def test_a_lying_body_standing_up_heads_where_it_would_lie_down(posture, base):
    """Past upright (pitched 95 deg) the long axis leans back, the way opposite to where the body
    faces; read ``facing``, the heading is the way it lies down, as it is at a lower pitch."""
    for pitch_deg in (20.0, 70.0, 95.0):
        quat = _pitched_up(base, pitch_deg, 30.0)
        att = attitude(quat, quat, posture, facing=True)
        assert att.pitch_rad == pytest.approx(math.radians(min(pitch_deg, 180.0 - pitch_deg)))
        assert math.degrees(att.heading_rad) == pytest.approx(30.0)
    long_axis = attitude(_pitched_up(base, 95.0, 30.0), _pitched_up(base, 95.0, 30.0), posture)
    assert math.degrees(long_axis.heading_rad) == pytest.approx(-150.0)


def test_the_chooser_holds_pitch_toward_the_target_depth_and_keeps_the_offset():
    """A swimmer 10 deg nose-down (its own pitch is 0) toward a target at its depth: pitch up, the
    held offset moving by half the error left each cycle; reset at a new first cycle."""
    chooser = TargetChooser(FixedTarget((5.0, 0.0, 0.0)), attitude_table(), "prone")
    state = still_state()
    nose_down = MeanAttitude(math.radians(-10.0), 0.0)
    assert chooser(0, state, nose_down).weights == {"pitch_up": pytest.approx(0.5)}      # 5 deg of its 10
    assert chooser(1, state, MeanAttitude(math.radians(-2.0), 0.0)).weights == {"pitch_up": pytest.approx(0.6)}
    assert chooser(2, state, MeanAttitude(math.radians(6.0), 0.0)).weights == {"pitch_up": pytest.approx(0.3)}
    assert chooser(0, state, MeanAttitude(math.radians(6.0), 0.0)).weights == {"pitch_down": pytest.approx(0.15)}
    # With a proportional share the error is also corrected at once: 4 deg low holds 2 + 4 deg.
    pi = TargetChooser(FixedTarget((5.0, 0.0, 0.0)), attitude_table(), "prone",
                       gains=SteeringGains(attitude_proportional=1.0))
    assert pi(0, state, MeanAttitude(math.radians(-4.0), 0.0)).weights == {"pitch_up": pytest.approx(0.6)}
    assert pi.held_rad["pitch"] == pytest.approx(math.radians(2.0))
    off = TargetChooser(FixedTarget((5.0, 0.0, 0.0)), attitude_table(), "prone", gains=SteeringGains(0.7, 0.0, 0.0))
    assert off(0, state, nose_down).weights == {}


def test_layers_parse():
    assert Layers.parse("basic") == Layers(cycle=False, palm=False, reach=False)
    assert Layers.parse("basic,cycle,rules") == Layers()
    assert Layers.parse("basic,palm").describe() == "basic,palm"
    with pytest.raises(ConfigError):
        Layers.parse("cycle")


def test_mirror_swaps_sides_and_flips_left_axes():
    keys = {"shoulder_l": JointKeys.model_validate({"abduction": {0.0: 10.0}}),
            "neck": JointKeys.model_validate({"rotation_left": {0.0: 20.0}, "flexion": {0.0: 5.0}})}
    mirrored = mirrored_keys(keys, phase_shift=0.5)
    assert mirrored["shoulder_r"].axis_keys() == {"abduction": {0.0: 10.0}}
    assert mirrored["neck"].axis_keys() == {"rotation_left": {0.0: -20.0}, "flexion": {0.0: 5.0}}
    assert mirrored["shoulder_r"].phase_shift == 0.5


def test_blending_adds_weighted_offsets_for_the_whole_cycle():
    stroke = load_stroke("breaststroke", LAYOUT)
    controller = LayeredController(stroke, LAYOUT, arm_indices(BODY, LAYOUT), fixed_weights({"yaw_left": 0.5}),
                                   Layers(cycle=True, palm=False, reach=False))
    controller.reset()
    state = still_state()
    controller.desired(0.0, None, None)
    pose, _ = controller.desired(0.3 * stroke.period_s, state, np.zeros((16, 3)))   # cycle 0: no weights yet
    basic, _ = stroke.pose(0.3)
    np.testing.assert_allclose(pose, LAYOUT.clamp(basic))
    t = (1.3) * stroke.period_s                                   # cycle 1: weights chosen at its start
    state.time_s = t
    pose, _ = controller.desired(t, state, np.zeros((16, 3)))
    offset, _ = stroke.perturbations["yaw_left"].at(1.3)
    np.testing.assert_allclose(pose, LAYOUT.clamp(basic + 0.5 * offset))
    assert controller.choice.weights == {"yaw_left": 0.5}


def test_glide_holds_the_pose_but_the_joints_that_keep_moving():
    stroke = load_stroke("front_crawl", LAYOUT)
    moving = stroke.glide_moving
    assert moving[LAYOUT.index("knee_l.flexion")] and not moving[LAYOUT.index("shoulder_l.flexion")]

    def glide(cycle, state, last_cycle):
        return CycleChoice(glide=True)
    controller = LayeredController(stroke, LAYOUT, arm_indices(BODY, LAYOUT), glide,
                                   Layers(cycle=True, palm=False, reach=False))
    state = still_state()
    pose, rate = controller.desired(0.0, state, np.zeros((16, 3)))
    state.time_s = 0.3 * stroke.period_s
    pose, rate = controller.desired(state.time_s, state, np.zeros((16, 3)))
    held, _ = stroke.pose(0.0)
    running, running_rate = stroke.pose(0.3)
    np.testing.assert_allclose(pose[~moving], LAYOUT.clamp(held)[~moving])       # the arms wait
    np.testing.assert_allclose(pose[moving], LAYOUT.clamp(running)[moving])      # the legs kick on
    assert np.all(rate[~moving] == 0.0)
    np.testing.assert_allclose(rate[moving], running_rate[moving] / stroke.period_s)
    assert np.ptp(running[moving]) > 0.05     # they do move


def test_a_short_glide_ends_its_cycle_early():
    """A glide of a third of a cycle (the crawl's: one beat of its kick) hands over to the next
    cycle after period/3 at tempo 1, and that cycle starts there."""
    stroke = load_stroke("front_crawl", LAYOUT)
    choices = iter([CycleChoice(glide=True, cycles=1 / 3), CycleChoice()])
    controller = LayeredController(stroke, LAYOUT, arm_indices(BODY, LAYOUT), lambda *_: next(choices),
                                   Layers(cycle=True, palm=False, reach=False))
    state = still_state()
    controller.desired(0.0, state, np.zeros((16, 3)))
    assert controller.choice.glide and not controller.cycle_ends(0.33 * stroke.period_s)
    assert controller.cycle_ends(0.34 * stroke.period_s)
    state.time_s = 0.34 * stroke.period_s
    controller.desired(state.time_s, state, np.zeros((16, 3)))
    assert controller.cycle == 1 and not controller.choice.glide
    assert controller.cycle_start_s == pytest.approx(stroke.period_s / 3)


def test_turning_toward_a_target_off_the_heading_swims_at_the_turn_tempo():
    """Behind a target 90 deg off to the left, a stroke with turn_tempo 1.2 swims at 1.2 (by
    default none: the tempo it has anyway); with the target ahead, or once ahead of it along its path by
    more than turn_tempo_until_ahead_s, at the tempo it would have anyway."""
    turning = TempoControl(turn_tempo=1.2, turn_tempo_until_ahead_s=0.5)
    assert turning.turning_tempo(0.8, math.radians(90.0), -1.0) == pytest.approx(1.2)
    assert turning.turning_tempo(0.8, math.radians(90.0), 0.5) == pytest.approx(1.2)
    assert turning.turning_tempo(0.8, math.radians(90.0), 0.6) == pytest.approx(0.8)
    assert turning.turning_tempo(0.8, math.radians(20.0), -1.0) == pytest.approx(0.8)
    assert TempoControl().turning_tempo(0.8, math.radians(90.0), -1.0) == pytest.approx(0.8)
    state = still_state(np.full(16, 1 / 16))          # at the origin, heading +x
    left = FixedTarget((0.0, 3.0, 0.0))
    assert TargetChooser(left, table(), "prone", tempo=turning)(0, state, None).tempo == pytest.approx(1.2)
    assert TargetChooser(left, table(), "prone")(0, state, None).tempo == pytest.approx(TempoControl().min_tempo)
    ahead = TargetChooser(FixedTarget((3.0, 0.0, 0.0)), table(), "prone", tempo=turning)(0, state, None)
    assert ahead.tempo == pytest.approx(1.0)


def test_full_tempo_from_far_m_and_in_proportion_nearer():
    """Full tempo from far_m off the target, the slowest within near_m, in proportion between (a
    stroke far faster than its target, the backstroke, swims flat out only from farther off)."""
    wide = TempoControl(min_tempo=0.5, far_m=1.5)
    assert wide.drive(0.1) == 0.0 and wide.drive(1.5) == wide.drive(3.0) == 1.0
    assert wide.tempo_for(wide.drive(0.85)) == pytest.approx(0.5 + 0.5 * (0.85 - 0.2) / 1.3)
    assert TempoControl().drive(0.6) == 1.0 > wide.drive(0.6)
    state = still_state(np.full(16, 1 / 16))          # at the origin, heading +x
    near = FixedTarget((1.0, 0.0, 0.0))
    assert TargetChooser(near, table(), "prone")(0, state, None).tempo == pytest.approx(1.0)
    assert TargetChooser(near, table(), "prone", tempo=wide)(0, state, None).tempo == pytest.approx(
        0.5 + 0.5 * 0.8 / 1.3)


def test_far_behind_a_moving_target_swims_at_the_turn_tempo():
    """Behind a target moving along a known path and more than catch_up_beyond_m from it, a stroke
    swims at its turn tempo; nearer, ahead of it, or with a target whose path is unknown (a jump),
    at the tempo it has anyway."""
    catching = TempoControl(turn_tempo=1.2, catch_up_beyond_m=2.0)
    assert catching.catching_up_tempo(1.0, 2.1, -0.5) == pytest.approx(1.2)
    assert catching.catching_up_tempo(1.0, 1.9, -0.5) == pytest.approx(1.0)
    assert catching.catching_up_tempo(1.0, 2.1, 0.5) == pytest.approx(1.0)
    assert TempoControl(turn_tempo=1.2).catching_up_tempo(1.0, 5.0, -1.0) == pytest.approx(1.0)
    state = still_state(np.full(16, 1 / 16))          # at the origin, heading +x
    ahead_along_x = TrajectoryTarget(np.array([[3.0, 0.0, 0.0], [33.0, 0.0, 0.0]]), np.array([0.0, 60.0]), 1.0, False)
    assert TargetChooser(ahead_along_x, table(), "prone", tempo=catching)(0, state, None).tempo == pytest.approx(1.2)
    assert TargetChooser(ahead_along_x, table(), "prone")(0, state, None).tempo == pytest.approx(1.0)
    jumped = FixedTarget((3.0, 0.0, 0.0))
    assert TargetChooser(jumped, table(), "prone", tempo=catching)(0, state, None).tempo == pytest.approx(1.0)


def test_behind_a_moving_target_at_the_surface_a_stroke_closes_the_gap():
    """With close_gap_s, a stroke behind a moving target swims at its pace plus the gap over
    close_gap_s (the test table's pace: 0.4 m/s at tempo 0.5, 0.8 at 1.0), up to its turn tempo,
    or only the gap beyond close_gap_beyond_m; ahead of it, at its pace; without, at its pace
    alone; and not where the path dives."""
    closing = TempoControl(close_gap_s=0.5)
    assert closing.closing_speed_m_s(0.5, 0.1) == pytest.approx(0.7)
    assert closing.closing_speed_m_s(0.5, -0.3) == pytest.approx(0.5)
    assert TempoControl().closing_speed_m_s(0.5, 0.1) == pytest.approx(0.5)
    beyond = TempoControl(close_gap_s=0.5, close_gap_beyond_m=1.0)     # only the gap beyond 1 m
    assert beyond.closing_speed_m_s(0.5, 0.8) == pytest.approx(0.5)
    assert beyond.closing_speed_m_s(0.5, 1.3) == pytest.approx(1.1)
    along_x = TrajectoryTarget(np.array([[0.1, 0.0, 0.0], [30.1, 0.0, 0.0]]), np.array([0.0, 60.0]), 1.0, False)
    assert behind_along_m(along_x, 0.0, np.zeros(3)) == pytest.approx(0.1)
    assert behind_along_m(along_x, 0.0, np.array([5.1, 2.0, -1.0])) == pytest.approx(-5.0)
    assert behind_along_m(FixedTarget((3.0, 0.0, 0.0)), 0.0, np.zeros(3)) == 0.0
    state = still_state(np.full(16, 1 / 16))          # at the origin, heading +x, 0.1 m behind
    assert TargetChooser(along_x, table(), "prone", tempo=closing)(0, state, None).tempo == pytest.approx(0.875)
    assert TargetChooser(along_x, table(), "prone")(0, state, None).tempo == pytest.approx(0.625)
    capped = TempoControl(close_gap_s=0.1, turn_tempo=0.8)
    assert TargetChooser(along_x, table(), "prone", tempo=capped)(0, state, None).tempo == pytest.approx(0.8)
    under_a_metre = Medium(surface_z_m=1.0)       # the swimmer and its target 1 m deep
    deep = TargetChooser(along_x, table(), "prone", tempo=closing, water=lambda: under_a_metre)
    assert deep(0, state, None).tempo == pytest.approx(0.625)


def test_a_stroke_closes_the_gap_it_will_have_at_the_speed_it_gained_over_its_last_cycle():
    """With close_gap_ahead_s, the gap closed is the one that far ahead at the speed gained on the
    target (its speed along the target's way less the target's); the chooser reads that speed
    off the centre of mass's move since the last cycle's start (none at the first cycle)."""
    ahead = TempoControl(close_gap_s=0.5, close_gap_ahead_s=2.0)
    assert ahead.closing_speed_m_s(0.5, 1.0, 0.3) == pytest.approx(0.5 + (1.0 - 0.6) / 0.5)
    assert ahead.closing_speed_m_s(0.5, 1.0, -0.2) == pytest.approx(0.5 + (1.0 + 0.4) / 0.5)
    assert ahead.closing_speed_m_s(0.5, 1.0, 0.6) == pytest.approx(0.5)     # it will be ahead: the pace
    assert TempoControl(close_gap_s=0.5).closing_speed_m_s(0.5, 1.0, 0.3) == pytest.approx(2.5)   # none: as it is
    along_x = TrajectoryTarget(np.array([[0.1, 0.0, 0.0], [30.1, 0.0, 0.0]]), np.array([0.0, 60.0]), 1.0, False)
    assert gain_along_m_s(along_x, 0.0, np.array([0.8, 0.3, -1.0])) == pytest.approx(0.3)
    assert gain_along_m_s(FixedTarget((3.0, 0.0, 0.0)), 0.0, np.array([0.8, 0.0, 0.0])) == 0.0
    start = still_state(np.full(16, 1 / 16))          # at the origin, 0.1 m behind
    later = BodyState(1.0, np.tile([0.2, 0.0, 0.0], (16, 1)), start.quat_xyzw, np.zeros((16, 3)),
                      np.zeros((16, 3)), start.segments)   # 0.2 m on a second later: 0.4 m behind, losing 0.3 m/s
    for close_gap_ahead_s, tempo in ((0.0, 0.875), (0.5, 0.96875)):
        # the test table's pace: 0.4 m/s at tempo 0.5, 0.8 at 1.0; 0.5 + 0.4 / 2 or 0.5 + (0.4 + 0.15) / 2 m/s
        chooser = TargetChooser(along_x, table(), "prone",
                                tempo=TempoControl(close_gap_s=2.0, close_gap_ahead_s=close_gap_ahead_s))
        assert chooser(0, start, None).tempo == pytest.approx(0.6875)      # 0.5 + 0.1 / 2 m/s
        assert chooser(1, later, None).tempo == pytest.approx(tempo)


def test_a_gap_is_closed_only_on_a_path_that_stays_at_the_surface():
    """deep_dive runs 0.3 m deep for 10 s, dives to 4 m by 30 s, holds, climbs back by 60 s: near
    the surface with a dive ahead, at depth, and climbing below 0.5 m, no; at the surface after, yes."""
    dive = load_trajectory("deep_dive")
    assert [stays_at_surface(dive, t, 0.0) for t in (0.0, 35.0, 50.0, 70.0)] == [False, False, False, True]
    assert stays_at_surface(load_trajectory("straight_line"), 0.0, 0.0)
    assert not stays_at_surface(load_trajectory("straight_line"), 0.0, 1.0)


def test_diving_swims_at_least_at_the_dive_tempo():
    """A target behind (the slowest tempo, turning round) and over 0.3 m below: a stroke with
    dive_tempo 1.0 swims at 1.0 (it lies flatter and pitches down further at speed); at its own
    depth, well ahead of the target along its path, or with no dive_tempo, at the slowest tempo."""
    diving = TempoControl(dive_tempo=1.0)
    assert diving.diving_tempo(0.5, 0.31) == pytest.approx(1.0)
    assert diving.diving_tempo(0.5, 0.3) == pytest.approx(0.5)
    assert diving.diving_tempo(1.2, 1.0) == pytest.approx(1.2)
    assert TempoControl().diving_tempo(0.5, 1.0) == pytest.approx(0.5)
    assert diving.diving_tempo(0.5, 1.0, well_ahead=True) == pytest.approx(0.5)     # it waits
    state = still_state(np.full(16, 1 / 16))          # at the origin, heading +x
    below, level = FixedTarget((-3.0, 0.0, -1.0)), FixedTarget((-3.0, 0.0, 0.0))
    assert TargetChooser(below, table(), "prone", tempo=diving)(0, state, None).tempo == pytest.approx(1.0)
    assert TargetChooser(level, table(), "prone", tempo=diving)(0, state, None).tempo == pytest.approx(0.5)
    assert TargetChooser(below, table(), "prone")(0, state, None).tempo == pytest.approx(0.5)


def test_steering_settings_come_from_the_stroke_file_and_leave_its_calibration_fresh():
    crawl = Episode("front_crawl", FollowTarget(FixedTarget([5.0, 0.0, -0.3])))
    crawl.close()
    steering = crawl.stroke.steering
    gains = crawl.controller.chooser.gains
    assert (gains.yaw_fraction, gains.pitch_fraction, gains.roll_fraction) == (
        steering.yaw_fraction, steering.pitch_fraction, steering.roll_fraction)
    pace = crawl.controller.chooser.tempo_control
    assert (pace.min_tempo, pace.glide_cycles, pace.turn_tempo, pace.turn_tempo_until_ahead_s) == (
        steering.min_tempo, steering.glide_cycles, steering.turn_tempo, steering.turn_tempo_until_ahead_s)
    assert pace.far_m == steering.full_tempo_beyond_m == TempoControl().far_m
    back = Episode("backstroke", FollowTarget(FixedTarget([5.0, 0.0, -0.3])))
    back.close()
    assert back.controller.chooser.tempo_control.far_m == back.stroke.steering.full_tempo_beyond_m > pace.far_m
    breast = Episode("breaststroke", FollowTarget(FixedTarget([5.0, 0.0, -0.3])))
    breast.close()       # its pitch is left alone within 5 deg (it swung pitch_up to pitch_down each cycle)
    assert breast.controller.chooser.gains.attitude_within_rad == pytest.approx(math.radians(5.0))
    lead = crawl.controller.chooser.lead
    assert (lead.bend_s, lead.wait_ahead_s) == (steering.lead_bend_s, steering.wait_ahead_s) != (
        Lead().bend_s, Lead().wait_ahead_s)
    # A task with its own tempo control (the goal, on which the shipped residuals were trained) keeps
    # the default aim and steers the heading only: no pitch, roll or breath.
    goal = Episode("front_crawl", FollowTarget(FixedTarget([5.0, 0.0, -0.3])), tempo_control=GOAL_TEMPO)
    goal.close()
    assert goal.controller.chooser.lead == Lead() and goal.controller.chooser.tempo_control is GOAL_TEMPO
    assert steering.pitch_fraction > 0 and steering.breathe
    goal_gains = goal.controller.chooser.gains
    assert (goal_gains.pitch_fraction, goal_gains.roll_fraction, goal.controller.lungs) == (0.0, 0.0, None)
    breast = Episode("breaststroke", FollowTarget(FixedTarget([5.0, 0.0, -0.3])))
    breast.close()
    assert breast.controller.chooser.tempo_control.wide_turn_rad == pytest.approx(math.radians(180.0))
    assert breast.controller.lungs is not None and crawl.controller.lungs is not None
    spec = load(StrokeSpec, stroke_path("front_crawl"))
    edited = spec.model_copy(update={"steering": spec.steering.model_copy(update={"yaw_fraction": 0.1})})
    assert build_stroke(edited, LAYOUT, "x").spec_sha256 == crawl.stroke.spec_sha256


def _facing_change(arm, offsets, quat, flow_dir):
    """First-order change of |palm normal . flow| when the palm offsets are applied."""
    from layered_swim.geometry import quat_rotate

    normal = quat_rotate(quat[arm.hand], np.array([0.0, 1.0, 0.0]))
    axes = quat_rotate(quat[arm.forearm], arm.wrist_axes)
    facing = normal @ flow_dir
    return np.sign(facing or 1.0) * float(offsets[list(arm.palm_coords)] @ (np.cross(axes, normal) @ flow_dir))


@pytest.mark.parametrize("hand_velocity", [[-1.0, -0.5, 0.3], [-1.0, 0.8, -0.2]])
def test_palm_rule_faces_a_helpful_flow_and_slices_a_hindering_one(hand_velocity):
    arms = arm_indices(BODY, LAYOUT)
    quat = np.tile(PRONE_QUAT_XYZW, (16, 1))
    arm = arms[0]
    velocity = np.zeros((16, 3))
    velocity[arm.hand] = hand_velocity          # the hand sweeps back: the water flows past it toward +x
    flow_dir = -velocity[arm.hand] / np.linalg.norm(velocity[arm.hand])
    none = np.zeros(LAYOUT.size)
    helpful = rule_offsets(none, arms, RulesSpec(), quat, velocity, np.zeros((16, 3)), np.array([1.0, 0.0, 0.0]), 0.01)
    assert _facing_change(arm, helpful, quat, flow_dir) > 0          # palm turns into the flow
    assert helpful[arm.elbow_coord] < 0                              # and the arm reaches further
    hindering = rule_offsets(none, arms, RulesSpec(), quat, velocity, np.zeros((16, 3)), np.array([-1.0, 0.0, 0.0]),
                             0.01)
    assert _facing_change(arm, hindering, quat, flow_dir) < 0        # palm slices
    assert hindering[arm.elbow_coord] > 0                            # and the arm stays closer


def test_rule_offsets_fade_and_stay_within_their_limits():
    arms = arm_indices(BODY, LAYOUT)
    quat = np.tile(PRONE_QUAT_XYZW, (16, 1))
    velocity = np.zeros((16, 3))
    velocity[arms[0].hand] = [-1.0, -0.5, 0.3]
    offsets = np.zeros(LAYOUT.size)
    for _ in range(2000):                        # a long push saturates at max_deg
        offsets = rule_offsets(offsets, arms, RulesSpec(), quat, velocity, np.zeros((16, 3)), np.array([1.0, 0, 0]),
                               0.01)
    assert np.abs(np.degrees(offsets)).max() == pytest.approx(RulesSpec().palm.max_deg)
    still = np.zeros((16, 3))                    # no flow past the hands: the offsets fade away
    for _ in range(200):
        offsets = rule_offsets(offsets, arms, RulesSpec(), quat, still, np.zeros((16, 3)), np.array([1.0, 0, 0]), 0.01)
    assert np.abs(offsets).max() < 1e-3


def write_breaststroke_table(directory, sha256, weights="[0, 1]", yaw_left="[[0, 1]]",
                             pace="{tempos: [1], speed_m_s: [1], roll_deg: [0], pitch_deg: [10], depth_m: [0.2]}"):
    """A hand-written calibration table for the breaststroke in ``directory``."""
    (directory / "breaststroke.yaml").write_text(
        f"stroke: breaststroke\nstroke_sha256: {sha256}\nweights: {weights}\ntempos: [1]\n"
        f"pace: {pace}\nturn_deg_per_cycle: {{yaw_left: {yaw_left}}}\n")


def test_missing_or_stale_calibration_is_a_clear_error(tmp_path):
    stroke = load_stroke("breaststroke", LAYOUT)
    with pytest.raises(ConfigError, match="calibrate --stroke breaststroke"):
        load_table(stroke, directory=tmp_path)
    write_breaststroke_table(tmp_path, "old")
    with pytest.raises(ConfigError, match="stale"):
        load_table(stroke, directory=tmp_path)


def test_a_table_calibrated_to_another_max_weight_is_a_clear_error(tmp_path):
    stroke = load_stroke("breaststroke", LAYOUT)            # steering.max_weight 1
    write_breaststroke_table(tmp_path, stroke.spec_sha256, weights="[0, 0.75, 1.5]", yaw_left="[[0, 1, 2]]")
    with pytest.raises(ConfigError, match="up to weight 1.5.*'steering.max_weight' is 1; run `layered-swim calibrate"):
        load_table(stroke, directory=tmp_path)
    assert weight_grid(1.5) == (0.0, 0.25, 0.5, 0.75, 1.0, 1.25, 1.5) and weight_grid(1.0)[-1] == 1.0


def test_a_pace_table_needs_one_value_per_tempo(tmp_path):
    stroke = load_stroke("breaststroke", LAYOUT)
    write_breaststroke_table(tmp_path, stroke.spec_sha256, pace="{tempos: [0.5, 1], speed_m_s: [0.3, 1], "
                             "roll_deg: [0, 0], pitch_deg: [10], depth_m: [0.2, 0.2]}")
    with pytest.raises(ConfigError, match="pace"):
        load_table(stroke, directory=tmp_path)


def test_short_follow_gets_closer_to_a_fixed_target():
    target = FixedTarget([6.0, 3.0, -0.2])
    episode = Episode("breaststroke", FollowTarget(target))
    try:
        start = np.linalg.norm(episode.sim.state.com_m - target.position(0.0))
        episode.run(6.0)
        end = np.linalg.norm(episode.sim.state.com_m - target.position(0.0))
    finally:
        episode.close()
    assert end < start - 2.5


@pytest.mark.parametrize("stroke_name", ["treading_water", "breaststroke", "front_crawl", "backstroke", "butterfly"])
def test_shipped_calibration_is_fresh_and_every_steering_sequence_acts_monotonically(stroke_name):
    """Yang Fig. 11: more weight, more turn, for the yaw sequences at every tempo, over weights 0-1
    and up to ``steering.max_weight``; and for every attitude axis the stroke steers (a fraction
    above 0), a sequence each way that holds more offset with more weight."""
    stroke = load_stroke(stroke_name, LAYOUT)
    shipped = load_table(stroke)                       # raises if missing or stale
    assert set(shipped.turn_rad) == {"yaw_left", "yaw_right"}
    assert set(shipped.attitude_rad) == set(stroke.perturbations) - set(UNCALIBRATED_SEQUENCES) - {
        "yaw_left", "yaw_right"} == set(
        ("pitch_up", "pitch_down", "roll_left", "roll_right"))
    assert shipped.weights[-1] == stroke.steering.max_weight
    for name, rows in shipped.turn_rad.items():
        assert np.all(np.diff(rows, axis=1) > 0), f"{stroke_name} {name}: {np.degrees(rows).round(2)}"
    steered = [axis for axis, fraction in (("pitch", stroke.steering.pitch_fraction),
                                           ("roll", stroke.steering.roll_fraction)) if fraction > 0]
    for axis in steered:
        for tempo in shipped.tempos:
            for sign in (1.0, -1.0):
                holding = shipped._holding(axis, tempo, sign)
                assert holding is not None and np.all(np.diff(holding[1]) > 0), f"{stroke_name} {axis} {sign}"


def test_palm_rule_adds_forward_displacement():
    """Yang Fig. 13: 10 s of breaststroke toward a target straight ahead, with and without the rule."""
    target = FixedTarget([100.0, 0.0, -0.2])
    travelled = {}
    for layers in ("basic", "basic,palm"):
        episode = Episode("breaststroke", FollowTarget(target), layers=Layers.parse(layers))
        try:
            start = episode.sim.state.pos_m[0, 0]
            episode.run(10.0)
            travelled[layers] = episode.sim.state.pos_m[0, 0] - start
        finally:
            episode.close()
    assert travelled["basic,palm"] >= 1.05 * travelled["basic"]       # +7.6 % measured


def _straight_speed_m_s(stroke: str, layers: str, seconds: float = 8.0) -> float:
    """Mean speed toward a target far straight ahead, after a cycle or two to settle."""
    episode = Episode(stroke, FollowTarget(FixedTarget([100.0, 0.0, -0.2])), layers=Layers.parse(layers))
    try:
        episode.run(2.0)
        start = episode.sim.state.com_m[0]
        episode.run(seconds)
        return (episode.sim.state.com_m[0] - start) / seconds
    finally:
        episode.close()


@pytest.mark.parametrize("stroke", ["front_crawl", "backstroke", "butterfly"])
def test_rules_only_add_thrust(stroke):
    """The rules push hardest toward a target far ahead: there they must not cost speed. (Slicing
    the palm from entry to catch once took the crawl from 1.34 to 0.05 m/s.)"""
    assert _straight_speed_m_s(stroke, "basic,rules") >= _straight_speed_m_s(stroke, "basic")


def test_rules_stay_out_when_no_more_thrust_is_wanted():
    stroke = load_stroke("breaststroke", LAYOUT)

    def enough(cycle, state, last_cycle):
        return CycleChoice(thrust_demand=0.0)
    controller = LayeredController(stroke, LAYOUT, arm_indices(BODY, LAYOUT), enough, Layers())
    state = still_state()
    flow = np.zeros((16, 3))
    flow[:, 0] = 1.0                           # water rushing past every hand: the rules would act
    for k in range(40):
        state.time_s = k / 60
        pose, _ = controller.desired(state.time_s, state, flow)
        basic, _ = stroke.pose(controller.phase(state.time_s))
        np.testing.assert_allclose(pose, LAYOUT.clamp(basic))
    assert not controller.rule_offsets.any()


def test_a_rule_kept_to_the_helping_phase_leaves_a_hindered_hand_alone():
    arms = arm_indices(BODY, LAYOUT)
    quat = np.tile(PRONE_QUAT_XYZW, (16, 1))
    flow = np.zeros((16, 3))
    flow[:, 0] = -1.0                          # water pushes every hand backward: it hinders +x
    desired = np.array([1.0, 0.0, 0.0])
    both = rule_offsets(np.zeros(LAYOUT.size), arms, RulesSpec(), quat, np.zeros((16, 3)), flow, desired, 0.1)
    helping = RulesSpec.model_validate({"palm": {"hindering": False}, "reach": {"hindering": False}})
    only = rule_offsets(np.zeros(LAYOUT.size), arms, helping, quat, np.zeros((16, 3)), flow, desired, 0.1)
    assert both[arms[0].elbow_coord] > 0.0 and not only.any()


def test_lead_looks_further_ahead_where_the_path_bends():
    lead = Lead(straight_s=1.5, bend_s=3.0)
    assert lead.seconds(FixedTarget((3.0, 0.0, -0.3)), 0.0) == pytest.approx(1.5)
    assert lead.seconds(load_trajectory("straight_line"), 5.0) == pytest.approx(1.5)
    assert lead.seconds(load_trajectory("circle"), 5.0) > 2.0      # a circle keeps turning
    # A stroke may look further where the path runs straight, and less far where it dives.
    longer = Lead(straight_s=2.5, bend_s=3.5, diving_straight_s=1.5)
    assert longer.seconds(load_trajectory("straight_line"), 5.0) == pytest.approx(2.5)
    assert longer.seconds(load_trajectory("straight_line"), 5.0, diving=True) == pytest.approx(1.5)
    assert Lead(straight_s=2.5).seconds(load_trajectory("straight_line"), 5.0, diving=True) == pytest.approx(2.5)
    # ... 1 m (2 s) behind a target on the straight line (x = 2 + 0.5 t): 2.5 s past it at x = 5.25,
    # but at the depth the target reaches depth_ahead_s (1.5 s) on, whatever the look.
    aim, ahead_s, _ = longer.aim(load_trajectory("straight_line"), 4.0, np.array([3.0, 0.0, -0.3]))
    assert ahead_s == pytest.approx(-2.0) and aim == pytest.approx([5.25, 0.0, -0.3])
    dive = TrajectoryTarget(np.array([[0.0, 0.0, -0.3], [2.0, 0.0, -4.3]]), np.array([0.0, 8.0]), 1.0, False)
    assert longer.aim(dive, 0.0, np.array([0.0, 0.0, -0.3]), diving=True)[0] == pytest.approx([0.375, 0.0, -1.05])
    assert longer.aim(dive, 0.0, np.array([0.0, 0.0, -0.3]))[0] == pytest.approx([0.625, 0.0, -1.05])


def test_lead_aims_from_the_swimmers_own_place_on_the_path_when_it_is_ahead():
    line = load_trajectory("straight_line")          # x = 2 + 0.5 t, y = 0, 0.3 m deep
    lead = Lead(straight_s=1.5, bend_s=3.0)
    aim, ahead_s, off_m = lead.aim(line, 0.0, np.array([0.0, 0.5, -0.3]))     # behind: aims 1.5 s past the target
    # 2 m behind a target that waited at its start before t = 0: as far behind as the search looks.
    assert ahead_s == pytest.approx(-lead.search_s) and aim == pytest.approx([2.75, 0.0, -0.3])
    assert off_m == pytest.approx(math.hypot(2.0, 0.5))
    aim, ahead_s, off_m = lead.aim(line, 4.0, np.array([3.0, 0.5, -0.3]))     # 1 m (2 s) behind the target at x = 4
    assert ahead_s == pytest.approx(-2.0) and aim == pytest.approx([4.75, 0.0, -0.3]) and off_m == pytest.approx(0.5)
    aim, ahead_s, off_m = lead.aim(line, 0.0, np.array([4.0, 1.0, -0.3]))     # 2 m (4 s) ahead of it, off the line
    assert ahead_s == pytest.approx(4.0) and aim == pytest.approx([4.75, 0.0, -0.3]) and off_m == pytest.approx(1.0)
    # A steep dive (x = 0.25 t, z = -0.3 - 0.5 t): 0.5 m along it, still at the surface, the swimmer
    # is over where the target will be in 2 s, but nearest (in 3-D) to where it is in 0.4 s.
    dive = TrajectoryTarget(np.array([[0.0, 0.0, -0.3], [2.0, 0.0, -4.3]]), np.array([0.0, 8.0]), 1.0, False)
    assert lead.aim(dive, 0.0, np.array([0.5, 0.0, -0.3]))[1] == pytest.approx(0.4)
    # It aims along the path from there, but at the depth the target reaches 1.5 s from now, not the
    # path's depth there: x = 0.25 (0.4 + 1.5) = 0.475 m, z = -0.3 - 0.5 * 1.5 = -1.05 m.
    assert lead.aim(dive, 0.0, np.array([0.5, 0.0, -0.3]))[0] == pytest.approx([0.475, 0.0, -1.05])
    aim, ahead_s, _ = lead.aim(dive, 0.0, np.array([1.0, 0.0, -2.3]))     # 4 s ahead, at the path's depth there
    assert ahead_s == pytest.approx(4.0) and aim == pytest.approx([0.25 * 5.5, 0.0, -1.05])


def test_a_swimmer_ahead_of_its_target_waits_for_it():
    state = still_state(np.full(16, 1 / 16))          # at the origin, heading +x
    behind = TrajectoryTarget(np.array([[-2.0, 0.0, 0.0], [20.0, 0.0, 0.0]]), np.array([0.0, 22.0]), 0.5, False)
    waiting = TargetChooser(behind, table(), "prone")(0, state, None)
    assert (not waiting.glide and waiting.thrust_demand == 0.0
            and waiting.tempo == pytest.approx(TempoControl().min_tempo))
    gliding = TargetChooser(behind, table(), "prone", tempo=TempoControl(glide_within_m=0.6, glide_cycles=0.5))(
        0, state, None)
    assert gliding.glide and gliding.cycles == 0.5      # a stroke that glides to wait (the crawl) glides
    ahead = TrajectoryTarget(np.array([[2.0, 0.0, 0.0], [20.0, 0.0, 0.0]]), np.array([0.0, 18.0]), 0.5, False)
    chasing = TargetChooser(ahead, table(), "prone")(0, state, None)
    assert not chasing.glide and chasing.cycles == 1.0 and chasing.thrust_demand == pytest.approx(1.0)


def test_a_swimmer_waiting_for_its_target_turns_at_the_wait_turn_tempo():
    """Waiting, a stroke with wait_turn_tempo swims at least that while the point it steers for is
    more than 30 deg off its heading (the backstroke stood up turning at its slowest tempo), and at
    its slowest tempo otherwise; without one, at its slowest tempo either way."""
    waiting = TempoControl(min_tempo=0.55, wait_turn_tempo=0.8)
    assert waiting.waiting_tempo(0.55, math.radians(40.0)) == pytest.approx(0.8)
    assert waiting.waiting_tempo(0.55, math.radians(-90.0)) == pytest.approx(0.8)
    assert waiting.waiting_tempo(0.55, math.radians(20.0)) == pytest.approx(0.55)
    assert waiting.waiting_tempo(1.0, math.radians(90.0)) == pytest.approx(1.0)
    assert TempoControl().waiting_tempo(0.5, math.radians(90.0)) == pytest.approx(0.5)
    state = still_state(np.full(16, 1 / 16))          # at the origin, heading +x
    # A path along +y through the origin, the target 2 m (4 s) behind: the swimmer waits, turning left.
    across = TrajectoryTarget(np.array([[0.0, -2.0, 0.0], [0.0, 20.0, 0.0]]), np.array([0.0, 22.0]), 0.5, False)
    turning = TargetChooser(across, table(), "prone", tempo=waiting)(0, state, None)
    assert turning.thrust_demand == 0.0 and turning.tempo == pytest.approx(0.8)
    assert turning.weights.get("yaw_left", 0.0) > 0.0
    along = TrajectoryTarget(np.array([[-2.0, 0.0, 0.0], [20.0, 0.0, 0.0]]), np.array([0.0, 22.0]), 0.5, False)
    straight = TargetChooser(along, table(), "prone", tempo=waiting)(0, state, None)
    assert straight.thrust_demand == 0.0 and straight.tempo == pytest.approx(0.55)
    plain = TargetChooser(across, table(), "prone", tempo=TempoControl(min_tempo=0.55))(0, state, None)
    assert plain.tempo == pytest.approx(0.55)


def test_a_swimmer_waiting_with_a_wait_pace_keeps_that_share_of_its_targets_pace():
    """Waiting, a stroke with wait_pace swims at least the tempo whose steady speed (its pace table)
    is that share of the target's pace, not its slowest (where the breaststroke stalls nose-up)."""
    pacing = TempoControl(min_tempo=0.5, wait_pace=1.0)
    assert pacing.waiting_tempo(0.5, 0.0, pace_tempo=0.75) == pytest.approx(0.75)
    assert pacing.waiting_tempo(0.9, 0.0, pace_tempo=0.75) == pytest.approx(0.9)
    assert TempoControl(min_tempo=0.5).waiting_tempo(0.5, 0.0, pace_tempo=0.75) == pytest.approx(0.5)
    state = still_state(np.full(16, 1 / 16))          # at the origin, heading +x
    # The target 2 m (4 s) behind on a path along +x at 0.5 m/s: the swimmer waits at the tempo of
    # 0.5 m/s, which the table's pace (0.4 m/s at 0.5, 0.8 m/s at 1.0) puts at 0.625.
    along = TrajectoryTarget(np.array([[-2.0, 0.0, 0.0], [20.0, 0.0, 0.0]]), np.array([0.0, 22.0]), 0.5, False)
    waiting = TargetChooser(along, table(), "prone", tempo=pacing)(0, state, None)
    assert waiting.thrust_demand == 0.0 and waiting.tempo == pytest.approx(0.625)
    slowest = TargetChooser(along, table(), "prone", tempo=TempoControl(min_tempo=0.5))(0, state, None)
    assert slowest.thrust_demand == 0.0 and slowest.tempo == pytest.approx(0.5)


def test_a_swimmer_ahead_of_its_target_but_far_off_its_path_swims_back_instead_of_waiting():
    """Ahead of the target along its path waits only near the path: 2 m off it (a current carried
    the swimmer across a corner) it swims at full tempo back toward the path."""
    lead = Lead()
    assert lead.waits(2.0, 0.5) and not lead.waits(2.0, 2.0) and not lead.waits(0.2, 0.5)
    path = TrajectoryTarget(np.array([[-2.0, -2.0, 0.0], [20.0, -2.0, 0.0]]), np.array([0.0, 22.0]), 0.5, False)
    off = TargetChooser(path, table(), "prone")(0, still_state(np.full(16, 1 / 16)), None)   # 2 m off, 2 m ahead
    assert off.thrust_demand > 0.0 and off.tempo > TempoControl().min_tempo


def test_a_swimmer_ahead_of_a_diving_target_but_above_it_dives_on_instead_of_waiting():
    """With ``wait_depth_within_m`` a swimmer ahead of its target waits only near the depth it
    steers for: 1.5 m above it (the breaststroke rode up nose-first at its slowest tempo and lost
    the deep dive) it swims on down."""
    lead = Lead(wait_depth_within_m=0.5)
    assert lead.waits(2.0, 0.5, 0.4) and not lead.waits(2.0, 0.5, 0.6) and Lead().waits(2.0, 0.5, 5.0)
    deep = TrajectoryTarget(np.array([[-2.0, 0.0, -1.5], [20.0, 0.0, -1.5]]), np.array([0.0, 22.0]), 0.5, False)
    state = still_state(np.full(16, 1 / 16))          # at the origin, 2 m (4 s) ahead of the target
    assert TargetChooser(deep, table(), "prone")(0, state, None).thrust_demand == 0.0
    diving = TargetChooser(deep, table(), "prone", lead=Lead(wait_depth_within_m=0.5))(0, state, None)
    assert diving.thrust_demand > 0.0 and diving.tempo > TempoControl().min_tempo


def test_waiting_on_a_straight_stretch_a_stroke_with_a_weave_weaves_across_the_path():
    """``weave_aim`` moves the aim across a straight path so the swimmer heads ``angle`` off it, and
    turns to the other side once the swimmer is more than ``within_m`` out; the chooser weaves only
    while waiting where the path runs straight, at ``weave_tempo`` at least (the backstroke, faster
    at its slowest tempo than a 0.5 m/s target, ran ahead of it on straight stretches)."""
    aim, place, along = np.array([2.0, 0.0, -0.3]), np.zeros(3), np.array([1.0, 0.0])    # a path along +x
    moved, side = weave_aim(aim, np.zeros(3), place, along, 1.0, math.radians(45.0), 0.6)
    assert side == 1.0 and moved == pytest.approx([2.0, 2.0, -0.3])         # 2 m ahead, tan 45 deg * 2 m left
    _, side = weave_aim(aim, np.array([0.0, 0.5, 0.0]), place, along, 1.0, math.radians(45.0), 0.6)
    assert side == 1.0                                                         # 0.5 m out: on to the left
    moved, side = weave_aim(aim, np.array([0.0, 0.7, 0.0]), place, along, 1.0, math.radians(45.0), 0.6)
    assert side == -1.0 and moved == pytest.approx([2.0, -math.hypot(2.0, 0.7), -0.3])   # 0.7 m out: back right
    line = TrajectoryTarget(np.array([[-2.0, 0.0, 0.0], [20.0, 0.0, 0.0]]), np.array([0.0, 22.0]), 0.5, False)
    angles = np.linspace(0.0, 2.0 * math.pi, 73)
    ring = np.stack([2.0 * np.sin(angles), 2.0 - 2.0 * np.cos(angles), np.zeros_like(angles)], axis=1)
    circle = TrajectoryTarget(ring, 2.0 * angles, 0.5, True)     # radius 2 m at 0.5 m/s: 43 deg over 3 s
    weave = Lead(weave_rad=math.radians(55.0))
    assert weave.weaves(line, 4.0) and not weave.weaves(circle, 4.0) and not Lead().weaves(line, 4.0)
    state = still_state(np.full(16, 1 / 16))          # at the origin heading +x, 2 m (4 s) ahead of the target
    slow = TempoControl(min_tempo=0.55, weave_tempo=0.7)
    weaving = TargetChooser(line, table(), "prone", tempo=slow, lead=weave)(0, state, None)
    assert weaving.thrust_demand == 0.0 and weaving.tempo == pytest.approx(0.7)
    assert weaving.weights.get("yaw_left", 0.0) > 0.0 and "yaw_right" not in weaving.weights
    straight = TargetChooser(line, table(), "prone", tempo=slow)(0, state, None)
    assert straight.tempo == pytest.approx(0.55) and not straight.weights.get("yaw_left", 0.0)


def test_drift_is_the_sideways_motion_over_a_cycle_and_a_steady_turn_has_none():
    drift, known = Drift(), Drift()
    for k in range(8):          # heading +x at 1 m/s, carried toward -y at 0.3 m/s
        drift.update(1.5 * k, np.array([1.5 * k, -0.45 * k, -0.3]), 0.0, np.zeros(3))
        known.update(1.5 * k, np.array([1.5 * k, -0.45 * k, -0.3]), 0.0, np.array([0.0, -0.2, 0.0]))
    assert drift.m_s == pytest.approx([0.0, -0.3], abs=0.01)
    assert known.m_s == pytest.approx([0.0, -0.1], abs=0.01)       # what the known current does not explain
    turning = Drift()
    for k in range(8):          # a steady 2 m circle, heading along the track
        angle = 0.5 * k
        turning.update(float(k), np.array([2 * math.sin(angle), 2 - 2 * math.cos(angle), 0.0]), angle, np.zeros(3))
    assert np.abs(turning.m_s).max() < 1e-9
    # Aimed off upstream by what the drift beyond its dead zone carries it while it swims there (3 s),
    # at most half the way; a drift within the dead zone (a stroke's own turns) changes nothing.
    aim = drift.aimed_off(np.zeros(3), np.array([3.0, 0.0, -0.3]), 1.0)
    assert aim == pytest.approx([3.0, 3.0 * (0.3 - Drift.DEADZONE_M_S), -0.3], abs=0.03)
    drift.m_s = np.array([0.0, -0.8 * Drift.DEADZONE_M_S])
    assert drift.aimed_off(np.zeros(3), np.array([3.0, 0.0, -0.3]), 1.0) == pytest.approx([3.0, 0.0, -0.3])
    strong = Drift()
    strong.m_s = np.array([0.0, -2.0])
    assert strong.aimed_off(np.zeros(3), np.array([3.0, 0.0, -0.3]), 1.0) == pytest.approx([3.0, 1.5, -0.3])


class UniformWater:
    surface_z_m = 0.0

    def __init__(self, current_m_s):
        self.current_m_s = np.asarray(current_m_s, float)

    def current_at(self, points_m, time_s, waves=True):
        return np.tile(self.current_m_s, (len(np.atleast_2d(points_m)), 1))


def test_a_known_current_is_steered_for_in_the_waters_frame():
    """A target on a line along +x at 0.5 m/s, the swimmer on it. Water flowing toward -y at 0.3 m/s
    moves the aim (1.5 s ahead) upstream by the 0.45 m the water carries the swimmer meanwhile: it
    turns into the current before any drift shows. Water flowing against the target asks the
    target's pace plus the current's (0.8 m/s: full tempo) where still water asks 0.5 m/s (0.625),
    and water across it asks their sum as vectors (0.58 m/s: 0.729)."""
    line = TrajectoryTarget(np.array([[0.0, 0.0, 0.0], [20.0, 0.0, 0.0]]), np.array([0.0, 20.0]), 0.5, False)
    seen = InWater(line, np.array([0.0, -0.3, 0.0]), 2.0)
    assert seen.position(2.0) == pytest.approx(line.position(2.0))
    assert seen.position(4.0) == pytest.approx(line.position(4.0) + [0.0, 0.6, 0.0])
    state = still_state(np.full(16, 1 / 16))          # at the origin, heading +x

    def choice(current_m_s):
        water = UniformWater(current_m_s)
        return TargetChooser(line, table(), "prone", water=lambda: water)(0, state, None)

    still, across, against = choice((0.0, 0.0, 0.0)), choice((0.0, -0.3, 0.0)), choice((-0.3, 0.0, 0.0))
    assert still.weights.get("yaw_left", 0.0) == 0.0 and still.tempo == pytest.approx(0.625)
    # The aim at (0.75, 0.45): 31 deg to the left, turned by its share this cycle (the table's 8 deg at most).
    assert across.weights["yaw_left"] > 0.0
    assert across.tempo == pytest.approx(0.5 + 0.5 * (math.hypot(0.5, 0.3) - 0.4) / 0.4)
    assert against.weights.get("yaw_left", 0.0) == 0.0 and against.tempo == pytest.approx(1.0)
    assert TargetChooser(line, table(), "prone")(0, state, None) == still       # no water to read: still water


def test_a_gliding_stroke_near_its_target_glides_only_once_ahead_of_it_along_its_path():
    """Within glide_within_m of a target on a path, 0.3 m behind it: swim on (gliding there, the
    crawl trailed its target); 0.3 m (0.6 s) ahead: glide. A target with no path (a jump) is
    glided to on distance alone."""
    state = still_state(np.full(16, 1 / 16))          # at the origin, heading +x
    tempo = TempoControl(glide_within_m=0.4)
    leading = TrajectoryTarget(np.array([[0.3, 0.0, 0.0], [20.0, 0.0, 0.0]]), np.array([0.0, 39.4]), 0.5, False)
    assert not TargetChooser(leading, table(), "prone", tempo=tempo)(0, state, None).glide
    trailing = TrajectoryTarget(np.array([[-0.3, 0.0, 0.0], [20.0, 0.0, 0.0]]), np.array([0.0, 40.6]), 0.5, False)
    chooser = TargetChooser(trailing, table(), "prone", tempo=tempo, lead=Lead(wait_ahead_s=10.0))   # near, not waiting
    assert chooser(0, state, None).glide
    assert TargetChooser(FixedTarget((0.3, 0.0, 0.0)), table(), "prone", tempo=tempo)(0, state, None).glide


def test_weights_above_one_only_for_a_turn_wanted_within_the_strokes_limit():
    to_1_5 = table((0.0, 2.0, 4.0, 6.0, 8.0, 10.0, 12.0), weights=(0.0, 0.25, 0.5, 0.75, 1.0, 1.25, 1.5))
    gains = SteeringGains(yaw_fraction=1.0, over_weight_within_rad=math.radians(75.0))
    state = still_state(np.full(16, 1 / 16))          # at the origin, heading +x

    def yaw_left_weight(bearing_deg):
        target = FixedTarget((5 * math.cos(math.radians(bearing_deg)), 5 * math.sin(math.radians(bearing_deg)), 0.0))
        return TargetChooser(target, to_1_5, "prone", gains=gains)(0, state, None).weights["yaw_left"]
    assert yaw_left_weight(50.0) == 1.5 and yaw_left_weight(100.0) == 1.0


def test_a_swimmer_keeps_a_moving_targets_pace_when_close_behind_it():
    """Close behind a target moving at 0.6 m/s, it swims no slower than the tempo whose steady
    speed is 0.6 m/s (0.75 in this table: 0.4 m/s at 0.5, 0.8 m/s at 1.0), not at its slowest."""
    state = still_state(np.full(16, 1 / 16))          # at the origin, heading +x
    moving = TrajectoryTarget(np.array([[0.1, 0.0, 0.0], [20.0, 0.0, 0.0]]), np.array([0.0, 19.9]), 0.6, False)
    assert TargetChooser(moving, table(), "prone")(0, state, None).tempo == pytest.approx(0.75)
    unkept = TargetChooser(moving, table(), "prone", tempo=TempoControl(keep_pace=False))(0, state, None)
    assert unkept.tempo == pytest.approx(TempoControl().min_tempo)
    still = TargetChooser(FixedTarget((0.1, 0.0, 0.0)), table(), "prone")(0, state, None)
    assert still.tempo == pytest.approx(TempoControl().min_tempo)   # a target that stays: no pace to keep


def test_the_pace_table_read_backwards_gives_the_tempo_for_a_speed():
    pace = Pace((0.4, 0.6, 0.8, 1.0), (0.1, 0.5, 0.9, 0.85), (0.0,) * 4, (0.0,) * 4, (0.2,) * 4)
    assert pace.tempo_for_speed(0.7) == pytest.approx(0.7)
    assert pace.tempo_for_speed(0.0) == pytest.approx(0.4)    # slower than its slowest: its slowest
    assert pace.tempo_for_speed(2.0) == pytest.approx(1.0)    # faster than it swims: full tempo


def test_a_swimmer_starting_pitched_up_levels_off_instead_of_correcting_pitch():
    """Starting standing up (from treading water after a jump, say), a lying stroke takes its
    level-off sequence at full weight in place of any pitch correction until it lies; lying, or
    pitched up mid-swim (a push), it steers as before."""
    from scipy.spatial.transform import Rotation

    lying_state = still_state(np.full(16, 1 / 16))
    nose_up = (Rotation.from_euler("y", -60.0, degrees=True) * Rotation.from_quat(PRONE_QUAT_XYZW)).as_quat()
    standing = BodyState(0.0, np.zeros((16, 3)), np.tile(nose_up, (16, 1)), np.zeros((16, 3)), np.zeros((16, 3)),
                         lying_state.segments)
    assert math.degrees(attitude_of(standing, "prone").pitch_rad) == pytest.approx(60.0)
    pitch_table = table()
    pitch_table.attitude_rad["pitch_down"] = -pitch_table.turn_rad["yaw_left"]
    target = FixedTarget((5.0, 1.0, 0.0))
    chooser = TargetChooser(target, pitch_table, "prone", level_off_beyond_rad=math.radians(35.0))
    assert "pitch_down" in TargetChooser(target, pitch_table, "prone")(0, standing, None).weights
    up = chooser(0, standing, None).weights
    assert up[LEVEL_OFF] == 1.0 and not any(name.startswith("pitch_") for name in up) and up["yaw_left"] > 0
    assert LEVEL_OFF in chooser(1, standing, None).weights          # still standing: still levelling
    assert LEVEL_OFF not in chooser(2, lying_state, None).weights   # lying: done...
    assert LEVEL_OFF not in chooser(3, standing, None).weights      # ...and a later pitch-up is not a start
    assert LEVEL_OFF not in chooser(0, lying_state, None).weights
    # Levelling off, it kicks at its level-off tempo even for a target behind (which would slow it).
    behind = TargetChooser(FixedTarget((-5.0, 1.0, 0.0)), pitch_table, "prone", level_off_beyond_rad=math.radians(35.0),
                           level_off_tempo=1.2)
    assert behind(0, standing, None).tempo == 1.2
    assert behind(1, lying_state, None).tempo == pytest.approx(TempoControl().min_tempo)
    # A stroke with no level-off sequence kicks at that tempo too, and corrects its pitch meanwhile.
    plain = TargetChooser(FixedTarget((-5.0, 1.0, 0.0)), pitch_table, "prone", level_off_beyond_rad=math.radians(35.0),
                          level_off_tempo=1.2, level_off_sequence=False)
    first = plain(0, standing, None)
    assert first.tempo == 1.2 and LEVEL_OFF not in first.weights and "pitch_down" in first.weights
    assert plain(1, lying_state, None).tempo == pytest.approx(TempoControl().min_tempo)


def test_a_stroke_aiming_under_water_takes_its_under_water_sequence_at_full_weight():
    """Below ``under_water_below_m`` (the point steered for, from the surface) the under-water
    sequence joins every cycle's weights at 1, glides and plain recovery cycles too; above, never."""
    state = still_state(np.full(16, 1 / 16))          # at the origin, heading +x
    for depth_m, under in ((0.3, False), (0.5, False), (2.0, True)):
        target = FixedTarget((5.0, 0.0, -depth_m))
        chooser = TargetChooser(target, table(), "prone", under_water_below_m=0.6,
                                tempo=TempoControl(glide_within_m=10.0))
        choice = chooser(0, state, None)
        assert (choice.weights.get(UNDER_WATER) == 1.0) is under and choice.glide
        recovering = TargetChooser(target, table(), "prone", under_water_below_m=0.6,
                                   recover_beyond_rad=(math.radians(25.0), None))
        stood = MeanAttitude(math.radians(40.0), 0.0)
        assert recovering(1, state, stood).weights == ({UNDER_WATER: 1.0} if under else {})
    assert UNDER_WATER not in TargetChooser(FixedTarget((5.0, 0.0, -2.0)), table(), "prone")(0, state, None).weights


def test_under_water_the_pitch_correction_steers_for_the_under_water_level():
    """A pace table lying 10 deg nose-up (as a slow breaststroke does at the surface): a level body
    2 m down, toward a target at its depth, is pitched up toward it (half the error, 5 deg: pitch-up
    0.5) unless the chooser has a level of its own under water (0 deg: no error); at the surface the
    table's pitch holds either way."""
    t = attitude_table()
    nose_up = dataclasses.replace(t, pace=Pace((0.5, 1.0), (0.4, 0.8), (0.0, 0.0), (math.radians(10.0),) * 2,
                                               (0.2, 0.2)))
    level = MeanAttitude(0.0, 0.0)
    for depth_m in (2.0, 0.0):
        base = still_state()
        state = BodyState(0.0, base.pos_m + np.array([0.0, 0.0, -depth_m]), base.quat_xyzw, base.linvel_m_s,
                          base.angvel_rad_s, base.segments)
        target = FixedTarget((5.0, 0.0, -depth_m))
        own = TargetChooser(target, nose_up, "prone", under_water_below_m=0.6, under_water_level_pitch_rad=0.0)
        table_level = TargetChooser(target, nose_up, "prone", under_water_below_m=0.6)
        mine, tables = own(0, state, level).weights, table_level(0, state, level).weights
        assert (mine.get(UNDER_WATER), tables.get(UNDER_WATER)) == ((1.0, 1.0) if depth_m else (None, None))
        assert mine.get("pitch_up", 0.0) == pytest.approx(0.0 if depth_m else 0.5)
        assert mine.get("pitch_down", 0.0) == pytest.approx(0.0, abs=1e-9)
        assert tables.get("pitch_up") == pytest.approx(0.5)


def test_under_water_the_heading_correction_takes_its_own_share_of_the_error():
    """A target 8 deg to the left, at the body's depth: at the surface the chooser turns by 0.75 of
    it (6 deg: yaw_left 0.75 on a table turning 8 deg at full weight); 2 m down by its under-water
    share, 0.25 (2 deg: 0.25), and without one by 0.75 there too."""
    gains = SteeringGains(yaw_fraction=0.75)
    for depth_m, expected, without in ((0.0, 0.75, 0.75), (2.0, 0.25, 0.75)):
        base = still_state()
        state = BodyState(0.0, base.pos_m + np.array([0.0, 0.0, -depth_m]), base.quat_xyzw, base.linvel_m_s,
                          base.angvel_rad_s, base.segments)
        target = FixedTarget((5.0, 5.0 * math.tan(math.radians(8.0)), -depth_m))
        own = TargetChooser(target, table(), "prone", gains=gains, under_water_below_m=0.6,
                            under_water_yaw_fraction=0.25)
        plain = TargetChooser(target, table(), "prone", gains=gains, under_water_below_m=0.6)
        assert own(0, state, None).weights["yaw_left"] == pytest.approx(expected, abs=0.02)
        assert plain(0, state, None).weights["yaw_left"] == pytest.approx(without, abs=0.02)


def test_a_stroke_levels_off_with_its_pitch_down_sequence_overweighted_until_its_cycles_lie():
    """With ``level_off_pitch_down_weight``, levelling off takes the pitch-down sequence at that
    weight (not the correction's calibrated weights), and goes on while the last cycle's mean
    pitch was still up, though the pitch dipped as the cycle began."""
    from scipy.spatial.transform import Rotation

    lying_state = still_state(np.full(16, 1 / 16))
    nose_up = (Rotation.from_euler("y", -60.0, degrees=True) * Rotation.from_quat(PRONE_QUAT_XYZW)).as_quat()
    standing = BodyState(0.0, np.zeros((16, 3)), np.tile(nose_up, (16, 1)), np.zeros((16, 3)), np.zeros((16, 3)),
                         lying_state.segments)
    pitch_table = table()
    pitch_table.attitude_rad["pitch_down"] = -pitch_table.turn_rad["yaw_left"]
    pitch_table.attitude_rad["pitch_up"] = pitch_table.turn_rad["yaw_left"]
    chooser = TargetChooser(FixedTarget((5.0, 1.0, 0.0)), pitch_table, "prone", level_off_beyond_rad=math.radians(35.0),
                            level_off_tempo=1.2, level_off_sequence=False, level_off_pitch_down_weight=2.5)
    first = chooser(0, standing, None)
    assert first.tempo == 1.2 and first.weights["pitch_down"] == 2.5 and "pitch_up" not in first.weights
    # Lying as the cycle starts, but its last cycle stood at 50 deg on average: still levelling.
    assert chooser(1, lying_state, MeanAttitude(math.radians(50.0), 0.0)).weights["pitch_down"] == 2.5
    # The last cycle lay too (10 deg): done; the correction's weights from now on (at most 1 here).
    after = chooser(2, lying_state, MeanAttitude(math.radians(10.0), 0.0))
    assert after.weights.get("pitch_down", 0.0) <= 1.0 and chooser.held_rad["pitch"] != 0.0
    # A swimmer lying at its start never levels off, whatever its last spell's mean.
    assert chooser(0, lying_state, MeanAttitude(math.radians(50.0), 0.0)).weights.get("pitch_down", 0.0) <= 1.0


def test_a_stroke_that_stood_up_or_rolled_over_mid_swim_swims_a_plain_cycle_at_its_level_off_tempo():
    """After a cycle whose mean pitch or shoulder roll went past the stroke's limits, the next
    cycle takes no sequence at all and runs at the level-off tempo; the held offsets wait; within
    the limits (or with none set) it steers as before."""
    pitch_table = table()
    pitch_table.attitude_rad["pitch_down"] = -pitch_table.turn_rad["yaw_left"]
    state = still_state(np.full(16, 1 / 16))
    chooser = TargetChooser(FixedTarget((5.0, 1.0, 0.0)), pitch_table, "prone", gains=SteeringGains(pitch_fraction=0.5),
                            level_off_tempo=1.2, recover_beyond_rad=(math.radians(25.0), math.radians(30.0)))
    level = MeanAttitude(math.radians(10.0), math.radians(5.0))
    steered = chooser(1, state, MeanAttitude(math.radians(20.0), 0.0))
    assert steered.weights["yaw_left"] > 0 and "pitch_down" in steered.weights and steered.tempo == 1.0
    held = dict(chooser.held_rad)
    for stood_or_rolled in (MeanAttitude(math.radians(30.0), 0.0), MeanAttitude(0.0, math.radians(-35.0))):
        plain = chooser(2, state, stood_or_rolled)
        assert plain.weights == {} and plain.tempo == 1.2 and not plain.glide
        assert chooser.held_rad == held
    assert chooser(3, state, level).weights["yaw_left"] > 0
    never = TargetChooser(FixedTarget((5.0, 1.0, 0.0)), pitch_table, "prone", level_off_tempo=1.2)
    assert never(2, state, MeanAttitude(math.radians(60.0), math.radians(60.0))).weights["yaw_left"] > 0


def test_the_backstroke_waiting_for_a_slow_target_rights_itself_instead_of_stalling():
    """Its slowest tempo swims faster than the straight line's 0.5 m/s target: ahead of it, it turns
    back to wait, and turning slowly it stands up; without the recovery it stalled there with every
    sequence at full weight and fell ever further behind (18-22 m after 90 s, seeds 1-3; with it 3-8 m)."""
    spec = SwimSpec.of("t", stroke="backstroke", task={"kind": "follow", "trajectory": "straight_line"},
                       seconds=90.0, seed=1)
    track = swim(spec.episode(), 90.0).task.track()
    distance = np.linalg.norm(track["swimmer_m"] - track["target_m"], axis=1)
    assert distance[track["track_time_s"] > 60.0].max() < 10.0


@pytest.mark.parametrize("posture, base", [("prone", PRONE_QUAT_XYZW), ("supine", SUPINE_QUAT_XYZW)])
def test_a_lying_body_rolled_past_its_side_is_turned_over(posture, base):
    """Rolled about its long axis (the local z) past 90 deg either way its chest faces the other
    way; within it, not; an upright posture never is."""
    for roll_deg, over in ((0.0, False), (80.0, False), (-80.0, False), (100.0, True), (-150.0, True), (180.0, True)):
        half = math.radians(roll_deg) / 2.0
        rolled = quat_multiply(np.asarray(base, float), np.array([0.0, 0.0, math.sin(half), math.cos(half)]))
        assert turned_over(rolled, posture) == over, roll_deg
    assert not turned_over(np.asarray(base, float), "upright")


def test_a_turned_over_stroke_with_a_roll_over_sequence_swims_a_cycle_of_it():
    """Face down, a supine stroke that has a roll_over sequence swims a cycle of it alone at tempo
    1; one without steers as ever, and so does one lying as it should."""
    face_down = still_state(np.full(16, 1 / 16))        # prone: a supine stroke's chest faces down
    target = FixedTarget((5.0, 1.0, 0.0))
    rolling = TargetChooser(target, table(), "supine", roll_over_sequence=True)(1, face_down, None)
    assert rolling.weights == {ROLL_OVER: 1.0} and rolling.tempo == 1.0 and not rolling.glide
    assert ROLL_OVER not in TargetChooser(target, table(), "supine")(1, face_down, None).weights
    lying_well = TargetChooser(target, table(), "prone", roll_over_sequence=True)(1, face_down, None)
    assert ROLL_OVER not in lying_well.weights and lying_well.weights["yaw_left"] > 0


def test_the_backstroke_that_fell_onto_its_front_rolls_back_and_follows_on():
    """This start stands up in a turn at 36 s and falls forward, face down; without its roll_over
    sequence it swam on that way, 2.4-3.6 m off its target by 45-50 s and 11 m by 120 s."""
    spec = SwimSpec.of("t", stroke="backstroke", task={"kind": "follow", "trajectory": "straight_line"},
                       seconds=50.0, seed=3, jitter="wide")
    track = swim(spec.episode(), 50.0).task.track()
    distance = np.linalg.norm(track["swimmer_m"] - track["target_m"], axis=1)
    assert distance[track["track_time_s"] > 45.0].max() < 1.5


@pytest.mark.parametrize("name", [LEVEL_OFF, ROLL_OVER])
def test_a_level_off_or_roll_over_sequence_leaves_the_calibration_valid(name):
    """Calibration swims lying down as it should, where neither the level-off nor the roll-over is
    taken: adding one leaves the stroke's calibration hash (and so its table) as it was."""
    spec = load(StrokeSpec, stroke_path("front_crawl"))
    added = PerturbationSpec.model_validate({"keys": {"neck": {"flexion": {0.0: 10.0}}}})
    edited = spec.model_copy(update={"perturbations": {**spec.perturbations, name: added}})
    assert build_stroke(edited, LAYOUT, "x").spec_sha256 == build_stroke(spec, LAYOUT, "x").spec_sha256
    assert name in build_stroke(edited, LAYOUT, "x").perturbations


def test_target_chooser_asks_for_thrust_only_when_far_and_ahead():
    state = still_state(np.full(16, 1 / 16))
    choice = lambda point: TargetChooser(FixedTarget(point), table(), "prone")(0, state, None)  # noqa: E731
    assert choice((5.0, 0.0, 0.0)).thrust_demand == pytest.approx(1.0)     # far, straight ahead
    assert choice((0.1, 0.0, 0.0)).thrust_demand == pytest.approx(0.0)     # there already
    assert choice((-5.0, 0.0, 0.0)).thrust_demand == pytest.approx(0.0)    # behind: turn first
    near = choice((0.1, 0.0, 0.0))
    assert near.tempo == pytest.approx(TempoControl().min_tempo)


def test_the_breaststroke_turns_nearly_as_tight_as_the_figure_eights_tightest_bend():
    """Its full yaw sequence at tempo 0.7 turns on a circle of 1.6 m radius, against the 1.25 m at
    the tops of figure_eight's lobes, which it cuts (before the re-authoring of issue 36: inside
    them; a sequence before that needed ~2 m)."""
    turn_rad_per_cycle, speed_m_s, *_ = calibration_swim(("breaststroke", "yaw_left", 1.0, 0.7))
    turn_rad_s = turn_rad_per_cycle * 0.7 / load_stroke("breaststroke", LAYOUT).period_s
    assert turn_rad_s > 0 and speed_m_s / turn_rad_s < 1.75
