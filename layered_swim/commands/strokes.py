"""``layered-swim strokes``: list the available strokes."""
from __future__ import annotations

from layered_swim.commands.tables import table


def add_parser(subparsers) -> None:
    subparsers.add_parser("strokes", help="list the available strokes")


def run(args) -> None:
    from layered_swim.body.layout import joint_layout
    from layered_swim.body.model import load_body
    from layered_swim.config import ConfigError
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
    print(table(rows, ["stroke", "cycles/min", "speed m/s", "description"]))
    print(f"\n{AUTO}: chases a target with {', '.join(AUTO_STROKES)}, switched between cycles "
          "(follow, goal, render, the app)")


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
