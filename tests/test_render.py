"""``layered-swim render`` without a display: frames from a trajectory swum now and from a finished
run's log, non-empty and changing over time; an MP4 when the encoder is installed."""
import os

import numpy as np
import pytest
from PIL import Image

from test_cli import assert_one_line_error, cli


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


@pytest.mark.parametrize("args, words", [
    (("nowhere", "--out", "x"), ("nowhere", "trajectory")),
    (("figure_eight", "--out", "x", "--fps", "0"), ("--fps",)),
    (("figure_eight", "--out", "x", "--size", "1x1"), ("--size",)),
    (("figure_eight", "--out", "x", "--stroke", "dog_paddle"), ("dog_paddle",)),
])
def test_render_bad_input(args, words, tmp_path):
    assert_one_line_error(cli("render", *args, cwd=tmp_path), *words)
