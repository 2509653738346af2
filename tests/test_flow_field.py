"""Flow fields from primitives (water files): each primitive's velocity against its formula, their
sum, the plate fluid seeing the water where each segment is, the command line and the picture."""
import json
import math

import numpy as np
import pytest
from test_cli import assert_one_line_error, cli

from layered_swim.body.model import load_body
from layered_swim.config import ConfigError
from layered_swim.fluid.flow_field import FlowField, available_waters, load_water, parse_water
from layered_swim.fluid.medium import water
from layered_swim.fluid.thin_plate import PlateFluid
from layered_swim.state import BodyState


def field(*flows) -> FlowField:
    return FlowField(parse_water({"name": "test", "flows": list(flows)}, "test.yaml"))


def test_a_vortex_circles_its_centre_at_circulation_over_two_pi_r():
    """2 pi m^2/s of circulation: 1 m/s at 1 m, 0.25 m/s at 4 m, counterclockwise (seen from
    above), the same at every depth; still at the centre (the core), never faster than outside it."""
    vortex = field({"type": "vortex", "center_m": {"x": 1.0, "y": 2.0}, "circulation_m2_s": 2 * math.pi,
                    "core_radius_m": 0.05})
    points = np.array([[2.0, 2.0, -0.3], [1.0, 6.0, -3.0], [1.0, 2.0, 0.0]])
    np.testing.assert_allclose(vortex.velocity_m_s(points, 0.0), [[0, 1, 0], [-0.25, 0, 0], [0, 0, 0]], atol=1e-12)
    near = vortex.velocity_m_s(np.column_stack([1.0 + np.linspace(0.001, 0.3, 50), np.full(50, 2.0), np.zeros(50)]), 0)
    assert np.all(np.isfinite(near)) and np.abs(near).max() < 1.0 / 0.05


@pytest.mark.parametrize("kind, sign", [("source", 1.0), ("sink", -1.0)])
def test_a_source_spreads_and_a_sink_draws_at_strength_over_two_pi_r(kind, sign):
    flow = field({"type": kind, "center_m": {"x": 0.0, "y": 0.0}, "strength_m2_s": 4 * math.pi,
                  "core_radius_m": 0.01})
    np.testing.assert_allclose(flow.velocity_m_s(np.array([[0.0, 2.0, -1.0], [-1.0, 0.0, 0.0]]), 5.0),
                               sign * np.array([[0, 1, 0], [-2, 0, 0]]), atol=1e-12)


def test_a_wave_moves_the_water_in_circles_that_shrink_with_depth():
    """Amplitude 0.1 m, 2 pi m long (k = 1): omega = sqrt(g), the surface water at a omega, e^-1 of
    it 1 m down; the same one period later; forward under a crest, up a quarter wave behind it."""
    wave = field({"type": "wave", "amplitude_m": 0.1, "wavelength_m": 2 * math.pi})
    omega = math.sqrt(9.81)
    surface, deep = wave.velocity_m_s(np.array([[0.0, 0.0, 0.0], [0.0, 0.0, -1.0]]), 0.0)
    np.testing.assert_allclose(surface, [0.1 * omega, 0, 0], atol=1e-12)
    np.testing.assert_allclose(deep, surface * math.exp(-1.0), atol=1e-12)
    np.testing.assert_allclose(wave.velocity_m_s(np.array([[math.pi / 2, 0.0, 0.0]]), 0.0)[0], [0, 0, 0.1 * omega],
                               atol=1e-12)
    points = np.random.default_rng(0).uniform(-5, 0, (20, 3))
    np.testing.assert_allclose(wave.velocity_m_s(points, 2 * math.pi / omega), wave.velocity_m_s(points, 0.0),
                               atol=1e-12)


def test_flows_add_and_a_medium_adds_its_current():
    uniform = {"type": "uniform", "velocity_m_s": {"x": 0.2}}
    vortex = {"type": "vortex", "center_m": {"x": 0.0, "y": 0.0}, "circulation_m2_s": 2 * math.pi,
              "core_radius_m": 0.01}
    points = np.array([[1.0, 0.0, -0.3], [0.0, -2.0, -0.3]])
    both = field(uniform, vortex).velocity_m_s(points, 0.0)
    np.testing.assert_allclose(both, field(uniform).velocity_m_s(points, 0.0) + field(vortex).velocity_m_s(points, 0.0))
    medium = water(current_m_s=(0.0, 0.1, 0.0), flow=field(uniform))
    np.testing.assert_allclose(medium.current_at(points, 0.0), [[0.2, 0.1, 0.0]] * 2)
    np.testing.assert_allclose(water(current_m_s=(0.3, 0, 0)).current_at(points, 0.0), [[0.3, 0, 0]] * 2)
    # The steady part (what steering reads) leaves a wave's circling water out.
    wave = {"type": "wave", "amplitude_m": 0.1, "wavelength_m": 2 * math.pi}
    swell = water(current_m_s=(0.0, 0.1, 0.0), flow=field(uniform, wave))
    assert np.abs(swell.current_at(points, 0.0) - [[0.2, 0.1, 0.0]]).max() > 0.05
    np.testing.assert_allclose(swell.current_at(points, 0.0, waves=False), [[0.2, 0.1, 0.0]] * 2)


def _state(pos_m) -> BodyState:
    body = load_body()
    n = len(body.segment_names)
    return BodyState(0.0, np.asarray(pos_m, float), np.tile([0.0, 0.0, 0.0, 1.0], (n, 1)), np.zeros((n, 3)),
                     np.zeros((n, 3)), body.segments)


def test_the_plates_meet_the_water_where_each_segment_is():
    """A water file that is one uniform flow gives the plates the forces the same --current gives;
    a vortex gives each segment the water at its own place (here, a body 2 m from the centre)."""
    body = load_body()
    pos = np.column_stack([np.linspace(-0.8, 0.8, len(body.segment_names)), np.full(len(body.segment_names), 2.0),
                           np.full(len(body.segment_names), -0.3)])
    state = _state(pos)
    current = PlateFluid(body, water(current_m_s=(0.3, 0.1, 0.0)), -9.81).wrenches(state)
    uniform = field({"type": "uniform", "velocity_m_s": {"x": 0.3, "y": 0.1}})
    as_file = PlateFluid(body, water(flow=uniform), -9.81).wrenches(state)
    np.testing.assert_allclose(as_file.force_n, current.force_n, atol=1e-9)
    vortex = field({"type": "vortex", "center_m": {"x": 0.0, "y": 0.0}, "circulation_m2_s": 5.0,
                    "core_radius_m": 0.1})
    flow = PlateFluid(body, water(flow=vortex), -9.81).wrenches(state).flow_m_s
    own = vortex.velocity_m_s(pos, 0.0)
    # Each segment's water differs by the same swimmer-induced part (the body is still: none here).
    np.testing.assert_allclose(flow, own, atol=1e-12)
    assert np.ptp(flow[:, 1]) > 0.05


@pytest.mark.parametrize("flows, words", [
    ([{"type": "whirlpool"}], ["flows.0", "whirlpool"]),
    ([{"type": "vortex", "center_m": {"x": 0, "y": 0}}], ["flows.0", "circulation_m2_s"]),
    ([{"type": "source", "center_m": {"x": 0, "y": 0}, "strength_m2_s": -1}], ["flows.0", "strength_m2_s"]),
    ([], ["flows"]),
])
def test_a_bad_water_file_is_a_clear_error(flows, words):
    with pytest.raises(ConfigError) as err:
        parse_water({"name": "bad", "flows": flows}, "bad.yaml")
    assert "bad.yaml" in str(err.value) and all(w in str(err.value) for w in words)


def test_a_wave_too_steep_for_linear_theory_is_refused():
    with pytest.raises(ConfigError, match="flows.0.amplitude_m"):
        field({"type": "wave", "amplitude_m": 1.0, "wavelength_m": 4.0})


def test_the_shipped_water_files_load():
    assert {"river_bend", "outflow", "wave_train"} <= set(available_waters())
    for name in available_waters():
        flow = load_water(name)
        assert np.all(np.isfinite(flow.velocity_m_s(np.array([[0.0, 0.0, -0.3], [5.0, 2.5, -0.3]]), 1.0)))


def test_follow_swims_in_a_water_file_and_saves_it_with_the_run(tmp_path):
    out = tmp_path / "fig8"
    result = cli("follow", "figure_eight", "--water", "river_bend", "--seconds", "2", "--out", str(out), "--json")
    assert result.returncode == 0, result.stderr
    saved = json.loads((out / "config.json").read_text())["swim"]["medium"]["flow"]
    assert saved["name"] == "river_bend" and saved["flows"][0]["type"] == "vortex"
    replay = cli("run", "--config", str(out / "config.json"), "--out", str(tmp_path / "again"), "--json")
    assert replay.returncode == 0, replay.stderr
    assert json.loads(replay.stdout)["mean_distance_m"] == json.loads(result.stdout)["mean_distance_m"]


def test_render_draws_a_water_files_flow(tmp_path):
    still = cli("render", "figure_eight", "--seconds", "1", "--frame", "1", "--size", "320x180", "--flow",
                "--out", str(tmp_path / "plain.png"))
    with_water = cli("render", "figure_eight", "--seconds", "1", "--frame", "1", "--size", "320x180", "--flow",
                     "--water", "river_bend", "--out", str(tmp_path / "bend.png"))
    assert still.returncode == 0 and with_water.returncode == 0, with_water.stderr
    plain, bend = (frames_of_png(tmp_path / name) for name in ("plain.png", "bend.png"))
    assert np.abs(plain - bend).mean() > 0.1


def frames_of_png(path):
    from PIL import Image

    return np.asarray(Image.open(path).convert("RGB")).astype(int)


@pytest.mark.parametrize("args, words", [
    (("follow", "figure_eight", "--water", "no_such_water"), ["water", "no_such_water"]),
    (("follow", "figure_eight", "--water", "river_bend", "--backend", "sph", "--seconds", "1"),
     ["--water", "plate"]),
])
def test_water_file_errors_are_one_line(args, words, tmp_path):
    assert_one_line_error(cli(*args, "--out", str(tmp_path / "x")), *words)


def test_the_app_session_swims_in_a_water_file_draws_its_flow_and_names_it():
    from layered_swim.render.hud import hud_lines
    from layered_swim.render.session import SwimSession

    session = SwimSession("breaststroke", water="river_bend")
    try:
        session.step(240)
        scene = session.scene()
        lattice = np.array([[0.0, 0.0, -0.3], [0.0, 4.0, -0.3]])
        np.testing.assert_allclose(scene.water_at(lattice), load_water("river_bend").velocity_m_s(lattice, 0.0))
        assert "water river_bend" in "\n".join(hud_lines(session, fps=30.0))
    finally:
        session.close()
    with pytest.raises(ConfigError, match="unknown water"):
        SwimSession(water="nowhere")
