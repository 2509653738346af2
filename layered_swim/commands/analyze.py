"""``layered-swim analyze``: swim steadily (or read a run's log) and report per-cycle stroke
metrics, plots and a report."""
from __future__ import annotations

import json
import sys
from pathlib import Path

from layered_swim.commands.options import analysis_config, analysis_options, out_dir
from layered_swim.commands.tables import summary_rows, table


def add_parser(subparsers) -> None:
    analyze = subparsers.add_parser("analyze", help="swim steadily and report per-cycle stroke metrics, plots "
                                                    "and a report")
    what = analyze.add_mutually_exclusive_group(required=True)
    what.add_argument("--stroke", help="stroke name (see `strokes`) or path to a stroke .yaml: swim it now")
    what.add_argument("--run", metavar="DIR", help="analyze the log of a `run` folder instead (a stopped, "
                                                   "partial one too)")
    analysis_options(analyze)
    analyze.add_argument("--out", help="output folder (default runs/analyze-<stroke>-<timestamp>)")


def run(args) -> None:
    from layered_swim.analysis.stroke_analysis import analyze_run, analyze_stroke, write_analysis
    from layered_swim.outputs import claim
    from layered_swim.runs import default_out_dir

    if args.run:
        out = out_dir(args, default_out_dir(f"analyze-{Path(args.run).name}"))
        result = analyze_run(args.run, args.settle)
    else:
        out = out_dir(args, default_out_dir(f"analyze-{Path(args.stroke).stem}"))
        config = analysis_config(args, args.stroke)
        claim(out)      # taken for the whole swim: a second analysis into it is refused now, not at the end
        result = analyze_stroke(config, progress=not args.json and sys.stderr.isatty())
    files = write_analysis(result, out)
    if args.json:
        print(json.dumps({"stroke": result["stroke"], **result["summary"], "out_dir": str(out.path)}, allow_nan=False))
        return
    print(table(summary_rows(result), ["quantity", "mean", "unit"]))
    print(f"\nwrote {', '.join(files)} to {out.path}")
