"""The under-water depth hold: pitch weights moved every control step toward the target's depth."""
import numpy as np
import pytest

from layered_swim.body.layout import joint_layout
from layered_swim.body.model import load_body
from layered_swim.control.depth_hold import DepthHold, with_pitch_added
from layered_swim.control.layered import LayeredController, Layers, fixed_weights
from layered_swim.control.rules import arm_indices
from layered_swim.control.stroke import UNDER_WATER, load_stroke
from layered_swim.control.targets import FixedTarget
from layered_swim.sim.simulation import PRONE_QUAT_XYZW
from layered_swim.state import BodyState

BODY = load_body()
LAYOUT = joint_layout(BODY)


class Sinking:
    """A target moving +x at 0.5 m/s and sinking 0.2 m/s from the origin."""

    def position(self, time_s):
        return np.array([0.5 * time_s, 0.0, -0.2 * time_s])


def test_the_weight_adds_the_height_above_and_the_rise_within_one():
    hold = DepthHold(per_m=3.0, per_m_s=5.0)
    assert hold.weight(0.1, 0.02) == pytest.approx(0.4)       # 3 * 0.1 + 5 * 0.02
    assert hold.weight(-0.05, -0.01) == pytest.approx(-0.2)
    assert hold.weight(0.5, 0.1) == 1.0 and hold.weight(-1.0, 0.0) == -1.0


def test_the_weight_reads_the_target_ahead_and_its_sinking_rate():
    """At t = 2 s, 1 s ahead: the target is at -0.6 m sinking 0.2 m/s; a pelvis at -0.5 m sinking
    0.1 m/s is 0.1 m above it and rises 0.1 m/s faster."""
    hold = DepthHold(per_m=3.0, per_m_s=5.0, ahead_s=1.0)
    assert hold.weight_toward(Sinking(), 2.0, -0.5, -0.1) == pytest.approx(3 * 0.1 + 5 * 0.1)
    assert hold.weight_toward(FixedTarget((5.0, 0.0, -2.0)), 2.0, -2.0, 0.0) == 0.0


@pytest.mark.parametrize("weights, added, expected", [
    ({"yaw_left": 0.4, "pitch_up": 0.3}, 0.5, {"yaw_left": 0.4, "pitch_down": 0.2}),
    ({"pitch_down": 0.8}, 0.5, {"pitch_down": 1.0}),
    ({"pitch_down": 0.2, UNDER_WATER: 1.0}, -0.7, {UNDER_WATER: 1.0, "pitch_up": 0.5}),
    ({"pitch_up": 0.3}, 0.3, {}),
    ({}, -2.0, {"pitch_up": 1.0}),
])
def test_the_added_weight_goes_to_the_one_pitch_sequence_that_pitches_that_way(weights, added, expected):
    before = dict(weights)
    out = with_pitch_added(weights, added)
    assert out.keys() == expected.keys() and all(out[k] == pytest.approx(v) for k, v in expected.items())
    assert weights == before


def test_the_controller_moves_the_pitch_weights_only_under_water():
    """A pelvis 0.5 m above its target: 3 per metre adds pitch-down 1 (capped) to the cycle's
    pitch-up 0.4 while the cycle takes the under-water sequence, and nothing otherwise."""
    stroke = load_stroke("breaststroke", LAYOUT)
    state = BodyState(0.0, np.zeros((16, 3)), np.tile(PRONE_QUAT_XYZW, (16, 1)), np.zeros((16, 3)), np.zeros((16, 3)),
                      BODY.segments)      # every segment at the origin, prone, at rest
    target = FixedTarget((5.0, 0.0, -0.5))
    t = 1.3 * stroke.period_s       # cycle 1: the weights were chosen at its start, and fully blended in
    state.time_s = t

    def pose(weights, hold):
        controller = LayeredController(stroke, LAYOUT, arm_indices(BODY, LAYOUT), fixed_weights(weights),
                                       Layers(cycle=True, palm=False, reach=False), target, depth_hold=hold)
        controller.desired(0.0, state, np.zeros((16, 3)))
        return controller.desired(t, state, np.zeros((16, 3)))[0]

    hold = DepthHold(per_m=3.0)
    under = {UNDER_WATER: 1.0, "pitch_up": 0.4}
    np.testing.assert_allclose(pose(under, hold), pose({UNDER_WATER: 1.0, "pitch_down": 0.6}, None))
    np.testing.assert_allclose(pose({"pitch_up": 0.4}, hold), pose({"pitch_up": 0.4}, None))
    assert not np.allclose(pose(under, hold), pose(under, None))
