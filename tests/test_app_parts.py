"""The app's parts that need no window: camera picking, scene geometry, the interactive session's
clock and switches, the HUD text and the frame writer."""
import math
from pathlib import Path

import numpy as np
import pytest
from PIL import Image

from layered_swim.config import ConfigError
from layered_swim.render import scene as sc
from layered_swim.render.camera import VIEWS, OrbitCamera, look_at, perspective
from layered_swim.render.frames import FrameWriter
from layered_swim.render.headless import steps_between
from layered_swim.render.hud import hud_lines
from layered_swim.render.session import MAX_LAG_S, SLOW_MOTION, SwimSession


def test_look_at_puts_the_focus_straight_ahead():
    view = look_at(np.array([0.0, -5.0, 0.0]), np.zeros(3))
    assert view @ np.array([0.0, 0.0, 0.0, 1.0]) == pytest.approx([0.0, 0.0, -5.0, 1.0])
    assert view @ np.array([1.0, 0.0, 0.0, 1.0]) == pytest.approx([1.0, 0.0, -5.0, 1.0])   # world +x is screen right


def test_perspective_maps_near_and_far_planes_to_the_depth_range():
    m = perspective(math.radians(60), 2.0, 0.1, 100.0)
    for z, ndc in ((-0.1, -1.0), (-100.0, 1.0)):
        clip = m @ np.array([0.0, 0.0, z, 1.0])
        assert clip[2] / clip[3] == pytest.approx(ndc)


def test_water_point_inverts_projection():
    camera = OrbitCamera(focus_m=np.array([3.0, -2.0, 0.0]))
    for point in ([3.0, -2.0, 0.0], [6.0, 1.0, 0.0], [1.0, -4.5, 0.0]):
        pixel = camera.project(np.array(point), 1280, 720)
        assert camera.water_point(*pixel, 1280, 720) == pytest.approx(point, abs=1e-6)
    assert camera.water_point(640, 719, 1280, 720)[2] == pytest.approx(0.0)
    assert OrbitCamera(pitch_rad=math.radians(5)).water_point(640, 719.9, 1280, 720) is None   # above the horizon


def test_camera_orbit_stays_above_water_and_zoom_is_bounded():
    camera = OrbitCamera()
    camera.orbit(0, 10_000)
    assert camera.eye_m[2] > 0
    camera.zoom(-100)
    assert camera.distance_m == pytest.approx(60.0)
    camera.follow(np.array([10.0, 0.0, -1.0]), dt_s=100.0)
    assert camera.focus_m == pytest.approx([10.0, 0.0, 0.0])     # focus kept at the surface


def test_views_put_the_eye_above_on_and_under_the_surface():
    camera = OrbitCamera(focus_m=np.array([2.0, 1.0, 0.0]))
    assert camera.eye_m[2] > 1.0
    camera.set_view("side")
    assert camera.eye_m[2] == pytest.approx(0.0)
    camera.orbit(0, 500)
    assert camera.eye_m[2] == pytest.approx(0.0)                  # level with the surface, however dragged
    assert camera.next_view() == "underwater"
    for drag in (-10_000, 10_000):
        camera.orbit(0, drag)
        assert camera.eye_m[2] < 0.0
    camera.zoom(-100)
    assert camera.distance_m == VIEWS["underwater"].max_distance_m
    assert camera.next_view() == "follow" and camera.eye_m[2] > 0


def test_side_and_underwater_views_turn_with_the_swimmer():
    camera = OrbitCamera()
    camera.set_view("side")
    for k in range(1, 301):                                      # 5 s swimming along +y at 1 m/s
        camera.follow(np.array([0.0, k / 60, -0.3]), 1 / 60)
    assert math.degrees(camera.heading_rad) == pytest.approx(90.0, abs=1.0)
    to_eye = camera.eye_m - camera.focus_m
    assert to_eye[0] > 0.99 * camera.distance_m                  # square to its right: +x of a swimmer heading +y
    held = camera.heading_rad
    for _ in range(60):                                           # it stops: the view holds
        camera.follow(np.array([0.0, 5.0, -0.3]), 1 / 60)
    camera.follow(np.array([0.0, 5.0, -0.3]), 1 / 60)
    assert camera.heading_rad == pytest.approx(held, abs=math.radians(3))


def test_water_point_from_under_water():
    camera = OrbitCamera(focus_m=np.array([1.0, 2.0, 0.0]))
    camera.set_view("underwater")
    point = np.array([1.5, 2.5, 0.0])
    assert camera.water_point(*camera.project(point, 960, 540), 960, 540) == pytest.approx(point, abs=1e-6)
    assert camera.water_point(480, 1, 960, 540) is None           # down into the deep: no surface there


def test_flow_lattice_stays_put_and_lies_under_water():
    a, b = sc.flow_lattice(np.array([0.2, 0.1, -0.3])), sc.flow_lattice(np.array([0.4, -0.3, -0.5]))
    assert np.array_equal(a, b) and len(a) == (2 * sc.FLOW_HALF_POINTS + 1) ** 2 * len(sc.FLOW_DEPTHS_M)
    assert (a[:, 2] < 0).all()
    assert sc.cross_lines(a).shape == (4 * len(a), 3)


def test_render_cameras_are_the_views():
    from layered_swim.commands.render import CAMERAS

    assert CAMERAS == tuple(VIEWS)


def test_box_triangles_span_the_rotated_box():
    quarter_turn_z = np.array([[0.0, 0.0, math.sin(math.pi / 4), math.cos(math.pi / 4)]])
    vertices, normals = sc.box_triangles(np.array([[1.0, 2.0, 3.0]]), quarter_turn_z, np.array([[0.5, 0.1, 0.2]]))
    assert vertices.shape == (36, 3)
    assert vertices.min(axis=0) == pytest.approx([0.9, 1.5, 2.8])      # the long x side now lies along y
    assert vertices.max(axis=0) == pytest.approx([1.1, 2.5, 3.2])
    assert np.linalg.norm(normals, axis=1) == pytest.approx(np.ones(36))
    # Every triangle winds counterclockwise seen from outside: its geometric normal matches.
    tri = vertices.reshape(-1, 3, 3)
    winding = np.cross(tri[:, 1] - tri[:, 0], tri[:, 2] - tri[:, 0])
    assert (np.einsum("ij,ij->i", winding, normals[::3]) > 0).all()


def test_arrow_lines_shaft_and_head():
    lines = sc.arrow_lines(np.array([0.0, 0.0, 0.0]), np.array([2.0, 0.0, 0.0]))
    assert lines.shape == (6, 3)
    assert lines[0] == pytest.approx([0, 0, 0]) and lines[1] == pytest.approx([2, 0, 0])
    assert lines[3] == pytest.approx([1.5, -0.25, 0.0]) and lines[5] == pytest.approx([1.5, 0.25, 0.0])
    assert np.isfinite(sc.arrow_lines(np.zeros(3), np.array([0.0, 0.0, 1.0]))).all()   # vertical arrow


def test_grid_snaps_to_world_multiples():
    a, b = sc.grid_lines(np.array([0.3, 0.2, 0.0])), sc.grid_lines(np.array([0.9, -0.7, 0.0]))
    assert np.array_equal(a, b)          # the grid stays put while the focus moves within a cell
    assert set(np.round(a[:, 2], 6)) == {-sc.GRID_DEPTH_M}


def test_segment_colors_tell_cap_suit_and_sides_apart():
    colors = sc.segment_colors(("pelvis", "head", "left_hand", "right_hand"))
    assert colors[1, :3] == pytest.approx(sc.CAP)
    assert colors[0, :3] == pytest.approx(sc.SUIT)
    assert colors[2, 0] < colors[3, 0]


def test_steps_between_frames_add_up_exactly():
    assert sum(steps_between(k / 30, (k + 1) / 30, 480) for k in range(30)) == 480
    assert sum(steps_between(k / 7, (k + 1) / 7, 480) for k in range(7 * 5)) == 480 * 5
    assert steps_between(0.9, 0.95, 480) == 24                   # a still's last stretch, off the frame grid


@pytest.fixture(scope="module")
def session():
    s = SwimSession("breaststroke")
    yield s
    s.close()


def test_session_fixed_step_clock(session):
    session.reset()
    assert session.advance(1 / 60) == 8                      # 480 Hz: eight steps a 60 Hz frame
    assert session.advance(1.0) == round(MAX_LAG_S * 480)    # a long stall is dropped, not owed
    assert session.falling_behind
    session.slow_motion = True
    assert sum(session.advance(1 / 60) for _ in range(60)) == round(480 * SLOW_MOTION)
    session.slow_motion, session.paused = False, True
    assert session.advance(1.0) == 0
    session.paused = False


def test_session_switches_apply_to_the_running_simulation(session):
    session.reset()
    session.toggle_layer("cycle")
    assert not session.sim.controller.layers.cycle
    session.toggle_layer("palm")
    assert not session.sim.controller.layers.palm
    session.toggle_layer("cycle")
    session.toggle_layer("palm")
    session.next_current()
    assert session.sim.fluid.medium.current_m_s == (0.0, 0.3, 0.0)
    sim = session.sim
    session.next_density()
    assert session.sim.fluid.medium.rho_kg_m3 == pytest.approx(1023.3)
    assert session.sim.fluid.medium == session._medium()
    assert session.sim is sim                     # seawater: the same stroke, no trim
    session.next_density()                        # light fluid: the breaststroke is rebuilt, trimmed
    assert session.sim is not sim and "trimmed" in session.message
    assert session.sim.fluid.medium.rho_kg_m3 == pytest.approx(800.0) and session.sim.fluid.medium == session._medium()
    assert session.sim.controller.layers.cycle and session.sim.fluid.medium.current_m_s == (0.0, 0.3, 0.0)
    session.current_index = session.density_index = 0
    session.step(480)
    where = session.com_m
    session.set_stroke("treading_water")
    assert session.stroke == "treading_water" and session.sim.controller.layers.cycle
    assert session.com_m[:2] == pytest.approx(where[:2], abs=0.3)    # switched in place
    session.set_stroke("rest")                                       # no calibration table
    assert not session.cycle_available and "calibration" in session.message
    assert not session.sim.controller.layers.cycle
    session.set_stroke("breaststroke")


def test_session_target_and_depth(session):
    session.reset()
    session.set_target((4.0, 3.0))
    assert session.target_m == pytest.approx([4.0, 3.0, -0.3])
    session.change_target_depth(10.0)
    assert session.target_m[2] == pytest.approx(-3.0)
    session.change_target_depth(-10.0)
    assert session.target_m[2] == pytest.approx(0.0)
    session.change_target_depth(0.3)


def test_session_rejects_bad_input():
    with pytest.raises(ConfigError, match="unknown stroke"):
        SwimSession("dog_paddle")
    with pytest.raises(ConfigError, match="unknown trajectory"):
        SwimSession(trajectory="nowhere")


def test_hud_lists_the_figures(session):
    session.reset()
    session.step(480)
    text = "\n".join(hud_lines(session, fps=42.0))
    for word in ("breaststroke", "m/s", "stroke rate", "phase", "weights", "per-cycle on", "palm on", "reach on",
                 "997.05 kg/m3", "current none", "distance", "real time", "42 FPS"):
        assert word in text
    session.paused = True
    assert "PAUSED" in "\n".join(hud_lines(session, 0.0))
    session.paused = False


def test_auto_stroke_in_the_app_holds_the_mouse_target_and_the_hud_names_its_choice():
    s = SwimSession("auto")
    try:
        assert s.strokes[-1] == "auto"
        assert hud_lines(s, 60.0)[0].split() == ["stroke", "auto:", "breaststroke"]
        s.set_target((1.5, 0.0))              # a click just ahead: reach it, then hold it
        s.step(480 * 6)
        assert hud_lines(s, 60.0)[0].split() == ["stroke", "auto:", "treading_water"]
        assert s.distance_to_target_m < 1.0
    finally:
        s.close()


def test_frame_writer_png_fallback(tmp_path):
    writer = FrameWriter(tmp_path / "frames", fps=10)
    for shade in (0, 128):
        writer.add(np.full((8, 12, 3), shade, np.uint8))
    path = writer.close()
    frames = sorted(path.glob("frame_*.png"))
    assert [np.asarray(Image.open(f)).mean() for f in frames] == [0, 128]


SHIPPED_POLICIES = Path(__file__).resolve().parents[1] / "layered_swim/rl/policies"


@pytest.mark.parametrize("name", sorted(p.name for p in SHIPPED_POLICIES.glob("*.pt")))
def test_every_shipped_policy_drives_the_session_and_the_hud_says_so(name):
    from layered_swim.render.hud import hud_lines
    from layered_swim.rl.policy import ResidualPolicy

    policy = ResidualPolicy.load(SHIPPED_POLICIES / name)
    stroke = policy.env.stroke
    s = SwimSession(stroke, policy=policy)
    s.step(64)
    assert np.isfinite(s.com_m).all() and np.any(s.sim.controller.residual_rad != 0.0)
    assert any(f"learned residual on the {policy.env.reference} controller" in line for line in hud_lines(s, 60.0))
    s.toggle_layer("palm")
    assert "keeps the layers" in s.message
    s.close()
    with pytest.raises(ConfigError, match=f"trained for {stroke}"):
        SwimSession("breaststroke", policy=policy)
