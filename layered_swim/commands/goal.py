"""``layered-swim goal``: SWIM's goal-reaching benchmark (Pos, Prog, Dev, Roll), for the layered
controller or a trained residual policy beside it."""
from __future__ import annotations

import json

from layered_swim.commands.options import (
    backend_option,
    count,
    integrator_option,
    medium,
    out_dir,
    overwrite_option,
    steering_options,
    swim_spec,
    vector,
)
from layered_swim.commands.tables import fmt, table

DEFAULT_STROKE = "front_crawl"      # without --policy; with one, the policy's own stroke


def add_parser(subparsers) -> None:
    goal = subparsers.add_parser("goal", help="SWIM's goal-reaching benchmark (Pos, Prog, Dev, Roll)")
    goal.add_argument("--pool", choices=("small", "large"), default="small")
    goal.add_argument("--stroke", help=f"stroke (default {DEFAULT_STROKE}; with --policy, the policy's own)")
    steering_options(goal, density=False)
    goal.add_argument("--json", action="store_true")
    goal.add_argument("--policy", metavar="FILE", help="a trained residual (policy.pt from `train`) on its reference "
                                                        "controller, the heuristic beside it")
    goal.add_argument("--seeds", type=count(1, 100), default=5,
                      help="starts per goal with --policy, 1-100 (default 5): the first is SWIM's fixed start, "
                           "the others moved by up to 10 deg and 0.3 m")
    goal.add_argument("--out", help="log each goal's swim into this folder (goal-<k>/, each a run folder; "
                                     "default: no files)")
    overwrite_option(goal)
    backend_option(goal, pool=None)
    integrator_option(goal)


def run(args) -> None:
    from layered_swim.config import ConfigError
    from layered_swim.runs import default_out_dir, goal_run
    from layered_swim.tasks.goal import GOAL_METRICS

    if args.policy:
        if args.out is not None:
            raise ConfigError("--out logs the layered controller's swims; with --policy, use --json for the numbers")
        return _goal_policy(args)
    spec = _spec(args, DEFAULT_STROKE if args.stroke is None else args.stroke)
    out = None if args.out is None else out_dir(args, default_out_dir("goal"))
    result = goal_run(spec, out)
    if args.backend != "plate":     # the same task on the plates, beside (seconds, against minutes)
        plate = goal_run(spec.with_(backend="plate", sph=None))
        result["plate"] = {k: plate[k] for k in GOAL_METRICS}
    if args.json:
        print(json.dumps(result if out is None else {**result, "out_dir": str(out.path)}, allow_nan=False))
        return
    rows = [[f"goal y={g['goal_m'][1]:+.2f}"] + [f"{g[k]:.3f}" for k in GOAL_METRICS] for g in result["goals"]]
    rows.append([f"mean ({args.backend})"] + [f"{result[k]:.3f}" for k in GOAL_METRICS])
    if "plate" in result:
        rows.append(["mean (plate)"] + [f"{result['plate'][k]:.3f}" for k in GOAL_METRICS])
    print(table(rows, ["", "Pos m", "Prog", "Dev m", "Roll deg"]))
    for g in result["goals"]:
        if not g["success"]:
            print(f"goal y={g['goal_m'][1]:+.2f}: {g['ended']} after {g['ended_s']:.1f} s (scored to the horizon "
                  "where it stopped)")
    if out is not None:
        print(f"\nwrote summary.json, config.json and goal-<k>/ (each a run folder) to {out.path}")


def _spec(args, stroke: str):
    return swim_spec(args, stroke, {"kind": "goal", "pool": args.pool}, medium=medium(args), layers=args.layers)


def _goal_policy(args) -> None:
    import numpy as np

    from layered_swim.config import ConfigError
    from layered_swim.rl.policy import ResidualPolicy, evaluate_goals
    from layered_swim.runs import goal_run
    from layered_swim.tasks.goal import GOAL_METRICS

    if args.water:
        raise ConfigError("--water with --policy: the policy's environment takes a uniform --current only")
    policy = ResidualPolicy.load(args.policy)
    policy.check_stroke(args.stroke)
    stroke, current = policy.env.stroke, vector(args.current, "--current")
    spec = _spec(args, stroke)
    result = evaluate_goals(policy, args.seeds, pool=args.pool, backend=args.backend,
                            fluid_settings=spec.fluid_settings(), current_m_s=tuple(current),
                            integrator=args.integrator)
    heuristic = goal_run(spec)
    result = {"policy": args.policy, "pool": args.pool, "stroke": stroke, "reference": policy.env.reference,
              "fluid_backend": args.backend, "current_m_s": list(current), "seeds": args.seeds, **result,
              "heuristic": {k: heuristic[k] for k in (*GOAL_METRICS, "success_rate")},
              "swim_published": heuristic["swim_published"]}
    if args.json:
        print(json.dumps(result, allow_nan=False))
        return
    rows = []
    for goal in sorted({r["goal"] for r in result["runs"]}):
        runs = [r for r in result["runs"] if r["goal"] == goal and "pos_m" in r]
        rows.append([f"goal {goal}"] + [f"{np.mean([r[k] for r in runs]):.3f}" if runs else "-" for k in GOAL_METRICS])
    rows.append(["mean (policy)"] + [fmt(result[k]) for k in GOAL_METRICS])
    rows.append(["heuristic (layered)"] + [fmt(result["heuristic"][k]) for k in GOAL_METRICS])
    print(table(rows, ["", "Pos m", "Prog", "Dev m", "Roll deg"]))
    if result["terminated"]:
        print(f"{result['terminated']} of {len(result['runs'])} episodes ended early (left the pool or sank; "
              "scored to the horizon where they stopped)")
