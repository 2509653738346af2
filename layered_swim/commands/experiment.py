"""``layered-swim experiment``: reproduce one of the papers' experiments (figure + CSV + report)."""
from __future__ import annotations

import json
from pathlib import Path

from layered_swim.commands.options import (
    backend_option,
    fluid_settings,
    out_dir,
    overwrite_option,
    parallel_options,
    progress,
    ray_option,
)
from layered_swim.commands.tables import table


def add_parser(subparsers) -> None:
    experiment = subparsers.add_parser("experiment",
                                       help="reproduce one of the papers' experiments (figure + CSV + report)")
    experiment.add_argument("name", help="experiment name; `layered-swim experiment list` lists them")
    experiment.add_argument("--out", help="output folder (default runs/experiment-<name>)")
    overwrite_option(experiment)
    experiment.add_argument("--quick", action="store_true", help="fewer and shorter runs, for a first look")
    parallel_options(experiment)
    ray_option(experiment)
    experiment.add_argument("--seed", type=int, default=0, help="seed of the random pushes (perturbation)")
    experiment.add_argument("--json", action="store_true", help="print the experiment's summary as one JSON object")
    backend_option(experiment, pool="large")     # only hand-force runs in SPH water (`experiment list`)


def run(args) -> None:
    from layered_swim.analysis.experiments import EXPERIMENTS, experiment
    from layered_swim.analysis.experiments.runner import run_experiment

    if args.name == "list":
        print(table([[name, module.TITLE, ",".join(getattr(module, "BACKENDS", ("plate",)))]
                     for name, module in EXPERIMENTS.items()], ["experiment", "reproduces", "backends"]))
        return
    module = experiment(args.name)
    out = out_dir(args, Path("runs") / f"experiment-{args.name}")
    settings = fluid_settings(args)
    if args.backend != "plate":       # a missing extra or bad setting: one line before any run starts
        from layered_swim.body.model import load_body
        from layered_swim.fluid import make_fluid
        from layered_swim.fluid.medium import Medium
        from layered_swim.sim.simulation import GRAVITY_M_S2

        make_fluid(args.backend, load_body(), Medium(), GRAVITY_M_S2, settings)
    summary = run_experiment(module, out, quick=args.quick, workers=args.workers, progress=progress(args),
                             seed=args.seed, backend=args.backend, fluid_settings=settings, ray_address=args.ray)
    if args.json:
        print(json.dumps({**summary, "out_dir": str(out.path)}, allow_nan=False))
        return
    print(summary["ours"])
    print(f"\nwrote {', '.join(summary['files'])} to {out.path}")
