"""``layered-swim train``: PPO with an episode buffer (ProgEvict or FIFO) on SWIM's goal task.

Each epoch: collect ``episodes_per_epoch`` episodes with the current policy (rollout workers),
update the observation normaliser, put the episodes in the buffer (evicting), run PPO over the
buffer. Every ``checkpoint_every`` epochs ``checkpoint.pt`` (everything, for ``--resume``) and
``policy.pt`` (the actor and normaliser, for ``goal --policy``) are written atomically; every
``eval_every`` epochs the deterministic policy swims the three goals. ``progress.csv`` logs
each epoch; ``config.json`` is the resolved configuration.
"""
from __future__ import annotations

import csv
import io
import time
from pathlib import Path

import numpy as np
import torch

from layered_swim.config import ConfigError, parse
from layered_swim.outputs import COMMAND_KEY, OutputFolder, atomic_path, claim, folder_path, write_json, write_text
from layered_swim.rl.buffer import EpisodeBuffer
from layered_swim.rl.checkpoint import (
    CHECKPOINT_FORMAT,
    MAX_COUNT,
    adam_state,
    buffer_episodes,
    episode_state,
    numpy_rng,
    read_checkpoint,
    torch_generator,
)
from layered_swim.rl.checks import check_normaliser, check_tensors, is_count, is_number
from layered_swim.rl.config import TrainSpec
from layered_swim.rl.policy import ResidualPolicy, env_arguments, evaluate_goals
from layered_swim.rl.ppo import ActorCritic, ModelArgs, Normaliser, update
from layered_swim.rl.rollouts import Rollouts, make_env

CHECKPOINT, POLICY, LOG = "checkpoint.pt", "policy.pt", "progress.csv"
LOG_FIELDS = ("epoch", "samples", "wall_s", "samples_per_s", "mean_return", "mean_steps", "terminated",
              "buffer_episodes", "evicted", "policy_loss", "value_loss", "clip_fraction", "approx_kl",
              "eval_pos_m", "eval_prog", "eval_dev_m", "eval_roll_deg")


def env_kwargs(spec: TrainSpec) -> dict:
    return env_arguments(spec.env, spec.reward)


class Trainer:
    def __init__(self, spec: TrainSpec, out_dir: Path, ray_address: str | None = None):
        self.spec, self.out = spec, Path(out_dir)
        probe = make_env(env_kwargs(spec))
        n_obs, n_act = probe.observation_space.shape[0], probe.action_space.shape[0]
        self.layout = probe.layout.describe()
        probe.close()
        self.model_args = ModelArgs(n_obs, n_act, tuple(spec.ppo.hidden), spec.ppo.init_log_std)
        torch.manual_seed(spec.run.seed)
        self.model = ActorCritic(*self.model_args)
        self.optimiser = torch.optim.Adam(self.model.parameters(), lr=spec.ppo.learning_rate)
        self.normaliser = Normaliser(n_obs)
        if spec.run.start_from is not None:
            self._start_from(spec.run.start_from)
        self.buffer = EpisodeBuffer(spec.buffer)
        self.rng = np.random.default_rng(spec.run.seed)
        self.generator = torch.Generator().manual_seed(spec.run.seed)
        self.epoch, self.samples, self.wall_s = 0, 0, 0.0
        self.ray_address = ray_address

    def _start_from(self, path: str) -> None:
        """The network and normaliser of a trained policy of the same shape (a curriculum's earlier stage)."""
        start = ResidualPolicy.load(path)
        shape = ("n_obs", "n_act", "hidden")        # its learnt noise replaces init_log_std
        if [getattr(start.model_args, k) for k in shape] != [getattr(self.model_args, k) for k in shape]:
            raise ConfigError(f"{path}: run.start_from has another network ({start.model_args}) than this "
                              f"configuration builds ({self.model_args})")
        self.model.load_state_dict(start.model.state_dict())
        self.normaliser.load_state_dict(start.normaliser.state_dict())

    # -- checkpoints ----------------------------------------------------------------------
    def policy(self) -> ResidualPolicy:
        return ResidualPolicy(self.model, self.normaliser, self.spec.env, self.spec.reward, self.model_args)

    def save(self) -> None:
        state = {"format": CHECKPOINT_FORMAT, "spec": self.spec.model_dump(mode="json"),
                 "model": self.model.state_dict(),
                 "optimiser": self.optimiser.state_dict(), "normaliser": self.normaliser.state_dict(),
                 "epoch": self.epoch, "samples": self.samples, "wall_s": self.wall_s,
                 "rng": self.rng.bit_generator.state, "generator": self.generator.get_state(),
                 "buffer": [episode_state(e) for e in self.buffer.episodes]}
        for name, data in ((CHECKPOINT, state), (POLICY, self.policy().to_file())):
            with atomic_path(self.out / name) as tmp:
                torch.save(data, tmp)

    def resume(self) -> None:
        """Continue from ``checkpoint.pt``, every part checked before any is used (it may be a
        file someone handed over): a bad one is one ConfigError line naming it."""
        path = self.out / CHECKPOINT
        if not path.exists():
            raise ConfigError(f"{path}: nothing to resume (no checkpoint)")
        state = read_checkpoint(path)
        spec = parse(TrainSpec, state["spec"], f"{path}: spec")
        if _what_trains(spec.model_dump(mode="json")) != _what_trains(self.spec.model_dump(mode="json")):
            raise ConfigError(f"{path}: the checkpoint was trained with another configuration than the one given "
                              f"(see {self.out / 'config.json'})")
        n_obs, n_act = self.model_args.n_obs, self.model_args.n_act
        weights = check_tensors(state["model"], self.model.state_dict(), "model", path)
        moments = adam_state(state["optimiser"], list(self.model.parameters()), path)
        scaling = check_normaliser(state["normaliser"], n_obs, path)
        epoch, samples, wall_s = state["epoch"], state["samples"], state["wall_s"]
        if not (is_count(epoch, 0, MAX_COUNT) and is_count(samples, 0, MAX_COUNT)
                and is_number(wall_s) and wall_s >= 0):
            raise ConfigError(f"{path}: epoch and samples must be whole numbers, wall_s a number, none below 0")
        rng, generator = numpy_rng(state["rng"], path), torch_generator(state["generator"], path)
        episodes = buffer_episodes(state["buffer"], n_obs, n_act, self.buffer.capacity, epoch, path)
        self.model.load_state_dict(weights)
        # The settings are the configuration's (the checkpoint's is the same: checked above).
        self.optimiser.load_state_dict({"state": moments, "param_groups": self.optimiser.state_dict()["param_groups"]})
        self.normaliser.load_state_dict(scaling)
        self.epoch, self.samples, self.wall_s = epoch, samples, float(wall_s)
        self.rng, self.generator = rng, generator
        self.buffer.episodes = episodes

    # -- the loop -------------------------------------------------------------------------
    def run(self, progress: bool = False, say=print) -> dict:
        spec = self.spec.run
        rollouts = Rollouts(env_kwargs(self.spec), spec.workers, self.ray_address)
        bar = None
        if progress:
            from tqdm import tqdm

            bar = tqdm(total=spec.samples, initial=min(self.samples, spec.samples), unit="sample", desc="train")
        last = {}
        try:
            while self.samples < spec.samples:
                started = time.perf_counter()
                seeds = [int(s) for s in self.rng.integers(2**31, size=spec.episodes_per_epoch)]
                episodes = rollouts.collect(self.model, self.model_args, self.normaliser, seeds)
                self.normaliser.update(np.concatenate([e.obs for e in episodes]))
                evicted = self.buffer.add(episodes, self.epoch, self.rng)
                stats = update(self.model, self.optimiser, self.buffer.episodes, self.normaliser, self.spec.ppo,
                               self.generator)
                new = sum(e.steps for e in episodes)
                self.samples += new
                self.epoch += 1
                elapsed = time.perf_counter() - started
                self.wall_s += elapsed
                row = {"epoch": self.epoch, "samples": self.samples, "wall_s": round(self.wall_s, 2),
                       "samples_per_s": round(new / elapsed, 1),
                       "mean_return": float(np.mean([e.episode_return for e in episodes])),
                       "mean_steps": float(np.mean([e.steps for e in episodes])),
                       "terminated": sum(not e.truncated for e in episodes),
                       "buffer_episodes": len(self.buffer.episodes), "evicted": evicted, **stats}
                if self.epoch % spec.eval_every == 0 or self.samples >= spec.samples:
                    scores = evaluate_goals(self.policy(), seeds=1)
                    row.update({f"eval_{k}": scores[k] for k in ("pos_m", "prog", "dev_m", "roll_deg")})
                _append_log(self.out / LOG, row)
                if self.epoch % spec.checkpoint_every == 0 or self.samples >= spec.samples:
                    self.save()
                if bar is not None:
                    bar.update(min(new, spec.samples - bar.n))
                    bar.set_postfix(samples_s=row["samples_per_s"], ret=f"{row['mean_return']:.1f}")
                elif say is not None:
                    say(f"epoch {self.epoch}: {self.samples} samples, {row['samples_per_s']:.0f}/s, "
                        f"mean return {row['mean_return']:.2f}")
                last = row
        finally:
            if bar is not None:
                bar.close()
            rollouts.close()
        return {"epochs": self.epoch, "samples": self.samples, "wall_s": round(self.wall_s, 1), "last": last,
                "checkpoint": str(self.out / CHECKPOINT), "policy": str(self.out / POLICY)}


def train(spec: TrainSpec, out_dir: OutputFolder | Path, resume: bool = False, progress: bool = False,
          ray_address: str | None = None, say=print) -> dict:
    """Train into ``out_dir``: claimed (an ``OutputFolder``) only once the environment is built
    and, with ``resume``, the checkpoint read and checked."""
    trainer = Trainer(spec, folder_path(out_dir), ray_address)
    if resume:
        trainer.resume()
    claim(out_dir)
    if resume:
        _truncate_log(trainer.out / LOG, trainer.epoch)
    write_json(trainer.out / "config.json", {COMMAND_KEY: "train", **spec.model_dump(mode="json"),
                                               "observation_layout": trainer.layout,
                                               "ray_address": ray_address})
    return trainer.run(progress, say)


def _what_trains(spec: dict) -> dict:
    """The configuration less what a resumed run may change: how long, on how many workers,
    how often it evaluates and saves."""
    run = {k: v for k, v in spec.get("run", {}).items()
           if k not in ("samples", "workers", "eval_every", "checkpoint_every")}
    return {**spec, "run": run}


def _append_log(path: Path, row: dict) -> None:
    new = not path.exists()
    with path.open("a", newline="") as f:
        writer = csv.DictWriter(f, LOG_FIELDS, extrasaction="ignore")
        if new:
            writer.writeheader()
        writer.writerow(row)


def _truncate_log(path: Path, epoch: int) -> None:
    """Drop log rows after the checkpoint's epoch (a kill between a log row and its checkpoint)."""
    if not path.exists():
        return
    rows = list(csv.DictReader(io.StringIO(path.read_text())))
    out = io.StringIO()
    writer = csv.DictWriter(out, LOG_FIELDS, extrasaction="ignore")
    writer.writeheader()
    writer.writerows(r for r in rows if int(r["epoch"]) <= epoch)
    write_text(path, out.getvalue())
