"""The plates' added mass (issue 36): Lamb's coefficients, the semi-implicit scheme, its validation
against springs with analytic periods, stable swims at 240, 480 and 960 Hz, and off by default."""
import json
import math

import numpy as np
import pytest

from layered_swim.analysis import added_mass as validation
from layered_swim.body.model import load_body
from layered_swim.config import ConfigError
from layered_swim.episode import Episode
from layered_swim.fluid.added_mass import AddedMass, ellipsoid_added_inertia, own_inertia
from layered_swim.fluid.medium import Medium
from layered_swim.fluid.thin_plate import PlateFluid, PlateSettings
from layered_swim.geometry import quat_rotate
from layered_swim.runs import run_swim
from layered_swim.sim.simulation import SimulationDiverged
from layered_swim.spec import SwimSpec
from layered_swim.state import BodyState
from layered_swim.tasks import FreeSwim

RHO = 1000.0
STROKES = ("front_crawl", "backstroke", "breaststroke", "butterfly", "treading_water", "rest")
RATES_HZ = (240, 480, 960)


# --- coefficients -------------------------------------------------------------------------------

def test_a_sphere_carries_half_its_displaced_water_and_no_inertia():
    added = ellipsoid_added_inertia([0.1, 0.1, 0.1], RHO)
    np.testing.assert_allclose(added[:3], 0.5 * RHO * 4 / 3 * math.pi * 0.1**3, rtol=1e-12)
    np.testing.assert_allclose(added[3:], 0.0, atol=1e-15)


def test_a_thin_disk_matches_the_closed_forms():
    radius = 0.2
    added = ellipsoid_added_inertia([radius, radius, 1e-5 * radius], RHO)
    assert added[2] == pytest.approx(8 / 3 * RHO * radius**3, rel=1e-4)            # face-on
    assert added[3] == pytest.approx(16 / 45 * RHO * radius**5, rel=1e-4)          # about a diameter
    assert added[0] < 1e-4 * added[2] and added[5] == 0.0                          # edge-on; about its axis


def test_a_prolate_spheroid_matches_the_closed_forms_and_lambs_table():
    """A 2:1 prolate spheroid (Lamb 1932, art. 115; table: k1 = 0.210, k2 = 0.704, k' = 0.240)."""
    a, b = 2.0, 1.0
    e = math.sqrt(1 - (b / a) ** 2)
    log = math.log((1 + e) / (1 - e))
    alpha = 2 * (1 - e * e) / e**3 * (log / 2 - e)                   # along the axis
    beta = 1 / e**2 - (1 - e * e) / (2 * e**3) * log                 # across it
    k1, k2 = alpha / (2 - alpha), beta / (2 - beta)
    k_turn = e**4 * (beta - alpha) / ((2 - e * e) * (2 * e * e - (2 - e * e) * (beta - alpha)))
    rho_v = RHO * 4 / 3 * math.pi * a * b * b
    added = ellipsoid_added_inertia([b, b, a], RHO)                   # long axis z
    assert added[2] / rho_v == pytest.approx(k1, rel=1e-10) and k1 == pytest.approx(0.210, abs=1e-3)
    assert added[0] / rho_v == pytest.approx(k2, rel=1e-10) and k2 == pytest.approx(0.704, abs=1e-3)
    turn = added[3] / (rho_v * (a * a + b * b) / 5)
    assert turn == pytest.approx(k_turn, rel=1e-9) and k_turn == pytest.approx(0.240, abs=1e-3)


def test_a_long_flat_ellipsoid_is_the_strip_of_strip_theory():
    """Per span, a strip of chord c moving normal to itself carries rho pi c^2 / 4."""
    chord, span = 0.1, 100.0
    added = ellipsoid_added_inertia([chord / 2, 1e-6, span / 2], RHO)     # flat, normal y, long z
    per_span = added[1] / (2 / 3 * span)      # an ellipse's chord falls off along the span: 2/3 of the strip
    assert per_span == pytest.approx(RHO * math.pi * chord**2 / 4, rel=1e-3)


def test_the_hand_carries_twice_its_mass_palm_first():
    body = load_body()
    i = body.index("hand_l")
    added = ellipsoid_added_inertia(body.semi_axes_m[i], Medium().rho_kg_m3)
    assert 1.0 < added[1] < 1.15 and added[1] > 2 * body.mass_kg[i]          # palm normal y
    assert added[0] < 0.2 and added[2] < 0.05
    np.testing.assert_allclose(own_inertia(body)[i, :3], body.mass_kg[i])


# --- the scheme ---------------------------------------------------------------------------------

def _free_box(added_mass: AddedMass, quat, force_n, steps=6, dt=1 / 240):
    """A free body under a constant force, stepped like PyBullet (semi-implicit Euler): its
    accelerations, step by step."""
    own = added_mass.own[0, 0]
    velocity, accelerations = np.zeros(3), []
    for n in range(steps):
        state = BodyState(n * dt, np.array([[0.0, 0.0, -2.0]]), np.array([quat]), velocity[None].copy(),
                          np.zeros((1, 3)), None)
        water, _ = added_mass.wrenches(state, 0.0)
        a = (force_n + water[0]) / own
        velocity = velocity + dt * a
        accelerations.append(a)
    return np.array(accelerations)


def test_a_free_body_gets_its_implicit_acceleration_one_step_late_along_every_body_axis():
    body = load_body()
    hand = AddedMass(load_body(), RHO)
    i = body.index("hand_l")
    hand.own, hand.added, hand.semi = hand.own[i:i + 1], hand.added[i:i + 1], hand.semi[i:i + 1]
    hand.reset()
    quat = np.array([0.3, -0.2, 0.5, 0.8]) / np.linalg.norm([0.3, -0.2, 0.5, 0.8])
    force = np.array([3.0, -7.0, 2.0])
    acc = _free_box(hand, quat, force)
    # In the hand's axes (s + m_j) a_j = F_j: the anisotropic answer, exactly, from the second step on.
    inverse = quat * [-1.0, -1.0, -1.0, 1.0]
    expected = quat_rotate(inverse, force) / (hand.own[0, :3] + hand.added[0, :3])
    for a in acc[1:]:
        np.testing.assert_allclose(quat_rotate(inverse, a), expected, rtol=1e-9)
    np.testing.assert_allclose(acc[0], force / hand.own[0, 0])                   # the first step carries none


def test_the_explicit_force_feeds_on_itself_and_the_scheme_does_not():
    body = load_body()
    i = body.index("hand_l")
    for explicit in (False, True):
        hand = AddedMass(body, RHO, explicit=explicit)
        hand.own, hand.added, hand.semi = hand.own[i:i + 1], hand.added[i:i + 1], hand.semi[i:i + 1]
        hand.reset()
        acc = _free_box(hand, [0.0, 0.0, 0.0, 1.0], np.array([0.0, 10.0, 0.0]), steps=30)
        if explicit:
            assert abs(acc[-1, 1]) > 1e6         # (-m/s)^n: m/s = 2.1 palm-first
        else:
            assert np.all(np.abs(acc[1:, 1] - 10.0 / (hand.own[0, 1] + hand.added[0, 1])) < 1e-9)


def test_out_of_the_water_a_segment_carries_nothing_and_memory_follows_the_clock():
    body = load_body()
    water = AddedMass(body, RHO)
    n = len(body.segment_names)
    pos, quat = np.zeros((n, 3)), np.tile([0.0, 0.0, 0.0, 1.0], (n, 1))
    still, moving = np.zeros((n, 3)), np.ones((n, 3))
    pos[:, 2] = 5.0                                               # all in the air
    water.wrenches(BodyState(0.0, pos, quat, still, still, None), 0.0)
    force, torque = water.wrenches(BodyState(0.01, pos, quat, moving, moving, None), 0.0)
    assert not force.any() and not torque.any()
    pos[:, 2] = -5.0
    force, _ = water.wrenches(BodyState(0.02, pos, quat, still, still, None), 0.0)
    assert np.all(force > 0.0)                                    # it slowed: the water pushes on
    again, _ = water.wrenches(BodyState(0.02, pos, quat, still, still, None), 0.0)
    assert again is force                                         # the same step asked twice
    fresh, _ = water.wrenches(BodyState(0.0, pos, quat, moving, moving, None), 0.0)
    assert not fresh.any()                                        # time went back: a new episode


def test_the_lungs_and_the_water_change_what_the_thorax_carries():
    fluid = PlateFluid(load_body(), Medium(), 9.81, PlateSettings(added_mass=True))
    i = fluid.body.index("thorax")
    before = fluid.added_mass.added[i].copy()
    fluid.breathe(fluid.body.lung_air_l + 2.0)
    assert np.all(fluid.added_mass.added[i, :3] > before[:3])
    fluid.set_medium(Medium(rho_kg_m3=2000.0))
    np.testing.assert_allclose(fluid.added_mass.added[i], fluid.added_mass._per_density[i] * 2000.0)


# --- on by default -------------------------------------------------------------------------------

def test_on_by_default_and_reported_in_the_settings():
    fluid = PlateFluid(load_body(), Medium(), 9.81)
    assert fluid.added_mass is not None and fluid.settings()["added_mass"] is True
    assert PlateFluid(load_body(), Medium(), 9.81, PlateSettings(added_mass=False)).added_mass is None
    assert SwimSpec(stroke="rest").fluid_settings() is None
    with pytest.raises(ConfigError, match="added_mass"):
        PlateSettings(added_mass=1)


def test_the_swim_spec_turns_it_on_and_repeats_it(tmp_path):
    spec = SwimSpec(stroke="rest", seconds=1.0, plate={"added_mass": True})
    assert spec.fluid_settings() == PlateSettings(added_mass=True)
    run_swim(spec, tmp_path / "first")
    config = json.loads((tmp_path / "first" / "config.json").read_text())
    assert config["fluid_backend"]["settings"]["added_mass"] is True
    assert config["swim"]["plate"] == {"added_mass": True}
    with pytest.raises(ConfigError, match="plate settings"):
        SwimSpec(stroke="rest", plate={"added_mas": True})
    with pytest.raises(ConfigError, match="backend plate"):
        SwimSpec(stroke="rest", backend="sph", plate={"added_mass": True})


def test_run_added_mass_on_by_default_and_off_on_the_command_line(tmp_path):
    from layered_swim import cli

    assert cli.main(["run", "--stroke", "rest", "--seconds", "0.5", "--json", "--out", str(tmp_path / "on")]) == 0
    config = json.loads((tmp_path / "on" / "config.json").read_text())
    assert config["fluid_backend"]["settings"]["added_mass"] is True
    assert cli.main(["run", "--stroke", "rest", "--seconds", "0.5", "--no-added-mass", "--json",
                     "--out", str(tmp_path / "off")]) == 0
    config = json.loads((tmp_path / "off" / "config.json").read_text())
    assert config["fluid_backend"]["settings"]["added_mass"] is False
    assert config["swim"]["plate"] == {"added_mass": False}


# --- validation: springs, a push, the explicit force ---------------------------------------------

@pytest.mark.parametrize("hz", RATES_HZ)
def test_the_hand_palm_first_on_a_spring_swings_with_its_water(hz):
    row = validation.spring("hand_l", 1, False, hz, periods=3)
    assert row["added"] > 2 * row["own"]
    assert abs(row["ratio"] - 1.0) < 0.01                          # the issue asks 10 %
    assert row["without_water_s"] < 0.6


@pytest.mark.parametrize("segment, axis, rotation", [("thorax", 2, False), ("foot_l", 1, True),
                                                     ("hand_l", 0, True), ("forearm_l", 0, False)])
def test_other_boxes_and_turns_on_springs(segment, axis, rotation):
    row = validation.spring(segment, axis, rotation, 240, periods=3)
    assert abs(row["ratio"] - 1.0) < 0.01


@pytest.mark.parametrize("axis", range(3))
def test_the_hand_on_its_free_forearm_swings_with_both_waters(axis):
    row = validation.wrist_spring(axis, 240, periods=3)
    assert abs(row["ratio"] - 1.0) < 0.01 and row["without_water_s"] < 0.9


def test_the_pushed_hand_accelerates_as_if_heavier():
    row = validation.pushed_plate(480)
    assert abs(row["ratio"] - 1.0) < 0.02
    assert abs(row["water_force_over_added_mass_times_a"] - 1.0) < 0.02


@pytest.mark.parametrize("hz", RATES_HZ)
def test_the_explicit_force_blows_up_at_every_rate(hz):
    assert validation.spring("hand_l", 1, False, hz, explicit=True, periods=1)["diverged_after_steps"] < 40


# --- stability: every stroke at every rate ------------------------------------------------------

@pytest.mark.parametrize("hz", RATES_HZ)
@pytest.mark.parametrize("stroke", STROKES)
def test_every_stroke_swims_stably_with_added_mass(stroke, hz):
    episode = Episode(stroke, FreeSwim(), physics_hz=hz, fluid_settings=PlateSettings(added_mass=True))
    peak = {"speed": 0.0, "force": 0.0}

    def watch(sim):
        peak["speed"] = max(peak["speed"], float(np.abs(sim.state.linvel_m_s).max()))
        peak["force"] = max(peak["force"], float(np.abs(sim.fluid.added_mass.force_n).max()))

    try:
        episode.run(3.0, observers=[watch])           # SimulationDiverged (NaN, > 50 m/s) would fail it
        state = episode.sim.state
    finally:
        episode.close()
    assert all(np.isfinite(a).all() for a in (state.pos_m, state.quat_xyzw, state.linvel_m_s, state.angvel_rad_s))
    assert peak["speed"] < 15.0                       # limbs, not an integration running away
    assert peak["force"] < 1500.0


def test_the_explicit_force_blows_a_swim_up():
    episode = Episode("front_crawl", FreeSwim(), physics_hz=960, fluid_settings=PlateSettings(added_mass=True))
    episode.sim.fluid.added_mass.explicit = True
    try:
        with pytest.raises(SimulationDiverged):
            episode.run(1.0)
    finally:
        episode.close()
