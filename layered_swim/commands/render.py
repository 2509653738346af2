"""``layered-swim render``: draw a run folder or a trajectory swim to a video, PNG frames or one
still PNG, no display needed."""
from __future__ import annotations

import sys
from pathlib import Path

from layered_swim.commands import PROG
from layered_swim.commands.options import (
    backend_option,
    fluid_settings,
    overwrite_option,
    progress,
    size,
    steering_options,
    vector,
)

CAMERAS = ("follow", "side", "underwater")     # render/camera.py's views, named here to keep --help light


def add_parser(subparsers) -> None:
    render = subparsers.add_parser("render", help="draw a run folder or a trajectory swim to a video, PNG frames "
                                                  "or one still, no display needed")
    render.add_argument("source", help="a folder written by `run`/`follow --out` (replayed), or a trajectory "
                                       "(swum now)")
    render.add_argument("--out", required=True, help="video.mp4 (needs the video extra; else PNG frames), a folder for "
                                                     "PNGs, or with --frame a .png")
    overwrite_option(render)
    render.add_argument("--seconds", type=float, help="length (default: the whole run, or 20 s of a trajectory; "
                                                      "with --frame, up to the frame)")
    render.add_argument("--frame", type=float, metavar="T", help="write one PNG of the moment T seconds into the swim")
    render.add_argument("--fps", type=float, default=30.0)
    render.add_argument("--size", default="960x540", metavar="WxH")
    render.add_argument("--camera", choices=CAMERAS, default="follow",
                        help="follow (from above, default), side (level with the surface) or underwater (looking up)")
    render.add_argument("--stroke", default="breaststroke", help="stroke for a trajectory (default breaststroke; "
                                                                "auto chooses)")
    steering_options(render)
    render.add_argument("--forces", action="store_true", help="draw the per-segment fluid-force arrows")
    render.add_argument("--flow", action="store_true", help="draw the water's flow: the current on a lattice around "
                                                            "the swimmer, the water velocity at each segment (a "
                                                            "trajectory swum now)")
    render.add_argument("--no-progress", action="store_true", help="no progress bar")
    backend_option(render, pool="large")


def run(args) -> None:
    from layered_swim.control.layered import Layers
    from layered_swim.render.headless import render

    result = render(args.source, args.out, args.seconds, args.fps, size(args.size), args.stroke,
                    Layers.parse(args.layers), vector(args.current, "--current"), args.density, args.forces,
                    progress=progress(args), backend=args.backend, fluid_settings=fluid_settings(args),
                    overwrite=args.overwrite, camera=args.camera, show_flow=args.flow, frame_s=args.frame,
                    water=args.water)
    if not result["video"] and Path(args.out).suffix.lower() == ".mp4":
        print(f"{PROG}: note: {result['note']}", file=sys.stderr)
    frames = result["frames"]
    print(f"wrote {frames} frame{'' if frames == 1 else 's'} to {result['out']}")
