"""``layered-swim render``: draw a run folder or a trajectory swim to a video or PNG frames, no
display needed."""
from __future__ import annotations

import sys
from pathlib import Path

from layered_swim.commands import PROG
from layered_swim.commands.options import (backend_option, fluid_settings, overwrite_option, progress, size,
                                           steering_options, vector)


def add_parser(subparsers) -> None:
    render = subparsers.add_parser("render", help="draw a run folder or a trajectory swim to a video or PNG frames, no display needed")
    render.add_argument("source", help="a folder written by `run`/`follow --out` (replayed), or a trajectory (swum now)")
    render.add_argument("--out", required=True, help="video.mp4 (needs the video extra; else PNG frames) or a folder for PNGs")
    overwrite_option(render)
    render.add_argument("--seconds", type=float, help="length (default: the whole run, or 20 s of a trajectory)")
    render.add_argument("--fps", type=float, default=30.0)
    render.add_argument("--size", default="960x540", metavar="WxH")
    render.add_argument("--stroke", default="breaststroke", help="stroke for a trajectory (default breaststroke; "
                                                                "auto chooses)")
    steering_options(render)
    render.add_argument("--forces", action="store_true", help="draw the per-segment fluid-force arrows")
    render.add_argument("--no-progress", action="store_true", help="no progress bar")
    backend_option(render, pool="large")


def run(args) -> None:
    from layered_swim.render.headless import render
    from layered_swim.control.layered import Layers

    result = render(args.source, args.out, args.seconds, args.fps, size(args.size), args.stroke, Layers.parse(args.layers),
                    vector(args.current, "--current"), args.density, args.forces,
                    progress=progress(args), backend=args.backend, fluid_settings=fluid_settings(args),
                    overwrite=args.overwrite)
    if not result["video"] and Path(args.out).suffix.lower() == ".mp4":
        print(f"{PROG}: note: {result['note']}", file=sys.stderr)
    print(f"wrote {result['frames']} frames to {result['out']}")
