import math

import numpy as np
import pytest

from layered_swim.geometry import quat_multiply
from layered_swim.sim.simulation import PRONE_QUAT_XYZW
from layered_swim.tasks.metrics import head_top_height_m, roll_deg, summary

LOG_HZ = 60


def quat_about(axis, angle_rad):
    axis = np.asarray(axis, dtype=float)
    half = np.asarray(angle_rad, dtype=float)[..., None] / 2
    return np.concatenate([axis * np.sin(half), np.cos(half)], axis=-1)


def test_head_top_height():
    centre = [0.3, 0.1, -0.2]
    upright = [0.0, 0.0, 0.0, 1.0]
    assert head_top_height_m(centre, upright, 0.125) == pytest.approx(-0.075)
    assert head_top_height_m(centre, PRONE_QUAT_XYZW, 0.125) == pytest.approx(-0.2)   # top faces +x
    upside_down = quat_about([1.0, 0.0, 0.0], math.pi)
    assert head_top_height_m(centre, upside_down, 0.125) == pytest.approx(-0.325)
    tilted = quat_about([0.0, 1.0, 0.0], math.radians(60))
    np.testing.assert_allclose(head_top_height_m([centre, centre], [upright, tilted], 0.1), [-0.1, -0.15])


def test_roll_of_a_prone_thorax():
    roll = np.radians([-30.0, 0.0, 10.0, 45.0])
    q = quat_multiply(quat_about([1.0, 0.0, 0.0], roll), np.tile(PRONE_QUAT_XYZW, (4, 1)))
    np.testing.assert_allclose(roll_deg(q), [-30.0, 0.0, 10.0, 45.0], atol=1e-12)


def swim(seconds=13.0, cycles_per_s=0.5):
    """Still for 5 s, then 1.2 m/s along +x with 0.06 m/s sideways drift of the pelvis; thorax
    rolls +-20 deg in even cycles and +-40 deg in odd ones; head top 0.1 m above the surface
    after the settle time, 0.5 m below before it."""
    t = np.arange(round(seconds * LOG_HZ) + 1) / LOG_HZ
    moving = np.clip(t - 5.0, 0.0, None)
    com = np.column_stack([1.2 * moving, np.zeros_like(t), np.full_like(t, -0.3)])
    pelvis = com + np.column_stack([np.zeros_like(t), 0.06 * moving, np.zeros_like(t)])
    phase = t * cycles_per_s
    amplitude = np.where(np.floor(phase) % 2 == 0, 20.0, 40.0)
    roll = np.radians(amplitude * np.sin(2 * np.pi * phase))
    thorax = quat_multiply(quat_about([1.0, 0.0, 0.0], roll), np.tile(PRONE_QUAT_XYZW, (len(t), 1)))
    head = np.where(t >= 5.0, 0.1, -0.5)
    return t, com, pelvis, thorax, head


def test_summary_over_the_settled_window():
    t, com, pelvis, thorax, head = swim()
    s = summary(t, com, pelvis, thorax, head, cycles_per_s=0.5, stroke="test")
    assert s["stroke"] == "test" and s["seconds"] == pytest.approx(13.0)
    assert s["mean_speed_m_s"] == pytest.approx(1.2)
    assert s["stroke_rate_cpm"] == pytest.approx(30.0)
    assert s["distance_per_cycle_m"] == pytest.approx(2.4)
    # Whole cycles inside 5..13 s: 6-8 s (40 deg), 8-10 s (20 deg), 10-12 s (40 deg).
    assert s["peak_shoulder_roll_deg"] == pytest.approx((40 + 20 + 40) / 3, abs=0.05)
    assert s["mean_head_height_m"] == pytest.approx(0.1)
    assert s["horizontal_drift_m_s"] == pytest.approx(math.hypot(1.2, 0.06))
    assert s["final_pelvis_depth_m"] == pytest.approx(0.3)
    assert s["note"] is None


def test_summary_of_a_run_shorter_than_the_settle_time():
    t, com, pelvis, thorax, head = swim(seconds=3.0)
    com = com + np.outer(t, [0.5, 0.0, 0.0])
    s = summary(t, com, pelvis, thorax, head, cycles_per_s=0.5, stroke="test")
    assert "settle" in s["note"]
    assert s["mean_speed_m_s"] == pytest.approx(0.5)
    assert s["mean_head_height_m"] == pytest.approx(-0.5)
    assert s["peak_shoulder_roll_deg"] == pytest.approx(20.0, abs=0.05)   # one whole cycle, 0-2 s
    assert s["horizontal_drift_m_s"] == pytest.approx(0.0)


def test_roll_without_a_whole_cycle_uses_the_window_maximum():
    t, com, pelvis, thorax, head = swim(seconds=1.0)
    s = summary(t, com, pelvis, thorax, head, cycles_per_s=0.5, stroke="test")
    assert s["peak_shoulder_roll_deg"] == pytest.approx(20.0, abs=0.05)   # sin peaks at 0.5 s
