"""``layered-swim compare``: analyze several strokes and report them side by side."""
from __future__ import annotations

import json

from layered_swim.commands.options import analysis_config, analysis_options, out_dir, parallel_options, progress
from layered_swim.commands.tables import summary_rows, table


def add_parser(subparsers) -> None:
    compare = subparsers.add_parser("compare", help="analyze several strokes and report them side by side")
    compare.add_argument("--strokes", required=True, metavar="A,B,...", help="comma-separated stroke names")
    analysis_options(compare)
    compare.add_argument("--out", help="output folder (default runs/compare-<timestamp>)")
    parallel_options(compare)


def run(args) -> None:
    from layered_swim.analysis.stroke_analysis import write_comparison
    from layered_swim.config import ConfigError
    from layered_swim.runs import default_out_dir

    strokes = [s.strip() for s in args.strokes.split(",") if s.strip()]
    if not strokes or len(set(strokes)) != len(strokes):
        raise ConfigError(f"--strokes must name one or more different strokes, got '{args.strokes}'")
    out = out_dir(args, default_out_dir("compare"))
    configs = [analysis_config(args, stroke) for stroke in strokes]
    results = write_comparison(configs, out, args.workers, progress=progress(args))
    if args.json:
        print(json.dumps({r["stroke"]: r["summary"] for r in results} | {"out_dir": str(out.path)}, allow_nan=False))
        return
    names = [r["stroke"] for r in results]
    by_name = [dict((row[0], row[1]) for row in summary_rows(r)) for r in results]
    labels = list(dict.fromkeys(label for rows in by_name for label in rows))
    print(table([[label] + [rows.get(label, "-") for rows in by_name] for label in labels], ["quantity"] + names))
    print(f"\nwrote report.md, compare_profiles.png and one folder per stroke to {out.path}")
