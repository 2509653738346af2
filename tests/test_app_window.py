"""The real window under Xvfb: a click on the water moves the target and the swimmer turns to it,
screenshots show swimmer, water and target, keys change the state, and the app's benchmark flag.

pyglet connects to the display when first imported, so it is imported only after the fixture has
started Xvfb (``.ci/run`` installs it). Without Xvfb these tests fail under CI and skip elsewhere.
"""
import json
import math
import os
import shutil
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
from PIL import Image

REPO = Path(__file__).resolve().parents[1]


@pytest.fixture(scope="module")
def display():
    if os.environ.get("DISPLAY"):
        yield os.environ["DISPLAY"]
        return
    if shutil.which("Xvfb") is None:
        message = "Xvfb is not installed (.ci/run installs it: apt-get install xvfb)"
        if os.environ.get("CI"):
            pytest.fail(message)
        pytest.skip(message)
    read_fd, write_fd = os.pipe()
    xvfb = subprocess.Popen(["Xvfb", "-displayfd", str(write_fd), "-screen", "0", "1280x800x24", "-nolisten", "tcp"],
                            pass_fds=[write_fd], stderr=subprocess.DEVNULL)
    os.close(write_fd)
    with os.fdopen(read_fd) as pipe:
        number = pipe.readline().strip()
    os.environ["DISPLAY"] = f":{number}"
    yield os.environ["DISPLAY"]
    xvfb.terminate()
    xvfb.wait(timeout=10)
    del os.environ["DISPLAY"]


@pytest.fixture
def window(display, tmp_path):
    from layered_swim.render.session import SwimSession
    from layered_swim.render.window import SwimWindow

    w = SwimWindow(SwimSession("breaststroke"), 960, 540, capture_dir=tmp_path)
    w.dispatch_events()
    w.frame(1 / 60)
    yield w
    if w.context is not None:
        w.close()


def press(window, symbol):
    window.dispatch_event("on_key_press", symbol, 0)
    window.dispatch_events()
    window.frame(1 / 60)


def test_click_on_the_water_sets_the_target_and_the_swimmer_turns_to_it(window):
    from pyglet.window import mouse

    s = window.session
    com = s.com_m
    wanted = np.array([com[0] + 3.0, com[1] + 5.0, 0.0])           # ahead and well to the left
    x, y = window.camera.project(wanted, window.width, window.height)
    window.dispatch_event("on_mouse_press", int(round(x)), int(round(y)), mouse.LEFT, 0)
    window.dispatch_events()
    assert not s.target.scripted
    assert s.target_m[:2] == pytest.approx(wanted[:2], abs=0.1)    # to within a pixel's width
    assert s.target_m[2] == pytest.approx(-s.target_depth_m)

    def heading_error_deg():
        to_target = s.target_m - s.com_m
        return abs(math.degrees(math.remainder(math.atan2(to_target[1], to_target[0]) - s.heading_rad, math.tau)))

    before = heading_error_deg()
    for _ in range(6):                      # six simulated seconds, drawing a frame after each
        s.step(s.physics_hz)
        window.frame(1 / 60)
    assert before > 45.0
    assert heading_error_deg() < 25.0
    assert math.degrees(s.heading_rad) > 30.0    # it turned left, toward the click


def test_screenshot_shows_swimmer_water_and_target(window, tmp_path):
    from pyglet.window import key

    s = window.session
    s.set_target((s.com_m[0] + 2.5, s.com_m[1] - 1.0))
    press(window, key.S)
    shots = list(tmp_path.glob("swim-*.png"))
    assert len(shots) == 1 and "screenshot saved" in s.message
    image = np.asarray(Image.open(shots[0]).convert("RGB")).astype(int)
    assert image.shape == (540, 960, 3)
    r, g, b = image[..., 0], image[..., 1], image[..., 2]
    is_water = b - r > 80                  # open water: neither the sky nor the swimmer under its surface
    assert is_water.mean() > 0.4
    is_target = (r > 150) & (b > 120) & (g < 90)
    assert is_target.sum() > 400           # the marker itself, not just its 1-pixel depth line

    # The swimmer: around its projected segments most pixels are not open water; an equal patch
    # of open water elsewhere is (grid lines aside).
    pixels = np.array([window.camera.project(p, 960, 540) for p in s.sim.state.pos_m])
    (x0, y0), (x1, y1) = pixels.min(axis=0).astype(int), pixels.max(axis=0).astype(int)
    rows = slice(540 - y1, 540 - y0 + 1)     # image rows run top down, pixel y bottom up
    swimmer_patch = ~is_water[rows, x0:x1 + 1]
    open_patch = ~is_water[-(y1 - y0 + 1):, :x1 - x0 + 1]
    assert swimmer_patch.size > 400
    assert swimmer_patch.mean() > 0.3
    assert open_patch.mean() < 0.1


def test_keys_change_the_state(window):
    from pyglet.window import key

    s = window.session
    strokes = s.strokes
    press(window, key.TAB)
    assert s.stroke == strokes[(strokes.index("breaststroke") + 1) % len(strokes)]
    press(window, key._1)
    assert s.stroke == strokes[0]
    for symbol, layer in ((key.C, "cycle"), (key.P, "palm"), (key.A, "reach")):
        before = getattr(s.sim.controller.layers, layer)
        press(window, symbol)
        assert getattr(s.sim.controller.layers, layer) != before
    press(window, key.U)
    assert s.current_index == 1 and s.sim.fluid.medium.current_m_s == (0.0, 0.3, 0.0)
    press(window, key.D)
    assert s.sim.fluid.medium.rho_kg_m3 == pytest.approx(1023.3)
    press(window, key.SPACE)
    assert s.paused
    t = s.sim.time_s
    press(window, key.N)
    assert s.sim.time_s == pytest.approx(t + 1 / 60)
    press(window, key.SPACE)
    press(window, key.M)
    assert s.slow_motion
    press(window, key.W)
    assert window.show_flow
    press(window, key.K)
    assert window.camera.view_name == "side" and window.camera.eye_m[2] == pytest.approx(0.0)
    assert "camera: side" in s.message
    press(window, key.K)
    assert window.camera.eye_m[2] < 0.0
    press(window, key.H)
    assert window.show_help and "palm-orientation rule" in window.help_text() and "next camera" in window.help_text()
    press(window, key.R)
    assert s.sim.time_s < 0.1


def test_video_recording_writes_frames(window):
    from pyglet.window import key

    press(window, key.V)
    assert window.recorder is not None
    for _ in range(5):
        window.frame(1 / 30)
    press(window, key.V)
    assert window.recorder is None and "saved" in window.session.message
    outputs = list(Path(window.capture_dir).glob("swim-*"))
    assert outputs and all(p.stat().st_size > 0 for p in outputs)


def app(*args, env=None):
    return subprocess.run([sys.executable, str(REPO / "app.py"), *args], cwd=REPO, capture_output=True, text=True,
                          timeout=180, env=env)


def test_benchmark_frames_prints_fps_and_realtime_factor(display):
    result = app("--benchmark-frames", "40", "--size", "640x360", env={**os.environ, "DISPLAY": display})
    assert result.returncode == 0, result.stderr
    figures = json.loads(result.stdout)
    assert figures["frames"] == 38
    assert figures["mean_fps"] > 5 and 0.2 < figures["realtime_factor"] < 1.5


@pytest.mark.parametrize("args, words", [
    (("--stroke", "dog_paddle"), ("unknown stroke", "dog_paddle")),
    (("--trajectory", "missing.yaml"), ("missing.yaml",)),
    (("--current", "1,2"), ("--current",)),
    (("--size", "big"), ("--size",)),
])
def test_bad_arguments_fail_before_any_window(args, words):
    result = app(*args, env={k: v for k, v in os.environ.items() if k != "DISPLAY"})
    assert result.returncode == 2
    lines = result.stderr.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith("app.py: error: ") and "Traceback" not in result.stderr
    assert all(w in lines[0] for w in words)


def test_readme_lists_every_key(display):
    from layered_swim.render.window import BINDINGS

    readme = (REPO / "README.md").read_text()
    table = readme[readme.index("| input | does |"):].split("\n\n")[0]
    listed = {key.strip() for row in table.splitlines()[2:] for cell in [row.split("|")[1]]
              for part in cell.split(",") for key in part.split(" / ")}
    for binding in BINDINGS:
        assert set(binding.label.split("/")) <= listed, binding.label
