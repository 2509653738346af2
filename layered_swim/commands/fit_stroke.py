"""``layered-swim fit-stroke``: search a stroke's numbers (CMA-ES, the [fit] extra) until its
swims land inside target ranges; resumable, with progress."""
from __future__ import annotations

import json
import sys
from pathlib import Path

from layered_swim.commands.options import MAX_WORKERS, count, out_dir, overwrite_option, progress


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
    fit.add_argument("--out", help="output folder (default runs/fit-<stroke>)")
    fit.add_argument("--resume", action="store_true", help="go on with the search in --out")
    overwrite_option(fit)
    fit.add_argument("--no-progress", action="store_true", help="no progress bar")
    fit.add_argument("--json", action="store_true", help="print the result as one JSON object")


def run(args) -> None:
    from layered_swim.analysis import stroke_fit
    from layered_swim.config import ConfigError, read_text
    from layered_swim.outputs import claim

    try:
        import cma  # noqa: F401
    except ImportError:
        raise ConfigError("fit-stroke needs the cma library: pip install 'layered-swim[fit]'") from None
    if args.resume and args.overwrite:
        raise ConfigError("--resume goes on with the search in --out and --overwrite starts it over: choose one")
    spec, stroke, source = stroke_fit.load_fit(args.targets, stroke=args.stroke, generations=args.generations)
    out = out_dir(args, Path("runs") / f"fit-{Path(spec.stroke).stem}")
    history = out.path / stroke_fit.HISTORY
    if args.resume and not history.is_file():
        raise ConfigError(f"{out.path}: nothing to resume (no {stroke_fit.HISTORY})")
    if not args.resume and history.is_file() and not args.overwrite:
        raise ConfigError(f"{out.path}: holds a search; add --resume to go on with it or --overwrite to start over")
    path = claim(out)
    say = None if args.json or progress(args) else (lambda text: print(text, file=sys.stderr))
    result = stroke_fit.fit(spec, stroke, read_text(source), path, workers=args.workers, resume=args.resume,
                            progress=progress(args), say=say)
    text = stroke_fit.report(result, spec)
    stroke_fit.write_report(path, text)
    print(json.dumps(result, allow_nan=False) if args.json else text)
