"""``layered-swim goal``: SWIM's goal-reaching benchmark (Pos, Prog, Dev, Roll), for the layered
controller or a trained residual policy beside it."""
from __future__ import annotations

import json

from layered_swim.commands.options import backend_option, count, fluid_settings, steering_options, vector
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
    backend_option(goal, pool=None)


def run(args) -> None:
    from layered_swim.control.layered import Layers
    from layered_swim.runs import goal_run
    from layered_swim.tasks.goal import GOAL_METRICS

    current, layers = vector(args.current, "--current"), Layers.parse(args.layers)
    if args.policy:
        return _goal_policy(args, current, layers)
    stroke = DEFAULT_STROKE if args.stroke is None else args.stroke
    result = goal_run(args.pool, stroke, current, layers, args.backend, fluid_settings(args))
    if args.backend != "plate":     # the same task on the plates, beside (seconds, against minutes)
        plate = goal_run(args.pool, stroke, current, layers)
        result["plate"] = {k: plate[k] for k in GOAL_METRICS}
    if args.json:
        print(json.dumps(result, allow_nan=False))
        return
    rows = [[f"goal y={g['goal_m'][1]:+.2f}"] + [f"{g[k]:.3f}" for k in GOAL_METRICS] for g in result["goals"]]
    rows.append([f"mean ({args.backend})"] + [f"{result[k]:.3f}" for k in GOAL_METRICS])
    if "plate" in result:
        rows.append(["mean (plate)"] + [f"{result['plate'][k]:.3f}" for k in GOAL_METRICS])
    print(table(rows, ["", "Pos m", "Prog", "Dev m", "Roll deg"]))


def _goal_policy(args, current, layers) -> None:
    import numpy as np

    from layered_swim.config import ConfigError
    from layered_swim.rl.policy import Policy, evaluate_goals
    from layered_swim.runs import goal_run
    from layered_swim.tasks.goal import GOAL_METRICS

    policy = Policy.load(args.policy)
    if args.stroke is not None and args.stroke != policy.env["stroke"]:
        raise ConfigError(f"{args.policy} was trained for {policy.env['stroke']}, not {args.stroke}")
    result = evaluate_goals(policy, args.seeds, pool=args.pool, backend=args.backend,
                            fluid_settings=fluid_settings(args), current_m_s=tuple(current))
    heuristic = goal_run(args.pool, policy.env["stroke"], current, layers, args.backend, fluid_settings(args))
    result = {"policy": args.policy, "pool": args.pool, "stroke": policy.env["stroke"], "reference": policy.env["reference"],
              "fluid_backend": args.backend, "current_m_s": list(current), "seeds": args.seeds, **result,
              "heuristic": {k: heuristic[k] for k in GOAL_METRICS}, "swim_published": heuristic["swim_published"]}
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
        print(f"{result['terminated']} of {len(result['runs'])} episodes ended early (left the pool or sank)")
