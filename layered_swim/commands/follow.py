"""``layered-swim follow``: chase a target moving along a trajectory file."""
from __future__ import annotations

import json
from pathlib import Path

from layered_swim.commands.export import export_option, export_swim, export_target
from layered_swim.commands.options import (
    backend_option,
    count,
    integrator_option,
    medium,
    out_dir,
    overwrite_option,
    parallel_options,
    progress,
    ray_option,
    steering_options,
    swim_spec,
)
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
    export_option(follow)
    follow.add_argument("--policy", metavar="FILE", help="a trained residual (policy.pt from `train`) on its reference "
                                                          "controller (--layers then comes from the policy)")
    follow.add_argument("--seeds", type=count(1, 1000), metavar="N",
                        help="swim N times from starts moved by up to 10 deg and 0.3 m, and report each headline "
                             "number's median (and range) over them (with --policy too)")
    parallel_options(follow)
    ray_option(follow)
    backend_option(follow, pool="large")       # a trajectory's target starts 2 m ahead
    integrator_option(follow)


def run(args) -> None:
    from layered_swim.learned import steering_for
    from layered_swim.runs import default_out_dir, follow_run

    spec = swim_spec(args, args.stroke, {"kind": "follow", "trajectory": args.trajectory}, seconds=args.seconds,
                     medium=medium(args), layers=args.layers, policy=args.policy)
    if args.seeds is not None:
        _follow_seeds(args, spec)
        return
    if args.ray:
        from layered_swim.config import ConfigError

        raise ConfigError("--ray spreads the starts of --seeds N: one swim runs here")
    out = out_dir(args, default_out_dir(f"follow-{Path(args.trajectory).stem}"))
    target = export_target(args)
    result = follow_run(spec, out, steering_for(spec))
    result.update(export_swim(target, out.path))
    if args.json:
        print(json.dumps({**result, "out_dir": str(out.path)}, allow_nan=False))
        return
    rows = {k: v for k, v in result.items() if not isinstance(v, dict) and k != "holds"}
    rows["strokes_swum"] = ", ".join(f"{spell['stroke']} {spell['from_s']:.1f}-{spell['to_s']:.1f} s"
                                     for spell in result["strokes_swum"])
    for n, hold in enumerate(result.get("holds", []), 1):
        rows[f"hold {n}"] = (f"z {hold['target_z_m']:.2f} m, {hold['from_s']:.1f}-{hold['to_s']:.1f} s: mean error "
                             f"{hold['mean_error_m']:.2f} m, worst {hold['max_error_m']:.2f} m at "
                             f"{hold['max_error_at_s']:.1f} s, pelvis {hold['mean_above_m']:+.2f} m above on average")
    rows.update({f"swim.{k}": v for k, v in result.get("swim_metrics", {}).items() if v is not None})
    print(table([[k, fmt(v)] for k, v in rows.items()]))
    print(f"\nwrote summary.json, config.json, track.npz, log.npz, timeseries.csv to {out.path}")


def _follow_seeds(args, spec) -> None:
    from layered_swim.analysis.robustness import follow_seeds
    from layered_swim.config import ConfigError
    from layered_swim.runs import default_out_dir

    if args.backend != "plate":
        raise ConfigError("--seeds runs on the plate backend only (no --backend sph)")
    if args.export:
        raise ConfigError("--export writes one swim: not with --seeds")
    out = out_dir(args, default_out_dir(f"follow-{Path(args.trajectory).stem}-seeds"))
    summary = follow_seeds(spec, args.seeds, out, args.workers, progress(args), ray_address=args.ray)
    if args.json:
        print(json.dumps({**summary, "out_dir": str(out.path)}, allow_nan=False))
        return
    rows = [[k, *(fmt(v[q]) for q in ("median", "min", "max"))] for k, v in summary["median"].items()]
    print(table(rows, ["over " + str(args.seeds) + " starts", "median", "min", "max"]))
    for n, hold in enumerate(summary.get("holds", []), 1):
        error = hold["max_error_m"]
        print(f"hold {n} (z {hold['target_z_m']:.2f} m, {hold['from_s']:.1f}-{hold['to_s']:.1f} s): largest depth "
              f"error {error['median']:.2f} m median ({error['min']:.2f}-{error['max']:.2f}), pelvis "
              f"{hold['mean_above_m']:+.2f} m above on average, the worst hold in {hold['worst_in_runs']} of "
              f"{args.seeds} starts")
    if "reached_all_share" in summary:
        print(f"\nreached every station in {summary['reached_all_share']:.0%} of the runs")
    print(f"\nwrote summary.json (every run) and config.json to {out.path}")
