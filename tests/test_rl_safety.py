"""Loading what someone hands over: checkpoints and policy files go through torch's safe
unpickler and are checked part by part (one line, never their code, never a traceback), and
the training configuration's every knob has bounds."""
import copy
import json
import os
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
import torch

from layered_swim.config import ConfigError
from layered_swim.rl.buffer import EpisodeData
from layered_swim.rl.checkpoint import CHECKPOINT_FORMAT
from layered_swim.rl.config import load_train_spec
from layered_swim.rl.policy import MAX_POLICY_BYTES, ResidualPolicy
from layered_swim.rl.ppo import ActorCritic, Normaliser, update
from layered_swim.rl.train import CHECKPOINT, Trainer

REPO = Path(__file__).resolve().parents[1]
SHIPPED_POLICY = REPO / "layered_swim/rl/policies/front_crawl_layered.pt"
TINY = ["run.episodes_per_epoch=2", "run.samples=150", "run.workers=1", "run.eval_every=100", "ppo.hidden=[16, 16]",
        "ppo.minibatch=64", "ppo.epochs=2"]


def cli(*args, timeout=120):
    env = {**os.environ, "PYTHONPATH": str(REPO) + os.pathsep + os.environ.get("PYTHONPATH", "")}
    return subprocess.run([sys.executable, "-m", "layered_swim", *args], cwd=REPO, env=env, capture_output=True,
                          text=True, timeout=timeout)


def assert_one_line_error(result, *words):
    assert result.returncode == 2, result.stderr
    assert "Traceback" not in result.stderr
    lines = result.stderr.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith("layered-swim: error: "), result.stderr
    for word in words:
        assert word in lines[0], lines[0]


def _mutated(data: dict, where: tuple, value) -> dict:
    """A copy of ``data`` with the entry at ``where`` set to ``value`` (None: removed)."""
    data = copy.deepcopy(data)
    node = data
    for key in where[:-1]:
        node = node[key]
    if value is None:
        del node[where[-1]]
    else:
        node[where[-1]] = value
    return data


# -- checkpoints -----------------------------------------------------------------------------
def _episode(rng: np.random.Generator, n_obs: int, n_act: int, steps: int, epoch: int) -> EpisodeData:
    return EpisodeData(rng.normal(size=(steps, n_obs)).astype(np.float32),
                       rng.uniform(-1, 1, (steps, n_act)).astype(np.float32), rng.normal(size=steps),
                       rng.normal(size=steps), rng.normal(size=n_obs).astype(np.float32), bool(rng.integers(2)), epoch)


def _trained_a_little(trainer: Trainer) -> Trainer:
    """``trainer`` after one synthetic epoch: a buffer, moments in the optimiser, drawn generators."""
    n_obs, n_act = trainer.model_args[:2]
    episodes = [_episode(trainer.rng, n_obs, n_act, steps, 0) for steps in (5, 9, 1)]
    trainer.normaliser.update(np.concatenate([e.obs for e in episodes]))
    trainer.buffer.add(episodes, 0, trainer.rng)
    update(trainer.model, trainer.optimiser, trainer.buffer.episodes, trainer.normaliser, trainer.spec.ppo,
           trainer.generator)
    trainer.epoch, trainer.samples, trainer.wall_s = 1, 15, 0.5
    return trainer


@pytest.fixture(scope="module")
def trainer(tmp_path_factory):
    """One trainer (building it builds an environment: seconds), its checkpoint in ``out``."""
    out = tmp_path_factory.mktemp("trained")
    trainer = _trained_a_little(Trainer(load_train_spec(None, TINY), out))
    trainer.save()
    return trainer


def _train_folder(path: Path, state) -> Path:
    """A training folder (as ``train`` leaves it) whose checkpoint is ``state``."""
    path.mkdir(parents=True, exist_ok=True)
    (path / "config.json").write_text(json.dumps({"command": "train"}))
    torch.save(state, path / CHECKPOINT)
    return path


def _checkpoint(trainer) -> dict:
    return torch.load(trainer.out / CHECKPOINT, weights_only=True)


def test_a_checkpoint_round_trip_gives_the_same_state_and_the_same_next_update(trainer, tmp_path):
    state = _checkpoint(trainer)           # plain data: the safe unpickler reads all of it
    assert state["format"] == CHECKPOINT_FORMAT and all(isinstance(e["obs"], torch.Tensor) for e in state["buffer"])
    original = _trained_a_little(Trainer(trainer.spec, tmp_path))
    original.save()
    resumed = Trainer(trainer.spec, tmp_path)
    resumed.resume()
    assert (resumed.epoch, resumed.samples, resumed.wall_s) == (original.epoch, original.samples, original.wall_s)
    for mine, theirs in zip(original.buffer.episodes, resumed.buffer.episodes):
        for name in ("obs", "actions", "log_probs", "rewards", "final_obs"):
            a, b = getattr(mine, name), getattr(theirs, name)
            assert a.dtype == b.dtype and np.array_equal(a, b)
        assert (mine.truncated, mine.epoch) == (theirs.truncated, theirs.epoch)
    assert np.array_equal(original.normaliser.mean, resumed.normaliser.mean)
    assert original.rng.bit_generator.state == resumed.rng.bit_generator.state
    steps = [update(t.model, t.optimiser, t.buffer.episodes, t.normaliser, t.spec.ppo, t.generator)
             for t in (original, resumed)]
    assert steps[0] == steps[1]
    for a, b in zip(original.model.parameters(), resumed.model.parameters()):
        assert torch.equal(a, b)
    assert original.rng.integers(2**31) == resumed.rng.integers(2**31)


class _Creates:
    """Unpickled by the unsafe loader, this opens (creates) ``path``: any code could run there."""

    def __init__(self, path: Path, how: str):
        self.path, self.how = str(path), how

    def __reduce__(self):
        return (open, (self.path, "w")) if self.how == "open" else (os.system, (f"touch {self.path}",))


@pytest.mark.parametrize("how", ["open", "os.system"])
def test_an_attackers_checkpoint_runs_none_of_its_code(trainer, tmp_path, how):
    marker = tmp_path / "created"
    state = {**_checkpoint(trainer), "model": _Creates(marker, how)}
    out = _train_folder(tmp_path / "run", state)
    torch.load(out / CHECKPOINT, weights_only=False)        # the payload works: the unsafe loader runs it
    assert marker.exists()
    marker.unlink()
    result = cli("train", *[x for item in TINY for x in ("--set", item)], "--resume", "--out", str(out),
                 "--no-progress")
    assert_one_line_error(result, str(out / CHECKPOINT), "tensors and plain data")
    assert not marker.exists()


def test_a_checkpoint_without_model_is_one_line(trainer, tmp_path):
    state = _checkpoint(trainer)
    del state["model"]
    out = _train_folder(tmp_path / "run", state)
    result = cli("train", *[x for item in TINY for x in ("--set", item)], "--resume", "--out", str(out),
                 "--no-progress")
    assert_one_line_error(result, str(out / CHECKPOINT), "lacks model")


BAD_CHECKPOINTS = {
    "an older format": (("format",), 1, "older version; start over with --overwrite"),
    "format 2 (buffer.policy, now buffer.eviction)": (("format",), 2, "older version; start over with --overwrite"),
    "NaN weights": (("model", "actor.0.weight"), torch.full((16, 255), float("nan")), "NaN"),
    "a weight of another shape": (("model", "actor.0.bias"), torch.zeros(17), "shape"),
    "integer weights": (("model", "actor.0.bias"), torch.zeros(16, dtype=torch.int64), "float tensor"),
    "a moment of another shape": (("optimiser", "state", 0, "exp_avg"), torch.zeros(3), "shape"),
    "an optimiser state for no parameter": (("optimiser", "state", 99), {}, "parameter indices"),
    "a short normaliser": (("normaliser", "mean"), [0.0] * 3, "normaliser mean"),
    "a negative epoch": (("epoch",), -1, "epoch"),
    "fractional samples": (("samples",), 1.5, "samples"),
    "a foreign rng": (("rng", "bit_generator"), "MT19937", "rng"),
    "an rng int beyond its type": (("rng", "uinteger"), 2**100, "rng"),
    "a damaged generator": (("generator",), torch.zeros(5056, dtype=torch.uint8), "generator"),
    "a short generator": (("generator",), torch.zeros(5, dtype=torch.uint8), "generator"),
    "an episode of another observation size": (("buffer", 0, "obs"), torch.zeros(5, 7), "observations"),
    "an episode of mismatched lengths": (("buffer", 0, "rewards"), torch.zeros(4, dtype=torch.float64), "steps"),
    "an episode of NaN rewards": (("buffer", 0, "rewards"), torch.full((5,), float("nan"), dtype=torch.float64), "NaN"),
    "an episode from the future": (("buffer", 0, "epoch"), 7, "epoch"),
    "a buffer that is not a list": (("buffer",), "x", "buffer"),
    "a configuration that is not one": (("spec", "ppo", "hidden"), [100000], "spec"),
}


@pytest.mark.parametrize("name", BAD_CHECKPOINTS)
def test_a_bad_checkpoint_is_one_line_and_leaves_the_trainer_as_it_was(trainer, tmp_path, name):
    where, value, words = BAD_CHECKPOINTS[name]
    out = _train_folder(tmp_path, _mutated(_checkpoint(trainer), where, value))
    before = copy.deepcopy(trainer.model.state_dict()), trainer.epoch, trainer.rng.bit_generator.state
    home, trainer.out = trainer.out, out
    try:
        with pytest.raises(ConfigError, match=words) as err:
            trainer.resume()
    finally:
        trainer.out = home
    assert "\n" not in str(err.value) and str(out / CHECKPOINT) in str(err.value)
    model, epoch, rng = before
    assert all(torch.equal(model[k], v) for k, v in trainer.model.state_dict().items())
    assert (epoch, rng) == (trainer.epoch, trainer.rng.bit_generator.state)


# -- policy files --------------------------------------------------------------------------
@pytest.fixture(scope="module")
def shipped():
    return torch.load(SHIPPED_POLICY, weights_only=True)


def _policy_file(path: Path, data) -> Path:
    torch.save(data, path)
    return path


BAD_POLICIES = {
    "a weight of another shape": (("model", "actor.0.weight"), torch.zeros(256, 254), "shape"),
    "a missing weight": (("model", "critic.4.bias"), None, "lacks critic.4.bias"),
    "NaN weights": (("model", "log_std"), torch.full((33,), float("nan")), "NaN"),
    "float64 weights beyond float32": (("model", "log_std"), torch.full((33,), 1e300, dtype=torch.float64), "NaN"),
    "integer weights": (("model", "log_std"), torch.zeros(33, dtype=torch.int32), "float tensor"),
    "an unknown weight": (("model", "extra"), torch.zeros(1), "unknown"),
    "no env": (("env",), None, "lacks env"),
    "negative sizes": (("model_args",), [-255, 33, (256, 256), -2.0], "model_args"),
    "a 100000-wide layer": (("model_args",), [255, 33, (100000,), -2.0], "hidden widths"),
    "nine layers": (("model_args",), [255, 33, (4,) * 9, -2.0], "hidden widths"),
    "three model_args": (("model_args",), [255, 33, (256, 256)], "model_args"),
    "a NaN log std": (("model_args",), [255, 33, (256, 256), float("nan")], "log std"),
    "a network too large for the file": (("model_args",), [10_000, 33, (4096,) * 8, -2.0], "more than"),
    "an unknown env field": (("env", "gravity"), 0.0, "unknown"),
    "an unknown pool": (("env", "pool"), "ocean", "env: field 'pool'"),
    "a policy rate that is not whole control steps": (("env", "policy_hz"), 7, "policy_hz"),
    "a missing env field": (("env", "stroke"), None, "lacks stroke"),
    "a negative reward weight": (("reward", "roll_per_rad"), -1.0, "reward: field 'roll_per_rad'"),
    "a negative variance": (("normaliser", "var"), [-1.0] * 255, "variances"),
    "a normaliser of text": (("normaliser", "mean"), ["0"] * 255, "normaliser mean"),
    "a zero count": (("normaliser", "count"), 0.0, "count"),
    "a boolean format": (("format",), True, "format 1"),
}


def test_the_shipped_policy_loads_and_checks_its_stroke():
    policy = ResidualPolicy.load(SHIPPED_POLICY)
    policy.check_stroke(None)
    policy.check_stroke("front_crawl")
    with pytest.raises(ConfigError, match="trained for front_crawl, not breaststroke; add --stroke front_crawl"):
        policy.check_stroke("breaststroke")
    with pytest.raises(ConfigError, match="expects 255 observations and 33 actions"):
        policy.check_sizes(254, 33, "this episode")


@pytest.mark.parametrize("name", BAD_POLICIES)
def test_a_bad_policy_file_is_one_line(shipped, tmp_path, name):
    where, value, words = BAD_POLICIES[name]
    path = _policy_file(tmp_path / "p.pt", _mutated(shipped, where, value))
    with pytest.raises(ConfigError) as err:
        ResidualPolicy.load(path)
    assert words in str(err.value) and str(err.value).startswith(f"{path}: ") and "\n" not in str(err.value)


@pytest.mark.parametrize("name", ["a weight of another shape", "a missing weight", "negative sizes", "NaN weights"])
def test_goal_with_a_bad_policy_file_is_one_line(shipped, tmp_path, name):
    where, value, words = BAD_POLICIES[name]
    path = _policy_file(tmp_path / "p.pt", _mutated(shipped, where, value))
    assert_one_line_error(cli("goal", "--policy", str(path), timeout=60), str(path), words)


def test_goal_with_a_fifo_policy_is_one_line_not_a_hang(tmp_path):
    fifo = tmp_path / "p.pt"
    os.mkfifo(fifo)
    assert_one_line_error(cli("goal", "--policy", str(fifo), timeout=60), str(fifo), "not a regular file")


def test_goal_with_dev_zero_as_policy_is_one_line(tmp_path):
    assert_one_line_error(cli("goal", "--policy", "/dev/zero", timeout=60), "/dev/zero", "not a regular file")


def test_an_oversized_policy_file_is_refused_unread(tmp_path):
    path = tmp_path / "p.pt"
    with open(path, "wb") as f:
        f.truncate(MAX_POLICY_BYTES + 1)      # sparse: no disk used
    with pytest.raises(ConfigError, match="more than"):
        ResidualPolicy.load(path)


def test_a_policy_written_by_the_trainer_loads(tmp_path):
    model, normaliser = ActorCritic(7, 2, (4,)), Normaliser(7)
    env, reward = load_train_spec(None).env, load_train_spec(None).reward
    written = ResidualPolicy(model, normaliser, env, reward, (7, 2, (4,), -1.0)).to_file()
    assert written["env"] == env.model_dump() and written["reward"] == reward.model_dump()   # plain dicts in the file
    path = _policy_file(tmp_path / "p.pt", written)
    loaded = ResidualPolicy.load(path)
    assert loaded.model_args == (7, 2, (4,), -1.0) and loaded.model_args.n_obs == 7 and loaded.source == str(path)
    assert loaded.env == env and loaded.reward == reward and loaded.env.stroke == env.stroke
    assert all(torch.equal(a, b) for a, b in zip(model.parameters(), loaded.model.parameters()))


# -- the training configuration ------------------------------------------------------------
@pytest.mark.parametrize("setting", ["ppo.hidden=[100000,100000]", "run.workers=5000"])
def test_train_with_an_absurd_setting_is_one_line_and_creates_nothing(tmp_path, setting):
    out = tmp_path / "never"
    result = cli("train", "--set", setting, "--out", str(out), "--no-progress", timeout=60)
    assert_one_line_error(result, setting.split("=")[0])
    assert not out.exists()


@pytest.mark.parametrize("setting", ["ppo.hidden=[]", "ppo.hidden=[8,8,8,8,8,8,8,8,8]", "ppo.hidden=[0]",
                                     "run.samples=20000000000", "run.episodes_per_epoch=10001",
                                     "buffer.capacity_episodes=100001", "ppo.epochs=1001", "ppo.minibatch=1000001",
                                     "env.policy_hz=7", "env.policy_hz=480", "run.seed=-1", "run.seed=2147483648",
                                     "run.eval_every=0", "run.checkpoint_every=1000001", "run.workers=0"])
def test_every_training_knob_has_bounds(setting):
    with pytest.raises(ConfigError, match=setting.split("=")[0].replace(".", r"\.")):
        load_train_spec(None, [setting])


def test_eviction_needs_some_weight():
    with pytest.raises(ConfigError, match="w_age and w_reward"):
        load_train_spec(None, ["buffer.w_age=0", "buffer.w_reward=0"])


def test_the_old_buffer_policy_key_says_its_new_name():
    with pytest.raises(ConfigError, match="field 'buffer'.*policy is now called eviction") as err:
        load_train_spec(None, ["buffer.policy=fifo"])
    assert "\n" not in str(err.value)
    assert load_train_spec(None, ["buffer.eviction=fifo"]).buffer.eviction == "fifo"
