"""One description of a swim: every run folder's config.json holds its SwimSpec, and
`run --config` swims it again, the same log byte for byte."""
import json

import pytest
from test_cli import assert_one_line_error, cli

from layered_swim.config import ConfigError
from layered_swim.spec import FollowTask, SwimSpec


def _logs(folder):
    return {p.relative_to(folder): p.read_bytes() for p in sorted(folder.rglob("log.npz"))}


@pytest.mark.parametrize("command", [
    ["run", "--stroke", "front_crawl", "--seconds", "1", "--seed", "3", "--tempo", "1.1", "--density", "1010"],
    ["follow", "figure_eight", "--stroke", "breaststroke", "--seconds", "1.5", "--current", "0.1,-0.2,0",
     "--layers", "basic,cycle,palm"],
    ["goal", "--stroke", "front_crawl", "--current", "0.1,0,0"]])
def test_run_config_repeats_a_folder_byte_for_byte(tmp_path, command):
    first, again = tmp_path / "first", tmp_path / "again"
    assert cli(*command, "--out", str(first)).returncode == 0
    result = cli("run", "--config", str(first / "config.json"), "--out", str(again), "--json")
    assert result.returncode == 0, result.stderr
    logs = _logs(first)
    assert logs and logs == _logs(again)
    config = json.loads((again / "config.json").read_text())
    assert config["command"] == command[0] and config["swim"] == json.loads((first / "config.json").read_text())["swim"]


def test_run_config_takes_no_other_swim_options(tmp_path):
    run = tmp_path / "run"
    assert cli("run", "--stroke", "rest", "--seconds", "0.3", "--out", str(run)).returncode == 0
    assert_one_line_error(cli("run", "--config", str(run / "config.json"), "--seconds", "2"), "--seconds")
    assert cli("run", "--config", str(run / "config.json"), "--stroke", "rest").returncode == 2


def test_run_config_refuses_what_it_cannot_repeat(tmp_path):
    (tmp_path / "config.json").write_text(json.dumps({"command": "analyze", "swim": {"stroke": "rest"}}))
    assert_one_line_error(cli("run", "--config", str(tmp_path / "config.json"), "--out", str(tmp_path / "o")),
                          "not the config.json")
    (tmp_path / "config.json").write_text(json.dumps({"command": "run", "swim": {"stroke": "rest", "tempo": 99}}))
    assert_one_line_error(cli("run", "--config", str(tmp_path / "config.json"), "--out", str(tmp_path / "o")),
                          "swim: field 'tempo'")
    assert not (tmp_path / "o").exists()


def test_a_spec_is_checked_field_by_field():
    with pytest.raises(ConfigError, match="field 'seconds'"):
        SwimSpec.of("here", stroke="rest", seconds=0.0)
    with pytest.raises(ConfigError, match="field 'medium.current_m_s"):
        SwimSpec.of("here", stroke="rest", medium={"current_m_s": [0, 0, 99]})
    with pytest.raises(ConfigError, match="--layers"):
        SwimSpec.of("here", stroke="rest", layers="cycle")
    with pytest.raises(ConfigError, match="field 'task"):
        SwimSpec.of("here", stroke="rest", task={"kind": "dance"})
    spec = SwimSpec.of("here", stroke="breaststroke", task={"kind": "follow", "trajectory": "circle"})
    assert isinstance(spec.task, FollowTask) and SwimSpec.model_validate(spec.model_dump(mode="json")) == spec
    assert spec.with_(seed=4).seed == 4 and spec.seed == 0
