"""The basic stroke layer: key interpolation, mirroring, and one-line errors for bad files."""
import textwrap

import numpy as np
import pytest

from layered_swim.body.layout import joint_layout
from layered_swim.body.model import load_body
from layered_swim.config import ConfigError
from layered_swim.control.stroke import available_strokes, load_stroke

LAYOUT = joint_layout(load_body())
KEYS_DEG = {0.0: 10.0, 0.25: 120.0, 0.5: 60.0, 0.75: 100.0}   # on the table grid (1/1024)
GOOD = textwrap.dedent("""\
    name: test
    period_s: 1.5
    keys:
      shoulder_l:
        flexion: {0.0: 10, 0.25: 120, 0.5: 60, 0.75: 100}
        abduction: {0.1: 20, 0.6: 0}
      shoulder_r: {mirror_of: shoulder_l, phase_shift: 0.5}
      elbow_l:
        flexion: {0.0: 0, 0.5: 145}
""")


def write(tmp_path, text, name="stroke.yaml"):
    path = tmp_path / name
    path.write_text(text)
    return path


@pytest.fixture
def stroke(tmp_path):
    return load_stroke(str(write(tmp_path, GOOD)), LAYOUT)


def test_keys_are_hit(stroke):
    k = LAYOUT.index("shoulder_l.flexion")
    for phase, deg in KEYS_DEG.items():
        assert np.degrees(stroke.pose(phase)[0][k]) == pytest.approx(deg, abs=1e-9)


def test_periodic(stroke):
    for phase in (0.0, 0.3, 0.77):
        for a, b in zip(stroke.pose(phase), stroke.pose(phase + 1.0)):
            np.testing.assert_allclose(a, b, atol=1e-12)
    np.testing.assert_allclose(stroke.table[0], stroke.table[-1])


def test_no_overshoot(stroke):
    deg = np.degrees(stroke.table)
    k = LAYOUT.index("shoulder_l.flexion")
    assert deg[:, k].min() >= 10.0 - 1e-9 and deg[:, k].max() <= 120.0 + 1e-9
    e = LAYOUT.index("elbow_l.flexion")
    assert deg[:, e].min() >= -1e-9 and deg[:, e].max() <= 145.0 + 1e-9


def test_mirror_is_half_a_cycle_later(stroke):
    for axis in ("flexion", "abduction"):
        left, right = LAYOUT.index(f"shoulder_l.{axis}"), LAYOUT.index(f"shoulder_r.{axis}")
        for phase in np.arange(0.0, 1.0, 1 / 64):
            assert stroke.pose(phase + 0.5)[0][right] == pytest.approx(stroke.pose(phase)[0][left], abs=1e-12)


def test_unkeyed_axes_hold_the_rest_pose(stroke):
    assert np.all(stroke.table[:, LAYOUT.index("knee_l.flexion")] == 0.0)


@pytest.mark.parametrize("name", available_strokes())
def test_shipped_strokes_load(name):
    s = load_stroke(name, LAYOUT)
    assert s.period_s > 0
    assert np.all(s.table >= LAYOUT.lower_rad - 1e-9) and np.all(s.table <= LAYOUT.upper_rad + 1e-9)


@pytest.mark.parametrize("text, words", [
    (GOOD.replace("elbow_l:", "elbow_x:"), ["keys.elbow_x", "unknown joint"]),
    (GOOD.replace("abduction: {0.1", "twist: {0.1"), ["keys.shoulder_l", "twist"]),
    (GOOD.replace("0.5: 145", "1.0: 145"), ["keys.elbow_l", "flexion", "[0, 1)"]),
    (GOOD.replace("0.5: 145", "0.5: 170"), ["keys.elbow_l", "flexion", "range"]),
    (GOOD.replace("period_s: 1.5\n", ""), ["period_s"]),
    (GOOD.replace("period_s: 1.5", "period_s: -1"), ["period_s"]),
    (GOOD.replace("flexion: {0.0: 0, 0.5: 145}", "flexion: {0.0: 0, 0.5: 145"), ["line"]),
    (GOOD + "steering: {glide_moving_joints: [hip_l, tail]}\n", ["steering.glide_moving_joints", "tail"]),
    (GOOD + "steering: {max_weight: 1.3}\n", ["steering.max_weight", "multiple of 0.25"]),
    (GOOD + "steering: {yaw_fraction: 1.5}\n", ["steering.yaw_fraction"]),
    (GOOD + "steering: {level_off_pitch_down_weight: 2}\n", ["steering.level_off_pitch_down_weight", "pitch_down"]),
    (GOOD + "steering: {level_off_pitch_down_weight: 4}\n", ["steering.level_off_pitch_down_weight"]),
    (GOOD + "steering: {under_water_below_m: 0.6}\n", ["steering.under_water_below_m", "under_water"]),
    (GOOD + "steering: {under_water_pitch_per_m: 3}\n", ["steering.under_water_pitch_per_m", "under_water_below_m"]),
    (GOOD + "steering: {under_water_pitch_per_m: -1}\n", ["steering.under_water_pitch_per_m"]),
    (GOOD + "steering: {under_water_level_pitch_deg: 0}\n", ["steering.under_water_level_pitch_deg",
                                                             "under_water_below_m"]),
    (GOOD + "steering: {under_water_level_pitch_deg: 60}\n", ["steering.under_water_level_pitch_deg"]),
    (GOOD + "steering: {under_water_yaw_fraction: 0.4}\n", ["steering.under_water_yaw_fraction",
                                                          "under_water_below_m"]),
    (GOOD + "steering: {under_water_yaw_fraction: 1.5}\n", ["steering.under_water_yaw_fraction"]),
    (GOOD + "steering: {full_tempo_beyond_m: 0.1}\n", ["steering.full_tempo_beyond_m"]),
    (GOOD + "steering: {lead_straight_s: 4}\n", ["steering", "lead_bend_s (3 s) must be at least lead_straight_s"]),
    (GOOD + "steering: {lead_straight_diving_s: 5, lead_bend_s: 4}\n", ["steering", "lead_bend_s (4 s)", "(5 s)"]),
    (GOOD + "trim: {joints: {elbow_l: {flexion: 10}}}\n", ["trim.joints", "elbow_l.flexion", "range"]),
    (GOOD + "trim: {joints: {tail: {flexion: 10}}}\n", ["trim.joints.tail", "unknown joint"]),
    (GOOD + "trim: {light_from: 0.9, light_full: 0.95}\n", ["trim", "light_full < light_from"]),
])
def test_bad_stroke_file(tmp_path, text, words):
    path = write(tmp_path, text, "bad.yaml")
    with pytest.raises(ConfigError) as err:
        load_stroke(str(path), LAYOUT)
    message = str(err.value)
    assert "\n" not in message
    assert str(path) in message and all(word in message for word in words), message


TRIMMED = GOOD + textwrap.dedent("""\
    trim:
      joints: {hip_l: {flexion: 20}}
      light_from: 0.95
      light_full: 0.9
      dense_from: 2.0
      dense_full: 3.0
""")


def test_trim_weight_is_nothing_near_the_body_density_and_all_far_from_it(tmp_path):
    trim = load_stroke(str(write(tmp_path, TRIMMED)), LAYOUT).trim_spec
    assert [trim.weight(r) for r in (0.95, 1.0, 1.5, 2.0)] == [0.0, 0.0, 0.0, 0.0]
    assert trim.weight(0.9) == trim.weight(0.5) == trim.weight(3.0) == trim.weight(8.0) == 1.0
    assert trim.weight(0.925) == pytest.approx(0.5) and trim.weight(2.5) == pytest.approx(0.5)  # smoothstep's middle
    assert trim.weight(2.25) == pytest.approx(0.25 ** 2 * (3 - 0.5))


def test_dense_water_eases_the_slowest_tempo_and_stills_the_glides(tmp_path):
    text = GOOD + textwrap.dedent("""\
        steering: {min_tempo: 0.8, glide_within_m: 0.5, glide_moving_joints: [hip_l]}
        trim: {dense_from: 2.0, dense_full: 3.0, dense_min_tempo: 0.6, dense_still_glide: true}
    """)
    stroke = load_stroke(str(write(tmp_path, text)), LAYOUT)
    assert stroke.glide_moving.any()
    for ratio, min_tempo, still in [(0.5, 0.8, False), (1.5, 0.8, False), (2.25, 0.8 - 0.2 * 0.25 ** 2 * 2.5, False),
                                    (2.5, 0.7, True), (3.0, 0.6, True), (5.0, 0.6, True)]:
        trimmed = stroke.trimmed(ratio)
        assert trimmed.steering.min_tempo == pytest.approx(min_tempo), ratio
        assert (not trimmed.glide_moving.any()) == still, ratio
        assert trimmed.steering.glide_within_m == 0.5
    assert stroke.steering.min_tempo == 0.8 and stroke.glide_moving.any()     # the stroke itself unchanged


def test_a_trimmed_stroke_moves_its_key_poses_by_the_trim(tmp_path):
    stroke = load_stroke(str(write(tmp_path, TRIMMED)), LAYOUT)
    assert stroke.trimmed(1.2) is stroke
    hip = LAYOUT.names.index("hip_l.flexion")
    heavy = stroke.trimmed(3.0)
    for phase in (0.0, 0.3, 0.77):
        pose, rate = stroke.pose(phase)
        moved, moved_rate = heavy.pose(phase)
        offset = np.zeros(LAYOUT.size)
        offset[hip] = np.radians(20.0)
        np.testing.assert_allclose(moved - pose, offset, atol=1e-12)
        np.testing.assert_array_equal(moved_rate, rate)
    half = stroke.trimmed(2.5).pose(0.3)[0] - stroke.pose(0.3)[0]
    assert half[hip] == pytest.approx(np.radians(10.0))
