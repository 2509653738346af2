"""``layered-swim validate``: compare the model with measurements (towed drag; the SPH water)."""
from __future__ import annotations

import argparse
import json
import sys

from layered_swim.commands.options import backend_option, fluid_settings
from layered_swim.commands.tables import fmt, table


def add_parser(subparsers) -> None:
    validate = subparsers.add_parser("validate", help="compare the model with measurements")
    validate.add_argument("what", choices=("drag", "sph"),
                          help="drag: towed passive drag vs Narita et al. 2017; sph: the SPH water against "
                               "rho g V, the thin plates and Narita (takes minutes)")
    validate.add_argument("--json", action="store_true")
    backend_option(validate)


def run(args) -> None:
    from layered_swim.analysis.drag import REFERENCE_PASSIVE_DRAG_N_S2_M2, towed_drag
    from layered_swim.body.model import load_body
    from layered_swim.config import ConfigError
    from layered_swim.fluid import make_fluid
    from layered_swim.fluid.medium import Medium
    from layered_swim.sim.simulation import GRAVITY_M_S2

    if args.what == "sph":
        return _validate_sph(args)
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
