"""``layered-swim``: headless runs, target following, calibration, benchmarks and rendering.

Heavy modules are imported inside the commands: PyBullet must not be loaded before ``main``
has moved C-level stdout out of the way (see ``_guard_stdout``).
"""
from __future__ import annotations

import argparse
import json
from dataclasses import asdict
import math
import os
import re
import signal
import sys
from pathlib import Path

PROG = "layered-swim"


class OneLineParser(argparse.ArgumentParser):
    """argparse with one-line errors, and values like ``-5,0,5`` taken as values, not options."""

    def __init__(self, *args, **kwargs):
        super().__init__(*args, **kwargs)
        self._negative_number_matcher = re.compile(r"^-\.?\d")

    def error(self, message: str):
        self.exit(2, f"{self.prog}: error: {message} (see --help)\n")


def _guard_stdout() -> None:
    """PyBullet's C code printf's (importer notes; its build time in some builds) into C's stdio
    buffer, which a piped stdout flushes at exit, after our output: it would corrupt ``--json``.
    Point fd 1 at /dev/null for C and keep Python's ``sys.stdout`` on a duplicate of the real one."""
    sys.stdout.flush()
    real = os.dup(1)
    devnull = os.open(os.devnull, os.O_WRONLY)
    os.dup2(devnull, 1)
    os.close(devnull)
    sys.stdout = open(real, "w", buffering=1, closefd=True)


def _parser() -> argparse.ArgumentParser:
    p = OneLineParser(prog=PROG, description="A physically simulated human swimmer.")
    sub = p.add_subparsers(dest="command", required=True, metavar="COMMAND")

    run = sub.add_parser("run", help="swim a stroke headless and write summary, log and config")
    run.add_argument("--stroke", required=True, help="stroke name (see `strokes`) or path to a stroke .yaml")
    run.add_argument("--seconds", type=float, default=30.0, help="simulated seconds (default 30)")
    run.add_argument("--out", help="output folder (default runs/<stroke>-<timestamp>)")
    _overwrite_option(run)
    run.add_argument("--json", action="store_true", help="print the summary as one JSON object")
    run.add_argument("--lung-volume", type=float, dest="lung_air_l", metavar="L",
                     help="inhaled air in litres, on top of the residual volume (default 3)")
    _water_options(run)
    run.add_argument("--tempo", type=float, default=1.0, help="stroke rate multiplier (default 1)")
    _backend_option(run)

    sub.add_parser("strokes", help="list the available strokes")

    validate = sub.add_parser("validate", help="compare the model with measurements")
    validate.add_argument("what", choices=("drag", "sph"),
                          help="drag: towed passive drag vs Narita et al. 2017; sph: the SPH water against "
                               "rho g V, the thin plates and Narita (takes minutes)")
    validate.add_argument("--json", action="store_true")
    _backend_option(validate)

    calibrate = sub.add_parser("calibrate", help="measure each perturbation sequence's turn per cycle (Yang 4.3)")
    calibrate.add_argument("--stroke", required=True, help="stroke name or path to a stroke .yaml")
    _parallel_options(calibrate)

    follow = sub.add_parser("follow", help="chase a target moving along a trajectory file")
    follow.add_argument("trajectory", help="trajectory name (see trajectories/) or path to a .yaml")
    follow.add_argument("--stroke", default="breaststroke", help="stroke name, path to a stroke .yaml, or auto "
                                                                 "(chooses and switches strokes)")
    steering_options(follow)
    follow.add_argument("--seconds", type=float, default=60.0)
    follow.add_argument("--out", help="output folder (default runs/follow-<trajectory>-<timestamp>)")
    _overwrite_option(follow)
    follow.add_argument("--json", action="store_true")
    follow.add_argument("--policy", metavar="FILE", help="a trained residual (policy.pt from `train`) on its reference "
                                                          "controller (--layers then comes from the policy)")
    follow.add_argument("--seeds", type=int, metavar="N",
                        help="swim N times from starts moved by up to 10 deg and 0.3 m, and report each headline "
                             "number's median (and range) over them (with --policy too)")
    _parallel_options(follow)
    _backend_option(follow, pool="large")       # a trajectory's target starts 2 m ahead

    goal = sub.add_parser("goal", help="SWIM's goal-reaching benchmark (Pos, Prog, Dev, Roll)")
    goal.add_argument("--pool", choices=("small", "large"), default="small")
    goal.add_argument("--stroke", default="front_crawl")
    steering_options(goal, density=False)
    goal.add_argument("--json", action="store_true")
    goal.add_argument("--policy", metavar="FILE", help="a trained residual (policy.pt from `train`) on its reference "
                                                        "controller, the heuristic beside it")
    goal.add_argument("--seeds", type=int, default=5, help="starts per goal with --policy (0: SWIM's fixed start; default 5)")
    _backend_option(goal, pool=None)

    render = sub.add_parser("render", help="draw a run folder or a trajectory swim to a video or PNG frames, no display needed")
    render.add_argument("source", help="a folder written by `run`/`follow --out` (replayed), or a trajectory (swum now)")
    render.add_argument("--out", required=True, help="video.mp4 (needs the video extra; else PNG frames) or a folder for PNGs")
    _overwrite_option(render)
    render.add_argument("--seconds", type=float, help="length (default: the whole run, or 20 s of a trajectory)")
    render.add_argument("--fps", type=float, default=30.0)
    render.add_argument("--size", default="960x540", metavar="WxH")
    render.add_argument("--stroke", default="breaststroke", help="stroke for a trajectory (default breaststroke; "
                                                                "auto chooses)")
    steering_options(render)
    render.add_argument("--forces", action="store_true", help="draw the per-segment fluid-force arrows")
    render.add_argument("--no-progress", action="store_true", help="no progress bar")
    _backend_option(render, pool="large")

    analyze = sub.add_parser("analyze", help="swim steadily and report per-cycle stroke metrics, plots and a report")
    what = analyze.add_mutually_exclusive_group(required=True)
    what.add_argument("--stroke", help="stroke name (see `strokes`) or path to a stroke .yaml: swim it now")
    what.add_argument("--run", metavar="DIR", help="analyze the log of a `run` folder instead (a stopped, partial one too)")
    compare = sub.add_parser("compare", help="analyze several strokes and report them side by side")
    compare.add_argument("--strokes", required=True, metavar="A,B,...", help="comma-separated stroke names")
    for command in (analyze, compare):
        command.add_argument("--seconds", type=float, default=60.0, help="simulated seconds (default 60)")
        command.add_argument("--settle", type=float, default=5.0, metavar="S", help="seconds left out at the start (default 5)")
        _water_options(command)
        _current_option(command)
        command.add_argument("--json", action="store_true", help="print the summary as one JSON object")
        _backend_option(command)
        _overwrite_option(command)
    analyze.add_argument("--out", help="output folder (default runs/analyze-<stroke>-<timestamp>)")
    compare.add_argument("--out", help="output folder (default runs/compare-<timestamp>)")
    _parallel_options(compare)

    experiment = sub.add_parser("experiment", help="reproduce one of the papers' experiments (figure + CSV + report)")
    experiment.add_argument("name", help="experiment name; `layered-swim experiment list` lists them")
    experiment.add_argument("--out", help="output folder (default runs/experiment-<name>)")
    _overwrite_option(experiment)
    experiment.add_argument("--quick", action="store_true", help="fewer and shorter runs, for a first look")
    _parallel_options(experiment)
    experiment.add_argument("--seed", type=int, default=0, help="seed of the random pushes (perturbation)")
    experiment.add_argument("--json", action="store_true", help="print the experiment's summary as one JSON object")
    _backend_option(experiment, pool="large")     # only hand-force runs in SPH water (`experiment list`)

    train = sub.add_parser("train", help="train a residual policy with PPO on SWIM's goal task ([rl] extra)")
    train.add_argument("--config", metavar="FILE", help="training YAML (default: the shipped front-crawl one)")
    train.add_argument("--set", action="append", default=[], metavar="KEY=VALUE",
                       help="override a field, e.g. --set ppo.learning_rate=1e-4 (repeatable)")
    train.add_argument("--samples", type=int, help="environment steps in all (run.samples)")
    train.add_argument("--workers", type=int, help="rollout worker processes (run.workers; default 2)")
    train.add_argument("--buffer", choices=("fifo", "progevict"), help="episode buffer eviction (buffer.policy)")
    train.add_argument("--ray", metavar="ADDRESS", help="run the rollout workers on a Ray cluster ('local': start one here)")
    train.add_argument("--out", help="output folder (default runs/train-<stroke>)")
    train.add_argument("--resume", action="store_true", help="continue the training in --out from its checkpoint")
    _overwrite_option(train)
    train.add_argument("--no-progress", action="store_true", help="no progress bar")
    train.add_argument("--json", action="store_true", help="print the summary as one JSON object")

    soak = sub.add_parser("soak", help="swim for hours with the log streaming to disk, sampling memory: "
                                       "reports RSS growth and whether everything stayed finite")
    soak.add_argument("--hours", type=float, default=1.0, help="simulated hours (default 1; ~10 min of wall time each)")
    soak.add_argument("--stroke", default="front_crawl")
    soak.add_argument("--out", help="output folder (default runs/soak-<timestamp>)")
    _overwrite_option(soak)
    soak.add_argument("--json", action="store_true")

    bench = sub.add_parser("bench", help="time one physics step, bare and through the whole loop")
    bench.add_argument("--json", action="store_true")
    bench.add_argument("--seconds", type=float, help="simulated seconds per repeat (default 5; 0.5 with SPH; 10 with --env)")
    bench.add_argument("--env", action="store_true", help="time the RL environment: steps per second on one core and "
                                                          "the shares of physics, observation, reward and policy ([rl] extra)")
    bench.add_argument("--physics-hz", type=int, default=480)
    _backend_option(bench)
    return p


def _overwrite_option(command: argparse.ArgumentParser) -> None:
    command.add_argument("--overwrite", action="store_true",
                         help="empty an output folder that holds something else first (default: refuse)")


def _out_dir(args, default: Path) -> Path:
    """The command's output folder, checked before any work (``layered_swim.outputs``)."""
    from layered_swim.outputs import prepare_out_dir

    return prepare_out_dir(args.out or default, args.command, args.overwrite)


def _water_options(command: argparse.ArgumentParser) -> None:
    """Density or fluid preset, seed and physics rate: the options of a single swim."""
    fluid = command.add_mutually_exclusive_group()
    fluid.add_argument("--density", type=float, metavar="KG_M3", help="water density (fresh water's viscosity)")
    fluid.add_argument("--fluid", choices=("fresh_water", "seawater"), default="fresh_water")
    command.add_argument("--seed", type=int, default=0,
                         help="0 (default): the stroke's exact start; any other: a start jittered by it "
                              "(heading, speed, depth, position; see README)")
    command.add_argument("--physics-hz", type=int, default=480)


def _backend_option(command: argparse.ArgumentParser, pool: str | None = "small") -> None:
    """--backend and the SPH water's options (used only with --backend sph); ``pool``: the
    default SPH pool (None: the command has its own --pool)."""
    command.add_argument("--backend", default="plate",
                         help="fluid model: plate (thin plates + buoyancy, default) or sph (SPlisHSPlasH, the [sph] extra)")
    sph = command.add_argument_group("SPH water (with --backend sph)")
    if pool:
        sph.add_argument("--pool", choices=("small", "large"), default=pool,
                         help=f"SWIM's pool: small 3 x 1.5 x 0.5 m, large 5 x 2 x 0.7 m (default {pool})")
    sph.add_argument("--water-depth", type=float, metavar="M", help="the pool's water depth (default: the pool's)")
    sph.add_argument("--particle-radius", type=float, default=0.025, metavar="M", help="default 0.025 m")
    sph.add_argument("--threads", type=int, metavar="N", help="solver threads (default: every core)")
    sph.add_argument("--deterministic", action="store_true", help="one solver thread: bit-identical runs")


def _fluid_settings(args):
    """The backend's settings from the command line: None (its defaults) but for SPH."""
    if args.backend != "sph":
        return None
    from layered_swim.runs import sph_settings_for

    return sph_settings_for(args.pool, args.water_depth, particle_radius_m=args.particle_radius,
                            threads=args.threads, deterministic=args.deterministic)


def _current_option(command: argparse.ArgumentParser) -> None:
    command.add_argument("--current", default="0,0,0", metavar="X,Y,Z", help="uniform current in m/s")


def steering_options(command: argparse.ArgumentParser, density: bool = True) -> None:
    """The options of a swim toward a target: layers, current and (optionally) density; app.py has them too."""
    command.add_argument("--layers", default="basic,cycle,rules", help="basic[,cycle][,rules|palm|reach]")
    _current_option(command)
    if density:
        command.add_argument("--density", type=float, metavar="KG_M3", help="water density (default fresh water)")


def _progress(args) -> bool:
    """A progress bar only where someone watches stderr."""
    return not args.no_progress and sys.stderr.isatty()


def _parallel_options(command: argparse.ArgumentParser) -> None:
    command.add_argument("--workers", type=int, default=2, help="parallel simulations (default 2)")
    command.add_argument("--no-progress", action="store_true", help="no progress bar")


def _table(rows: list[list[str]], header: list[str] | None = None) -> str:
    rows = ([header] if header else []) + rows
    widths = [max(len(r[i]) for r in rows) for i in range(len(rows[0]))]
    return "\n".join("  ".join(c.ljust(w) for c, w in zip(r, widths)).rstrip() for r in rows)


def _fmt(value) -> str:
    return f"{value:.3f}" if isinstance(value, float) else str(value)


def _cmd_run(args) -> None:
    from layered_swim.runs import default_out_dir, run_swim

    out_dir = _out_dir(args, default_out_dir(args.stroke))
    result = run_swim(args.stroke, args.seconds, args.lung_air_l, args.density, out_dir, args.seed,
                      args.physics_hz, args.tempo, fluid=args.fluid, progress=not args.json and sys.stderr.isatty(),
                      backend=args.backend, fluid_settings=_fluid_settings(args))
    if args.json:
        print(json.dumps({**result, "out_dir": str(out_dir)}, allow_nan=False))
        return
    print(_table([[k, _fmt(v)] for k, v in _flat(result).items() if v is not None]))
    print(f"\nwrote summary.json, config.json, log.npz, timeseries.csv to {out_dir}")


def _flat(result: dict) -> dict:
    """Nested summaries (the fluid's report) as ``fluid.key`` rows."""
    flat = {}
    for key, value in result.items():
        if isinstance(value, dict):
            flat.update({f"{key}.{k}": v for k, v in value.items() if not isinstance(v, (dict, list))})
        elif not isinstance(value, list):
            flat[key] = value
    return flat


def _cmd_strokes(args) -> None:
    from layered_swim.body.model import load_body
    from layered_swim.config import ConfigError
    from layered_swim.body.layout import joint_layout
    from layered_swim.control.auto import AUTO, AUTO_STROKES
    from layered_swim.control.stroke import available_strokes, load_stroke

    layout = joint_layout(load_body())
    rows = []
    for name in available_strokes():
        try:
            stroke = load_stroke(name, layout)
        except ConfigError as err:   # one broken file should not hide the others
            rows.append([name, "-", "-", f"invalid: {err}"])
            continue
        first_line = (stroke.description.strip().splitlines() or [""])[0]
        rows.append([name, f"{60.0 / stroke.period_s:.1f}", _speed_range(stroke), first_line])
    print(_table(rows, ["stroke", "cycles/min", "speed m/s", "description"]))
    print(f"\n{AUTO}: chases a target with {', '.join(AUTO_STROKES)}, switched between cycles (follow, goal, render, the app)")


def _speed_range(stroke) -> str:
    """The calibrated steady speed from the stroke's slowest working tempo (its ``min_tempo``) to
    the fastest tempo measured; '-' without a table."""
    from layered_swim.control.calibration import CalibrationError, load_table

    try:
        pace = load_table(stroke).pace
    except CalibrationError:
        return "-"
    slowest = stroke.steering.min_tempo
    speeds = [pace.speed_at(slowest)] + [v for t, v in zip(pace.tempos, pace.speed_m_s) if t > slowest]
    return f"{min(speeds):.2f}-{max(speeds):.2f}"


def _cmd_validate(args) -> None:
    from layered_swim.analysis.drag import REFERENCE_PASSIVE_DRAG_N_S2_M2, towed_drag
    from layered_swim.body.model import load_body
    from layered_swim.config import ConfigError
    from layered_swim.fluid import make_fluid
    from layered_swim.fluid.medium import Medium
    from layered_swim.sim.simulation import SimConfig

    if args.what == "sph":
        return _validate_sph(args)
    if args.backend != "plate":
        raise ConfigError("validate drag reads a memoryless fluid in one evaluation; "
                          "the SPH water is validated by `validate sph`")
    rows = towed_drag(make_fluid(args.backend, load_body(), Medium(), SimConfig().gravity_m_s2))
    if args.json:
        print(json.dumps(rows))
        return
    print(_table([[f"{r['speed_m_s']:.1f}", f"{r['drag_n']:.1f}", f"{r['reference_n']:.1f}", f"{r['ratio']:.3f}"]
                  for r in rows],
                 ["speed m/s", "model drag N", f"reference {REFERENCE_PASSIVE_DRAG_N_S2_M2:g} v^2 N", "ratio"]))


def _validate_sph(args) -> None:
    from layered_swim.analysis.sph_validation import validate_sph
    from layered_swim.fluid import make_fluid
    from layered_swim.body.model import load_body
    from layered_swim.fluid.medium import Medium

    settings = _fluid_settings(argparse.Namespace(**{**vars(args), "backend": "sph"}))
    make_fluid("sph", load_body(), Medium(), 9.81, settings)       # the extra is installed, the settings valid
    say = None if args.json else (lambda text: print(f"... {text}", file=sys.stderr))
    result = validate_sph(settings, progress=say)
    if args.json:
        print(json.dumps(result, allow_nan=False))
        return
    for label in ("before", "after"):
        part = result[label]
        print(f"\n{label} the correction (boxes shrunk by {result['mesh_shrink_radii'] if label == 'after' else 0:g} "
              f"particle radii per side; r = {result['particle_radius_m']:g} m; means of {1000 * result['window_s']:g} ms windows)")
        rows = [[name, f"{part[key]['lift_n']:.1f} +- {part[key]['window_sd_n']:.1f}", f"{part[key]['rho_g_v_n']:.1f}",
                 f"{part[key]['ratio']:.3f}"] for name, key in (("torso box, full", "held_box_full"),
                                                                ("torso box, half", "held_box_half"))]
        print(_table(rows, ["held box", "SPH lift N", "rho g V N", "ratio"]))
        f = part["floating_box"]
        print(_table([["0.3 x 0.3 x 0.2 m, 500 kg/m3", f"{f['draft_m']:.4f}", f"{f['expected_m']:.4f}", f"{f['ratio']:.3f}"]],
                     ["floating box", "SPH draft m", "expected m", "ratio"]))
        print(_table([[f"{r['angle_deg']:g}", f"{r['speed_m_s']:g}", f"{r['drag_n']:.1f} +- {r['window_sd_n']:.1f}",
                       f"{r['plate_model_n']:.1f}", _fmt(r["ratio"])] for r in part["towed_plate"]],
                     ["plate deg", "speed m/s", "SPH drag N", "plate model N", "ratio"]))
        print(_table([[f"{r['speed_m_s']:g}", f"{r['drag_n']:.1f} +- {r['window_sd_n']:.1f}", f"{r['reference_n']:.1f}",
                       f"{r['ratio']:.3f}"] for r in part["towed_swimmer"]],
                     ["swimmer m/s", "SPH drag N", "Narita 23.5 v^2 N", "ratio"]))
    flow = result["current"]
    print(f"\ncurrent {flow[0]['current_m_s'][0]:g} m/s along x through the small pool (no swimmer): the water's mean "
          "velocity x in the middle, 0.2 m in from every wall")
    print(_table([[f"{r['time_s']:g}", *(f"{r[layer][0]:.2f}" for layer in ("floor", "middle", "surface"))]
                  for r in flow], ["s", "near the floor m/s", "mid-depth m/s", "near the surface m/s"]))
    print("\ndiagnostic: the broadside plate (shrunk) at 0.5 m/s towed deeper in a 1.0 m deep tank: its excess over "
          "the plate model follows the pressure around it, a share of rho g d A (README, 'SPH backend')")
    print(_table([[f"{r['depth_m']:g}", f"{r['drag_n']:.1f} +- {r['window_sd_n']:.1f}", f"{r['plate_model_n']:.1f}",
                   _fmt(r["ratio"]), f"{r['excess_share_of_rho_g_d_a']:.3f}"] for r in result["broadside_by_depth"]],
                 ["depth m", "SPH drag N", "plate model N", "ratio", "excess / rho g d A"]))


def _cmd_bench(args) -> None:
    from layered_swim.runs import bench_sph, bench_step

    if args.env:
        from layered_swim.config import ConfigError

        if args.backend != "plate":
            raise ConfigError("bench --env times the environment on the plate backend")
        from layered_swim.rl.bench import bench_env

        result = bench_env(10.0 if args.seconds is None else args.seconds)
    elif args.backend == "sph":
        result = bench_sph(0.5 if args.seconds is None else args.seconds, _fluid_settings(args))
    else:
        result = bench_step(5.0 if args.seconds is None else args.seconds, args.physics_hz)
    if args.json:
        print(json.dumps(result))
        return
    print(_table([[k, _fmt(v)] for k, v in result.items()]))


def _cmd_soak(args) -> None:
    from layered_swim.runs import default_out_dir, soak

    out = _out_dir(args, default_out_dir("soak"))
    result = soak(args.hours, args.stroke, out, progress=not args.json and sys.stderr.isatty())
    if args.json:
        print(json.dumps({**result, "out_dir": str(out)}, allow_nan=False))
        return
    print(_table([[k, _fmt(v)] for k, v in _flat(result).items() if v is not None]))
    print(f"\nwrote summary.json, config.json, log.npz, timeseries.csv to {out}")


def _vector(text: str, what: str) -> tuple[float, float, float]:
    from layered_swim.config import ConfigError

    try:
        values = tuple(float(v) for v in text.split(","))
    except ValueError:
        values = ()
    if len(values) != 3 or not all(math.isfinite(v) for v in values):
        raise ConfigError(f"{what} must be three numbers X,Y,Z, got '{text}'")
    return values


def _size(text: str) -> tuple[int, int]:
    from layered_swim.config import ConfigError

    try:
        width, height = (int(v) for v in text.lower().split("x"))
    except ValueError:
        raise ConfigError(f"--size must be WIDTHxHEIGHT in pixels, e.g. 1280x720, got '{text}'") from None
    if not (16 <= width <= 3840 and 16 <= height <= 2160):
        raise ConfigError(f"--size must be between 16x16 and 3840x2160, got '{text}'")
    return width, height


def _cmd_calibrate(args) -> None:
    from layered_swim.body.model import load_body
    from layered_swim.analysis.calibrate import calibrate
    from layered_swim.control.calibration import calibration_path, save_table
    from layered_swim.body.layout import joint_layout
    from layered_swim.control.stroke import load_stroke

    stroke = load_stroke(args.stroke, joint_layout(load_body()))
    table = calibrate(stroke, workers=max(1, args.workers), progress=_progress(args))
    path = save_table(table, calibration_path(stroke.name))
    rows = [[name, f"{table.tempos[-1]:g}"] + [f"{math.degrees(v):.1f}" for v in turns[-1]]
            for name, turns in table.turn_rad.items()]
    print(_table(rows, ["sequence", "tempo"] + [f"w={w:g}" for w in table.weights]))
    pace = table.pace
    print(f"\nturn in degrees per cycle; speed {min(pace.speed_m_s):.2f}-{max(pace.speed_m_s):.2f} m/s at tempo "
          f"{pace.tempos[0]:g}-{pace.tempos[-1]:g}; wrote {path}")


def _cmd_follow(args) -> None:
    from layered_swim.control.layered import Layers
    from layered_swim.runs import default_out_dir, follow_run

    layers, steered = Layers.parse(args.layers), {}
    if args.seeds is not None:
        _follow_seeds(args, layers)
        return
    if args.policy:        # the residual on its own reference controller, run by its driver
        from layered_swim.rl.policy import follow_steering

        layers, steered = follow_steering(args.policy, args.stroke)
    out = str(_out_dir(args, default_out_dir(f"follow-{Path(args.trajectory).stem}")))
    result = follow_run(args.trajectory, args.stroke, layers, _vector(args.current, "--current"),
                        args.density, args.seconds, out, args.backend, _fluid_settings(args), **steered)
    if args.json:
        print(json.dumps({**result, "out_dir": out}, allow_nan=False))
        return
    flat = {k: v for k, v in result.items() if not isinstance(v, dict)}
    flat.update({f"swim.{k}": v for k, v in result.get("swim_metrics", {}).items() if v is not None})
    print(_table([[k, _fmt(v)] for k, v in flat.items()]))
    print(f"\nwrote summary.json, config.json, track.npz, log.npz to {out}")


def _follow_seeds(args, layers) -> None:
    from layered_swim.analysis.robustness import follow_seeds
    from layered_swim.config import ConfigError
    from layered_swim.runs import default_out_dir

    if args.backend != "plate":
        raise ConfigError("--seeds runs on the plate backend only (no --backend sph)")
    if args.policy:
        from layered_swim.rl.policy import follow_steering

        layers = follow_steering(args.policy, args.stroke)[0]     # fails here, in one line, not in every worker
    out = str(_out_dir(args, default_out_dir(f"follow-{Path(args.trajectory).stem}-seeds")))
    summary = follow_seeds(args.trajectory, args.stroke, layers, _vector(args.current, "--current"), args.density,
                           args.seconds, args.seeds, out, max(1, args.workers), _progress(args), policy=args.policy)
    if args.json:
        print(json.dumps({**summary, "out_dir": out}, allow_nan=False))
        return
    rows = [[k, *(_fmt(v[q]) for q in ("median", "min", "max"))] for k, v in summary["median"].items()]
    print(_table(rows, ["over " + str(args.seeds) + " starts", "median", "min", "max"]))
    if "reached_all_share" in summary:
        print(f"\nreached every station in {summary['reached_all_share']:.0%} of the runs")
    print(f"\nwrote summary.json (every run) and config.json to {out}")


def _cmd_goal(args) -> None:
    from layered_swim.control.layered import Layers
    from layered_swim.runs import goal_run
    from layered_swim.tasks.goal import GOAL_METRICS

    current, layers = _vector(args.current, "--current"), Layers.parse(args.layers)
    if args.policy:
        return _goal_policy(args, current, layers)
    result = goal_run(args.pool, args.stroke, current, layers, args.backend, _fluid_settings(args))
    if args.backend != "plate":     # the same task on the plates, beside (seconds, against minutes)
        plate = goal_run(args.pool, args.stroke, current, layers)
        result["plate"] = {k: plate[k] for k in GOAL_METRICS}
    if args.json:
        print(json.dumps(result, allow_nan=False))
        return
    rows = [[f"goal y={g['goal_m'][1]:+.2f}"] + [f"{g[k]:.3f}" for k in GOAL_METRICS] for g in result["goals"]]
    rows.append([f"mean ({args.backend})"] + [f"{result[k]:.3f}" for k in GOAL_METRICS])
    if "plate" in result:
        rows.append(["mean (plate)"] + [f"{result['plate'][k]:.3f}" for k in GOAL_METRICS])
    print(_table(rows, ["", "Pos m", "Prog", "Dev m", "Roll deg"]))


def _goal_policy(args, current, layers) -> None:
    import numpy as np

    from layered_swim.config import ConfigError
    from layered_swim.rl.policy import Policy, evaluate_goals
    from layered_swim.runs import goal_run
    from layered_swim.tasks.goal import GOAL_METRICS

    policy = Policy.load(args.policy)
    if args.stroke != policy.env["stroke"] and args.stroke != "front_crawl":
        raise ConfigError(f"{args.policy} was trained for {policy.env['stroke']}, not {args.stroke}")
    if not 1 <= args.seeds <= 100:
        raise ConfigError(f"--seeds must be in 1..100, got {args.seeds}")
    result = evaluate_goals(policy, args.seeds, pool=args.pool, backend=args.backend,
                            fluid_settings=_fluid_settings(args), current_m_s=tuple(current))
    heuristic = goal_run(args.pool, policy.env["stroke"], current, layers, args.backend, _fluid_settings(args))
    result = {"policy": args.policy, "pool": args.pool, "stroke": policy.env["stroke"], "reference": policy.env["reference"],
              "fluid_backend": args.backend, "current_m_s": list(current), "seeds": args.seeds, **result,
              "heuristic": {k: heuristic[k] for k in GOAL_METRICS}, "swim_published": heuristic["swim_published"]}
    if args.json:
        print(json.dumps(result, allow_nan=False))
        return
    rows = []
    for goal in sorted({r["goal"] for r in result["runs"]}):
        runs = [r for r in result["runs"] if r["goal"] == goal and "pos_m" in r]
        rows.append([f"goal {goal}"] + [f"{np.mean([r[k] for r in runs]):.3f}" if runs else "-" for k in GOAL_METRICS])
    rows.append(["mean (policy)"] + [_fmt(result[k]) for k in GOAL_METRICS])
    rows.append(["heuristic (layered)"] + [_fmt(result["heuristic"][k]) for k in GOAL_METRICS])
    print(_table(rows, ["", "Pos m", "Prog", "Dev m", "Roll deg"]))
    if result["terminated"]:
        print(f"{result['terminated']} of {len(result['runs'])} episodes ended early (left the pool or sank)")


def _cmd_train(args) -> None:
    from layered_swim.config import ConfigError
    from layered_swim.rl.config import load_train_spec
    from layered_swim.rl.train import CHECKPOINT, train

    overrides = list(args.set)
    for key, value in (("run.samples", args.samples), ("run.workers", args.workers), ("buffer.policy", args.buffer)):
        if value is not None:
            overrides.append(f"{key}={value}")
    spec = load_train_spec(args.config, overrides)
    default = Path("runs") / f"train-{spec.env.stroke}"
    if args.resume:
        out = Path(args.out or default)
        if not (out / CHECKPOINT).is_file():
            raise ConfigError(f"{out}: nothing to resume (no {CHECKPOINT})")
    else:
        out = _out_dir(args, default)
        if (out / CHECKPOINT).is_file() and not args.overwrite:
            raise ConfigError(f"{out}: holds a training run; add --resume to continue it or --overwrite to start over")
    say = None if args.json or _progress(args) else (lambda text: print(text, file=sys.stderr))
    result = train(spec, out, resume=args.resume, progress=_progress(args), ray_address=args.ray, say=say)
    if args.json:
        print(json.dumps(result, allow_nan=False))
        return
    print(f"trained {result['samples']} samples in {result['epochs']} epochs ({result['wall_s']:.0f} s); "
          f"policy: {result['policy']}")


def _cmd_render(args) -> None:
    from layered_swim.render.headless import render
    from layered_swim.control.layered import Layers

    result = render(args.source, args.out, args.seconds, args.fps, _size(args.size), args.stroke, Layers.parse(args.layers),
                    _vector(args.current, "--current"), args.density, args.forces,
                    progress=_progress(args), backend=args.backend, fluid_settings=_fluid_settings(args),
                    overwrite=args.overwrite)
    if not result["video"] and Path(args.out).suffix.lower() == ".mp4":
        print(f"{PROG}: note: {result['note']}", file=sys.stderr)
    print(f"wrote {result['frames']} frames to {result['out']}")


def _analysis_config(args, stroke: str) -> dict:
    from layered_swim.analysis.stroke_analysis import analysis_config

    settings = _fluid_settings(args)
    return analysis_config(stroke, args.seconds, args.density, _vector(args.current, "--current"),
                           args.fluid, args.settle, args.seed, args.physics_hz, args.backend,
                           None if settings is None else asdict(settings))


def _summary_rows(result: dict) -> list[list[str]]:
    from layered_swim.analysis.report import QUANTITIES, fmt

    rows = []
    for name, (text, unit, _) in QUANTITIES.items():
        value = result["summary"].get(name)
        if value is not None:
            rows.append([text, fmt(name, value["mean"] if isinstance(value, dict) else value), unit])
    return rows


def _cmd_analyze(args) -> None:
    from layered_swim.analysis.stroke_analysis import analyze_run, analyze_stroke, write_analysis
    from layered_swim.runs import default_out_dir

    if args.run:
        out = _out_dir(args, default_out_dir(f"analyze-{Path(args.run).name}"))
        result = analyze_run(args.run, args.settle)
    else:
        config = _analysis_config(args, args.stroke)
        out = _out_dir(args, default_out_dir(f"analyze-{Path(args.stroke).stem}"))
        result = analyze_stroke(config, progress=not args.json and sys.stderr.isatty())
    files = write_analysis(result, out)
    if args.json:
        print(json.dumps({"stroke": result["stroke"], **result["summary"], "out_dir": str(out)}, allow_nan=False))
        return
    print(_table(_summary_rows(result), ["quantity", "mean", "unit"]))
    print(f"\nwrote {', '.join(files)} to {out}")


def _cmd_compare(args) -> None:
    from layered_swim.analysis.stroke_analysis import write_comparison
    from layered_swim.config import ConfigError
    from layered_swim.runs import default_out_dir

    strokes = [s.strip() for s in args.strokes.split(",") if s.strip()]
    if not strokes or len(set(strokes)) != len(strokes):
        raise ConfigError(f"--strokes must name one or more different strokes, got '{args.strokes}'")
    configs = [_analysis_config(args, stroke) for stroke in strokes]
    out = _out_dir(args, default_out_dir("compare"))
    results = write_comparison(configs, out, args.workers, progress=_progress(args))
    if args.json:
        print(json.dumps({r["stroke"]: r["summary"] for r in results} | {"out_dir": str(out)}, allow_nan=False))
        return
    names = [r["stroke"] for r in results]
    by_name = [dict((row[0], row[1]) for row in _summary_rows(r)) for r in results]
    labels = list(dict.fromkeys(label for rows in by_name for label in rows))
    print(_table([[label] + [rows.get(label, "-") for rows in by_name] for label in labels], ["quantity"] + names))
    print(f"\nwrote report.md, compare_profiles.png and one folder per stroke to {out}")


def _cmd_experiment(args) -> None:
    from layered_swim.analysis.experiments import EXPERIMENTS, experiment
    from layered_swim.analysis.experiments.runner import run_experiment

    if args.name == "list":
        print(_table([[name, module.TITLE, ",".join(getattr(module, "BACKENDS", ("plate",)))]
                      for name, module in EXPERIMENTS.items()], ["experiment", "reproduces", "backends"]))
        return
    module = experiment(args.name)
    out = _out_dir(args, Path("runs") / f"experiment-{args.name}")
    settings = _fluid_settings(args)
    if args.backend != "plate":       # a missing extra or bad setting: one line before any run starts
        from layered_swim.body.model import load_body
        from layered_swim.fluid import make_fluid
        from layered_swim.fluid.medium import Medium

        make_fluid(args.backend, load_body(), Medium(), 9.81, settings)
    summary = run_experiment(module, out, quick=args.quick, workers=args.workers, progress=_progress(args),
                             seed=args.seed, backend=args.backend, fluid_settings=settings)
    if args.json:
        print(json.dumps({**summary, "out_dir": str(out)}, allow_nan=False))
        return
    print(summary["ours"])
    print(f"\nwrote {', '.join(summary['files'])} to {out}")


COMMANDS = {"run": _cmd_run, "strokes": _cmd_strokes, "validate": _cmd_validate, "bench": _cmd_bench,
            "calibrate": _cmd_calibrate, "follow": _cmd_follow, "goal": _cmd_goal, "analyze": _cmd_analyze,
            "compare": _cmd_compare, "experiment": _cmd_experiment, "render": _cmd_render,
            "soak": _cmd_soak, "train": _cmd_train}


def main(argv: list[str] | None = None) -> int:
    """Entry point. Redirects fd 1 for the rest of the process (see ``_guard_stdout``): call it
    in a subprocess, not inside a test runner that captures output."""
    _guard_stdout()
    # A shell script's background job starts with SIGINT ignored; `kill -INT` must still stop a
    # run (keeping its log), so take Ctrl-C's handler back.
    signal.signal(signal.SIGINT, signal.default_int_handler)
    args = _parser().parse_args(argv)
    return report_errors(PROG, lambda: COMMANDS[args.command](args))


def report_errors(prog: str, action) -> int:
    """Run ``action``; bad input or a blown-up simulation is one line on stderr and exit code 2,
    Ctrl-C is 130 (the CLI and app.py both end this way)."""
    from layered_swim.config import ConfigError
    from layered_swim.fluid.backend import FluidError
    from layered_swim.sim.simulation import SimulationDiverged  # imports PyBullet quietly (sim/world.py)

    try:
        action()
    except (ConfigError, SimulationDiverged, FluidError, OSError) as err:
        print(f"{prog}: error: {_one_line(err)}", file=sys.stderr)
        return 2
    except KeyboardInterrupt:
        print(f"{prog}: interrupted", file=sys.stderr)
        return 130
    return 0


def _one_line(err: Exception) -> str:
    text = str(err) if not isinstance(err, OSError) or not err.filename else f"{err.filename}: {err.strerror}"
    return " ".join(text.split())


if __name__ == "__main__":
    sys.exit(main())
