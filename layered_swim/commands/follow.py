"""``layered-swim follow``: chase a target moving along a trajectory file."""
from __future__ import annotations

import json
from pathlib import Path

from layered_swim.commands.options import (backend_option, count, fluid_settings, out_dir, overwrite_option,
                                           parallel_options, progress, steering_options, vector)
from layered_swim.commands.tables import fmt, table


def add_parser(subparsers) -> None:
    follow = subparsers.add_parser("follow", help="chase a target moving along a trajectory file")
    follow.add_argument("trajectory", help="trajectory name (see trajectories/) or path to a .yaml")
    follow.add_argument("--stroke", default="breaststroke", help="stroke name, path to a stroke .yaml, or auto "
                                                                 "(chooses and switches strokes)")
    steering_options(follow)
    follow.add_argument("--seconds", type=float, default=60.0)
    follow.add_argument("--out", help="output folder (default runs/follow-<trajectory>-<timestamp>)")
    overwrite_option(follow)
    follow.add_argument("--json", action="store_true")
    follow.add_argument("--policy", metavar="FILE", help="a trained residual (policy.pt from `train`) on its reference "
                                                          "controller (--layers then comes from the policy)")
    follow.add_argument("--seeds", type=count(1, 1000), metavar="N",
                        help="swim N times from starts moved by up to 10 deg and 0.3 m, and report each headline "
                             "number's median (and range) over them (with --policy too)")
    parallel_options(follow)
    backend_option(follow, pool="large")       # a trajectory's target starts 2 m ahead


def run(args) -> None:
    from layered_swim.control.layered import Layers
    from layered_swim.runs import default_out_dir, follow_run

    layers, steered = Layers.parse(args.layers), {}
    if args.seeds is not None:
        _follow_seeds(args, layers)
        return
    if args.policy:        # the residual on its own reference controller, run by its driver
        from layered_swim.rl.policy import follow_steering

        layers, steered = follow_steering(args.policy, args.stroke)
    out = out_dir(args, default_out_dir(f"follow-{Path(args.trajectory).stem}"))
    result = follow_run(args.trajectory, args.stroke, layers, vector(args.current, "--current"),
                        args.density, args.seconds, out, args.backend, fluid_settings(args), **steered)
    if args.json:
        print(json.dumps({**result, "out_dir": str(out.path)}, allow_nan=False))
        return
    rows = {k: v for k, v in result.items() if not isinstance(v, dict)}
    rows.update({f"swim.{k}": v for k, v in result.get("swim_metrics", {}).items() if v is not None})
    print(table([[k, fmt(v)] for k, v in rows.items()]))
    print(f"\nwrote summary.json, config.json, track.npz, log.npz to {out.path}")


def _follow_seeds(args, layers) -> None:
    from layered_swim.analysis.robustness import follow_seeds
    from layered_swim.config import ConfigError
    from layered_swim.runs import default_out_dir

    if args.backend != "plate":
        raise ConfigError("--seeds runs on the plate backend only (no --backend sph)")
    if args.policy:
        from layered_swim.rl.policy import follow_steering

        layers = follow_steering(args.policy, args.stroke)[0]     # fails here, in one line, not in every worker
    out = out_dir(args, default_out_dir(f"follow-{Path(args.trajectory).stem}-seeds"))
    summary = follow_seeds(args.trajectory, args.stroke, layers, vector(args.current, "--current"), args.density,
                           args.seconds, args.seeds, out, args.workers, progress(args), policy=args.policy)
    if args.json:
        print(json.dumps({**summary, "out_dir": str(out.path)}, allow_nan=False))
        return
    rows = [[k, *(fmt(v[q]) for q in ("median", "min", "max"))] for k, v in summary["median"].items()]
    print(table(rows, ["over " + str(args.seeds) + " starts", "median", "min", "max"]))
    if "reached_all_share" in summary:
        print(f"\nreached every station in {summary['reached_all_share']:.0%} of the runs")
    print(f"\nwrote summary.json (every run) and config.json to {out.path}")
