"""``layered-swim validate strokes``: every swimming stroke swum steadily and measured the way
swimming science measures, each figure against real swimmers' ranges and issue 36's targets.

Per stroke, one free swim (``analyze``'s: the basic stroke, logged at 120 Hz, cut into cycles
after the settle time) and, for the strokes that travel, a second swim towing a buoy
(``swim_observers.TowedBuoy``) for the velocity perturbation method's active drag
(``active_drag``). The swims are independent sweep jobs (``sweep.run_sweep``: parallel, cached
by configuration). ``measure_swim`` and ``stroke_figures``/``validation_rows`` are pure.
"""
from __future__ import annotations

import math

import numpy as np

from layered_swim.analysis import active_drag
from layered_swim.analysis.drag import towed_drag
from layered_swim.analysis.head_clearance import cycles_above_pct, face_height_m, per_cycle_max, time_below_pct
from layered_swim.analysis.reference_ranges import VALIDATION_RANGES, Range, must_hold, ranges_for
from layered_swim.analysis.stroke_analysis import ANALYSIS_LOG_HZ, analysis_config, analysis_spec
from layered_swim.analysis.stroke_metrics import SwimmerInfo, analyze_log
from layered_swim.analysis.sweep import run_sweep
from layered_swim.analysis.swim_observers import JointWork, TowedBuoy
from layered_swim.config import ConfigError
from layered_swim.fluid import make_fluid
from layered_swim.recorder import Recorder
from layered_swim.runs import swim
from layered_swim.sim.simulation import SimulationDiverged
from layered_swim.state import lying
from layered_swim.tasks.metrics import SETTLE_S

STROKES = ("front_crawl", "breaststroke", "backstroke", "butterfly", "treading_water")
VPM_STROKES = ("front_crawl", "breaststroke", "backstroke", "butterfly")     # those that travel
DEFAULT_SECONDS = 60.0
# The buoy: a body of drag 5 v^2 N (5 N at 1 m/s, about a tenth of a swimmer's active drag): a
# small perturbation, the swimmer 5-10 % slower. Our choice; the estimate depends on it where the
# swimmer's drag is not ~v^2 (docs/results.md gives 5, 10 and 20 kg/m).
BUOY_DRAG_KG_M = 5.0
PROFILE_NAMES = ("forward_speed_m_s", "hand_l_force_n", "hand_r_force_n")
METHOD = {
    "active_drag": "velocity perturbation method (Kolmogorov & Duplishcheva 1992): the stroke swum freely (v1) and "
                   "towing a buoy of known drag F_b = k v^2 from the pelvis (v2); equal power and D = k v^2 give "
                   "D1 = F_b v2 v1^2 / (v1^3 - v2^3)",
    "passive_drag": "the same body towed in a streamlined glide at v1 (analysis/drag.py), for comparison",
    "resistive_force_summed": "per sample, the sum over segments of each segment's force against the travel "
                              "(a limb recovering against the water and another pulling both count): not active drag",
    "joint_power": "net: the joints' torque x rate summed over joints, mean over the analysed cycles; positive: each "
                   "joint's power clipped at zero before summing",
    "propelling_efficiency": "D1 v1 / net joint power (the joints' power includes the work of moving the limbs)",
    "face": "the centre of the head box's front (about nose height) against the surface",
}


def validation_configs(seconds: float = DEFAULT_SECONDS, settle_s: float = SETTLE_S,
                       buoy_kg_m: float = BUOY_DRAG_KG_M, strokes=STROKES, plate: dict | None = None) -> list[dict]:
    """The sweep's jobs: each stroke's free swim and, for a travelling stroke, its swim towing the
    buoy (``plate``: the plates' settings, e.g. added mass). Checked: a bad length, settle time or
    buoy is one ConfigError line."""
    if not (isinstance(buoy_kg_m, (int, float)) and math.isfinite(buoy_kg_m) and buoy_kg_m > 0.0):
        raise ConfigError(f"the buoy's drag must be a positive number of kg/m, got {buoy_kg_m}")
    configs = []
    for stroke in strokes:
        base = analysis_config(stroke, seconds, settle_s=settle_s, plate=plate)
        configs.append({**base, "buoy_kg_m": None})
        if stroke in VPM_STROKES:
            configs.append({**base, "buoy_kg_m": float(buoy_kg_m)})
    return configs


def swim_measured(config: dict) -> dict:
    """The sweep task: swim one configuration (towing the buoy where it has one) and measure it.
    A swim that blows up or does not cycle is measured as its error line."""
    episode = analysis_spec(config).episode()
    try:
        sim = episode.sim
        recorder = Recorder(sim, ANALYSIS_LOG_HZ, joint_work=True)
        work = JointWork(sim, ANALYSIS_LOG_HZ)
        buoy = (TowedBuoy(config["buoy_kg_m"], sim.config.physics_hz, ANALYSIS_LOG_HZ)
                if config["buoy_kg_m"] else None)
        info = SwimmerInfo(sim.body.segment_names, episode.stroke.start.posture, episode.stroke.period_s,
                           config["settle_s"])
        head_half_depth_m = float(sim.body.half_extents_m[sim.body.index("head"), 0])
    except BaseException:
        episode.close()
        raise
    try:
        swim(episode, config["seconds"], [recorder, work] + ([buoy] if buoy else []))
        log = recorder.arrays()
        result = measure_swim(analyze_log(log, info), log, work.arrays(), buoy.arrays() if buoy else None,
                              info, head_half_depth_m)
    except (ConfigError, SimulationDiverged) as err:
        return {"error": str(err), "posture": info.posture}
    if lying(info.posture) and not buoy:      # the same body towed in a glide at the swimming speed
        water = make_fluid(sim.fluid.name, sim.body, sim.fluid.medium, sim.config.gravity_m_s2)
        result["passive_drag_n"] = towed_drag(water, (abs(result["speed_m_s"]),))[0]["drag_n"]
    return result


def measure_swim(analysis: dict, log: dict, work: dict, buoy: dict | None, info: SwimmerInfo,
                 head_half_depth_m: float) -> dict:
    """One swim's figures from ``stroke_metrics.analyze_log``'s result and the logs: speed over
    the whole analysed span, net and positive joint power, the buoy's mean pull, the face."""
    cycles = analysis["cycles"]
    starts = [c["start_s"] for c in cycles] + [cycles[-1]["start_s"] + cycles[-1]["duration_s"]]
    first, last = starts[0], starts[-1]
    t = np.asarray(log["time_s"], dtype=float)
    head = info.segment_names.index("head")
    face = face_height_m(log["segment_pos_m"][:, head], log["segment_quat_xyzw"][:, head], head_half_depth_m)
    distance = sum(c["distance_per_cycle_m"] for c in cycles)
    return {
        "posture": info.posture,
        "summary": analysis["summary"],
        "speed_m_s": distance / (last - first),
        "joint_power_w": active_drag.window_rate(t, log["joint_work_j"], first, last),
        "positive_joint_power_w": active_drag.window_rate(work["time_s"], work["positive_j"], first, last),
        "buoy_force_n": active_drag.window_rate(buoy["time_s"], buoy["impulse_ns"], first, last) if buoy else None,
        "face_breath_cycles_pct": cycles_above_pct(t, face, starts),
        "face_under_time_pct": time_below_pct(t, face, first, last),
        "face_lowest_m": float(face[(t >= first) & (t <= last)].min()),
        "face_cycle_peak_m": float(np.mean(per_cycle_max(t, face, starts))),
        "head_top_above_time_pct": 100.0 - time_below_pct(t, log["head_top_m"], first, last),
        "profiles": {name: analysis["profiles"][name] for name in PROFILE_NAMES},
    }


def vpm(free: dict, towing: dict, buoy_kg_m: float) -> dict:
    """The velocity perturbation method's numbers from a free and a towing swim."""
    v1, v2, buoy_n = free["speed_m_s"], towing["speed_m_s"], towing["buoy_force_n"]
    ratio = towing["joint_power_w"] / free["joint_power_w"] if free["joint_power_w"] > 0.0 else None
    drag = active_drag.vpm_active_drag_n(buoy_n, v1, v2) if min(v1, v2, buoy_n) > 0.0 else None
    readable = drag is not None and ratio is not None and ratio > 0.0
    matched = active_drag.vpm_active_drag_n(buoy_n, v1, v2, ratio) if readable else None
    narita, passive = active_drag.narita_active_drag_n(v1), free.get("passive_drag_n")
    return {"passive_drag_n": passive, "active_over_passive": drag / passive if drag is not None and passive else None,
            "free_speed_m_s": v1, "towing_speed_m_s": v2, "speed_drop_pct": 100.0 * (1.0 - v2 / v1),
            "buoy_drag_kg_m": buoy_kg_m, "buoy_force_n": buoy_n, "free_joint_power_w": free["joint_power_w"],
            "towing_joint_power_w": towing["joint_power_w"], "power_ratio": ratio, "active_drag_n": drag,
            "active_drag_power_matched_n": matched, "narita_n": narita,
            "ratio_to_narita": drag / narita if drag is not None else None}


def stroke_figures(free: dict, method: dict | None) -> dict:
    """Every figure ``validate strokes`` checks, by quantity (None where it cannot be had)."""
    s = free["summary"]
    mean = {name: value["mean"] for name, value in s.items() if isinstance(value, dict) and "mean" in value}
    drag = method["active_drag_n"] if method else None
    figures = {"stroke_rate_cpm": mean["stroke_rate_cpm"], "pitch_deg": mean["pitch_deg"],
               "joint_power_w": free["joint_power_w"], "positive_joint_power_w": free["positive_joint_power_w"],
               "face_breath_cycles_pct": free["face_breath_cycles_pct"],
               "face_under_time_pct": free["face_under_time_pct"],
               "head_top_above_time_pct": free["head_top_above_time_pct"]}
    if lying(free["posture"]):
        figures.update({
            "mean_speed_m_s": free["speed_m_s"], "distance_per_cycle_m": mean["distance_per_cycle_m"],
            "speed_fluctuation_pct": mean.get("speed_fluctuation_pct"),
            "body_inclination_deg": mean["body_inclination_deg"],
            "shoulder_roll_deg": mean["shoulder_roll_deg"], "hip_roll_deg": mean["hip_roll_deg"],
            "peak_hand_force_n": mean["peak_hand_force_n"], "active_drag_n": drag,
            "resistive_force_summed_n": mean["resistive_force_n"],
            "propelling_efficiency": active_drag.propelling_efficiency(drag, free["speed_m_s"], free["joint_power_w"])})
    return figures


# Quantities in table order: label, unit, number format. Face and head rows appear only where a
# range applies (they are one stroke's question each).
QUANTITIES = {
    "mean_speed_m_s": ("mean speed", "m/s", "{:.2f}"),
    "stroke_rate_cpm": ("stroke rate", "cycles/min", "{:.1f}"),
    "distance_per_cycle_m": ("distance per cycle", "m", "{:.2f}"),
    "speed_fluctuation_pct": ("intracycle speed fluctuation", "+-%", "{:.0f}"),
    "pitch_deg": ("body pitch (the pelvis)", "deg", "{:.1f}"),
    "body_inclination_deg": ("body inclination (feet to head)", "deg", "{:.1f}"),
    "shoulder_roll_deg": ("shoulder roll per side", "deg", "{:.1f}"),
    "hip_roll_deg": ("hip roll per side", "deg", "{:.1f}"),
    "peak_hand_force_n": ("peak hand force", "N", "{:.0f}"),
    "active_drag_n": ("active drag (velocity perturbation method)", "N", "{:.0f}"),
    "resistive_force_summed_n": ("resistive force summed over segments (not active drag)", "N", "{:.0f}"),
    "joint_power_w": ("net joint power", "W", "{:.0f}"),
    "positive_joint_power_w": ("positive joint power", "W", "{:.0f}"),
    "propelling_efficiency": ("propelling efficiency D1 v1 / net joint power", "-", "{:.2f}"),
    "face_breath_cycles_pct": ("cycles with the face above water (a breath)", "%", "{:.0f}"),
    "face_under_time_pct": ("time with the face under water", "%", "{:.1f}"),
    "head_top_above_time_pct": ("time with the top of the head above water", "%", "{:.1f}"),
}
RANGED_ONLY = ("face_breath_cycles_pct", "face_under_time_pct", "head_top_above_time_pct")


def passes(value: float | None, rng: Range) -> bool | None:
    """✔ (True) inside the closed range, ✘ (False) outside, None for a figure that could not be had."""
    if value is None or not math.isfinite(value):
        return None
    return rng.low <= value <= rng.high


def validation_rows(stroke: str, figures: dict) -> list[dict]:
    """One row per figure and range: issue 36's target ("must") and the real swimmers' range
    ("reference"); a figure with neither is shown alone ("measured")."""
    targets = must_hold(stroke, figures.get("mean_speed_m_s"))
    references = {**ranges_for(stroke, figures.get("mean_speed_m_s")), **VALIDATION_RANGES.get(stroke, {})}
    rows = []
    for name, (label, unit, _) in QUANTITIES.items():
        if name not in figures:
            continue
        value = figures[name]
        ranges = [(kind, ranges[name]) for kind, ranges in (("must", targets), ("reference", references))
                  if name in ranges]
        if not ranges and (name in RANGED_ONLY or value is None):
            continue
        base = {"quantity": name, "label": label, "unit": unit, "value": value}
        if not ranges:
            rows.append({**base, "kind": "measured", "low": None, "high": None, "ok": None, "source": ""})
        for kind, rng in ranges:
            rows.append({**base, "kind": kind, "low": _finite(rng.low), "high": _finite(rng.high),
                         "ok": passes(value, rng), "source": rng.source})
    return rows


def _finite(bound: float) -> float | None:
    return bound if math.isfinite(bound) else None      # JSON has no infinity: None is open


def validate_strokes(configs: list[dict], workers: int = 2, cache_dir=None, progress: bool = False) -> dict:
    """Swim every configuration (in parallel, cached under ``cache_dir``) and check each stroke:
    ``{"strokes": {stroke: {"rows", "vpm", ...}}, ...}``; each stroke's free-swim profiles under
    ``profiles`` (for the figure, not the summary)."""
    results = run_sweep(swim_measured, configs, cache_dir, workers, progress, desc="swims")
    by_stroke: dict[str, dict] = {}
    for config, result in zip(configs, results):
        by_stroke.setdefault(config["stroke"], {})["towing" if config["buoy_kg_m"] else "free"] = (config, result)
    strokes, profiles = {}, {}
    for stroke, swims in by_stroke.items():
        strokes[stroke], profiles[stroke] = _check_stroke(stroke, swims)
    first = configs[0]
    return {"seconds": first["seconds"], "settle_s": first["settle_s"],
            "buoy_drag_kg_m": next((c["buoy_kg_m"] for c in configs if c["buoy_kg_m"]), None),
            "method": METHOD, "strokes": strokes, "must": _tally(strokes), "profiles": profiles}


def _check_stroke(stroke: str, swims: dict) -> tuple[dict, dict | None]:
    free_config, free = swims["free"]
    towing_config, towing = swims.get("towing", (None, None))
    errors = [r["error"] for r in (free, towing) if r is not None and "error" in r]
    if errors:
        return {"posture": free["posture"], "error": "; ".join(errors), "rows": [], "vpm": None}, None
    method = vpm(free, towing, towing_config["buoy_kg_m"]) if towing is not None else None
    summary = free["summary"]
    entry = {"posture": free["posture"], "error": None, "cycles": summary["cycles"],
             "analysed_s": summary["analysed_s"], "rows": validation_rows(stroke, stroke_figures(free, method)),
             "vpm": method, "face_lowest_m": free["face_lowest_m"], "face_cycle_peak_m": free["face_cycle_peak_m"]}
    return entry, free["profiles"]


def _tally(strokes: dict) -> dict:
    """Issue 36's targets over every stroke: how many hold, and which do not (or could not be had)."""
    rows = [(stroke, r) for stroke, entry in strokes.items() for r in entry["rows"] if r["kind"] == "must"]
    return {"held": sum(1 for _, r in rows if r["ok"]), "total": len(rows),
            "failed": [f"{stroke}: {r['quantity']}" for stroke, r in rows if not r["ok"]],
            "not_measured": [stroke for stroke, entry in strokes.items() if entry["error"]]}
