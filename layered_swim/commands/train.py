"""``layered-swim train``: train a residual policy with PPO on SWIM's goal task ([rl] extra)."""
from __future__ import annotations

import json
import sys
from pathlib import Path

from layered_swim.commands.options import MAX_WORKERS, count, progress, resumable_options, resumable_out_dir


def add_parser(subparsers) -> None:
    train = subparsers.add_parser("train", help="train a residual policy with PPO on SWIM's goal task ([rl] extra)")
    train.add_argument("--config", metavar="FILE", help="training YAML (default: the shipped front-crawl one)")
    train.add_argument("--set", action="append", default=[], metavar="KEY=VALUE",
                       help="override a field, e.g. --set ppo.learning_rate=1e-4 (repeatable)")
    train.add_argument("--samples", type=count(1, 10**10), help="environment steps in all (run.samples)")
    train.add_argument("--workers", type=count(1, MAX_WORKERS),
                       help="rollout worker processes (run.workers; default 2)")
    train.add_argument("--buffer", choices=("fifo", "progevict"), help="episode buffer eviction (buffer.eviction)")
    train.add_argument("--ray", metavar="ADDRESS",
                       help="run the rollout workers on a Ray cluster ('local': start one here)")
    resumable_options(train, "runs/train-<stroke>", "continue the training in --out from its checkpoint")


def run(args) -> None:
    from layered_swim.rl.config import load_train_spec
    from layered_swim.rl.train import CHECKPOINT, train

    overrides = list(args.set)
    for key, value in (("run.samples", args.samples), ("run.workers", args.workers), ("buffer.eviction", args.buffer)):
        if value is not None:
            overrides.append(f"{key}={value}")
    spec = load_train_spec(args.config, overrides)
    out = resumable_out_dir(args, Path("runs") / f"train-{spec.env.stroke}", CHECKPOINT, "training run")
    say = None if args.json or progress(args) else (lambda text: print(text, file=sys.stderr))
    result = train(spec, out, resume=args.resume, progress=progress(args), ray_address=args.ray, say=say)
    if args.json:
        print(json.dumps(result, allow_nan=False))
        return
    print(f"trained {result['samples']} samples in {result['epochs']} epochs ({result['wall_s']:.0f} s); "
          f"policy: {result['policy']}")
