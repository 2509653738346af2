"""The options several commands share, and the values built from them (output folder, fluid
settings, vectors). argparse only at the top: the rest of the package is imported inside."""
from __future__ import annotations

import argparse
import math
import sys
from dataclasses import asdict
from pathlib import Path

MAX_WORKERS = 64        # processes on one machine; more spread over a cluster (train --ray)


def count(low: int, high: int):
    """An argparse type: an integer in [low, high], else argparse's one-line error."""
    def parse(text: str) -> int:
        try:
            value = int(text)
        except ValueError:
            raise argparse.ArgumentTypeError(f"expected a whole number, got '{text}'") from None
        if not low <= value <= high:
            raise argparse.ArgumentTypeError(f"must be between {low} and {high}, got {value}")
        return value
    return parse


def overwrite_option(command: argparse.ArgumentParser) -> None:
    command.add_argument("--overwrite", action="store_true",
                         help="replace an earlier layered-swim output of another command in --out (moved aside "
                              "into .previous/ there); other files are never touched")


def out_dir(args, default: Path):
    """The command's output folder, checked before any work and claimed only once everything
    else is checked (``layered_swim.outputs``)."""
    from layered_swim.outputs import check_out_dir

    return check_out_dir(default if args.out is None else args.out, args.command, args.overwrite)


def resumable_options(command: argparse.ArgumentParser, default_out: str, resume_help: str) -> None:
    """--out, --resume, --overwrite, --no-progress and --json of a long command that can go on
    from what it saved (train, fit-stroke)."""
    command.add_argument("--out", help=f"output folder (default {default_out})")
    command.add_argument("--resume", action="store_true", help=resume_help)
    overwrite_option(command)
    command.add_argument("--no-progress", action="store_true", help="no progress bar")
    command.add_argument("--json", action="store_true", help="print the result as one JSON object")


def resumable_out_dir(args, default: Path, saved: str, what: str):
    """The folder of a resumable command: --resume needs its ``saved`` file there; a folder that
    holds one is gone on with or started over only when asked."""
    from layered_swim.config import ConfigError

    if args.resume and args.overwrite:
        raise ConfigError(f"--resume goes on with the {what} in --out and --overwrite starts it over: choose one")
    out = out_dir(args, default)
    if args.resume and not (out.path / saved).is_file():
        raise ConfigError(f"{out.path}: nothing to resume (no {saved})")
    if not args.resume and (out.path / saved).is_file() and not args.overwrite:
        raise ConfigError(f"{out.path}: holds a {what}; add --resume to go on with it or --overwrite to start over")
    return out


def water_options(command: argparse.ArgumentParser) -> None:
    """Density or fluid preset, seed and physics rate: the options of a single swim."""
    fluid = command.add_mutually_exclusive_group()
    fluid.add_argument("--density", type=float, metavar="KG_M3", help="water density (fresh water's viscosity)")
    fluid.add_argument("--fluid", choices=("fresh_water", "seawater"), default="fresh_water")
    command.add_argument("--seed", type=int, default=0,
                         help="0 (default): the stroke's exact start; any other: a start jittered by it "
                              "(heading, speed, depth, position; see README)")
    command.add_argument("--physics-hz", type=int, help="physics rate in Hz (default 480)")


def backend_option(command: argparse.ArgumentParser, pool: str | None = "small") -> None:
    """--backend and the SPH water's options (used only with --backend sph); ``pool``: the
    default SPH pool (None: the command has its own --pool)."""
    command.add_argument("--backend", default="plate",
                         help="fluid model: plate (thin plates + buoyancy, default) or sph (SPlisHSPlasH, "
                              "the [sph] extra)")
    sph = command.add_argument_group("SPH water (with --backend sph)")
    if pool:
        sph.add_argument("--pool", choices=("small", "large"), default=pool,
                         help=f"SWIM's pool: small 3 x 1.5 x 0.5 m, large 5 x 2 x 0.7 m (default {pool})")
    sph.add_argument("--water-depth", type=float, metavar="M", help="the pool's water depth (default: the pool's)")
    sph.add_argument("--particle-radius", type=float, default=0.025, metavar="M", help="default 0.025 m")
    sph.add_argument("--threads", type=count(1, 256), metavar="N", help="solver threads (default: every core)")
    sph.add_argument("--deterministic", action="store_true", help="one solver thread: bit-identical runs")


def integrator_option(command: argparse.ArgumentParser) -> None:
    command.add_argument("--integrator", choices=("own", "bullet"), default="own",
                         help="who steps the body: own (default: PyBullet's integration, compiled; docs/cli.md) "
                              "or bullet (PyBullet's step)")


def added_mass_option(command: argparse.ArgumentParser) -> None:
    """--no-added-mass: the thin plates without their added mass (``PlateSettings.added_mass``, on by default)."""
    command.add_argument("--no-added-mass", dest="added_mass", action="store_false",
                         help="leave out the water each segment carries (plate backend; on by default; docs/fluid.md)")


def flag(name: str) -> str:
    """The command-line flag that sets ``args.<name>`` (for errors that name what was given)."""
    return "--no-added-mass" if name == "added_mass" else f"--{name.replace('_', '-')}"


def plate_fields(args) -> dict | None:
    """``SwimSpec.plate`` from the command line: None (the plates' defaults) but with --no-added-mass."""
    return {"added_mass": False} if not getattr(args, "added_mass", True) else None


def fluid_settings(args):
    """The backend's settings from the command line: None (its defaults) but for SPH."""
    if args.backend != "sph":
        return None
    from layered_swim.runs import sph_settings_for

    return sph_settings_for(args.pool, args.water_depth, particle_radius_m=args.particle_radius,
                            threads=args.threads, deterministic=args.deterministic)


def swim_spec(args, stroke: str, task: dict, **fields):
    """The command line's swim as a ``SwimSpec``: ``task`` and ``fields`` (None: the spec's
    default) with the backend options; a bad value is one line naming its field."""
    from layered_swim.spec import SwimSpec, sph_fields

    return SwimSpec.of("the command line", stroke=stroke, task=task, backend=args.backend,
                       sph=sph_fields(fluid_settings(args)), plate=plate_fields(args),
                       integrator=args.integrator, **fields)


def medium(args, current: bool = True) -> dict:
    """``SwimSpec.medium`` from --fluid, --density, --current and --water (those the command has)."""
    water = {"fluid": getattr(args, "fluid", None), "density_kg_m3": getattr(args, "density", None),
             "current_m_s": vector(args.current, "--current") if current and hasattr(args, "current") else None,
             "flow": flow_spec(args)}
    return {k: v for k, v in water.items() if v is not None}


def flow_spec(args) -> dict | None:
    """The --water file's content (checked), or None without one."""
    from layered_swim.fluid.flow_field import load_water

    return load_water(args.water).to_json() if getattr(args, "water", None) else None


def current_option(command: argparse.ArgumentParser) -> None:
    command.add_argument("--current", default="0,0,0", metavar="X,Y,Z", help="uniform current in m/s")


def water_option(command: argparse.ArgumentParser) -> None:
    command.add_argument("--water", metavar="FILE", help="a flow field: a water file's name (see waters/) or path "
                                                         "(sources, sinks, vortices, waves), added to --current")


def steering_options(command: argparse.ArgumentParser, density: bool = True) -> None:
    """The options of a swim toward a target: layers, current and (optionally) density; the app has them too."""
    command.add_argument("--layers", default="basic,cycle,rules", help="basic[,cycle][,rules|palm|reach]")
    current_option(command)
    water_option(command)
    if density:
        command.add_argument("--density", type=float, metavar="KG_M3", help="water density (default fresh water)")


def analysis_options(command: argparse.ArgumentParser) -> None:
    """The options of a steady swim analysed per cycle (``analyze``, ``compare``)."""
    command.add_argument("--seconds", type=float, default=60.0, help="simulated seconds (default 60)")
    command.add_argument("--settle", type=float, default=5.0, metavar="S",
                         help="seconds left out at the start (default 5)")
    water_options(command)
    current_option(command)
    command.add_argument("--json", action="store_true", help="print the summary as one JSON object")
    backend_option(command)
    overwrite_option(command)


def analysis_config(args, stroke: str) -> dict:
    """The analysis's configuration, checked: its episode is built once (and closed)."""
    from layered_swim.analysis import stroke_analysis

    settings = fluid_settings(args)
    config = stroke_analysis.analysis_config(stroke, args.seconds, args.density, vector(args.current, "--current"),
                                             args.fluid, args.settle, args.seed, args.physics_hz, args.backend,
                                             None if settings is None else asdict(settings))
    stroke_analysis.analysis_spec(config).episode().close()
    return config


def progress(args) -> bool:
    """A progress bar only where someone watches stderr."""
    return not args.no_progress and sys.stderr.isatty()


def parallel_options(command: argparse.ArgumentParser) -> None:
    command.add_argument("--workers", type=count(1, MAX_WORKERS), default=2,
                         help=f"parallel simulations (1-{MAX_WORKERS}, default 2)")
    command.add_argument("--no-progress", action="store_true", help="no progress bar")


def ray_option(command: argparse.ArgumentParser) -> None:
    command.add_argument("--ray", metavar="ADDRESS", help="run the sweep's simulations as Ray tasks on this cluster "
                                                          "(`local`: one started here with --workers CPUs; the [ray] "
                                                          "extra) instead of local processes")


def vector(text: str, what: str) -> tuple[float, float, float]:
    """``X,Y,Z`` as three finite numbers, else a one-line ConfigError naming ``what``."""
    from layered_swim.config import ConfigError

    try:
        values = tuple(float(v) for v in text.split(","))
    except ValueError:
        values = ()
    if len(values) != 3 or not all(math.isfinite(v) for v in values):
        raise ConfigError(f"{what} must be three numbers X,Y,Z, got '{text}'")
    return values


def size(text: str) -> tuple[int, int]:
    """``WxH`` in pixels, within 16x16 and 3840x2160, else a one-line ConfigError."""
    from layered_swim.config import ConfigError

    try:
        width, height = (int(v) for v in text.lower().split("x"))
    except ValueError:
        raise ConfigError(f"--size must be WIDTHxHEIGHT in pixels, e.g. 1280x720, got '{text}'") from None
    if not (16 <= width <= 3840 and 16 <= height <= 2160):
        raise ConfigError(f"--size must be between 16x16 and 3840x2160, got '{text}'")
    return width, height
