"""Text for ``validate strokes``: the rows as table cells (the console) and report.md. Text
only; the numbers come in ready-made from ``stroke_validation``."""
from __future__ import annotations

from pathlib import Path

from layered_swim.analysis.stroke_validation import METHOD, QUANTITIES
from layered_swim.analysis.validation_figure import validation_figure
from layered_swim.outputs import COMMAND_KEY, write_json, write_text

MARKS = {True: "✔", False: "✘", None: "–"}
KINDS = {"must": "target", "reference": "real swimmers", "measured": "-"}
HEADER = ["quantity", "ours", "range", "", "range of", "source"]
FIGURE = "validation.png"


def _number(name: str, value: float | None) -> str:
    return "n/a" if value is None else QUANTITIES[name][2].format(value)


def range_text(row: dict) -> str:
    name, low, high = row["quantity"], row["low"], row["high"]
    if row["kind"] == "measured":
        return "-"
    if low is None and high is None:
        return "any"
    if low is None:
        return f"<= {_number(name, high)}"
    if high is None:
        return f">= {_number(name, low)}"
    if low == high:
        return f"= {_number(name, low)}"
    if low == -high:
        return f"within +-{_number(name, high)}"
    return f"{_number(name, low)} - {_number(name, high)}"


def cells(row: dict) -> list[str]:
    """One row as [quantity (unit), ours, range, mark, range of, source]."""
    unit = "" if row["unit"] == "-" else f" ({row['unit']})"
    return [f"{row['label']}{unit}", _number(row["quantity"], row["value"]), range_text(row), MARKS[row["ok"]],
            KINDS[row["kind"]], row["source"]]


def _n(value: float | None, spec: str = ".1f", unit: str = " N") -> str:
    return "n/a" if value is None else f"{value:{spec}}{unit}"


def vpm_line(method: dict | None) -> str:
    """The velocity perturbation method's inputs and result in one line."""
    if method is None:
        return "no active drag: the stroke does not travel (no velocity perturbation swim)"
    m = method
    drag = ("D1 not readable (the buoy did not slow the swimmer)" if m["active_drag_n"] is None else
            f"D1 = {m['active_drag_n']:.1f} N, {m['ratio_to_narita']:.2f} x Narita's {m['narita_n']:.1f} N")
    return (f"velocity perturbation: v1 {m['free_speed_m_s']:.3f} m/s free, v2 {m['towing_speed_m_s']:.3f} m/s "
            f"towing a {m['buoy_drag_kg_m']:g} v^2 N buoy ({m['speed_drop_pct']:.1f} % slower, F_b "
            f"{m['buoy_force_n']:.1f} N); {drag}; passive drag at v1 {_n(m['passive_drag_n'])}; joint power "
            f"{m['free_joint_power_w']:.0f} -> {m['towing_joint_power_w']:.0f} W (P2/P1 "
            f"{_n(m['power_ratio'], '.3f', '')}, D1 with that ratio {_n(m['active_drag_power_matched_n'])})")


def face_line(entry: dict) -> str:
    return (f"face (front of the head, about nose height): highest {entry['face_cycle_peak_m']:+.2f} m a cycle on "
            f"average, lowest {entry['face_lowest_m']:+.2f} m (surface 0)")


def markdown(report: dict, figure_file: str) -> str:
    must = report["must"]
    lines = ["# Strokes measured against real swimmers (`layered-swim validate strokes`)", "",
             f"Each stroke swum {report['seconds']:g} s, analysed after a {report['settle_s']:g} s settle time, "
             f"whole cycles only; the travelling strokes swum again towing a {report['buoy_drag_kg_m']:g} v^2 N buoy. "
             f"Issue 36's targets: {must['held']} of {must['total']} hold.", "",
             "Marks: ✔ inside the range, ✘ outside, – not measurable. Ranges: issue 36's targets and real swimmers' "
             "figures (`layered_swim/reference.md`; M measured, R recalled from the literature, E estimated).", ""]
    for stroke, entry in report["strokes"].items():
        lines += [f"## {stroke}", ""]
        if entry["error"]:
            lines += [f"Not measured: {entry['error']}", ""]
            continue
        method = vpm_line(entry["vpm"])
        lines += [f"{entry['cycles']} cycles over {entry['analysed_s']:.1f} s. {method[0].upper()}{method[1:]}; "
                  f"{face_line(entry)}.", "",
                  "| " + " | ".join(h or "✔/✘" for h in HEADER) + " |", "|---" * len(HEADER) + "|"]
        lines += ["| " + " | ".join(cells(row)) + " |" for row in entry["rows"]]
        lines.append("")
    lines += ["## How the numbers are measured", ""]
    lines += [f"- **{name.replace('_', ' ')}**: {text}." for name, text in METHOD.items()]
    lines += ["", f"![{figure_file}]({figure_file})", "",
              "Force and speed over one cycle (mean +- SD over the analysed cycles) beside the published curves' "
              "shapes, drawn schematically from the papers' descriptions (not digitised data).", ""]
    return "\n".join(lines)


def summary(report: dict) -> dict:
    """The report without the profiles the figure is drawn from: summary.json, ``--json``."""
    return {k: v for k, v in report.items() if k != "profiles"}


def write_validation(report: dict, configs: list[dict], out: Path) -> list[str]:
    """summary.json, config.json, report.md and the figure into the claimed folder ``out``."""
    write_json(out / "summary.json", summary(report))
    write_json(out / "config.json", {COMMAND_KEY: "validate", "what": "strokes", "swims": configs})
    validation_figure(report["profiles"], out / FIGURE)
    write_text(out / "report.md", markdown(report, FIGURE))
    return ["summary.json", "config.json", FIGURE, "report.md"]
