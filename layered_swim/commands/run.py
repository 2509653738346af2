"""``layered-swim run``: swim a stroke headless and write summary, log and config."""
from __future__ import annotations

import json
import sys

from layered_swim.commands.options import backend_option, fluid_settings, out_dir, overwrite_option, water_options
from layered_swim.commands.tables import flat, fmt, table


def add_parser(subparsers) -> None:
    command = subparsers.add_parser("run", help="swim a stroke headless and write summary, log and config")
    command.add_argument("--stroke", required=True, help="stroke name (see `strokes`) or path to a stroke .yaml")
    command.add_argument("--seconds", type=float, default=30.0, help="simulated seconds (default 30)")
    command.add_argument("--out", help="output folder (default runs/<stroke>-<timestamp>)")
    overwrite_option(command)
    command.add_argument("--json", action="store_true", help="print the summary as one JSON object")
    command.add_argument("--lung-volume", type=float, dest="lung_air_l", metavar="L",
                         help="inhaled air in litres, on top of the residual volume (default 3)")
    water_options(command)
    command.add_argument("--tempo", type=float, default=1.0, help="stroke rate multiplier (default 1)")
    backend_option(command)


def run(args) -> None:
    from layered_swim.runs import default_out_dir, run_swim

    out = out_dir(args, default_out_dir(args.stroke))
    result = run_swim(args.stroke, args.seconds, args.lung_air_l, args.density, out, args.seed,
                      args.physics_hz, args.tempo, fluid=args.fluid, progress=not args.json and sys.stderr.isatty(),
                      backend=args.backend, fluid_settings=fluid_settings(args))
    if args.json:
        print(json.dumps({**result, "out_dir": str(out.path)}, allow_nan=False))
        return
    print(table([[k, fmt(v)] for k, v in flat(result).items() if v is not None]))
    print(f"\nwrote summary.json, config.json, log.npz, timeseries.csv to {out.path}")
