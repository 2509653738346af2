"""Markdown reports: one stroke's analysis, several strokes side by side, and an experiment's
figure with the paper's finding and ours. Text only; the numbers come in ready-made."""
from __future__ import annotations

# Summary quantities in report order: label, unit, format.
QUANTITIES = {
    "mean_speed_m_s": ("mean speed", "m/s", "{:.2f}"),
    "speed_fluctuation_pct": ("intracycle speed fluctuation", "+-%", "{:.0f}"),
    "stroke_rate_cpm": ("stroke rate", "cycles/min", "{:.1f}"),
    "distance_per_cycle_m": ("distance per cycle", "m", "{:.2f}"),
    "shoulder_roll_deg": ("shoulder roll amplitude per side", "deg", "{:.1f}"),
    "hip_roll_deg": ("hip roll amplitude per side", "deg", "{:.1f}"),
    "pitch_deg": ("body pitch", "deg", "{:.1f}"),
    "head_top_m": ("top of the head above the surface", "m", "{:.2f}"),
    "peak_hand_force_n": ("peak hand force (per cycle, larger hand)", "N", "{:.0f}"),
    "peak_foot_force_n": ("peak foot force (per cycle, larger foot)", "N", "{:.0f}"),
    "propulsive_force_n": ("mean propulsive force", "N", "{:.0f}"),
    "resistive_force_n": ("mean resistive force", "N", "{:.0f}"),
    "active_drag_n": ("resistive force summed over segments at the swimming speed (not active drag)", "N",
                      "{:.0f}"),
    "passive_drag_n": ("passive drag, same body towed in a glide at that speed", "N", "{:.1f}"),
    "active_drag_per_v2_kg_m": ("summed resistive force / speed^2", "kg/m", "{:.0f}"),
    "mechanical_power_w": ("mechanical power of the joint torques", "W", "{:.0f}"),
    "propelling_efficiency": ("summed resistive force x speed / joint power (not propelling efficiency)", "-",
                              "{:.3f}"),
}

DEFINITIONS = """\
- **Cycles** start when the cycle marker rises through its mean: for prone and supine strokes
  how far the left hand is ahead of the pelvis along the body (the hand passing mid-reach as it
  recovers forward), for upright ones the left foot's height along the body (mid-way up before the press).
  Every number is averaged over whole cycles after the settle time; +- is the SD across cycles.
- **Forward** is the horizontal direction the centre of mass travelled. The **thrust axis** is
  forward for prone and supine strokes and straight up for upright ones (treading water holds
  the body up).
- **Intracycle speed fluctuation**: half the range of the centre-of-mass forward speed within a
  cycle, as a percentage of that cycle's mean speed.
- **Body pitch**: elevation of the pelvis long axis above the horizontal (head up > 0),
  or for upright strokes of its front axis (leaning back > 0).
- **Roll**: tilt of the thorax (shoulders) or pelvis (hips) lateral axis out of the horizontal;
  the amplitude is half its range within a cycle, i.e. the roll to each side.
- **Forces** are hydrodynamic (the fluid force minus buoyancy). **Propulsive / resistive**: per
  sample, the sum over the 16 segments of the positive / negative parts of each segment's force
  along the thrust axis. The mean resistive force summed over segments (in steady swimming it
  equals the mean propulsive force; summary key `active_drag_n`) is **not active drag**: a limb
  recovering against the water and another pulling both count, so it is larger than a whole-body
  measurement. `layered-swim validate strokes` measures active drag as swimming science does
  (velocity perturbation method, Kolmogorov & Duplishcheva 1992).
- **Mechanical power**: the stable-PD torques the joints applied (they close the energy balance
  of a swim) times the joint rates, summed over joints and averaged over the cycle. \
The summed resistive force x mean speed / mechanical power (summary key `propelling_efficiency`)
is not the propelling efficiency either; `validate strokes` gives that from the active drag.
"""


def fmt(name: str, value) -> str:
    if value is None:
        return "-"
    return QUANTITIES[name][2].format(value) if name in QUANTITIES else f"{value:.3g}"


def label(name: str) -> str:
    text, unit, _ = QUANTITIES[name]
    return f"{text} ({unit})" if unit != "-" else text


def _range_text(row: dict) -> str:
    if row["low"] is None:
        return "-"
    return f"{fmt(row['quantity'], row['low'])} - {fmt(row['quantity'], row['high'])}"


def _value_text(row: dict) -> str:
    value = fmt(row["quantity"], row["mean"])
    return value if row["sd"] is None else f"{value} +- {fmt(row['quantity'], row['sd'])}"


def setting_line(config: dict) -> str:
    a, medium = config["analysis"], config["medium"]
    return (f"{a['seconds']:g} s swim, fluid density {medium['rho_kg_m3']:g} kg/m^3, current "
            f"{tuple(medium['current_m_s'])} m/s, physics {config['physics_hz']} Hz, seed {config['swim']['seed']}; "
            f"analysed after a {a['settle_s']:g} s settle time")


def analysis_report(result: dict, table: list[dict], plot_files: list[str]) -> str:
    s = result["summary"]
    lines = [f"# Stroke analysis: {result['stroke']}", "",
             f"{setting_line(result['config'])}: {s['cycles']} whole cycles over {s['analysed_s']:.1f} s "
             f"(the controller's nominal rate is {s['nominal_stroke_rate_cpm']:.1f} cycles/min).", "",
             "## Numbers next to real swimmers", "",
             "Ranges from `layered_swim/reference.md` section 3 (R: recalled from the literature, E: estimated);",
             "elite ranges are for racing swimmers, so a recreational-speed swimmer is expected below them.", "",
             "| quantity | ours (mean +- SD over cycles) | real swimmers | verdict | source |",
             "|---|---|---|---|---|"]
    lines += [f"| {label(r['quantity'])} | {_value_text(r)} | {_range_text(r)} | {r['verdict']} | {r['source']} |"
              for r in table]
    off = [r for r in table if r["verdict"] in ("below", "above")]
    if off:
        lines += ["", "Outside the real swimmers' ranges: " + "; ".join(
            f"{QUANTITIES[r['quantity']][0]} {fmt(r['quantity'], r['mean'])} {QUANTITIES[r['quantity']][1]} is "
            f"{r['verdict']} {_range_text(r)}" for r in off) + "."]
    lines += ["", "## How the numbers are measured", "", DEFINITIONS, "## Figures", ""]
    captions = {
        "speed.png": "Top: the first analysed cycles, forward speed and the cycle marker, with the cycle starts. "
                     "Bottom: forward speed over the normalised cycle.",
        "limb_forces.png": "Force of the water on each hand and foot over the cycle: magnitude and the part along "
                           "the thrust axis (positive pushes the swimmer on).",
        "propulsion_power.png": "Propulsive and resistive force summed over segments, and the joints' "
                                "mechanical power.",
        "attitude.png": "Shoulder and hip roll, pelvis pitch and head height over the cycle.",
    }
    for name in plot_files:
        lines += [f"![{name}]({name})", "", captions[name], ""]
    lines += ["Files: `summary.json` (these numbers and the comparison), `cycles.csv` (one row per cycle), "
              "`profiles.csv` (mean and SD over the normalised cycle), `config.json` (resolved configuration).", ""]
    return "\n".join(lines)


def compare_report(results: list[dict], tables: list[list[dict]], figure_file: str) -> str:
    strokes = [r["stroke"] for r in results]
    by_stroke = [{row["quantity"]: row for row in table} for table in tables]
    lines = ["# Strokes side by side", "",
             "Each cell: ours (mean +- SD over cycles) and, in brackets, the verdict against the real "
             "swimmers' range for that stroke (layered_swim/reference.md section 3; '-' where it gives none).", "",
             "| quantity | " + " | ".join(strokes) + " |", "|---|" + "---|" * len(strokes)]
    for name in QUANTITIES:
        cells = []
        for rows in by_stroke:
            row = rows.get(name)
            if row is None:
                cells.append("-")
                continue
            verdict = row["verdict"] if row["low"] is not None else "-"
            cells.append(f"{_value_text(row)} ({verdict})")
        if any(c != "-" for c in cells):
            lines.append(f"| {label(name)} | " + " | ".join(cells) + " |")
    lines += ["", f"![{figure_file}]({figure_file})", "",
              "Mean +- SD over the normalised cycle for each stroke (cycle starts as defined in each report).", "",
              "Per-stroke reports: " + ", ".join(f"[{s}]({s}/report.md)" for s in strokes) + ".", "",
              "## How the numbers are measured", "", DEFINITIONS]
    for result in results:
        lines.append(f"- {result['stroke']}: {setting_line(result['config'])}.")
    lines.append("")
    return "\n".join(lines)


def experiment_report(title: str, figure_file: str, csv_file: str, paper: str, ours: str, setting: str,
                      differs: str | None) -> str:
    lines = [f"# {title}", "", f"![{figure_file}]({figure_file})", "",
             f"**The paper:** {paper}", "", f"**Ours:** {ours}", ""]
    if differs:
        lines += [f"**Where ours differs, and why:** {differs}", ""]
    lines += [f"**Setting:** {setting}", "", f"Numbers: `{csv_file}`; every run's resolved configuration: "
              "`config.json`; cached results per configuration: `cache/`.", ""]
    return "\n".join(lines)
