"""``layered-swim bench``: time one physics step, bare and through the whole loop (or the RL
environment)."""
from __future__ import annotations

import json

from layered_swim.commands.options import backend_option, fluid_settings, integrator_option
from layered_swim.commands.tables import fmt, table


def add_parser(subparsers) -> None:
    bench = subparsers.add_parser("bench", help="time one physics step, bare and through the whole loop")
    bench.add_argument("--json", action="store_true")
    bench.add_argument("--seconds", type=float,
                       help="simulated seconds per repeat (default 5; 0.5 with SPH; 10 with --env)")
    bench.add_argument("--env", action="store_true", help="time the RL environment: steps per second on one core and "
                                                          "the shares of physics, observation, reward and policy, "
                                                          "and over all cores with the trainer's workers ([rl] extra)")
    bench.add_argument("--workers", type=int, help="with --env: also time this many worker processes stepping "
                                                    "environments at once, as the trainer's rollouts do (default: "
                                                    "the training config's run.workers; 1: one core only)")
    bench.add_argument("--physics-hz", type=int, help="physics rate in Hz (default 480)")
    backend_option(bench)
    integrator_option(bench)


def run(args) -> None:
    from layered_swim.runs import bench_sph, bench_step

    if args.env:
        from layered_swim.config import ConfigError

        if args.backend != "plate":
            raise ConfigError("bench --env times the environment on the plate backend")
        from layered_swim.rl.bench import bench_env

        if args.workers is not None and not 1 <= args.workers <= 64:
            raise ConfigError(f"--workers must be in 1..64, got {args.workers}")
        result = bench_env(10.0 if args.seconds is None else args.seconds, workers=args.workers,
                           integrator=args.integrator)
    elif args.backend == "sph":
        result = bench_sph(0.5 if args.seconds is None else args.seconds, fluid_settings(args))
    else:
        result = bench_step(5.0 if args.seconds is None else args.seconds, args.physics_hz,
                            integrator=args.integrator)
    if args.json:
        print(json.dumps(result))
        return
    print(table([[k, fmt(v)] for k, v in result.items()]))
