"""``layered-swim render`` without a display: frames from a trajectory swum now and from a finished
run's log, non-empty and changing over time; an MP4 when the encoder is installed; one still PNG;
the water drawn as water (the surface over what is under it, tinted, from each camera)."""
import json
import os
import subprocess
import sys

import numpy as np
import pytest
from PIL import Image
from test_cli import REPO, assert_one_line_error, cli


def frames_of(folder):
    paths = sorted(folder.glob("frame_*.png"))
    return [np.asarray(Image.open(p).convert("RGB")).astype(int) for p in paths]


def assert_moving_picture(frames, count):
    assert len(frames) == count
    for frame in frames:
        assert frame.std() > 10                                   # a picture, not an empty image
    changes = [np.abs(a - b).mean() for a, b in zip(frames, frames[1:])]
    assert min(changes) > 0.05                                    # every frame differs from the last
    assert np.abs(frames[0] - frames[-1]).mean() > 0.5


@pytest.fixture(autouse=True)
def no_display(monkeypatch):
    monkeypatch.delenv("DISPLAY", raising=False)                 # headless EGL, whatever the test machine has


def test_render_trajectory_to_frames(tmp_path):
    result = cli("render", "figure_eight", "--seconds", "1", "--fps", "5", "--size", "320x180", "--forces",
                 "--out", str(tmp_path / "frames"))
    assert result.returncode == 0, result.stderr
    assert "wrote 6 frames" in result.stdout
    frames = frames_of(tmp_path / "frames")
    assert frames[0].shape == (180, 320, 3)
    assert_moving_picture(frames, 6)


def test_render_replays_a_run_folder(tmp_path):
    run = tmp_path / "run"
    assert cli("run", "--stroke", "breaststroke", "--seconds", "1", "--out", str(run)).returncode == 0
    result = cli("render", str(run), "--fps", "4", "--size", "320x180", "--out", str(tmp_path / "replay"))
    assert result.returncode == 0, result.stderr
    assert_moving_picture(frames_of(tmp_path / "replay"), 5)


def test_render_mp4(tmp_path):
    imageio_ffmpeg = pytest.importorskip("imageio_ffmpeg", reason="the video extra is not installed")
    out = tmp_path / "swim.mp4"
    result = cli("render", "straight_line", "--seconds", "1", "--fps", "8", "--size", "320x180", "--out", str(out))
    assert result.returncode == 0, result.stderr
    reader = imageio_ffmpeg.read_frames(str(out))
    meta = reader.__next__()
    assert meta["size"] == (320, 180)
    frames = [np.frombuffer(f, np.uint8).reshape(180, 320, 3).astype(int) for f in reader]
    assert len(frames) == 9
    assert frames[0].std() > 10 and np.abs(frames[0] - frames[-1]).mean() > 0.5


def test_a_still_frame_is_one_png_and_each_camera_shows_another_picture(tmp_path):
    pictures = {}
    for camera in ("follow", "side", "underwater"):
        out = tmp_path / camera / "swim.png"
        result = cli("render", "figure_eight", "--seconds", "1", "--frame", "0.5", "--camera", camera, "--flow",
                     "--size", "320x180", "--out", str(out))
        assert result.returncode == 0, result.stderr
        assert result.stdout.strip() == f"wrote 1 frame to {out}"
        assert [p.name for p in out.parent.iterdir()] == ["swim.png"]      # no frames, no leftovers
        pictures[camera] = np.asarray(Image.open(out).convert("RGB")).astype(int)
        assert pictures[camera].shape == (180, 320, 3) and pictures[camera].std() > 10
    for a, b in (("follow", "side"), ("side", "underwater"), ("follow", "underwater")):
        assert np.abs(pictures[a] - pictures[b]).mean() > 10, (a, b)
    again = cli("render", "figure_eight", "--seconds", "1", "--frame", "0.5", "--camera", "side", "--size", "320x180",
                "--out", str(tmp_path / "side" / "swim.png"))
    assert_one_line_error(again, "exists", "--overwrite")


def test_a_still_of_a_run_folder(tmp_path):
    run = tmp_path / "run"
    assert cli("run", "--stroke", "breaststroke", "--seconds", "1", "--out", str(run)).returncode == 0
    result = cli("render", str(run), "--frame", "0.75", "--size", "320x180", "--out", str(tmp_path / "still.png"))
    assert result.returncode == 0, result.stderr
    assert np.asarray(Image.open(tmp_path / "still.png")).std() > 10
    assert_one_line_error(cli("render", str(run), "--frame", "5", "--out", str(tmp_path / "late.png")),
                          "--frame", "past the swim's end")
    assert not (tmp_path / "late.png").exists()


# One upright post through the surface (half above, half under it), drawn by the renderer itself
# from each camera at two moments: what each picture shows where the post and the water are.
POST = """
import json, os, sys
os.environ["PYGLET_HEADLESS"] = "1"
import pyglet
pyglet.options["headless"] = True
import numpy as np
from layered_swim.render.camera import OrbitCamera
from layered_swim.render.renderer import Renderer, gl_config, read_pixels
from layered_swim.render.scene import Scene

W, H, folder = 320, 180, sys.argv[1]
scene = Scene(("pelvis",), np.array([[0.15, 0.15, 0.6]]), np.zeros((1, 3)), np.array([[0.0, 0.0, 0.0, 1.0]]))
window = pyglet.window.Window(W, H, visible=False, config=gl_config())
renderer = Renderer(scene.segment_names)
points = {"above": (0.0, 0.0, 0.35), "under": (0.0, 0.0, -0.35), "water": (0.0, -1.2, 0.0)}
pixels = {}
for view in ("follow", "side", "underwater"):
    camera = OrbitCamera()
    camera.set_view(view)
    for time_s in (0.0, 0.7):
        renderer.draw(scene, camera, W, H, time_s=time_s)
        np.save(f"{folder}/{view}-{time_s}.npy", read_pixels(W, H))
    pixels[view] = {name: [int(round(c)) for c in camera.project(np.array(p), W, H)] for name, p in points.items()}
print(json.dumps(pixels))
"""


@pytest.fixture(scope="module")
def post(tmp_path_factory):
    folder = tmp_path_factory.mktemp("post")
    env = {k: v for k, v in os.environ.items() if k != "DISPLAY"}
    result = subprocess.run([sys.executable, "-c", POST, str(folder)], cwd=REPO, env=env, capture_output=True,
                            text=True, timeout=120)
    assert result.returncode == 0, result.stderr
    return folder, json.loads(result.stdout)


def picture(post, view, time_s=0.0):
    return np.load(post[0] / f"{view}-{time_s}.npy").astype(int)


def patch(post, view, name, time_s=0.0):
    """The 5 x 5 pixels around where a point of the post (or the water beside it) is drawn."""
    x, y = post[1][view][name]
    return picture(post, view, time_s)[180 - y - 2:180 - y + 3, x - 2:x + 3].reshape(-1, 3)   # rows run top down


def bluer(rgb):
    return float((rgb[..., 2] - rgb[..., 0]).mean())


@pytest.mark.parametrize("view", ["follow", "side"])
def test_the_body_under_the_surface_is_tinted_and_above_it_is_not(post, view):
    above, under = patch(post, view, "above"), patch(post, view, "under")
    assert above[:, 0].mean() > above[:, 2].mean() + 40                  # the red suit, in air
    assert bluer(under) > bluer(above) + 60                               # the same suit, under water


def test_the_surface_lies_across_the_submerged_body_not_the_part_above(post):
    """From above, the surface's ripples move over the open water and over the post under the
    surface, not over the post above it."""
    moved = {name: np.abs(patch(post, "follow", name) - patch(post, "follow", name, 0.7)).mean()
             for name in ("above", "under", "water")}
    assert moved["above"] == 0
    assert moved["under"] > 0.5 and moved["water"] > 0.5
    assert bluer(patch(post, "follow", "water")) > 60                     # water around the body, not sky


def test_the_side_view_has_air_above_the_surface_and_water_below(post):
    image = picture(post, "side")
    assert bluer(image[:10]) < 80 and image[:10].mean() > 180             # the sky
    assert bluer(image[-10:]) > 60 and image[-10:].mean() < 150           # the water


def test_the_underwater_view_looks_up_at_the_surface(post):
    image = picture(post, "underwater")
    assert bluer(image) > 40                                              # under water everywhere
    assert np.abs(image - picture(post, "underwater", 0.7)).mean() > 0.5   # the surface overhead ripples


@pytest.mark.parametrize("args, words", [
    (("nowhere", "--out", "x"), ("nowhere", "trajectory")),
    (("figure_eight", "--out", "x", "--fps", "0"), ("--fps",)),
    (("figure_eight", "--out", "x", "--size", "1x1"), ("--size",)),
    (("figure_eight", "--out", "x", "--stroke", "dog_paddle"), ("dog_paddle",)),
    (("figure_eight", "--out", "x.png", "--frame", "-1"), ("--frame",)),
    (("figure_eight", "--out", "x.png", "--frame", "nan"), ("--frame",)),
    (("figure_eight", "--out", "x.png", "--frame", "3", "--seconds", "2"), ("--frame", "2")),
    (("figure_eight", "--out", "x.mp4", "--frame", "1"), ("--frame", ".png")),
])
def test_render_bad_input(args, words, tmp_path):
    assert_one_line_error(cli("render", *args, cwd=tmp_path), *words)
    assert not any(tmp_path.iterdir())


@pytest.mark.parametrize("args, words", [
    (("--camera", "top"), ("--camera", "invalid choice", "underwater")),
    (("--frame", "soon"), ("--frame", "soon")),
])
def test_render_bad_camera_or_frame_is_argparse_one_line(args, words, tmp_path):
    result = cli("render", "figure_eight", "--out", "x.png", *args, cwd=tmp_path)
    assert result.returncode == 2 and result.stdout == ""
    lines = result.stderr.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith("layered-swim render: error: ")
    assert all(word in lines[0] for word in words)
