"""The trainer: ProgEvict against eqs. 16-20 on a toy buffer, GAE and the normaliser by hand,
checkpoints (save -> load -> the same actions), resume, the command line, and Ray."""
import csv
import json
import math
import subprocess
import sys

import numpy as np
import pytest
import torch

from layered_swim.config import ConfigError
from layered_swim.rl.buffer import EpisodeBuffer, EpisodeData, eviction_probabilities, transition
from layered_swim.rl.config import BufferSpec, load_train_spec
from layered_swim.rl.policy import ResidualPolicy
from layered_swim.rl.ppo import ActorCritic, ActorSnapshot, Normaliser, gae
from layered_swim.rl.train import Trainer, train

TINY = ["run.episodes_per_epoch=2", "run.samples=150", "run.workers=1", "run.eval_every=100", "ppo.hidden=[16, 16]",
        "ppo.minibatch=64", "ppo.epochs=2"]


def test_progevict_probabilities_follow_the_equations():
    s = BufferSpec(e_mid=0.0, k=1.0, w_age=0.5, w_reward=0.5, sigma=0.5)
    p = eviction_probabilities([0, 0, 1, 2], [5.0, 1.0, 3.0, 2.0], current_epoch=2, s=s)
    t = 1 / (1 + math.exp(2.0))                                   # eq. 17 at e = 2
    age = np.array([9.0, 9.0, 4.0, 1.0]) / 23.0                   # eq. 19: (2 - e_i + 1)^2
    z = np.array([1.0, -1.0, 1 / 3, -1 / 3])                      # ranks 3, 0, 2, 1 (eq. 20)
    reward = np.exp(-z**2 / 0.5)
    reward /= reward.sum()
    fifo = np.array([1.0, 0.0, 0.0, 0.0])                         # the oldest, first inserted
    assert p == pytest.approx(t * fifo + (1 - t) * (0.5 * age + 0.5 * reward))
    assert p.sum() == pytest.approx(1.0)
    assert transition(-50, s) == pytest.approx(1.0) and transition(50, s) == pytest.approx(0.0, abs=1e-12)


def _episode(ret: float) -> EpisodeData:
    return EpisodeData(np.zeros((1, 2), np.float32), np.zeros((1, 1), np.float32), np.zeros(1), np.array([ret]),
                       np.zeros(2, np.float32), True)


def test_fifo_evicts_the_oldest_and_late_progevict_keeps_the_best_and_the_worst():
    fifo = EpisodeBuffer(BufferSpec(eviction="fifo", capacity_episodes=3))
    rng = np.random.default_rng(0)
    fifo.add([_episode(r) for r in (1.0, 2.0)], 0, rng)
    assert fifo.add([_episode(r) for r in (3.0, 4.0)], 1, rng) == 1
    assert [e.episode_return for e in fifo.episodes] == [2.0, 3.0, 4.0]
    kept = {r: 0 for r in range(9)}
    for seed in range(200):
        late = EpisodeBuffer(BufferSpec(eviction="progevict", capacity_episodes=8, e_mid=0.0, k=1.0, w_age=0.0,
                                        w_reward=1.0))
        late.add([_episode(float(r)) for r in range(9)], 100, np.random.default_rng(seed))
        for e in late.episodes:
            kept[int(e.episode_return)] += 1
    assert kept[0] > kept[4] and kept[8] > kept[4]        # middling returns go first


def test_gae_by_hand():
    rewards, values = np.array([1.0, 2.0]), np.array([0.5, 1.0])
    gamma, lam = 0.9, 0.8
    d1 = 2.0 + gamma * 3.0 - 1.0                          # bootstrapped from V(final) = 3 (truncated)
    d0 = 1.0 + gamma * 1.0 - 0.5
    assert gae(rewards, values, 3.0, gamma, lam) == pytest.approx([d0 + gamma * lam * d1, d1])
    assert gae(rewards, values, 0.0, gamma, lam)[1] == pytest.approx(2.0 - 1.0)   # terminated: no future


def test_the_numpy_actor_matches_the_torch_distribution():
    torch.manual_seed(0)
    model = ActorCritic(6, 3, (8,), init_log_std=-0.5)
    with torch.no_grad():
        model.actor[-1].weight.normal_()
    snapshot = ActorSnapshot(model)
    obs = np.random.default_rng(3).normal(size=6).astype(np.float32)
    action, log_prob = snapshot.act(obs, False, np.random.default_rng(4))
    dist = model.distribution(torch.as_tensor(obs)[None])
    assert snapshot.act(obs, True)[0] == pytest.approx(dist.mean[0].detach().numpy(), abs=1e-6)
    assert log_prob == pytest.approx(float(dist.log_prob(torch.as_tensor(action)[None]).sum().detach()), abs=1e-4)


def test_normaliser_merges_batches_exactly():
    x = np.random.default_rng(1).normal(3.0, 2.0, (500, 4))
    n = Normaliser(4)
    n.update(x[:123])
    n.update(x[123:])
    assert n.mean == pytest.approx(x.mean(axis=0), rel=1e-6) and n.var == pytest.approx(x.var(axis=0), rel=1e-3)


def test_bad_training_config_is_one_line():
    with pytest.raises(ConfigError, match="ppo.learning_rate"):
        load_train_spec(None, ["ppo.learning_rate=-1"])
    with pytest.raises(ConfigError, match="run.workers"):
        load_train_spec(None, ["run.workers=0"])
    with pytest.raises(ConfigError, match="key=value"):
        load_train_spec(None, ["samples"])


def _rows(path):
    with open(path) as f:
        return list(csv.DictReader(f))


def test_checkpoint_policy_and_resume(tmp_path):
    spec = load_train_spec(None, TINY)
    first = train(spec, tmp_path / "a", say=None)
    assert first["samples"] >= 150
    # The policy file gives the trainer's actions and normaliser back.
    trainer = Trainer(spec, tmp_path / "a")
    trainer.resume()
    policy = ResidualPolicy.load(tmp_path / "a" / "policy.pt")
    assert policy.normaliser.mean == pytest.approx(trainer.normaliser.mean)
    obs = np.random.default_rng(2).normal(size=(5, trainer.model_args.n_obs)).astype(np.float32)
    mine, loaded = ActorSnapshot(trainer.model), ActorSnapshot(policy.model)
    for o in obs:
        assert np.array_equal(mine.act(trainer.normaliser(o), True)[0], loaded.act(policy.normaliser(o), True)[0])
    # Resuming with more samples continues the count and gives what one long run gives.
    longer = load_train_spec(None, TINY + ["run.samples=400"])
    resumed = train(longer, tmp_path / "a", resume=True, say=None)
    straight = train(longer, tmp_path / "b", say=None)
    assert resumed["samples"] == straight["samples"] > first["samples"]
    a_rows, b_rows = _rows(tmp_path / "a" / "progress.csv"), _rows(tmp_path / "b" / "progress.csv")
    assert [r["samples"] for r in a_rows] == [r["samples"] for r in b_rows]
    assert [r["mean_return"] for r in a_rows] == [r["mean_return"] for r in b_rows]
    with pytest.raises(ConfigError, match="another configuration"):
        Trainer(load_train_spec(None, TINY + ["ppo.clip=0.1"]), tmp_path / "a").resume()


def test_a_damaged_policy_file_is_one_line(tmp_path):
    (tmp_path / "p.pt").write_bytes(b"not a policy")
    with pytest.raises(ConfigError, match="not a layered-swim policy file"):
        ResidualPolicy.load(tmp_path / "p.pt")
    with pytest.raises(ConfigError, match="no such policy file"):
        ResidualPolicy.load(tmp_path / "none.pt")


def _cli(*args):
    return subprocess.run([sys.executable, "-m", "layered_swim", *args], capture_output=True, text=True, timeout=600)


def test_cli_train_then_goal_with_the_policy(tmp_path):
    out = tmp_path / "t"
    sets = [x for item in TINY for x in ("--set", item)]
    done = _cli("train", *sets, "--samples", "150", "--buffer", "fifo", "--out", str(out), "--no-progress", "--json")
    assert done.returncode == 0, done.stderr
    assert json.loads(done.stdout)["samples"] >= 150
    config = json.loads((out / "config.json").read_text())
    assert config["command"] == "train" and config["buffer"]["eviction"] == "fifo"     # --buffer is buffer.eviction
    again = _cli("train", *sets, "--out", str(out), "--no-progress")
    assert again.returncode == 2 and "--resume" in again.stderr and len(again.stderr.strip().splitlines()) == 1
    goal = _cli("goal", "--policy", str(out / "policy.pt"), "--seeds", "1", "--json")
    assert goal.returncode == 0, goal.stderr
    result = json.loads(goal.stdout)
    assert len(result["runs"]) == 3
    assert set(result["heuristic"]) == {"pos_m", "prog", "dev_m", "roll_deg", "success_rate"}
    follow = _cli("follow", "straight_line", "--stroke", "front_crawl", "--seconds", "2", "--policy",
                  str(out / "policy.pt"), "--out", str(tmp_path / "f"), "--json")
    assert follow.returncode == 0, follow.stderr
    followed = json.loads(follow.stdout)
    assert followed["reference"] == "layered" and np.isfinite(followed["mean_distance_m"])
    # Over perturbed starts, in two worker processes (a parent holding torch once hung forked ones).
    seeds = subprocess.run([sys.executable, "-m", "layered_swim", "follow", "straight_line", "--stroke", "front_crawl",
                            "--seconds", "2", "--seeds", "2", "--workers", "2", "--policy", str(out / "policy.pt"),
                            "--out", str(tmp_path / "s"), "--json"], capture_output=True, text=True, timeout=300)
    assert seeds.returncode == 0, seeds.stderr
    summary = json.loads(seeds.stdout)
    assert summary["policy"] == str(out / "policy.pt") and summary["layers"] == followed["layers"]
    distances = [r["mean_distance_m"] for r in summary["runs"]]
    assert len(distances) == 2 and np.all(np.isfinite(distances)) and distances[0] != distances[1]
    wrong = _cli("follow", "straight_line", "--seconds", "2", "--policy", str(out / "policy.pt"),
                 "--out", str(tmp_path / "g"))
    assert wrong.returncode == 2 and "--stroke front_crawl" in wrong.stderr
    bad = _cli("goal", "--policy", str(tmp_path / "missing.pt"))
    assert bad.returncode == 2 and "no such policy file" in bad.stderr


def test_ray_workers_give_the_local_result(tmp_path):
    pytest.importorskip("ray")
    spec = load_train_spec(None, TINY + ["run.workers=2"])
    on_ray = train(spec, tmp_path / "ray", ray_address="local", say=None)
    local = train(spec, tmp_path / "local", say=None)
    assert on_ray["last"]["mean_return"] == local["last"]["mean_return"]


def test_swim_table_quick_has_every_controller_and_swims_the_shipped_policy(tmp_path):
    done = _cli("experiment", "swim-table", "--quick", "--out", str(tmp_path), "--no-progress", "--json")
    assert done.returncode == 0, done.stderr
    summary = json.loads(done.stdout)
    rows = {(r["controller"], r["column"]): r for r in summary["rows"]}
    names = ("basic stroke", "layered", "basic + residual", "layered + residual")
    assert set(rows) == {(n, c) for n in names for c in ("3 m static", "3 m dynamic")}
    for column in ("3 m static", "3 m dynamic"):
        for name in ("layered + residual", "basic + residual"):      # both shipped policies swim
            mine = rows[(name, column)]
            assert mine["missing"] is None and 0 < mine["pos_m"] < 1.0 and mine["episodes"] == 1
            assert mine["prog_error"] == pytest.approx(abs(1.0 - mine["prog"]))      # one episode
            assert set(mine["beats_swim"]) == {"pos", "prog", "dev", "all"}
        assert rows[("layered + residual", column)]["success_rate"] == 1.0
    assert set(summary["residual_vs_swim"]["columns"]) == {"3 m static", "3 m dynamic"}
    assert not summary["residual_vs_swim"]["all"]         # two columns of four are no verdict
    assert (tmp_path / "swim_table.png").is_file() and "SWIM" in (tmp_path / "swim_table.csv").read_text()


def test_swim_table_scores_against_swim_by_hand():
    from layered_swim.analysis.experiments import swim_table as st

    runs = [{"pos_m": 0.1, "prog": 0.9, "dev_m": 0.03, "roll_deg": 0.0, "success": True},
            {"pos_m": 0.2, "prog": 1.2, "dev_m": 0.05, "roll_deg": 1.0, "success": False}]
    row = st.column_scores(runs)
    assert row == pytest.approx({"episodes": 2, "pos_m": 0.15, "prog": 1.05, "prog_error": 0.15, "dev_m": 0.04,
                                 "roll_deg": 0.5, "success_rate": 0.5})
    swim = {"pos_m": 0.126, "prog": 0.712, "dev_m": 0.037}
    assert st.against_swim(row, swim) == {"pos": False, "prog": True, "dev": False, "all": False}
    good = {**row, "pos_m": 0.1, "dev_m": 0.03}
    assert st.against_swim(good, swim)["all"]
    rows = [{"controller": "layered + residual", "fluid": "plate", "column": c, "missing": None,
             "beats_swim": {"all": True}, "success_rate": 1.0 if c != "5 m static" else 0.9} for c in st.COLUMNS]
    verdict = st.verdict(rows)
    assert verdict["columns"]["5 m static"] is False and not verdict["all"]      # an early end in quiet water
    rows[2]["success_rate"] = 1.0
    assert st.verdict(rows)["all"]
    missing = st.run({"residual": "layered", "policy_sha256": None})       # no policy file: a row that says so
    assert "no trained layered-reference policy" in missing["missing"]


def test_pool_workers_end_with_a_killed_trainer():
    import os
    import signal
    import time

    code = ("import time\nfrom layered_swim.rl.rollouts import Rollouts\n"
            "r = Rollouts({'env_state': 'NoEnv'}, 2)\nlist(r._pool.map(abs, [1, 2]))\n"
            "print(' '.join(str(p) for p in r._pool._processes), flush=True)\ntime.sleep(120)\n")
    parent = subprocess.Popen([sys.executable, "-c", code], stdout=subprocess.PIPE, text=True)
    workers = [int(p) for p in parent.stdout.readline().split()]
    os.kill(parent.pid, signal.SIGKILL)
    parent.wait()
    deadline = time.time() + 10
    while time.time() < deadline and any(os.path.exists(f"/proc/{p}") and
                                         open(f"/proc/{p}/stat").read().split()[2] != "Z" for p in workers):
        time.sleep(0.2)
    assert len(workers) == 2
    assert not [p for p in workers if os.path.exists(f"/proc/{p}") and open(f"/proc/{p}/stat").read().split()[2] != "Z"]


def test_a_training_starts_from_a_policy_of_the_same_shape(tmp_path):
    first = train(load_train_spec(None, TINY), tmp_path / "a", say=None)
    config = tmp_path / "stage2.yaml"
    config.write_text("run:\n  start_from: a/policy.pt\n")          # relative to the configuration file
    spec = load_train_spec(config, TINY)
    assert spec.run.start_from == str((tmp_path / "a" / "policy.pt").resolve())
    trainer, policy = Trainer(spec, tmp_path / "b"), ResidualPolicy.load(first["policy"])
    for name, value in policy.model.state_dict().items():
        assert torch.equal(trainer.model.state_dict()[name], value)
    assert trainer.normaliser.mean == pytest.approx(policy.normaliser.mean)
    with pytest.raises(ConfigError, match="another network"):
        Trainer(load_train_spec(config, TINY + ["ppo.hidden=[8]"]), tmp_path / "c")
    with pytest.raises(ConfigError, match="run.start_from: no policy file"):
        load_train_spec(None, ["run.start_from=nowhere.pt"])



def test_a_start_typed_with_set_is_read_from_the_working_folder(tmp_path, monkeypatch):
    (tmp_path / "a").mkdir()
    (tmp_path / "a" / "policy.pt").write_bytes(b"")
    (tmp_path / "configs").mkdir()
    config = tmp_path / "configs" / "stage.yaml"
    config.write_text("run:\n  start_from: ../a/policy.pt\n")
    monkeypatch.chdir(tmp_path)
    expected = str((tmp_path / "a" / "policy.pt").resolve())
    assert load_train_spec(config, TINY).run.start_from == expected
    assert load_train_spec(config, TINY + ["run.start_from=a/policy.pt"]).run.start_from == expected
    with pytest.raises(ConfigError, match="--set run.start_from: no policy file"):
        load_train_spec(config, ["run.start_from=../a/policy.pt"])


def test_a_policy_file_from_before_draws_loads_as_trained_without_them():
    from layered_swim.analysis.experiments.swim_table import POLICIES

    quiet = ResidualPolicy.load(POLICIES / "front_crawl_layered_quiet.pt")
    assert quiet.env.draws is None and quiet.env.pool == "small"
    shipped = ResidualPolicy.load(POLICIES / "front_crawl_layered.pt")
    assert shipped.env.reference == "layered" and shipped.env.draws.pools == ("small", "large")


@pytest.mark.parametrize("name", ["front_crawl.yaml", "front_crawl_anywhere.yaml", "front_crawl_steady.yaml"])
def test_each_shipped_training_file_loads_and_starts_from_a_shipped_policy(name):
    from layered_swim.rl.config import SHIPPED_CONFIG

    spec = load_train_spec(SHIPPED_CONFIG.parent / name)
    if spec.run.start_from is not None:
        policy = ResidualPolicy.load(spec.run.start_from)
        assert policy.env.stroke == spec.env.stroke == "front_crawl"
