"""``layered-swim validate``: compare the model with measurements (towed drag; the SPH water; every
stroke against real swimmers and issue 36's targets)."""
from __future__ import annotations

import argparse
import json
import sys

from layered_swim.commands.options import (
    MAX_WORKERS,
    backend_option,
    count,
    flag,
    fluid_settings,
    out_dir,
    overwrite_option,
)
from layered_swim.commands.tables import fmt, table

STROKES_ONLY = ("seconds", "settle", "workers", "out", "added_mass")      # options of `validate strokes` alone


def add_parser(subparsers) -> None:
    validate = subparsers.add_parser("validate", help="compare the model with measurements")
    validate.add_argument("what", choices=("drag", "sph", "strokes", "added-mass"),
                          help="drag: towed passive drag vs Narita et al. 2017; sph: the SPH water against "
                               "rho g V, the thin plates and Narita (takes minutes); strokes: every stroke swum and "
                               "measured against real swimmers and issue 36's targets (a few minutes)"
                               "; added-mass: the plates' added mass on springs and pushed, "
                               "against T = 2 pi sqrt((m + m_a) / k)")
    validate.add_argument("--json", action="store_true")
    backend_option(validate)
    strokes = validate.add_argument_group("validate strokes")
    strokes.add_argument("--seconds", type=float, help="simulated seconds of each swim (default 60)")
    strokes.add_argument("--settle", type=float, metavar="S", help="seconds left out at the start (default 5)")
    strokes.add_argument("--workers", type=count(1, MAX_WORKERS), help="parallel swims (default 2)")
    strokes.add_argument("--out", help="output folder for report.md, summary.json and the figure (default: none)")
    strokes.add_argument("--no-added-mass", dest="added_mass", action="store_const", const=False,
                         help="the swims without the plates' added mass (on by default; docs/fluid.md)")
    strokes.add_argument("--no-progress", action="store_true", help="no progress bar")
    overwrite_option(strokes)


def run(args) -> None:
    from layered_swim.analysis.drag import REFERENCE_PASSIVE_DRAG_N_S2_M2, towed_drag
    from layered_swim.body.model import load_body
    from layered_swim.config import ConfigError
    from layered_swim.fluid import make_fluid
    from layered_swim.fluid.medium import Medium
    from layered_swim.sim.simulation import GRAVITY_M_S2

    given = [flag(name) for name in STROKES_ONLY if getattr(args, name) is not None]
    if args.what == "strokes":
        return _validate_strokes(args)
    if given:
        raise ConfigError(f"{', '.join(given)}: for `validate strokes` only, not `validate {args.what}`")
    if args.what == "sph":
        return _validate_sph(args)
    if args.what == "added-mass":
        return _validate_added_mass(args)
    if args.backend != "plate":
        raise ConfigError("validate drag reads a memoryless fluid in one evaluation; "
                          "the SPH water is validated by `validate sph`")
    rows = towed_drag(make_fluid(args.backend, load_body(), Medium(), GRAVITY_M_S2))
    if args.json:
        print(json.dumps(rows))
        return
    print(table([[f"{r['speed_m_s']:.1f}", f"{r['drag_n']:.1f}", f"{r['reference_n']:.1f}", f"{r['ratio']:.3f}"]
                 for r in rows],
                ["speed m/s", "model drag N", f"reference {REFERENCE_PASSIVE_DRAG_N_S2_M2:g} v^2 N", "ratio"]))


def _validate_strokes(args) -> None:
    from layered_swim.analysis import stroke_validation, validation_report
    from layered_swim.analysis.sweep import DEFAULT_WORKERS
    from layered_swim.config import ConfigError
    from layered_swim.outputs import claim
    from layered_swim.tasks.metrics import SETTLE_S

    if args.backend != "plate":
        raise ConfigError("validate strokes swims in the plate water only (--backend plate)")
    out = out_dir(args, None) if args.out is not None else None
    seconds = stroke_validation.DEFAULT_SECONDS if args.seconds is None else args.seconds
    configs = stroke_validation.validation_configs(seconds, SETTLE_S if args.settle is None else args.settle,
                                                   plate={"added_mass": False} if args.added_mass is False else None)
    folder = claim(out) if out is not None else None      # everything checked: now the folder is ours
    report = stroke_validation.validate_strokes(configs, args.workers or DEFAULT_WORKERS,
                                                folder / "cache" if folder else None,
                                                progress=not args.no_progress and sys.stderr.isatty())
    files = validation_report.write_validation(report, configs, folder) if folder else []
    if args.json:
        print(json.dumps({**validation_report.summary(report), "out_dir": str(folder) if folder else None},
                         allow_nan=False))
        return
    for stroke, entry in report["strokes"].items():
        print(f"\n{stroke} ({entry['posture']})")
        if entry["error"]:
            print(f"  not measured: {entry['error']}")
            continue
        print(f"  {entry['cycles']} cycles over {entry['analysed_s']:.1f} s; "
              f"{validation_report.vpm_line(entry['vpm'])}; {validation_report.face_line(entry)}")
        print(table([validation_report.cells(row) for row in entry["rows"]], validation_report.HEADER))
    must = report["must"]
    print(f"\nissue 36's targets: {must['held']} of {must['total']} hold"
          + (f"; not met: {', '.join(must['failed'])}" if must["failed"] else ""))
    if files:
        print(f"wrote {', '.join(files)} to {folder}")


def _validate_sph(args) -> None:
    from layered_swim.analysis.sph_validation import validate_sph
    from layered_swim.body.model import load_body
    from layered_swim.fluid import make_fluid
    from layered_swim.fluid.medium import Medium
    from layered_swim.sim.simulation import GRAVITY_M_S2

    settings = fluid_settings(argparse.Namespace(**{**vars(args), "backend": "sph"}))
    make_fluid("sph", load_body(), Medium(), GRAVITY_M_S2, settings)       # the extra is installed, the settings valid
    say = None if args.json else (lambda text: print(f"... {text}", file=sys.stderr))
    result = validate_sph(settings, progress=say)
    if args.json:
        print(json.dumps(result, allow_nan=False))
        return
    for label in ("before", "after"):
        part = result[label]
        print(f"\n{label} the correction (boxes shrunk by {result['mesh_shrink_radii'] if label == 'after' else 0:g} "
              f"particle radii per side; r = {result['particle_radius_m']:g} m; "
              f"means of {1000 * result['window_s']:g} ms windows)")
        rows = [[name, f"{part[key]['lift_n']:.1f} +- {part[key]['window_sd_n']:.1f}", f"{part[key]['rho_g_v_n']:.1f}",
                 f"{part[key]['ratio']:.3f}"] for name, key in (("torso box, full", "held_box_full"),
                                                                ("torso box, half", "held_box_half"))]
        print(table(rows, ["held box", "SPH lift N", "rho g V N", "ratio"]))
        f = part["floating_box"]
        print(table([["0.3 x 0.3 x 0.2 m, 500 kg/m3", f"{f['draft_m']:.4f}", f"{f['expected_m']:.4f}",
                      f"{f['ratio']:.3f}"]],
                    ["floating box", "SPH draft m", "expected m", "ratio"]))
        print(table([[f"{r['angle_deg']:g}", f"{r['speed_m_s']:g}", f"{r['drag_n']:.1f} +- {r['window_sd_n']:.1f}",
                      f"{r['plate_model_n']:.1f}", fmt(r["ratio"])] for r in part["towed_plate"]],
                    ["plate deg", "speed m/s", "SPH drag N", "plate model N", "ratio"]))
        print(table([[f"{r['speed_m_s']:g}", f"{r['drag_n']:.1f} +- {r['window_sd_n']:.1f}", f"{r['reference_n']:.1f}",
                      f"{r['ratio']:.3f}"] for r in part["towed_swimmer"]],
                    ["swimmer m/s", "SPH drag N", "Narita 23.5 v^2 N", "ratio"]))
    flow = result["current"]
    print(f"\ncurrent {flow[0]['current_m_s'][0]:g} m/s along x through the small pool (no swimmer): the water's mean "
          "velocity x in the middle, 0.2 m in from every wall")
    print(table([[f"{r['time_s']:g}", *(f"{r[layer][0]:.2f}" for layer in ("floor", "middle", "surface"))]
                 for r in flow], ["s", "near the floor m/s", "mid-depth m/s", "near the surface m/s"]))
    print("\ndiagnostic: the broadside plate (shrunk) at 0.5 m/s towed deeper in a 1.0 m deep tank: its excess over "
          "the plate model follows the pressure around it, a share of rho g d A (README, 'SPH backend')")
    print(table([[f"{r['depth_m']:g}", f"{r['drag_n']:.1f} +- {r['window_sd_n']:.1f}", f"{r['plate_model_n']:.1f}",
                  fmt(r["ratio"]), f"{r['excess_share_of_rho_g_d_a']:.3f}"] for r in result["broadside_by_depth"]],
                ["depth m", "SPH drag N", "plate model N", "ratio", "excess / rho g d A"]))


def _validate_added_mass(args) -> None:
    from layered_swim.analysis.added_mass import validate_added_mass
    from layered_swim.config import ConfigError

    if args.backend != "plate":
        raise ConfigError("validate added-mass checks the plate backend's added mass (--backend plate)")
    result = validate_added_mass()
    if args.json:
        print(json.dumps(result, allow_nan=False))
        return
    print(f"one box alone (or the hand on its free forearm) on a spring, deep in still water without gravity, "
          f"k set for T = {result['period_s']:g} s with the water; own and added: kg along, kg m^2 about")
    print(table([[str(r["physics_hz"]), r["segment"], r["motion"], f"{r['own']:.4g}" if "own" in r else "",
                  f"{r['added']:.4g}" if "added" in r else "", f"{r['analytic_s']:.4f}", f"{r['simulated_s']:.4f}",
                  f"{r['ratio']:.4f}", f"{r['without_water_s']:.4f}"] for r in result["springs"]],
                ["Hz", "segment", "motion", "own", "added", "T analytic s", "T simulated s", "ratio",
                 "T without water s"]))
    print("\nthe hand pushed from rest along its palm normal: acceleration against (F + plate drag) / (m + m_a)")
    print(table([[str(r["physics_hz"]), f"{r['force_n']:g}", f"{r['own_kg']:.4g}", f"{r['added_kg']:.4g}",
                  f"{r['simulated_m_s2']:.3f}", f"{r['analytic_m_s2']:.3f}", f"{r['ratio']:.4f}",
                  f"{r['without_water_m_s2']:.3f}", f"{r['water_force_over_added_mass_times_a']:.4f}"]
                 for r in result["pushed"]],
                ["Hz", "F N", "m kg", "m_a kg", "a simulated m/s2", "a analytic m/s2", "ratio", "a without water",
                 "water force / (m_a a)"]))
    blow_ups = [f"{r['physics_hz']} Hz diverged after {r['diverged_after_steps']} steps" for r in result["explicit"]]
    print(f"\nthe explicit force F_n = -m_a a_(n-1) instead, on the hand's palm-first spring: {'; '.join(blow_ups)}")
    print(f"\nevery period and acceleration within {100 * result['tolerance']:g} % of the analytic answer: "
          f"{'yes' if result['pass'] else 'NO'}")
