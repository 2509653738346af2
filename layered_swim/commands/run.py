"""``layered-swim run``: swim a stroke headless and write summary, log and config; or, with
``--config``, swim a run, follow or goal folder's swim again, bit for bit."""
from __future__ import annotations

import json
import sys

from layered_swim.commands.export import export_option, export_swim, export_target
from layered_swim.commands.options import (
    added_mass_option,
    backend_option,
    flag,
    integrator_option,
    medium,
    out_dir,
    overwrite_option,
    swim_spec,
    water_option,
    water_options,
)
from layered_swim.commands.tables import flat, fmt, table

# What describes the swim itself: with --config these come from the file, so none may be given.
SWIM_OPTIONS = ("stroke", "seconds", "lung_air_l", "density", "fluid", "seed", "physics_hz", "integrator", "tempo",
                "backend", "pool", "water_depth", "particle_radius", "threads", "deterministic", "added_mass")


def add_parser(subparsers) -> None:
    command = subparsers.add_parser("run", help="swim a stroke headless and write summary, log and config "
                                                "(or repeat a run folder's swim with --config)")
    what = command.add_mutually_exclusive_group(required=True)
    what.add_argument("--stroke", help="stroke name (see `strokes`) or path to a stroke .yaml")
    what.add_argument("--config", metavar="FILE", help="a run, follow or goal folder's config.json: swim it again, "
                                                       "the same log bit for bit")
    command.add_argument("--seconds", type=float, default=30.0, help="simulated seconds (default 30)")
    command.add_argument("--out", help="output folder (default runs/<stroke>-<timestamp>)")
    overwrite_option(command)
    command.add_argument("--json", action="store_true", help="print the summary as one JSON object")
    export_option(command)
    command.add_argument("--lung-volume", type=float, dest="lung_air_l", metavar="L",
                         help="inhaled air in litres, on top of the residual volume (default 3)")
    water_options(command)
    water_option(command)
    command.add_argument("--tempo", type=float, default=1.0, help="stroke rate multiplier (default 1)")
    backend_option(command)
    integrator_option(command)
    added_mass_option(command)
    command.set_defaults(swim_defaults={name: command.get_default(name) for name in SWIM_OPTIONS})


def run(args) -> None:
    from layered_swim.runs import default_out_dir, run_swim

    if args.config:
        return _repeat(args)
    spec = swim_spec(args, args.stroke, {"kind": "free"}, seconds=args.seconds, medium=medium(args, current=False),
                     physics_hz=args.physics_hz, tempo=args.tempo, lung_air_l=args.lung_air_l, seed=args.seed)
    out = out_dir(args, default_out_dir(args.stroke))
    target = export_target(args)
    result = run_swim(spec, out, progress=not args.json and sys.stderr.isatty())
    result.update(export_swim(target, out.path))
    _report(args, result, out.path, "summary.json, config.json, log.npz, timeseries.csv")


def _repeat(args) -> None:
    from layered_swim.config import ConfigError
    from layered_swim.learned import steering_for
    from layered_swim.outputs import check_out_dir
    from layered_swim.runs import default_out_dir, follow_run, goal_run, repeatable, run_swim

    given = [flag(name) for name in SWIM_OPTIONS if getattr(args, name) != args.swim_defaults[name]]
    if given:
        raise ConfigError(f"--config repeats the swim as its file describes it: drop {', '.join(given)}")
    command, spec = repeatable(args.config)
    if command == "goal" and args.export:
        raise ConfigError("--export writes one swim, and a goal folder holds one per goal: export its goal-<k> "
                          "folders with `layered-swim export`")
    default = default_out_dir(f"{command}-{spec.stroke}")
    out = check_out_dir(default if args.out is None else args.out, command, args.overwrite)
    target = export_target(args)
    if command == "follow":
        result = follow_run(spec, out, steering_for(spec))
    else:
        result = {"run": run_swim, "goal": goal_run}[command](spec, out)
    result.update(export_swim(target, out.path))
    _report(args, result, out.path, f"the `{command}` swim of {args.config}")


def _report(args, result: dict, path, what: str) -> None:
    if args.json:
        print(json.dumps({**result, "out_dir": str(path)}, allow_nan=False))
        return
    print(table([[k, fmt(v)] for k, v in flat(result).items() if v is not None]))
    print(f"\nwrote {what} to {path}")
