"""``layered-swim app`` (and ``python app.py``): the swimmer chases the point you click on the
water, in a real-time 3-D window.

It checks the arguments and builds the swim (``layered_swim/render/session.py``) before any window
opens, so bad input is a one-line error, then hands it to the window
(``layered_swim/render/window.py``). ``--help`` for the options, H in the window for the keys."""
from __future__ import annotations

import argparse
import json
import os
import sys
from pathlib import Path

from layered_swim.commands.options import size, steering_options, vector

DESCRIPTION = "Swim after the mouse (or a trajectory) in a real-time 3-D window."


def add_parser(subparsers) -> None:
    add_arguments(subparsers.add_parser("app", help="swim after the mouse (or a trajectory) in a real-time 3-D window "
                                                    "(app.py)", description=DESCRIPTION))


def add_arguments(p: argparse.ArgumentParser) -> None:
    """The app's options, on its sub-parser or on app.py's own parser (``cli.main(command="app")``)."""
    p.add_argument("--stroke", default="breaststroke",
                   help="stroke name, path to a stroke .yaml, or auto (chooses and switches strokes; "
                        "default breaststroke)")
    p.add_argument("--trajectory", help="a trajectory name or .yaml file: show its path and chase its target")
    p.add_argument("--backend", default="plate",
                   help="fluid model; the window runs only plate (SPH is ~20x slower than real time: "
                        "use `layered-swim render --backend sph`)")
    steering_options(p)   # --layers (keys toggle them), --current, --density
    p.add_argument("--policy", metavar="FILE", help="a trained residual (policy.pt from `layered-swim train`) drives "
                                                     "its stroke (needs the [rl] extra)")
    p.add_argument("--size", default="1280x720", metavar="WxH", help="window size in pixels")
    p.add_argument("--capture-dir", default="captures", help="where screenshots and videos go (default captures/)")
    p.add_argument("--benchmark-frames", type=int, metavar="N",
                   help="run N frames, print mean FPS and real-time factor as JSON, and exit")


def run(args) -> None:
    """Open the window (after every check: no display, bad input and a wrong backend fail first)."""
    from layered_swim.config import ConfigError
    from layered_swim.control.layered import Layers
    from layered_swim.render.session import SwimSession

    if args.backend != "plate":
        raise ConfigError(f"the window runs only --backend plate (got {args.backend!r}): SPH water is about 20x slower "
                          "than real time; watch it with `layered-swim render TRAJECTORY --backend sph --out sph.mp4`")
    width, height = size(args.size)
    if args.benchmark_frames is not None and args.benchmark_frames < 2:
        raise ConfigError(f"--benchmark-frames must be at least 2, got {args.benchmark_frames}")
    policy = None
    if args.policy:
        from layered_swim.rl.policy import ResidualPolicy

        policy = ResidualPolicy.load(args.policy)
    session = SwimSession(args.stroke, Layers.parse(args.layers), vector(args.current, "--current"), args.density,
                          args.trajectory, policy=policy, water=args.water)
    if sys.platform.startswith("linux") and not (os.environ.get("DISPLAY") or os.environ.get("WAYLAND_DISPLAY")):
        session.close()
        raise ConfigError("no display to open a window on (run it on a desktop, or under xvfb-run); "
                          "`layered-swim render` draws videos without one")
    from layered_swim.render.window import SwimWindow

    window = SwimWindow(session, width, height, Path(args.capture_dir), args.benchmark_frames)
    window.run()
    if window.benchmark is not None:
        print(json.dumps(window.benchmark))
