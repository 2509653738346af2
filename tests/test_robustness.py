"""Nothing lost, nothing cryptic: bad files and options are one line, output folders are checked
before any work, a stopped run keeps its log, seeds mean something."""
import json
import signal
import subprocess
import sys
import time

import numpy as np
import pytest
import yaml
from test_cli import REPO, assert_one_line_error, cli

from layered_swim.control.stroke import STROKES_DIR
from layered_swim.control.targets import TRAJECTORIES_DIR
from layered_swim.episode import Episode
from layered_swim.outputs import atomic_path
from layered_swim.recorder import CHUNK_ROWS, read_log


def _stroke_with(tmp_path, **changes):
    spec = yaml.safe_load((STROKES_DIR / "breaststroke.yaml").read_text())
    spec.update(changes)
    path = tmp_path / "odd.yaml"
    path.write_text(yaml.safe_dump(spec))
    return path


def test_files_that_are_not_text_or_out_of_range_are_one_line(tmp_path):
    binary = tmp_path / "binary.yaml"
    binary.write_bytes(b"name: \xff\xfe\x00 swim\n")
    assert_one_line_error(cli("run", "--stroke", str(binary), "--seconds", "1", "--out", str(tmp_path / "a")),
                          "not UTF-8")
    assert_one_line_error(cli("run", "--stroke", str(_stroke_with(tmp_path, period_s=1e308)), "--seconds", "1",
                              "--out", str(tmp_path / "b")), "period_s")
    line = yaml.safe_load((TRAJECTORIES_DIR / "straight_line.yaml").read_text()) | {"speed_m_s": 1e300}
    (tmp_path / "fast.yaml").write_text(yaml.safe_dump(line))
    assert_one_line_error(cli("follow", str(tmp_path / "fast.yaml"), "--seconds", "1"), "speed_m_s")


def test_render_of_a_broken_run_folder_is_one_line_and_leaves_no_video(tmp_path):
    run = tmp_path / "run"
    assert cli("run", "--stroke", "rest", "--seconds", "0.5", "--out", str(run)).returncode == 0
    (run / "log.npz").write_bytes(b"not a zip at all")
    out = tmp_path / "broken.mp4"
    assert_one_line_error(cli("render", str(run), "--out", str(out)), "not a readable log")
    assert list(tmp_path.glob("*.mp4")) == [] and not list(tmp_path.glob(".*tmp*"))
    assert json.loads((run / "config.json").read_text())["command"] == "run"


def test_an_unwritable_out_fails_before_simulating():
    started = time.perf_counter()
    assert_one_line_error(cli("run", "--stroke", "breaststroke", "--out", "/proc/nope/x"), "/proc/nope")
    assert time.perf_counter() - started < 10      # the 30 s swim never ran (2 s plus interpreter start)


def test_a_failed_write_leaves_nothing_half_written(tmp_path):
    target = tmp_path / "summary.json"
    with pytest.raises(RuntimeError):
        with atomic_path(target) as tmp:
            tmp.write_text("{half")
            raise RuntimeError("disk full")
    assert list(tmp_path.iterdir()) == []


def test_seeds_jitter_the_start_and_repeat_exactly():
    def start(seed):
        episode = Episode("breaststroke", seed=seed)
        episode.close()
        return episode.sim.state.pos_m.copy()

    np.testing.assert_array_equal(start(1), start(1))
    assert np.abs(start(1) - start(2)).max() > 1e-3
    assert np.abs(start(0) - start(1)).max() > 1e-3


def test_negative_vector_values_and_argparse_errors_are_one_line(tmp_path):
    result = cli("follow", "straight_line", "--seconds", "0.2", "--current", "-0.1,0,0", "--json")
    assert result.returncode == 0, result.stderr
    assert json.loads(result.stdout)["current_m_s"] == [-0.1, 0.0, 0.0]
    bad = cli("run", "--stroke")
    assert bad.returncode == 2 and len(bad.stderr.strip().splitlines()) == 1 and "--stroke" in bad.stderr


def _start_run(out, seconds="600"):      # long enough to stop midway; no warm-up child (runs.WARM_UP_AFTER_S)
    return subprocess.Popen([sys.executable, "-m", "layered_swim", "run", "--stroke", "breaststroke", "--seconds",
                             seconds, "--out", str(out)], cwd=REPO, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE,
                            text=True)


def _wait_for_chunk(out, process, timeout_s=120.0):
    deadline = time.monotonic() + timeout_s
    while not list((out / "log.partial").glob("chunk-*.npz")):
        assert process.poll() is None and time.monotonic() < deadline
        time.sleep(0.2)


def test_ctrl_c_keeps_a_readable_partial_log(tmp_path):
    out = tmp_path / "stopped"
    process = _start_run(out)
    _wait_for_chunk(out, process)
    process.send_signal(signal.SIGINT)
    _, err = process.communicate(timeout=120)
    assert process.returncode == 130 and "interrupted" in err, err
    summary = json.loads((out / "summary.json").read_text())
    assert summary["partial"]["reason"] == "interrupted" and 0 < summary["partial"]["stopped_at_s"] < 600
    log = read_log(out)
    assert not log["partial"] and len(log["time_s"]) >= CHUNK_ROWS and not (out / "log.partial").exists()
    assert np.isfinite(log["desired_pose_rad"]).all() and np.isfinite(log["fluid_force_n"]).all()
    analysed = cli("analyze", "--run", str(out), "--json", "--out", str(tmp_path / "analysis"))
    assert analysed.returncode == 0, analysed.stderr
    assert json.loads(analysed.stdout)["cycles"] >= 2
    config = json.loads((tmp_path / "analysis" / "config.json").read_text())
    assert config["command"] == "analyze" and config["analysis"]["partial_log"] is True


def test_a_killed_run_leaves_chunks_that_read_back(tmp_path):
    out = tmp_path / "killed"
    process = _start_run(out)
    _wait_for_chunk(out, process)
    process.kill()
    process.communicate(timeout=60)
    log = read_log(out)
    assert log["partial"] and len(log["time_s"]) % CHUNK_ROWS == 0 and log["time_s"][0] > 0


def test_soak_reports_memory_and_finiteness(tmp_path):
    result = cli("soak", "--hours", "0.006", "--stroke", "breaststroke", "--json", "--out", str(tmp_path / "soak"))
    assert result.returncode == 0, result.stderr
    summary = json.loads(result.stdout)
    memory = summary["memory"]
    assert summary["finite"] is True and memory["samples"] == 3      # at 0, 10 and 20 s of 21.6
    assert 0 < memory["rss_start_mb"] <= memory["rss_peak_mb"] and abs(memory["growth_mb"]) < 100
    assert read_log(tmp_path / "soak")["time_s"][-1] == pytest.approx(21.6)
    assert_one_line_error(cli("soak", "--hours", "-1", "--out", str(tmp_path / "bad")), "--hours")
