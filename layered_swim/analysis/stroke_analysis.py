"""``layered-swim analyze``: a steady swim, measured cycle by cycle.

``analyze_stroke`` simulates one configuration and returns everything the report needs as plain
JSON-able data (so ``compare`` can cache it and draw again without simulating);
``write_analysis`` turns that into summary.json, cycles.csv, profiles.csv, config.json, the
plots and report.md.
"""
from __future__ import annotations

import math
from pathlib import Path

from layered_swim.analysis import plots, report
from layered_swim.analysis.drag import towed_drag
from layered_swim.analysis.files import write_csv
from layered_swim.analysis.reference_ranges import ranges_for
from layered_swim.analysis.stroke_metrics import SwimmerInfo, analyze_log
from layered_swim.analysis.sweep import file_sha256, run_sweep
from layered_swim.config import ConfigError, load_json
from layered_swim.control.stroke import stroke_path
from layered_swim.fluid import make_fluid
from layered_swim.outputs import COMMAND_KEY, OutputFolder, claim, write_json, write_text
from layered_swim.recorder import logged_names, read_log
from layered_swim.runs import check_seconds, record, resolved_config
from layered_swim.sim.simulation import PHYSICS_HZ
from layered_swim.spec import SwimSpec
from layered_swim.tasks.metrics import SETTLE_S

ANALYSIS_LOG_HZ = 120      # ~100 samples per stroke cycle for the profiles
PLOTS = {"speed.png": plots.speed_figure, "limb_forces.png": plots.limb_force_figure,
         "propulsion_power.png": plots.propulsion_figure, "attitude.png": plots.attitude_figure}


def analysis_config(stroke: str, seconds: float = 60.0, density_kg_m3: float | None = None,
                    current_m_s=(0.0, 0.0, 0.0), fluid: str = "fresh_water", settle_s: float = SETTLE_S,
                    seed: int = 0, physics_hz: int | None = None, backend: str = "plate",
                    sph: dict | None = None, plate: dict | None = None) -> dict:
    """The resolved, JSON-able configuration of one analysis (also its cache key); ``sph``: the
    SPH settings' fields, with ``backend="sph"``; ``plate``: the plates' (``SwimSpec.plate``)."""
    check_seconds(seconds)
    if not (math.isfinite(settle_s) and 0.0 <= settle_s < seconds):
        raise ConfigError(f"settle time must be at least 0 and shorter than the swim ({seconds:g} s), got {settle_s}")
    return {"stroke": stroke, "stroke_file_sha256": file_sha256(stroke_path(stroke)), "seconds": float(seconds),
            "density_kg_m3": density_kg_m3, "current_m_s": [float(c) for c in current_m_s], "fluid": fluid,
            "settle_s": float(settle_s), "seed": seed, "physics_hz": physics_hz or PHYSICS_HZ, "backend": backend,
            "sph": sph, "plate": plate}


def analysis_spec(config: dict) -> SwimSpec:
    """The swim ``config`` analyses: free swimming, logged at ``ANALYSIS_LOG_HZ``."""
    return SwimSpec.of("the analysis", stroke=config["stroke"], seconds=config["seconds"],
                       medium={"fluid": config["fluid"], "density_kg_m3": config["density_kg_m3"],
                               "current_m_s": config["current_m_s"]},
                       backend=config.get("backend", "plate"), sph=config.get("sph"), plate=config.get("plate"),
                       physics_hz=config["physics_hz"],
                       log_hz=ANALYSIS_LOG_HZ, seed=config["seed"])


def analyze_stroke(config: dict, progress: bool = False) -> dict:
    spec = analysis_spec(config)
    episode = spec.episode()
    settings = spec.fluid_settings()
    sim, stroke = episode.sim, episode.stroke
    recorder = record(episode, spec.seconds, spec.log_hz, progress, joint_work=True)
    posture = stroke.start.posture
    result = analyze_log(recorder.arrays(), SwimmerInfo(sim.body.segment_names, posture, stroke.period_s,
                                                        config["settle_s"]))
    summary = result["summary"]
    speed = summary["mean_speed_m_s"]["mean"]
    # The same body towed in a streamlined glide at the swimming speed: what the stroke adds. A
    # fluid with memory (SPH) cannot be read in one evaluation: `validate sph` tows it instead.
    towed = (make_fluid(sim.fluid.name, sim.body, sim.fluid.medium, sim.config.gravity_m_s2)
             if settings is None else None)
    summary["passive_drag_n"] = (towed_drag(towed, (abs(speed),))[0]["drag_n"]
                                 if posture == "prone" and towed is not None else None)
    summary["nominal_stroke_rate_cpm"] = 60.0 / stroke.period_s
    return {"stroke": stroke.name, "posture": posture, **result,
            "config": resolved_config(episode, spec, "analyze",
                                      analysis=_settings(config["seconds"], config["settle_s"],
                                                         stroke_file_sha256=config["stroke_file_sha256"]))}


def _settings(seconds: float, settle_s: float, **more) -> dict:
    """config.json's ``analysis`` section: what was analysed of the swim, and how."""
    return {"seconds": seconds, "settle_s": settle_s, **more}


def analyze_run(run_dir: str | Path, settle_s: float = SETTLE_S) -> dict:
    """The same analysis of a finished (or stopped, partial) ``run`` folder's log, no new swim."""
    run_dir = Path(run_dir)
    log = read_log(run_dir)
    config_path = run_dir / "config.json"
    config = load_json(config_path)
    try:
        swim = config.get("swim") or config["arguments"]          # "arguments": an older version's folder
        spec, tempo = config["stroke"], float(swim["tempo"])
        name, posture, period_s = str(spec["name"]), str(spec["start"]["posture"]), float(spec["period_s"]) / tempo
    except (KeyError, TypeError, ValueError, ZeroDivisionError):
        raise ConfigError(f"{config_path}: not the config of a `layered-swim run` folder (no stroke, posture, "
                          "period or tempo)") from None
    if "joint_work_j" not in log:
        raise ConfigError(f"{run_dir}: its log has no joint work (joint_work_j), which the power figures need")
    if not (math.isfinite(settle_s) and 0.0 <= settle_s < log["time_s"][-1]):
        raise ConfigError(f"settle time must be at least 0 and shorter than the run ({log['time_s'][-1]:g} s), "
                          f"got {settle_s}")
    arrays = {name: log[name] for name in logged_names(log)}
    result = analyze_log(arrays, SwimmerInfo(tuple(str(n) for n in log["segment_names"]), posture, period_s, settle_s))
    result["summary"]["nominal_stroke_rate_cpm"] = 60.0 / period_s
    analysis = _settings(float(log["time_s"][-1]), settle_s, run_dir=str(run_dir),
                         partial_log=bool(log["partial"]) or _stopped_early(run_dir))
    return {"stroke": name, "posture": posture, **result,
            "config": {**config, COMMAND_KEY: "analyze", "analysis": analysis}}


def _stopped_early(run_dir: Path) -> bool:
    summary = run_dir / "summary.json"
    return summary.exists() and "partial" in (load_json(summary) or {})


# The summed resistive force is no active drag: real swimmers' active drag is no range for it.
NOT_ACTIVE_DRAG = "summed over segments, not active drag (validate strokes measures that)"


def comparisons(result: dict) -> list[dict]:
    """Every summary number next to the real swimmers' range for this stroke, where there is one."""
    summary = result["summary"]
    ranges = ranges_for(result["stroke"], summary["mean_speed_m_s"]["mean"])
    ranges.pop("active_drag_n", None)
    rows = []
    for name in report.QUANTITIES:
        value = summary.get(name)
        if value is None:
            continue
        mean = value["mean"] if isinstance(value, dict) else value
        sd = value["sd"] if isinstance(value, dict) else None
        rng = ranges.get(name)
        rows.append({"quantity": name, "mean": mean, "sd": sd,
                     "low": rng.low if rng else None, "high": rng.high if rng else None,
                     "verdict": rng.verdict(mean) if rng else
                     NOT_ACTIVE_DRAG if name == "active_drag_n" else "no range in reference.md",
                     "source": rng.source if rng else ""})
    return rows


def write_analysis(result: dict, out_dir: OutputFolder | str | Path) -> list[str]:
    """Write every output file of one analysis into ``out_dir``; returns their names."""
    out = claim(out_dir)
    table = comparisons(result)
    write_json(out / "summary.json", {"stroke": result["stroke"], "posture": result["posture"],
                                       **result["summary"], "comparison": table})
    write_json(out / "config.json", result["config"])
    write_csv(out / "cycles.csv", result["cycles"])
    profiles = result["profiles"]
    points = len(next(iter(profiles.values()))["mean"])
    write_csv(out / "profiles.csv", [
        {"cycle_pct": 100.0 * i / (points - 1),
         **{f"{name}_{stat}": profiles[name][stat][i] for name in profiles for stat in ("mean", "sd")}}
        for i in range(points)])
    for name, draw in PLOTS.items():
        draw(result, out / name)
    write_text(out / "report.md", report.analysis_report(result, table, list(PLOTS)))
    return ["summary.json", "config.json", "cycles.csv", "profiles.csv", *PLOTS, "report.md"]


def write_comparison(configs: list[dict], out_dir: OutputFolder | str | Path, workers: int = 2,
                     progress: bool = False) -> list[dict]:
    """Analyze every configuration (in parallel, cached under ``out_dir/cache``), write each
    stroke's full outputs into ``out_dir/<stroke>/`` and the side-by-side report."""
    out = claim(out_dir)
    results = run_sweep(analyze_stroke, configs, out / "cache", workers, progress, desc="strokes")
    tables = []
    for result in results:
        write_analysis(result, out / result["stroke"])
        tables.append(comparisons(result))
    plots.compare_figure(results, out / "compare_profiles.png")
    write_json(out / "config.json", {COMMAND_KEY: "compare", "analyses": configs})
    write_text(out / "report.md", report.compare_report(results, tables, "compare_profiles.png"))
    return results
