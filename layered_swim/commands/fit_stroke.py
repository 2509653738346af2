"""``layered-swim fit-stroke``: search a stroke's numbers (CMA-ES, the [fit] extra) until its
swims land inside target ranges; resumable, with progress."""
from __future__ import annotations

import json
import sys
from pathlib import Path

from layered_swim.commands.options import MAX_WORKERS, count, progress, resumable_options, resumable_out_dir


def add_parser(subparsers) -> None:
    fit = subparsers.add_parser(
        "fit-stroke", help="search a stroke's key values, key times and period (CMA-ES) until its swims land "
                           "inside target ranges ([fit] extra; docs/cli.md)")
    fit.add_argument("--targets", required=True, metavar="FILE",
                     help="fit YAML (a path, or a name in strokes/fit/: front_crawl, ...): the stroke, target ranges "
                          "and the knobs the search may move")
    fit.add_argument("--stroke", help="stroke name or path (default: the fit file's)")
    fit.add_argument("--generations", type=count(1, 100_000), help="generations in all (default: the fit file's)")
    fit.add_argument("--workers", type=count(1, MAX_WORKERS), default=2, help="parallel swims (default 2)")
    resumable_options(fit, "runs/fit-<stroke>", "go on with the search in --out")


def run(args) -> None:
    from layered_swim.analysis import stroke_fit
    from layered_swim.config import ConfigError, read_text
    from layered_swim.outputs import claim, write_text

    try:
        import cma  # noqa: F401
    except ImportError:
        raise ConfigError("fit-stroke needs the cma library: pip install 'layered-swim[fit]'") from None
    spec, stroke, source = stroke_fit.load_fit(args.targets, stroke=args.stroke, generations=args.generations)
    out = resumable_out_dir(args, Path("runs") / f"fit-{Path(spec.stroke).stem}", stroke_fit.HISTORY, "search")
    path = claim(out)
    say = None if args.json or progress(args) else (lambda text: print(text, file=sys.stderr))
    result = stroke_fit.fit(spec, stroke, read_text(source), path, workers=args.workers, resume=args.resume,
                            progress=progress(args), say=say)
    text = stroke_fit.report(result, spec)
    write_text(path / "report.txt", text + "\n")
    print(json.dumps(result, allow_nan=False) if args.json else text)
