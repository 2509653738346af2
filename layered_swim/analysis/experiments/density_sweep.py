"""Yang et al. 2004, Fig. 16 (and SWIM 2026 section 4.4.3): how deep the swimmer sinks and how
well it follows a horizontally moving target as the fluid's density changes."""
from __future__ import annotations

from pathlib import Path

import numpy as np
from matplotlib.ticker import FormatStrFormatter

from layered_swim.analysis import plots
from layered_swim.analysis.experiments.runner import Outcome
from layered_swim.control.targets import load_trajectory
from layered_swim.episode import Episode
from layered_swim.fluid.medium import PRESETS_KG_M3_PA_S, water
from layered_swim.runs import swim
from layered_swim.sim.simulation import SimulationDiverged
from layered_swim.tasks import FollowTarget
from layered_swim.tasks.follow import TRACK_HZ
from layered_swim.tasks.metrics import SETTLE_S

NAME = "density-sweep"
TITLE = "Sinking depth and tracking error over fluid densities (Yang et al. 2004, Fig. 16; SWIM 2026, 4.4.3)"
PAPER = ("Yang: the swimmer sinks less as the fluid gets denser; it struggles to follow the horizontally moving "
         "target in the least dense fluid (too little thrust) and in a very dense one (more drag). SWIM (densities "
         "500-2500 kg/m^3): its policy succeeds between 920 and 1500 kg/m^3; low density makes it sink, high density "
         "degrades heading control.")
FIGURE = "density_sweep.png"
CSV = "density_sweep.csv"
STROKE = "breaststroke"
TRAJECTORY = "straight_line"
DENSITIES_KG_M3 = (500.0, 750.0, 900.0, 920.0, 997.05, 1100.0, 1250.0, 1500.0, 2000.0, 2500.0)
QUICK_DENSITIES_KG_M3 = (500.0, 997.05, 1500.0, 2500.0)
FAIL_DISTANCE_M = 2.0      # tracking fails: mean distance to the target over the run's second half above this
SWIM_SUCCESS_KG_M3 = (920.0, 1500.0)
TARGET_DEPTH_M = 0.3       # the straight_line trajectory's depth
DEPTH_TICKS_M = (-0.5, 0.0, 0.5, 1.0, 3.0, 10.0, 30.0, 100.0, 300.0)
FRESH_KG_M3 = PRESETS_KG_M3_PA_S["fresh_water"][0]


def configs(quick: bool, seed: int) -> list[dict]:
    seconds = 20.0 if quick else 40.0
    return [{"stroke": STROKE, "trajectory": TRAJECTORY, "density_kg_m3": rho, "seconds": seconds}
            for rho in (QUICK_DENSITIES_KG_M3 if quick else DENSITIES_KG_M3)]


def run(config: dict) -> dict:
    try:
        task = FollowTarget(load_trajectory(config["trajectory"]))
        swim(Episode(config["stroke"], task, medium=water(density_kg_m3=config["density_kg_m3"])), config["seconds"])
    except SimulationDiverged as err:
        return {"diverged": str(err)}
    a = task.track()
    t = a["track_time_s"]
    distance = np.linalg.norm(a["swimmer_m"] - a["target_m"], axis=1)
    settled, second_half = t >= SETTLE_S, t >= t[-1] / 2
    return {"depth_m": float(-a["swimmer_m"][settled, 2].mean()), "mean_distance_m": float(distance.mean()),
            "late_distance_m": float(distance[second_half].mean()), "final_distance_m": float(distance[-1]),
            "time_s": t[::TRACK_HZ // 2].tolist(), "com_depth_m": (-a["swimmer_m"][::TRACK_HZ // 2, 2]).tolist(),
            "distance_m": distance[::TRACK_HZ // 2].tolist()}


def fails(result: dict) -> bool:
    return "diverged" in result or result["late_distance_m"] > FAIL_DISTANCE_M


def measure(configs: list[dict], results: list[dict]) -> dict:
    rows = [{"density_kg_m3": c["density_kg_m3"], "com_depth_m": r.get("depth_m"),
             "mean_distance_m": r.get("mean_distance_m"),
             "late_distance_m": r.get("late_distance_m"), "final_distance_m": r.get("final_distance_m"),
             "tracking_fails": fails(r), "diverged": r.get("diverged", "")} for c, r in zip(configs, results)]
    by_density = [{"density_kg_m3": c["density_kg_m3"], **{
        k: r.get(k) for k in ("depth_m", "mean_distance_m", "late_distance_m", "final_distance_m", "diverged")},
        "tracking_fails": fails(r)} for c, r in zip(configs, results)]
    values = lambda key: np.array([r.get(key, np.nan) for r in results])   # noqa: E731  (NaN: diverged)
    return {"rows": rows, "summary": {"by_density": by_density}, "seconds": configs[0]["seconds"],
            "density_kg_m3": np.array([c["density_kg_m3"] for c in configs]),
            "tracks": np.array([not fails(r) for r in results]),
            "depth_m": values("depth_m"), "late_distance_m": values("late_distance_m")}


def plot(numbers: dict, path: Path) -> None:
    rho, good = numbers["density_kg_m3"], numbers["tracks"]
    fig, axes = plots.figure(2, 1, height_in=3.2)
    depth_ax, error_ax = axes[:, 0]
    for ax in (depth_ax, error_ax):
        ax.axvspan(*SWIM_SUCCESS_KG_M3, color="C2", alpha=0.12, label="SWIM's policy succeeds")
        ax.axvline(FRESH_KG_M3, color="C0", linestyle=":", linewidth=1.0, label="fresh water")
        ax.set_xlabel("fluid density (kg/m^3)")
    depth = numbers["depth_m"]
    depth_ax.plot(rho, depth, "o-", color="k")
    depth_ax.axhline(TARGET_DEPTH_M, color="C1", linestyle="--", linewidth=0.8, label="target depth")
    depth_ax.axhline(0.0, color="C0", linewidth=0.8, label="surface")
    depth_ax.set_yscale("symlog", linthresh=1.0)      # from riding on the surface to sinking tens of metres
    deepest = max(1.0, float(np.nanmax(depth)))
    depth_ax.set_ylim(1.5 * deepest, -0.5)             # deeper is lower
    depth_ax.set_yticks([d for d in DEPTH_TICKS_M if d <= 1.5 * deepest])
    depth_ax.yaxis.set_major_formatter(FormatStrFormatter("%g"))
    depth_ax.set_ylabel("mean depth of the centre of mass (m)")
    depth_ax.set_title(f"{STROKE} following a target moving at 0.5 m/s, 0.3 m deep")
    depth_ax.legend(loc="best", fontsize="small")
    late = numbers["late_distance_m"]
    error_ax.plot(rho, late, "-", color="k")
    error_ax.plot(rho[good], late[good], "o", color="C2", label="tracks")
    error_ax.plot(rho[~good], np.where(np.isnan(late[~good]), FAIL_DISTANCE_M, late[~good]), "x", color="C3",
                  markersize=9, markeredgewidth=2, label="tracking fails")
    error_ax.axhline(FAIL_DISTANCE_M, color="C3", linestyle="--", linewidth=0.8,
                     label=f"failure threshold {FAIL_DISTANCE_M:g} m")
    error_ax.set_yscale("log")
    error_ax.set_ylabel("distance to target, 2nd half (m)")
    error_ax.legend(loc="best", fontsize="small")
    plots.save(fig, path)


def describe(numbers: dict) -> Outcome:
    by_density = numbers["summary"]["by_density"]
    swam = [d for d in by_density if d["diverged"] is None]
    depths = [d["depth_m"] for d in swam]
    monotone = all(a >= b for a, b in zip(depths[:-1], depths[1:]))
    light, dense = swam[0], swam[-1]
    ours = (f"The centre of mass rides {light['depth_m']:.2f} m deep at {light['density_kg_m3']:g} kg/m^3 and "
            f"{dense['depth_m']:.2f} m at {dense['density_kg_m3']:g} kg/m^3 (negative: above the surface); "
            "it sinks less "
            f"{'at every step up in density' if monotone else 'overall as the density grows'}.")
    tracked = [d["density_kg_m3"] for d in by_density if not d["tracking_fails"]]
    failing = [d["density_kg_m3"] for d in by_density if d["tracking_fails"]]
    ours += (f" Tracking (mean distance over the run's second half below {FAIL_DISTANCE_M:g} m) holds from "
             f"{min(tracked):g} to {max(tracked):g} kg/m^3" if tracked else " Tracking fails at every density")
    ours += f" and fails at {', '.join(f'{x:g}' for x in failing)} kg/m^3." if failing else " and never fails here."
    dense_fail = [x for x in failing if x > FRESH_KG_M3]
    light_fail = [x for x in failing if x < FRESH_KG_M3]
    differs = None
    if not (dense_fail and light_fail):
        where = "at every density here" if not failing else f"only in {'denser' if dense_fail else 'lighter'} fluid"
        differs = f"Yang's swimmer struggles at both ends of the range; ours fails {where}."
    setting = (f"{STROKE}, all three layers, following `{TRAJECTORY}` for {numbers['seconds']:g} s at each density "
               "(fresh water's viscosity); depth averaged after the first 5 s. Open water with no floor: in a fluid "
               "much lighter than the body it sinks freely.")
    return Outcome(ours, setting, differs)
