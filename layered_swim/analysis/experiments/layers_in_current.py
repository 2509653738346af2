"""Yang et al. 2004, Fig. 15: following a target across a strong cross current with the basic
layer alone, with the per-cycle layer added, and with the continuous layer too; overhead paths."""
from __future__ import annotations

from pathlib import Path

import numpy as np

from layered_swim.analysis import plots
from layered_swim.analysis.experiments.runner import Outcome
from layered_swim.control.layered import Layers
from layered_swim.control.targets import load_trajectory
from layered_swim.episode import Episode
from layered_swim.fluid.medium import Medium
from layered_swim.runs import swim
from layered_swim.tasks import FollowTarget

NAME = "layers-in-current"
TITLE = "Target tracking in a strong cross current, layer by layer (Yang et al. 2004, Fig. 15)"
PAPER = ("With the basic stroke layer alone the swimmer is at the mercy of the current and cannot follow the target; "
         "the per-cycle layer turns it to face into the current every cycle and keeps its heading; the continuous "
         "layer adds thrust so that it tracks the target more closely still.")
FIGURE = "layers_in_current.png"
CSV = "layers_in_current.csv"
STROKE = "breaststroke"
TRAJECTORY = "straight_line"
CURRENT_M_S = (0.0, 0.3, 0.0)       # across the target's path, 40 % of the stroke's speed
LAYER_SETS = ("basic", "basic,cycle", "basic,cycle,rules")
NEAR_Y_M = 3.0


def configs(quick: bool, seed: int) -> list[dict]:
    seconds = 30.0 if quick else 60.0
    return [{"stroke": STROKE, "trajectory": TRAJECTORY, "current_m_s": list(CURRENT_M_S), "layers": layers,
             "seconds": seconds} for layers in LAYER_SETS]


def run(config: dict) -> dict:
    task = FollowTarget(load_trajectory(config["trajectory"]))
    swim(Episode(config["stroke"], task, medium=Medium(current_m_s=tuple(config["current_m_s"])),
                 layers=Layers.parse(config["layers"])), config["seconds"])
    a = task.track()
    return {"time_s": a["track_time_s"].tolist(), "swimmer_m": a["swimmer_m"].tolist(),
            "target_m": a["target_m"].tolist(), **task.metrics()}


def measure(configs: list[dict], results: list[dict]) -> dict:
    rows = []
    for c, r in zip(configs, results):
        rows += [{"layers": c["layers"], "time_s": t, "swimmer_x_m": s[0], "swimmer_y_m": s[1], "target_x_m": g[0],
                  "target_y_m": g[1], "distance_m": float(np.hypot(s[0] - g[0], s[1] - g[1]))}
                 for t, s, g in zip(r["time_s"], r["swimmer_m"], r["target_m"])]
    runs = [{"layers": c["layers"], "time_s": r["time_s"], "swimmer_m": np.array(r["swimmer_m"]),
             "distance_m": np.linalg.norm(np.array(r["swimmer_m"])[:, :2] - np.array(r["target_m"])[:, :2], axis=1)}
            for c, r in zip(configs, results)]
    tracking = {c["layers"]: {k: r[k] for k in ("mean_distance_m", "final_distance_m", "max_distance_m")}
                for c, r in zip(configs, results)}
    return {"rows": rows, "summary": {"tracking": tracking}, "runs": runs, "target_m": np.array(results[0]["target_m"]),
            "seconds": configs[0]["seconds"]}


def plot(numbers: dict, path: Path) -> None:
    fig, axes = plots.figure(1, 3, height_in=4.6, width_in=16.0, gridspec_kw={"width_ratios": [1.0, 1.4, 1.0]})
    paths, near, distance = axes[0]
    target = numbers["target_m"]
    for ax in (paths, near):
        ax.plot(target[:, 0], target[:, 1], "k--", linewidth=1.0, label="target path")
    for run in numbers["runs"]:
        xy = run["swimmer_m"]
        paths.plot(xy[:, 0], xy[:, 1], label=run["layers"])
        near.plot(xy[:, 0], xy[:, 1], label=run["layers"])
        distance.plot(run["time_s"], run["distance_m"], label=run["layers"])
    paths.annotate("", xy=(0.12, 0.75), xytext=(0.12, 0.55), xycoords="axes fraction",
                   arrowprops={"arrowstyle": "->", "color": "C0"})
    paths.text(0.15, 0.62, f"current {CURRENT_M_S[1]:g} m/s", transform=paths.transAxes, color="C0", fontsize="small")
    paths.set_aspect("equal", adjustable="datalim")
    paths.set_title("overhead view, to scale")
    near.set_ylim(-NEAR_Y_M, NEAR_Y_M)
    near.set_title(f"near the target's path (y stretched, +-{NEAR_Y_M:g} m)")
    for ax in (paths, near):
        ax.set_xlabel("x (m)")
        ax.set_ylabel("y (m)")
        ax.legend(loc="best", fontsize="small")
    distance.set_xlabel("time (s)")
    distance.set_ylabel("distance to the target (m)")
    distance.set_yscale("log")
    distance.set_title("tracking error")
    distance.legend(loc="best", fontsize="small")
    fig.suptitle(f"{STROKE} following a target along +x across a {CURRENT_M_S[1]:g} m/s current (+y): "
                 "swimmer's centre of mass and the target")
    plots.save(fig, path)


def describe(numbers: dict) -> Outcome:
    basic, cycle, rules = (numbers["summary"]["tracking"][k] for k in LAYER_SETS)
    closer = rules["mean_distance_m"] < cycle["mean_distance_m"]
    ours = (f"Basic layer alone: swept away, {basic['final_distance_m']:.1f} m from the target at the end "
            f"(mean {basic['mean_distance_m']:.1f} m). With the per-cycle layer: mean distance "
            f"{cycle['mean_distance_m']:.2f} m, final {cycle['final_distance_m']:.2f} m. With the continuous layer "
            f"too: mean {rules['mean_distance_m']:.2f} m, final {rules['final_distance_m']:.2f} m"
            + (" - closer, as in the paper." if closer else "."))
    differs = None if closer else (
        f"The continuous layer does not bring the swimmer closer here ({rules['mean_distance_m']:.2f} m against "
        f"{cycle['mean_distance_m']:.2f} m with the per-cycle layer alone). Its rules push for thrust toward the "
        "target and step back while the per-cycle layer turns (our rules' engagement); crossing the current, the "
        "swimmer turns every cycle, so the rules rarely act at full strength.")
    setting = (f"{STROKE} following `{TRAJECTORY}` (target at 0.5 m/s along +x, 0.3 m deep, starting 2 m ahead), "
               f"uniform current {CURRENT_M_S} m/s, {numbers['seconds']:g} s, fresh water.")
    return Outcome(ours, setting, differs)
