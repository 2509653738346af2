"""``layered-swim soak``: swim for hours with the log streaming to disk, sampling memory."""
from __future__ import annotations

import json
import sys

from layered_swim.commands.options import out_dir, overwrite_option
from layered_swim.commands.tables import flat, fmt, table


def add_parser(subparsers) -> None:
    soak = subparsers.add_parser("soak", help="swim for hours with the log streaming to disk, sampling memory: "
                                              "reports RSS growth and whether everything stayed finite")
    soak.add_argument("--hours", type=float, default=1.0, help="simulated hours (default 1; ~10 min of wall time each)")
    soak.add_argument("--stroke", default="front_crawl")
    soak.add_argument("--out", help="output folder (default runs/soak-<timestamp>)")
    overwrite_option(soak)
    soak.add_argument("--json", action="store_true")


def run(args) -> None:
    from layered_swim.runs import default_out_dir, soak

    out = out_dir(args, default_out_dir("soak"))
    result = soak(args.hours, args.stroke, out, progress=not args.json and sys.stderr.isatty())
    if args.json:
        print(json.dumps({**result, "out_dir": str(out.path)}, allow_nan=False))
        return
    print(table([[k, fmt(v)] for k, v in flat(result).items() if v is not None]))
    print(f"\nwrote summary.json, config.json, log.npz, timeseries.csv to {out.path}")
