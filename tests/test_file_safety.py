"""Never touch what is not ours: output folders are checked before anything is written, replaced
only when they hold our own output (moved aside, not deleted), written by one command at a
time; input files are read only when they are regular files of a sane size."""
import json
import os
import subprocess
import sys
import time

import numpy as np
import pytest
from test_cli import REPO, assert_one_line_error, cli

from layered_swim.config import ConfigError, read_text
from layered_swim.outputs import LOCK, MARKER, PREVIOUS, check_out_dir, claim, release


def _tree(folder):
    return sorted(str(p.relative_to(folder)) for p in folder.rglob("*"))


def test_a_rejected_command_leaves_the_folder_as_it_was(tmp_path):
    victim = tmp_path / "v"
    victim.mkdir()
    (victim / "keep").write_text("x")
    assert_one_line_error(cli("run", "--stroke", "nosuch", "--out", str(victim), "--overwrite"),
                          "not a layered-swim output")
    assert (victim / "keep").read_text() == "x" and _tree(victim) == ["keep"]
    mine = tmp_path / "mine"       # our own output, but the arguments are wrong: nothing moves either
    assert cli("run", "--stroke", "rest", "--seconds", "0.2", "--out", str(mine)).returncode == 0
    before = _tree(mine)
    assert_one_line_error(cli("analyze", "--stroke", "nosuch", "--out", str(mine), "--overwrite"), "unknown stroke")
    assert _tree(mine) == before


@pytest.mark.parametrize("command", [
    ["run", "--stroke", "nosuch"], ["follow", "nosuch", "--seconds", "1"], ["analyze", "--stroke", "nosuch"],
    ["compare", "--strokes", "rest,nosuch"], ["experiment", "nosuch"], ["soak", "--hours", "0"],
    ["follow", "straight_line", "--seeds", "2", "--stroke", "nosuch"], ["render", "nosuch"],
    ["train", "--set", "run.samples=0"], ["run", "--stroke", "rest", "--tempo", "nan"]])
def test_a_rejected_command_creates_no_folder(tmp_path, command):
    out = tmp_path / "new" / "out"
    assert_one_line_error(cli(*command, "--out", str(out)))
    assert list(tmp_path.iterdir()) == []


def test_a_home_folder_or_tmp_is_never_emptied(tmp_path):
    home = tmp_path / "home"
    (home / "Documents").mkdir(parents=True)
    (home / "Documents" / "thesis.tex").write_text("years of work")
    (home / ".bashrc").write_text("alias")
    env = {**os.environ, "HOME": str(home), "PYTHONPATH": str(REPO)}
    for out in (str(home), str(home / "Documents"), str(tmp_path)):
        result = subprocess.run([sys.executable, "-m", "layered_swim", "run", "--stroke", "front_crawl", "--seconds",
                                 "1", "--out", out, "--overwrite"], cwd=tmp_path, env=env, capture_output=True,
                                text=True, timeout=120)
        assert_one_line_error(result, "refusing")
    assert _tree(home) == [".bashrc", "Documents", "Documents/thesis.tex"]


def test_a_marked_home_folder_is_still_refused(tmp_path, monkeypatch):
    home = tmp_path / "home"
    home.mkdir()
    (home / MARKER).write_text(json.dumps({"command": "run"}))    # forged, or a run once written there
    (home / "notes.txt").write_text("mine")
    monkeypatch.setenv("HOME", str(home))
    with pytest.raises(ConfigError, match="home folder"):
        check_out_dir(home, "analyze", overwrite=True)


def test_a_symlinked_out_is_refused_and_its_target_untouched(tmp_path):
    target = tmp_path / "target"
    target.mkdir()
    (target / "data.csv").write_text("1,2,3")
    link = tmp_path / "link"
    link.symlink_to(target)
    assert_one_line_error(cli("run", "--stroke", "rest", "--seconds", "0.2", "--out", str(link), "--overwrite"),
                          "symbolic link")
    assert _tree(target) == ["data.csv"]


def test_overwrite_moves_our_earlier_output_aside(tmp_path):
    out = claim(check_out_dir(tmp_path / "r", "run"))
    (out / "config.json").write_text(json.dumps({"command": "run"}))
    (out / "log.npz").write_text("old")
    release(out)
    assert claim(check_out_dir(out, "run")) == out                 # the same command again: fine, nothing moved
    assert (out / "log.npz").read_text() == "old"
    release(out)
    with pytest.raises(ConfigError, match="holds the output of `run`.*--overwrite"):
        check_out_dir(out, "analyze")
    claim(check_out_dir(out, "analyze", overwrite=True))
    assert (out / PREVIOUS / "log.npz").read_text() == "old"          # recoverable, not deleted
    assert sorted(p.name for p in out.iterdir()) == sorted([MARKER, LOCK, PREVIOUS])
    assert json.loads((out / MARKER).read_text())["command"] == "analyze"
    release(out)
    (out / "report.md").write_text("second")
    claim(check_out_dir(out, "run", overwrite=True))                       # the one before is dropped
    assert _tree(out / PREVIOUS) == ["report.md"]
    release(out)


def test_a_folder_of_foreign_files_is_refused_even_with_overwrite(tmp_path):
    (tmp_path / "notes.txt").write_text("mine")
    for overwrite in (False, True):
        with pytest.raises(ConfigError, match="not a layered-swim output"):
            check_out_dir(tmp_path, "run", overwrite)
    with pytest.raises(ConfigError, match="empty"):
        check_out_dir("", "run")


def test_an_older_version_s_output_is_recognised_by_its_config(tmp_path):
    (tmp_path / "config.json").write_text(json.dumps({"command": "follow"}))
    (tmp_path / "log.npz").write_text("old")
    assert check_out_dir(tmp_path, "follow").path == tmp_path
    with pytest.raises(ConfigError, match="output of `follow`"):
        check_out_dir(tmp_path, "run")


def test_one_writer_per_folder_and_a_stale_lock_is_taken(tmp_path):
    out = tmp_path / "busy"
    holder = subprocess.Popen([sys.executable, "-c", (
        "import sys, time\nfrom layered_swim.outputs import check_out_dir, claim\n"
        f"claim(check_out_dir({str(out)!r}, 'run'))\nprint('held', flush=True)\ntime.sleep(60)\n")],
        cwd=REPO, stdout=subprocess.PIPE, text=True, env={**os.environ, "PYTHONPATH": str(REPO)})
    try:
        assert holder.stdout.readline().strip() == "held"
        with pytest.raises(ConfigError, match=rf"another layered-swim command \(pid {holder.pid}\)"):
            claim(check_out_dir(out, "run"))
        assert_one_line_error(cli("run", "--stroke", "rest", "--seconds", "0.2", "--out", str(out)), "is writing there")
    finally:
        holder.kill()
        holder.wait()
    assert (out / LOCK).exists()              # a killed run leaves its lock file, not its lock
    assert claim(check_out_dir(out, "run")) == out
    release(out)


def test_two_runs_into_one_folder_leave_one_consistent_run(tmp_path):
    out = tmp_path / "both"
    command = [sys.executable, "-m", "layered_swim", "run", "--stroke", "rest", "--seconds", "2", "--out", str(out)]
    env = {**os.environ, "PYTHONPATH": str(REPO)}
    runs = [subprocess.Popen(command, cwd=REPO, env=env, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE,
                             text=True) for _ in range(2)]
    errors = [run.communicate(timeout=120)[1] for run in runs]
    codes = sorted(run.returncode for run in runs)
    assert codes == [0, 2], errors
    refused = errors[[run.returncode for run in runs].index(2)]
    assert len(refused.strip().splitlines()) == 1 and "is writing there" in refused
    config = json.loads((out / "config.json").read_text())
    summary = json.loads((out / "summary.json").read_text())
    assert config["swim"]["seconds"] == 2.0 and "partial" not in summary
    assert not (out / "log.partial").exists()
    assert len(np.load(out / "log.npz")["time_s"]) > 1


@pytest.mark.parametrize("special", ["fifo", "/dev/zero", "/dev/urandom", "folder"])
def test_a_stroke_or_trajectory_that_is_not_a_regular_file_is_one_line_at_once(tmp_path, special):
    if special == "fifo":
        path = tmp_path / "pipe.yaml"
        os.mkfifo(path)
    elif special == "folder":
        path = tmp_path / "folder.yaml"
        path.mkdir()
    else:
        path = tmp_path / f"{special.rsplit('/', 1)[1]}.yaml"
        path.symlink_to(special)
    commands = {"fifo": ["analyze", "--stroke", str(path), "--out", str(tmp_path / "a")],
                "/dev/zero": ["run", "--stroke", str(path), "--seconds", "1", "--out", str(tmp_path / "o")],
                "/dev/urandom": ["follow", str(path), "--seconds", "1"], "folder": ["follow", str(path)]}
    started = time.monotonic()
    assert_one_line_error(cli(*commands[special]), str(path))
    assert time.monotonic() - started < 15        # interpreter and imports; the read itself never waits
    with pytest.raises(ConfigError, match="folder" if special == "folder" else "not a regular file"):
        read_text(path)


def test_an_oversized_file_is_refused(tmp_path):
    path = tmp_path / "huge.yaml"
    with path.open("wb") as f:
        f.truncate(32 * 2**20)       # sparse: no real disk
    with pytest.raises(ConfigError, match="more than"):
        read_text(path)


def _run_folder(tmp_path):
    run = tmp_path / "run"
    assert cli("run", "--stroke", "rest", "--seconds", "0.3", "--out", str(run)).returncode == 0
    return run


def test_a_log_with_broken_name_lists_is_one_line(tmp_path):
    run = _run_folder(tmp_path)
    with np.load(run / "log.npz") as archive:
        log = {name: archive[name] for name in archive.files}
    np.savez(run / "log.npz", **{**log, "segment_names": np.array("pelvis")})
    assert_one_line_error(cli("analyze", "--run", str(run), "--out", str(tmp_path / "a")), "segment_names")
    assert_one_line_error(cli("render", str(run), "--out", str(tmp_path / "v")), "segment_names")
    (run / "log.npz").unlink()
    spool = run / "log.partial"
    spool.mkdir()
    np.savez(spool / "chunk-00000.npz", **{k: v for k, v in log.items() if not k.endswith("_names")})
    (spool / "names.json").write_text("[]")
    assert_one_line_error(cli("render", str(run), "--out", str(tmp_path / "w")), "names.json")
    assert not (tmp_path / "a").exists() and not (tmp_path / "v").exists() and not (tmp_path / "w").exists()


def test_render_of_a_run_whose_config_is_not_a_mapping_is_one_line(tmp_path):
    run = _run_folder(tmp_path)
    (run / "config.json").write_text("[1, 2, 3]")
    assert_one_line_error(cli("render", str(run), "--out", str(tmp_path / "v")), "config.json")
    assert not (tmp_path / "v").exists()


def test_render_never_replaces_a_video_or_foreign_files_unasked(tmp_path):
    run = _run_folder(tmp_path)
    video = tmp_path / "swim.mp4"
    video.write_bytes(b"someone's film")
    assert_one_line_error(cli("render", str(run), "--out", str(video), "--seconds", "0.1"), "--overwrite")
    assert video.read_bytes() == b"someone's film"
    frames = tmp_path / "frames"
    frames.mkdir()
    (frames / "notes.txt").write_text("mine")
    assert_one_line_error(cli("render", str(run), "--out", str(frames), "--seconds", "0.1", "--overwrite"),
                          "not rendered frames")
    assert _tree(frames) == ["notes.txt"]


@pytest.mark.parametrize("arguments, words", [
    (["follow", "straight_line", "--workers", "0", "--seeds", "2"], ["--workers"]),
    (["goal", "--seeds", "0"], ["--seeds"]),
    (["train", "--workers", "5000"], ["--workers"]),
    (["run", "--stroke", "rest", "--out", ""], ["--out"])])
def test_nonsense_counts_are_refused(tmp_path, arguments, words):
    result = cli(*arguments, cwd=tmp_path)
    assert result.returncode == 2 and len(result.stderr.strip().splitlines()) == 1, result.stderr
    assert all(word in result.stderr for word in words)
    assert list(tmp_path.iterdir()) == []


def test_goal_help_matches_the_code():
    text = cli("goal", "--help").stdout
    assert "0: SWIM's fixed start" not in text and "1-100" in " ".join(text.split())
