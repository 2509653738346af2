"""Targets: constant speed along curves, polyline timing, looping, shipped files, one-line errors."""
import textwrap

import numpy as np
import pytest

from layered_swim.config import ConfigError
from layered_swim.control.targets import (
    FixedTarget,
    MovableTarget,
    StationTarget,
    Target,
    available_trajectories,
    load_trajectory,
)

CURVES = {
    "figure_eight": "size_m: {x: 10, y: 5}\ncenter_m: {x: 1, y: -2}\n",
    "circle": "radius_m: 4\ncenter_m: {x: 0, y: 4}\n",
    "sinusoid": "start_m: {x: 0, y: 0}\nheading_deg: 30\nlength_m: 20\namplitude_m: 1.5\nwavelength_m: 6\n",
    "line": "start_m: {x: 2, y: 0}\nheading_deg: 0\nlength_m: 80\n",
}
POLYLINE = textwrap.dedent("""\
    name: p
    type: polyline
    loop: true
    closing_s: 5
    waypoints:
      - {t_s: 0, x: 0, y: 0, z: -0.3}
      - {t_s: 10, x: 5, y: 0, z: -0.3}
      - {t_s: 20, x: 5, y: 4, z: -2.3}
""")


def write(tmp_path, text, name="traj.yaml"):
    path = tmp_path / name
    path.write_text(text)
    return path


def curve(tmp_path, kind, extra="", speed=0.5, depth=0.3):
    text = f"name: {kind}\ntype: {kind}\nspeed_m_s: {speed}\ndepth_m: {depth}\n" + CURVES[kind] + extra
    return load_trajectory(write(tmp_path, text))


def positions(target, times):
    return np.array([target.position(t) for t in times])


@pytest.mark.parametrize("kind", sorted(CURVES))
def test_constant_speed_along_curves(tmp_path, kind):
    target = curve(tmp_path, kind, "loop: true\n", speed=0.7, depth=0.4)
    assert isinstance(target, Target)
    dt = 0.01
    times = np.arange(0.0, min(target.duration_s, 60.0) - dt, 0.37)
    steps = np.linalg.norm(positions(target, times + dt) - positions(target, times), axis=1)
    np.testing.assert_allclose(steps / dt, 0.7, rtol=1e-3)
    assert np.all(positions(target, times)[:, 2] == -0.4)


def test_figure_eight_extents_and_crossing(tmp_path):
    target = curve(tmp_path, "figure_eight")
    pts = target.path_points(4000)
    assert pts[:, 0].max() - pts[:, 0].min() == pytest.approx(10.0, abs=1e-3)
    assert pts[:, 1].max() - pts[:, 1].min() == pytest.approx(5.0, abs=1e-3)
    np.testing.assert_allclose(pts.mean(axis=0)[:2], [1.0, -2.0], atol=1e-2)
    np.testing.assert_allclose(target.position(0.0), [1.0, -2.0, -0.3], atol=1e-9)   # starts at the crossing
    assert target.position(1.0)[0] > 1.0                                            # into the +x lobe


def test_circle_radius_direction_and_start(tmp_path):
    target = curve(tmp_path, "circle", "loop: true\n")
    np.testing.assert_allclose(target.position(0.0), [0.0, 0.0, -0.3], atol=1e-9)
    assert target.duration_s == pytest.approx(2 * np.pi * 4 / 0.5, rel=1e-5)
    radii = np.linalg.norm(positions(target, np.linspace(0, 60, 97))[:, :2] - [0.0, 4.0], axis=1)
    np.testing.assert_allclose(radii, 4.0, atol=1e-4)
    assert target.position(0.5)[0] > 0 and target.position(0.5)[1] > 0       # counterclockwise: +x, turning left
    cw = curve(tmp_path, "circle", "counterclockwise: false\nstart_angle_deg: 90\n")
    np.testing.assert_allclose(cw.position(0.0), [0.0, 8.0, -0.3], atol=1e-9)
    assert cw.position(0.5)[0] > 0                                             # clockwise from the top: +x


def test_start_s_and_no_loop_clamp(tmp_path):
    target = curve(tmp_path, "line", "start_s: 4\n")
    np.testing.assert_allclose(target.position(0.0), [4.0, 0.0, -0.3])
    np.testing.assert_allclose(target.position(10.0), [9.0, 0.0, -0.3])
    np.testing.assert_allclose(target.position(1000.0), [82.0, 0.0, -0.3])
    np.testing.assert_allclose(target.position(-100.0), [2.0, 0.0, -0.3])


def test_loop_wraps(tmp_path):
    target = curve(tmp_path, "circle", "loop: true\n")
    for t in (0.0, 3.3, 17.0):
        np.testing.assert_allclose(target.position(t + 2 * target.duration_s), target.position(t), atol=1e-6)
    line = curve(tmp_path, "line", "loop: true\n")
    np.testing.assert_allclose(line.position(161.0), [2.5, 0.0, -0.3], atol=1e-9)


def test_polyline_interpolates_in_time_and_closes_the_loop(tmp_path):
    target = load_trajectory(write(tmp_path, POLYLINE))
    np.testing.assert_allclose(target.position(0.0), [0, 0, -0.3])
    np.testing.assert_allclose(target.position(10.0), [5, 0, -0.3])
    np.testing.assert_allclose(target.position(20.0), [5, 4, -2.3])
    np.testing.assert_allclose(target.position(2.5), [1.25, 0, -0.3])
    np.testing.assert_allclose(target.position(15.0), [5, 2, -1.3])
    np.testing.assert_allclose(target.position(22.5), [2.5, 2, -1.3])         # half-way back over closing_s
    assert target.duration_s == pytest.approx(25.0)
    np.testing.assert_allclose(target.position(25.0 + 15.0), target.position(15.0))
    once = load_trajectory(write(tmp_path, POLYLINE.replace("loop: true\nclosing_s: 5\n", "")))
    np.testing.assert_allclose(once.position(100.0), [5, 4, -2.3])


def test_straight_line_file():
    target = load_trajectory("straight_line")
    np.testing.assert_allclose(target.position(0.0), [2.0, 0.0, -0.3])
    times = np.linspace(0.0, 120.0, 13)
    np.testing.assert_allclose(positions(target, times),
                               np.column_stack([2 + 0.5 * times, 0 * times, -0.3 + 0 * times]), atol=1e-9)


@pytest.mark.parametrize("name", available_trajectories())
def test_shipped_trajectories_load(name):
    target = load_trajectory(name)
    assert target.name == name and target.description
    assert np.all(np.isfinite(target.path_points())) and np.all(target.path_points()[:, 2] <= 0.0)
    if target.kind != "stations":          # a fixed or jumping target may be anywhere
        assert target.duration_s > 0
        assert np.linalg.norm(target.position(0.0)[:2]) < 3.0      # starts near the swimmer


def test_required_files_are_shipped():
    assert {"figure_eight", "circle", "zigzag", "dive_and_surface", "straight_line", "square", "small_loops",
            "deep_dive", "stationary_behind", "jumping", "sinusoid"} <= set(available_trajectories())
    dive = load_trajectory("dive_and_surface").path_points(2000)
    assert dive[:, 2].min() == pytest.approx(-2.0) and dive[0, 2] == dive[-1, 2] == pytest.approx(-0.3)
    weave = load_trajectory("sinusoid").path_points(4000)          # 1.5 m either side of the x axis
    assert weave[:, 1].max() == pytest.approx(1.5, abs=1e-3) and weave[:, 1].min() == pytest.approx(-1.5, abs=1e-3)


def test_fixed_and_movable_targets():
    fixed = FixedTarget([1, 2, -0.5])
    np.testing.assert_allclose(fixed.position(3.0), [1, 2, -0.5])
    assert fixed.path_points().shape == (1, 3)
    mouse = MovableTarget((0, 0, -0.3))
    mouse.set(np.array([4.0, -1.0, -0.2]))
    np.testing.assert_allclose(mouse.position(0.0), [4, -1, -0.2])
    np.testing.assert_allclose(mouse.path_points(), [[4, -1, -0.2]])
    with pytest.raises(ValueError):
        mouse.set([1.0, np.nan, 0.0])
    assert isinstance(fixed, Target) and isinstance(mouse, Target)


LINE = "name: l\ntype: line\nspeed_m_s: 0.5\ndepth_m: 0.3\nstart_m: {x: 2, y: 0}\nheading_deg: 0\nlength_m: 80\n"


@pytest.mark.parametrize("text, words", [
    (POLYLINE.replace("t_s: 20", "t_s: 10"), ["waypoints.2.t_s", "times must increase"]),
    (POLYLINE.replace("t_s: 0,", "t_s: 1,"), ["waypoints.0.t_s"]),
    (POLYLINE.replace("z: -2.3", "z: 2.3"), ["waypoints.2.z", "<= 0"]),
    (POLYLINE.replace("x: 5, y: 4", "x: .nan, y: 4"), ["waypoints.2.x"]),
    (POLYLINE.replace("x: 5, y: 4", "y: 4"), ["waypoints.2.x", "required"]),
    (POLYLINE.split("  - {t_s: 10")[0], ["waypoints", "at least 2"]),
    (POLYLINE.replace("closing_s: 5\n", ""), ["closing_s", "required when loop"]),
    (POLYLINE.replace("loop: true", "loop: false"), ["closing_s", "only used when loop"]),
    (POLYLINE.replace("loop: true", "loop: true\nspeed_m_s: 0.5"), ["speed_m_s"]),
    (LINE.replace("speed_m_s: 0.5", "speed_m_s: -0.5"), ["speed_m_s"]),
    (LINE.replace("speed_m_s: 0.5", "speed_m_s: .nan"), ["speed_m_s"]),
    (LINE.replace("depth_m: 0.3", "depth_m: -0.3"), ["depth_m"]),
    (LINE.replace("length_m: 80", "length_m: 0"), ["length_m"]),
    (LINE.replace("heading_deg: 0\n", ""), ["heading_deg"]),
    (LINE.replace("{x: 2, y: 0}", "[2, 0]"), ["start_m"]),
    (LINE.replace("{x: 2, y: 0}", "{x: 2, y: 0, z: 0}"), ["start_m.z"]),
    (LINE.replace("type: line", "type: spiral"), ["type", "spiral", "circle, figure_eight, line, polyline, sinusoid"]),
    (LINE.replace("type: line\n", ""), ["type", "missing"]),
    ("name: c\ntype: circle\nspeed_m_s: 0.5\ndepth_m: 0.3\nradius_m: -4\ncenter_m: {x: 0, y: 4}\n", ["radius_m"]),
    ("name: f\ntype: figure_eight\nspeed_m_s: 0.5\ndepth_m: 0.3\nsize_m: {x: 10, y: -5}\ncenter_m: {x: 0, y: 0}\n",
     ["size_m.y"]),
    ("- just\n- a list\n", ["mapping"]),
    ("name: [unclosed\n", ["line"]),
])
def test_bad_trajectory_file(tmp_path, text, words):
    path = write(tmp_path, text, "bad.yaml")
    with pytest.raises(ConfigError) as err:
        load_trajectory(path)
    message = str(err.value)
    assert "\n" not in message
    assert str(path) in message and all(word in message for word in words), message


def test_missing_file_and_unknown_name(tmp_path):
    with pytest.raises(ConfigError, match="not found"):
        load_trajectory(tmp_path / "nope.yaml")
    with pytest.raises(ConfigError, match="unknown trajectory 'nope'.*figure_eight"):
        load_trajectory("nope")


def test_position_is_cheap(tmp_path):
    import time
    target = curve(tmp_path, "figure_eight", "loop: true\n")
    start = time.perf_counter()
    for k in range(2000):
        target.position(k / 120.0)
    assert (time.perf_counter() - start) / 2000 < 1e-4


STATIONS = textwrap.dedent("""\
    name: s
    type: stations
    stations:
      - {t_s: 0, x: 4, y: 0, z: -0.3}
      - {t_s: 25, x: 4, y: -8, z: -1}
""")


def test_a_station_target_holds_each_point_until_its_jump(tmp_path):
    target = load_trajectory(write(tmp_path, STATIONS))
    assert isinstance(target, StationTarget) and isinstance(target, Target) and target.kind == "stations"
    np.testing.assert_allclose(positions(target, [0.0, 24.99, 25.0, 1e4]),
                               [[4, 0, -0.3], [4, 0, -0.3], [4, -8, -1], [4, -8, -1]])
    assert [t for t, _ in target.stations] == [0.0, 25.0]
    np.testing.assert_allclose(target.path_points(), [[4, 0, -0.3], [4, -8, -1]])


def test_only_a_path_known_ahead_invites_looking_ahead(tmp_path):
    assert load_trajectory("figure_eight").foresight
    assert not load_trajectory(write(tmp_path, STATIONS)).foresight          # a jump is not announced
    assert not FixedTarget([0, 0, -0.3]).foresight and not MovableTarget([0, 0, -0.3]).foresight


@pytest.mark.parametrize("text, field", [
    (STATIONS.replace("t_s: 25", "t_s: 0"), "stations.1.t_s"),
    (STATIONS.replace("t_s: 0,", "t_s: 1,"), "stations.0.t_s"),
    (STATIONS.replace("z: -1", "z: 1"), "stations.1.z"),
])
def test_bad_stations_name_the_field(tmp_path, text, field):
    with pytest.raises(ConfigError, match=field.replace(".", r"\.")):
        load_trajectory(write(tmp_path, text))
