"""Every stroke metric on hand-made trajectories, then the whole per-cycle analysis on a made-up
log whose answers are known in closed form."""
import math

import numpy as np
import pytest

from layered_swim.analysis.reference_ranges import Range, active_drag_range, ranges_for
from layered_swim.analysis.stroke_metrics import (
    SwimmerInfo,
    amplitude,
    analyze_log,
    heading_deg,
    mean_power_w,
    pitch_deg,
    propelling_efficiency,
    propulsive_resistive_n,
    reach_along_body_m,
    speed_fluctuation_pct,
    travel_direction,
)
from layered_swim.config import ConfigError
from layered_swim.geometry import quat_multiply
from layered_swim.sim.simulation import PRONE_QUAT_XYZW

HZ = 120
PRONE_FORWARD = (0.0, 0.0, 1.0)     # a prone pelvis's long axis, local


def quat_about(axis, angle_rad):
    axis = np.asarray(axis, dtype=float)
    half = np.asarray(angle_rad, dtype=float)[..., None] / 2
    return np.concatenate([np.broadcast_to(axis, half.shape[:-1] + (3,)) * np.sin(half), np.cos(half)], axis=-1)


def test_travel_direction():
    com = np.array([[1.0, 1.0, -0.3], [2.0, 1.5, -0.1], [4.0, 5.0, -0.9]])
    np.testing.assert_allclose(travel_direction(com), [0.6, 0.8, 0.0])
    np.testing.assert_allclose(travel_direction(np.zeros((4, 3))), [1.0, 0.0, 0.0])


def test_pitch_of_a_prone_pelvis():
    pitch = np.radians([-20.0, 0.0, 15.0])
    q = quat_multiply(quat_about([0.0, 1.0, 0.0], -pitch), np.tile(PRONE_QUAT_XYZW, (3, 1)))   # about +y: nose down
    np.testing.assert_allclose(pitch_deg(q, PRONE_FORWARD), [-20.0, 0.0, 15.0], atol=1e-12)


def test_heading_unwraps_past_180():
    yaw = np.radians(np.arange(0.0, 400.0, 20.0))
    q = quat_multiply(quat_about([0.0, 0.0, 1.0], yaw), np.tile(PRONE_QUAT_XYZW, (len(yaw), 1)))
    np.testing.assert_allclose(heading_deg(q, PRONE_FORWARD), np.degrees(yaw), atol=1e-9)


def test_reach_along_the_body():
    pelvis = np.array([[1.0, 2.0, -0.2]])
    hand = np.array([[1.7, 2.3, -0.1]])
    assert reach_along_body_m(hand, pelvis, [PRONE_QUAT_XYZW])[0] == pytest.approx(0.7)   # long axis = +x


def test_propulsive_and_resistive():
    force = np.array([[[30.0, 5.0, 0.0], [-10.0, 0.0, 50.0], [-5.0, 1.0, 0.0]],
                      [[0.0, 0.0, 0.0], [20.0, 0.0, 0.0], [0.0, -40.0, 0.0]]])
    push, drag = propulsive_resistive_n(force, [1.0, 0.0, 0.0])
    np.testing.assert_allclose(push, [30.0, 20.0])
    np.testing.assert_allclose(drag, [15.0, 0.0])
    push, drag = propulsive_resistive_n(force, [0.0, 1.0, 0.0])
    np.testing.assert_allclose(push, [6.0, 0.0])
    np.testing.assert_allclose(drag, [0.0, 40.0])


def test_fluctuation_amplitude_power_efficiency():
    phase = np.linspace(0.0, 1.0, 101)
    speed = np.stack([1.0 + 0.2 * np.sin(2 * np.pi * phase), 0.5 + 0.25 * np.cos(2 * np.pi * phase)])
    np.testing.assert_allclose(speed_fluctuation_pct(speed), [20.0, 50.0], rtol=1e-3)
    np.testing.assert_allclose(amplitude(speed), [0.2, 0.25], rtol=1e-3)
    t = np.linspace(0.0, 10.0, 1001)
    work = np.where(t < 5.0, 100.0 * t, 500.0 + 300.0 * (t - 5.0))
    np.testing.assert_allclose(mean_power_w(t, work, [1.0, 3.0, 6.0, 9.0]), [100.0, (800.0 - 300.0) / 3, 300.0])
    assert propelling_efficiency(50.0, 1.2, 300.0) == pytest.approx(0.2)


NAMES = ("pelvis", "thorax", "hand_l", "hand_r", "foot_l", "foot_r")


def made_up_log(seconds=12.0, f_hz=0.8, speed=1.1, surge=0.22):
    """Prone, heading +x at ``speed`` with a +-``surge`` m/s surge once a cycle; the left hand
    reaches 0.5 +- 0.3 m ahead of the pelvis; thorax rolls +-30 deg, pelvis +-12 deg; the left
    hand is pushed ahead by 100 max(0, sin) N, the pelvis held back by 50 N (plus 800 N of
    buoyancy, which the analysis must leave out); the joints work at 300 W."""
    t = np.arange(round(seconds * HZ) + 1) / HZ
    w = 2 * np.pi * f_hz
    n = len(t)
    com = np.column_stack([speed * t + surge * np.sin(w * t) / w, np.zeros(n), np.full(n, -0.3)])
    vel = np.column_stack([speed + surge * np.cos(w * t), np.zeros(n), np.zeros(n)])
    pos = np.repeat(com[:, None, :], len(NAMES), axis=1)
    pos[:, 2, 0] += 0.5 + 0.3 * np.sin(w * t)
    quat = np.tile(PRONE_QUAT_XYZW, (n, len(NAMES), 1))
    for k, degrees in ((0, 12.0), (1, 30.0)):
        quat[:, k] = quat_multiply(quat_about([1.0, 0.0, 0.0], np.radians(degrees) * np.sin(w * t)), quat[:, k])
    force = np.zeros((n, len(NAMES), 3))
    force[:, 2, 0] = 100.0 * np.maximum(0.0, np.sin(w * t))
    force[:, 0, 0] = -50.0
    buoyancy = np.zeros_like(force)
    buoyancy[:, 0, 2] = 800.0
    return {"time_s": t, "com_pos_m": com, "com_vel_m_s": vel, "segment_pos_m": pos, "segment_quat_xyzw": quat,
            "fluid_force_n": force + buoyancy, "buoyancy_force_n": buoyancy,
            "head_top_m": 0.05 + 0.02 * np.sin(w * t), "joint_work_j": 300.0 * t}


def test_analysis_of_a_made_up_swim():
    f_hz, speed = 0.8, 1.1
    result = analyze_log(made_up_log(f_hz=f_hz, speed=speed), SwimmerInfo(NAMES, "prone", 1.0 / f_hz, settle_s=2.0))
    s = result["summary"]
    assert s["cycles"] == 7          # rises at 2.5 + 1.25 k s, k = 0..7, inside 2-12 s
    mean = {k: v["mean"] for k, v in s.items() if isinstance(v, dict)}
    assert mean["stroke_rate_cpm"] == pytest.approx(60.0 * f_hz, rel=1e-6)
    assert mean["mean_speed_m_s"] == pytest.approx(speed, rel=1e-6)
    assert mean["distance_per_cycle_m"] == pytest.approx(speed / f_hz, rel=1e-6)
    assert mean["speed_fluctuation_pct"] == pytest.approx(100.0 * 0.22 / speed, rel=1e-3)
    assert mean["shoulder_roll_deg"] == pytest.approx(30.0, rel=1e-3)
    assert mean["hip_roll_deg"] == pytest.approx(12.0, rel=1e-3)
    assert mean["pitch_deg"] == pytest.approx(0.0, abs=1e-9)
    assert mean["head_top_m"] == pytest.approx(0.05, abs=1e-4)
    assert mean["propulsive_force_n"] == pytest.approx(100.0 / math.pi, rel=1e-3)
    assert mean["resistive_force_n"] == pytest.approx(50.0)
    assert mean["mechanical_power_w"] == pytest.approx(300.0)
    assert mean["peak_hand_force_n"] == pytest.approx(100.0, rel=1e-3)
    assert s["active_drag_n"] == pytest.approx(50.0)
    assert s["propelling_efficiency"] == pytest.approx(50.0 * speed / 300.0)
    assert s["thrust_axis"] == "forward" and s["travel_direction"] == pytest.approx([1.0, 0.0, 0.0])
    assert all(s[k]["sd"] < 1e-6 for k in ("stroke_rate_cpm", "mean_speed_m_s", "mechanical_power_w"))
    assert len(result["cycles"]) == 7 and result["cycles"][0]["start_s"] == pytest.approx(2.5, abs=1e-3)
    profile = result["profiles"]["hand_l_thrust_n"]["mean"]
    assert len(profile) == 101 and max(profile) == pytest.approx(100.0, rel=1e-3)


def test_upright_swims_measure_support_not_drag():
    log = made_up_log()
    log["segment_pos_m"][:, 4] = log["segment_pos_m"][:, 2]   # the left foot marks the cycles
    log["fluid_force_n"][:, 4, 2] += 40.0                      # and is pushed up
    s = analyze_log(log, SwimmerInfo(NAMES, "upright", 1.25, settle_s=2.0))["summary"]
    assert s["thrust_axis"] == "up"
    assert s["propulsive_force_n"]["mean"] == pytest.approx(40.0)
    assert s["active_drag_n"] is None and s["propelling_efficiency"] is None and "speed_fluctuation_pct" not in s


def test_too_short_a_swim_is_an_error():
    with pytest.raises(ConfigError, match="whole stroke cycles"):
        analyze_log(made_up_log(seconds=3.0), SwimmerInfo(NAMES, "prone", 1.25, settle_s=2.0))


def test_verdicts_against_the_data_sheet():
    r = Range(0.6, 1.0, "x")
    assert [r.verdict(v) for v in (0.5, 0.6, 0.8, 1.0, 1.2, None)] == ["below", "inside", "inside", "inside",
                                                                       "above", "n/a"]
    drag = active_drag_range(1.0)
    assert (drag.low, drag.high) == (32.2, 38.0)
    assert "speed_fluctuation_pct" in ranges_for("breaststroke", 0.7) and ranges_for("made_up_stroke", 1.0) == {}


def test_the_sample_before_any_force_is_left_out():
    log = made_up_log()
    log["fluid_force_n"][0] = np.nan          # as the recorder logs it: nothing applied yet at t = 0
    result = analyze_log(log, SwimmerInfo(NAMES, "prone", 1.25, settle_s=0.0))
    assert np.isfinite(result["profiles"]["propulsive_force_n"]["mean"]).all()
    assert result["summary"]["resistive_force_n"]["mean"] == pytest.approx(50.0)
