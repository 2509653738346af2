"""``layered-swim calibrate``: measure each perturbation sequence's turn per cycle or held offset (Yang 4.3)."""
from __future__ import annotations

import math

from layered_swim.commands.options import parallel_options, progress
from layered_swim.commands.tables import table


def add_parser(subparsers) -> None:
    calibrate = subparsers.add_parser("calibrate",
                                      help="measure each perturbation sequence's turn per cycle (Yang 4.3)")
    calibrate.add_argument("--stroke", required=True, help="stroke name or path to a stroke .yaml")
    parallel_options(calibrate)


def run(args) -> None:
    from layered_swim.analysis.calibrate import calibrate
    from layered_swim.body.layout import joint_layout
    from layered_swim.body.model import load_body
    from layered_swim.control.calibration import calibration_path, save_table
    from layered_swim.control.stroke import load_stroke

    stroke = load_stroke(args.stroke, joint_layout(load_body()))
    calibrated = calibrate(stroke, workers=args.workers, progress=progress(args))
    path = save_table(calibrated, calibration_path(stroke))
    rows = [[name, f"{calibrated.tempos[-1]:g}"] + [f"{math.degrees(v):.1f}" for v in effects[-1]]
            for name, effects in {**calibrated.turn_rad, **calibrated.attitude_rad}.items()]
    print(table(rows, ["sequence", "tempo"] + [f"w={w:g}" for w in calibrated.weights]))
    pace = calibrated.pace
    print(f"\nyaw: turn in degrees per cycle; pitch, roll: offset held in degrees; speed "
          f"{min(pace.speed_m_s):.2f}-{max(pace.speed_m_s):.2f} m/s at tempo "
          f"{pace.tempos[0]:g}-{pace.tempos[-1]:g}; wrote {path}")
