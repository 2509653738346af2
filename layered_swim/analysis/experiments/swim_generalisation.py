"""SWIM 2026, section 4.4 (Figs. 4-6): how far a goal-reaching controller trained on the small
pool's three goals in quiet fresh water carries over to goals, fluids and flows it never met, with
SWIM's published points beside ours. Three sweeps, each point one controller on one condition:

- Fig. 4: one goal 3 m ahead in the large pool, moved sideways by SWIM's d_lat;
- Fig. 5 (its numbers are in section 4.4.3's text): the small pool's goals in water of another
  density, and of another viscosity;
- Fig. 6: the small pool's goals under a uniform inflow, four directions.

Ours: the shipped residual (``front_crawl_layered.pt`` on the layered controller, run as its
training environment runs it) and the layered heuristic alone. ``plot`` writes the three
figures (``FIGURES``) beside ``FIGURE``, which holds all three for the report.
"""
from __future__ import annotations

import hashlib
import math
from pathlib import Path

import numpy as np

from layered_swim.analysis import plots
from layered_swim.analysis.experiments.current_sweep import DIRECTIONS, current_m_s
from layered_swim.analysis.experiments.runner import Outcome
from layered_swim.config import ConfigError
from layered_swim.fluid.medium import PRESETS_KG_M3_PA_S
from layered_swim.sim.simulation import SimulationDiverged
from layered_swim.tasks import swim_benchmark as bench
from layered_swim.tasks.goal import GOAL_METRICS

NAME = "swim-generalisation"
TITLE = "Unseen goals, fluids and flows, SWIM's published points beside (SWIM 2026, Figs. 4-6)"
PAPER = ("SWIM's freestyle policy, trained on the small pool's three goals in quiet water, reaches large-pool goals "
         "from about 1.0 m left (-18.4 deg) to 1.25 m right (+22.6 deg) of the straight line (Fig. 4); it succeeds "
         "in densities of 920-1500 of the 500-2500 kg/m^3 it was tried in and over the whole viscosity range tried, "
         "1e-3 to 5e-2 m^2/s (section 4.4.3, illustrated by Fig. 5); it stays stable under inflows up to about "
         "0.75 m/s and then struggles (Fig. 6). Only these limits, Table 3's means and the trends are in the text: "
         "the figures' per-point values are not.")
FIGURE = "swim_generalisation.png"
CSV = "swim_generalisation.csv"
FIGURES = {"fig4": "swim_generalisation_fig4_lateral.png", "fig5": "swim_generalisation_fig5_fluid.png",
           "fig6": "swim_generalisation_fig6_flow.png"}
STROKE = "front_crawl"
POLICY = Path(__file__).resolve().parents[2] / "rl" / "policies" / "front_crawl_layered.pt"
CONTROLLERS = {"residual": "shipped residual", "layered": "layered heuristic"}
STYLE = {"residual": {"marker": "o", "linestyle": "-", "color": "C1"},
         "layered": {"marker": "s", "linestyle": "--", "color": "0.35"}}

# SWIM's points (SWIM 2026, "SWIM: single-instance whole-body imitation..."), in our words. d_lat
# is SWIM's lateral offset of the goal, negative to the swimmer's left ("-18.4 deg (d_lat = -1.0 m)
# to the left"); ours is the goal's y with +y to the left, so y = -d_lat.
SWIM = {
    "source": "SWIM 2026: section 4.4.1 and Fig. 4 caption; section 4.4.3 (Fig. 5); Fig. 6 caption; Table 3",
    "fig4": {
        "pool": "large (5 m x 2 m x 0.7 m), goals 2x as far and 2x the time as in the small pool",
        "goal_ahead_m": 3.0,                     # worked back: atan(1.0 / 3.0) = 18.4 deg, atan(1.25 / 3.0) = 22.6 deg
        "training_offset_m": 0.375, "training_angle_deg": 14.0,
        "holds_left_m": -1.0, "holds_left_deg": -18.4, "holds_right_m": 1.25, "holds_right_deg": 22.6,
        "farthest": "up to 2.5x the training offset (the sweep's own range is not given)",
        "trend": "beyond those limits the policy starts to fail, not in every case; freestyle stays stable in Prog, "
                 "Roll and Vel over the whole sweep",
        "table3_5m_static": {k: v[0] for k, v in bench.SWIM_PUBLISHED["large"]["SWIM"].items()},
    },
    "fig5": {
        "pool": "not named (section 4.4.3 says the unseen goal-reaching targets of 4.4.1)",
        "water_kg_m3": 1000.0,
        "density_tested_kg_m3": (500.0, 2500.0), "density_succeeds_kg_m3": (920.0, 1500.0),
        "viscosity_tested_m2_s": (1e-3, 5e-2), "viscosity_succeeds_m2_s": (1e-3, 5e-2),
        "viscosity_text": "the same section also says 'viscosity up to 20x of water', which the 1e-3 to 5e-2 m^2/s "
                          "range (50x) does not match",
        "trend": "low density makes it sink, high density degrades heading control, higher viscosity reduces "
                 "progress but improves lateral stability",
        "table3_3m_static": {k: v[0] for k, v in bench.SWIM_PUBLISHED["small"]["SWIM"].items()},
    },
    "fig6": {
        "pool": "small (3 m)", "speeds_m_s": (0.0, 1.5), "directions": tuple(DIRECTIONS),
        "stable_up_to_m_s": 0.75,
        "trend": "stable and robust up to about 0.75 m/s, then struggles under stronger flows",
        "quiet": {k: v[0] for k, v in bench.SWIM_PUBLISHED["small"]["SWIM"].items()},
        # Table 3's "3m dynamic" column: SWIM, averaged over targets and flows filtered to four directions
        # (the flows' speeds not given).
        "dynamic_mean": {"pos_m": 0.254, "prog": 0.675, "dev_m": 0.069},
    },
}

FRESH_KG_M3, FRESH_PA_S = PRESETS_KG_M3_PA_S["fresh_water"]
FRESH_M2_S = FRESH_PA_S / FRESH_KG_M3
D_LAT_M = (-1.75, -1.5, -1.25, -1.0, -0.75, -0.5, -0.375, -0.25, 0.0, 0.25, 0.375, 0.5, 0.75, 1.0, 1.25, 1.5, 1.75)
QUICK_D_LAT_M = (-1.75, -1.0, -0.375, 0.0, 0.375, 1.25, 1.75)
DENSITIES_KG_M3 = (500.0, 750.0, 900.0, 920.0, FRESH_KG_M3, 1100.0, 1250.0, 1500.0, 1750.0, 2000.0, 2500.0)
QUICK_DENSITIES_KG_M3 = (500.0, 920.0, FRESH_KG_M3, 1500.0, 2500.0)
VISCOSITIES_M2_S = (None, 1e-3, 2e-3, 5e-3, 1e-2, 2e-2, 5e-2)     # None: fresh water's own
QUICK_VISCOSITIES_M2_S = (None, 1e-3, 5e-2)
SPEEDS_M_S = (0.25, 0.5, 0.75, 1.0, 1.25, 1.5)
QUICK_SPEEDS_M_S = (0.5, 1.0, 1.5)
STARTS = 3                 # seed 0: SWIM's fixed start; the others jittered (quick: seed 0 only)
SIDE_ROOM_M = bench.SIDE_ROOM_M    # the lateral sweep keeps its goal this far inside the widened side walls
HOLD_POS_FACTOR = 2.0      # a point holds while Pos stays within twice the controller's own at the reference
LABELS = {"pos_m": "Pos (m)", "prog": "Prog (1 = on schedule)", "dev_m": "Dev (m)",
          "roll_deg": "Roll beyond tolerance (deg)"}
CONDITION = ("pool", "goal", "d_lat_m", "density_kg_m3", "viscosity_m2_s", "direction", "speed_m_s", "current_m_s")


def _digest(path: Path) -> str | None:
    """The policy's content in the cache key: a retrained policy is measured again."""
    return hashlib.sha256(path.read_bytes()).hexdigest()[:16] if path.is_file() else None


def theta_lat_deg(d_lat_m: float) -> float:
    return math.degrees(math.atan2(d_lat_m, SWIM["fig4"]["goal_ahead_m"]))


def _condition(pool: str = "small", goal: int = 0, d_lat_m: float | None = None, density_kg_m3: float = FRESH_KG_M3,
               viscosity_m2_s: float | None = None, direction: str = "quiet", speed_m_s: float = 0.0) -> dict:
    current = current_m_s(direction, speed_m_s)
    return {"pool": pool, "goal": goal, "d_lat_m": d_lat_m, "density_kg_m3": density_kg_m3,
            "viscosity_m2_s": viscosity_m2_s, "direction": direction, "speed_m_s": speed_m_s, "current_m_s": current}


def configs(quick: bool, seed: int) -> list[dict]:
    goals = (0,) if quick else tuple(range(len(bench.pool("small").goal_offsets_m)))
    conditions = [_condition("large", 0, d) for d in (QUICK_D_LAT_M if quick else D_LAT_M)]
    for g in goals:
        conditions += [_condition(goal=g, density_kg_m3=rho)
                       for rho in (QUICK_DENSITIES_KG_M3 if quick else DENSITIES_KG_M3)]
        conditions += [_condition(goal=g, viscosity_m2_s=nu)
                       for nu in (QUICK_VISCOSITIES_M2_S if quick else VISCOSITIES_M2_S)]
        conditions += [_condition(goal=g, direction=d, speed_m_s=s)
                       for d in DIRECTIONS for s in (QUICK_SPEEDS_M_S if quick else SPEEDS_M_S)]
    unique = list({repr(sorted(c.items())): c for c in conditions}.values())   # quiet fresh water is in every sweep
    digest = _digest(POLICY)
    return [{"controller": name, "stroke": STROKE, "policy_sha256": digest if name == "residual" else None,
             "starts": 1 if quick else STARTS, **c} for name in CONTROLLERS for c in unique]


def sweep_pool(config: dict) -> bench.Pool:
    """The config's pool; for a lateral offset, the pool with that one goal, widened to hold it."""
    pool = bench.pool(config["pool"])
    return pool if config["d_lat_m"] is None else pool.holding(-config["d_lat_m"], SIDE_ROOM_M)


def _aim(episode, pool: bench.Pool) -> None:
    """Point the episode's goal task at ``pool``'s goals (a pool of the sweep, not one of the named two),
    in boundless water: both controllers swim the whole horizon, what the track says of the pool is
    reported beside (``_outcome``)."""
    episode.task.pool, episode.task.goals = pool, bench.goal_tasks(pool)
    episode.task.ends_at_walls = False


def _set_viscosity(episode, viscosity_m2_s: float | None) -> None:
    """The water's dynamic viscosity from a kinematic one (None: keep the preset's)."""
    if viscosity_m2_s is not None:
        fluid = episode.sim.fluid
        fluid.set_medium(fluid.medium.with_(eta_pa_s=viscosity_m2_s * fluid.medium.rho_kg_m3))


def _spec(config: dict):
    from layered_swim.spec import SwimSpec

    return SwimSpec.of(NAME, stroke=config["stroke"], task={"kind": "goal", "pool": config["pool"]},
                       medium={"density_kg_m3": config["density_kg_m3"], "current_m_s": config["current_m_s"]})


def _outcome(episode, pool: bench.Pool) -> dict:
    """The metrics and what the track says of the pool: whether the centre of mass left it sideways or
    lengthways, or went below its floor (the plates have no walls and no floor; both controllers swim on)."""
    com = episode.task.track()["swimmer_m"]
    x0, x1 = pool.x_range_m
    left = bool(np.any((com[:, 0] <= x0) | (com[:, 0] >= x1) | (np.abs(com[:, 1]) >= pool.width_m / 2)))
    metrics = episode.metrics()
    return {**{k: metrics[k] for k in GOAL_METRICS}, "deepest_m": float(-com[:, 2].min()), "left_pool": left,
            "sank": bool(np.any(com[:, 2] < -pool.depth_m))}


def _layered(config: dict, pool: bench.Pool) -> list[dict]:
    from layered_swim.runs import goal_episode

    episode = goal_episode(_spec(config))
    runs = []
    try:
        _aim(episode, pool)
        _set_viscosity(episode, config["viscosity_m2_s"])
        for start in range(config["starts"]):
            episode.reset(seed=start, goal=config["goal"])      # as the residual's environment resets
            try:
                episode.run(episode.task.duration_s)
            except SimulationDiverged as err:
                runs.append({"start": start, "diverged": str(err)})
                continue
            runs.append({"start": start, **_outcome(episode, pool)})
    finally:
        episode.close()
    return runs


def _residual(config: dict, pool: bench.Pool) -> list[dict]:
    """The policy in its training environment, in this config's water, on this pool's goal; its
    pool's walls are off (``_aim``), so it swims the whole horizon like the heuristic."""
    from layered_swim.rl.policy import ResidualPolicy
    from layered_swim.rl.ppo import ActorSnapshot
    from layered_swim.rl.rollouts import make_env, play

    policy = ResidualPolicy.load(POLICY)
    policy.check_stroke(config["stroke"])
    env = make_env(policy.env_kwargs(start_jitter=False, pool=config["pool"], current_m_s=tuple(config["current_m_s"]),
                                     density_kg_m3=config["density_kg_m3"]))
    runs = []
    try:
        policy.check_sizes(env.observation_space.shape[0], env.action_space.shape[0], "the goal task")
        _aim(env.episode, pool)
        _set_viscosity(env.episode, config["viscosity_m2_s"])
        actor = ActorSnapshot(policy.model)
        for start in range(config["starts"]):
            option = {"goal": config["goal"], "start_seed": start}
            [played] = play(env, actor, policy.normaliser, [start], True, [option])
            reason = played.info.get("termination")      # only a blow-up ends it early here
            runs.append({"start": start, "diverged": reason} if reason else
                        {"start": start, **_outcome(env.episode, pool)})
    finally:
        env.close()
    return runs


def run(config: dict) -> dict:
    pool = sweep_pool(config)
    if config["controller"] == "layered":
        return {"runs": _layered(config, pool)}
    if config["policy_sha256"] is None:
        return {"missing": f"no shipped policy {POLICY.name}"}
    try:
        return {"runs": _residual(config, pool)}
    except (ConfigError, ImportError) as err:       # the [rl] extra missing: points that say so
        return {"missing": str(err)}


# -- the numbers -------------------------------------------------------------------------------

def _point(config: dict, result: dict) -> dict:
    """One controller on one condition: the metrics' means over its swims (those that did not blow
    up) and how many swims left the pool, sank below its floor or blew up."""
    runs = result.get("runs", [])
    swum = [r for r in runs if "diverged" not in r]
    point = {"controller": config["controller"], **{k: config[k] for k in CONDITION}, "missing": result.get("missing"),
             "runs": len(runs), "diverged": len(runs) - len(swum), "left_pool": sum(r["left_pool"] for r in swum),
             "sank": sum(r["sank"] for r in swum), "off": sum(r["left_pool"] or r["sank"] for r in swum)}
    point.update({k: float(np.mean([r[k] for r in swum])) if swum else None for k in GOAL_METRICS})
    return point


def _pool_goals(points: list[dict]) -> dict:
    """Several points of one controller and condition (the small pool's goals) as one."""
    swum = [p for p in points if p["pos_m"] is not None]
    merged = {**points[0], "goal": None, "missing": points[0]["missing"]}
    for key in ("runs", "diverged", "left_pool", "sank", "off"):
        merged[key] = sum(p[key] for p in points)
    weights = [p["runs"] - p["diverged"] for p in swum]
    merged.update({k: float(np.average([p[k] for p in swum], weights=weights)) if swum and sum(weights) else None
                   for k in GOAL_METRICS})
    return merged


def _series(points: list[dict], key, where) -> dict:
    """controller -> [(x, point)] sorted by x, over the points ``where`` picks, goals pooled."""
    groups: dict = {}
    for p in points:
        if where(p):
            groups.setdefault((p["controller"], key(p)), []).append(p)
    series: dict = {name: [] for name in CONTROLLERS}
    for (name, x), group in groups.items():
        series[name].append((x, _pool_goals(group)))
    return {name: sorted(s, key=lambda item: item[0]) for name, s in series.items()}


def _holds(point: dict, reference: dict) -> bool | None:
    if point["pos_m"] is None or reference["pos_m"] is None:
        return None
    return point["pos_m"] <= HOLD_POS_FACTOR * reference["pos_m"]


def _holding_range(series: list, reference_x) -> tuple | None:
    """The widest stretch of x around ``reference_x`` over which every point holds."""
    xs = [x for x, _ in series]
    if reference_x not in xs:
        return None
    ref = series[xs.index(reference_x)][1]
    i = j = xs.index(reference_x)
    while i > 0 and _holds(series[i - 1][1], ref):
        i -= 1
    while j < len(xs) - 1 and _holds(series[j + 1][1], ref):
        j += 1
    return xs[i], xs[j]


def _metrics(point: dict) -> dict | None:
    return None if point["pos_m"] is None else {k: point[k] for k in (*GOAL_METRICS, "runs", "left_pool", "sank")}


def _row(figure: str, point: dict, reference: dict | None = None, **fields) -> dict:
    row = {"figure": figure, "source": "ours", "controller": point["controller"], "d_lat_m": None,
           "theta_lat_deg": None, "density_kg_m3": None, "viscosity_m2_s": None, "direction": None, "speed_m_s": None,
           **fields, "runs": point["runs"], "diverged": point["diverged"], "left_pool": point["left_pool"],
           "sank": point["sank"], **{k: point[k] for k in GOAL_METRICS},
           "holds": None if reference is None else _holds(point, reference), "note": point["missing"]}
    return row


def _swim_rows() -> list[dict]:
    """SWIM's published points as CSV rows: the means it gives, and its limits (no metrics)."""
    blank = {"figure": None, "source": SWIM["source"], "controller": "SWIM freestyle", "d_lat_m": None,
             "theta_lat_deg": None, "density_kg_m3": None, "viscosity_m2_s": None, "direction": None,
             "speed_m_s": None, "runs": None, "diverged": None, "left_pool": None, "sank": None,
             **{k: None for k in GOAL_METRICS}, "holds": None, "note": None}      # the CSV's columns, in order
    fig4, fig5, fig6 = SWIM["fig4"], SWIM["fig5"], SWIM["fig6"]
    return [
        {**blank, "figure": "fig4", **fig4["table3_5m_static"], "note": "Table 3, 5 m static: mean over its targets"},
        {**blank, "figure": "fig4", "d_lat_m": fig4["holds_left_m"], "theta_lat_deg": fig4["holds_left_deg"],
         "holds": True, "note": "generalises up to here on the left"},
        {**blank, "figure": "fig4", "d_lat_m": fig4["holds_right_m"], "theta_lat_deg": fig4["holds_right_deg"],
         "holds": True, "note": "generalises up to here on the right"},
        {**blank, "figure": "fig5 density", "density_kg_m3": fig5["water_kg_m3"], **fig5["table3_3m_static"],
         "note": "Table 3, 3 m static (water)"},
        {**blank, "figure": "fig5 density", "density_kg_m3": fig5["density_succeeds_kg_m3"][0], "holds": True,
         "note": "succeeds from here"},
        {**blank, "figure": "fig5 density", "density_kg_m3": fig5["density_succeeds_kg_m3"][1], "holds": True,
         "note": "succeeds up to here (tried up to 2500)"},
        {**blank, "figure": "fig5 viscosity", "viscosity_m2_s": fig5["viscosity_succeeds_m2_s"][1], "holds": True,
         "note": "handles the whole range tried, from 1e-3"},
        {**blank, "figure": "fig6", "direction": "quiet", "speed_m_s": 0.0, **fig6["quiet"],
         "note": "Table 3, 3 m static: the quiet-water point all curves share"},
        {**blank, "figure": "fig6", "direction": "four directions", **fig6["dynamic_mean"],
         "note": "Table 3, 3 m dynamic: mean over its flows (speeds not given)"},
        {**blank, "figure": "fig6", "speed_m_s": fig6["stable_up_to_m_s"], "holds": True,
         "note": "stable up to about here"},
    ]


def measure(configs: list[dict], results: list[dict]) -> dict:
    points = [_point(c, r) for c, r in zip(configs, results)]
    small = lambda p: p["pool"] == "small"                 # noqa: E731
    lateral = _series(points, lambda p: p["d_lat_m"], lambda p: p["pool"] == "large")
    density = _series(points, lambda p: p["density_kg_m3"],
                      lambda p: small(p) and p["viscosity_m2_s"] is None and p["speed_m_s"] == 0.0)
    viscosity = _series(points, lambda p: FRESH_M2_S if p["viscosity_m2_s"] is None else p["viscosity_m2_s"],
                        lambda p: small(p) and p["density_kg_m3"] == FRESH_KG_M3 and p["speed_m_s"] == 0.0)
    flow = {name: {} for name in CONTROLLERS}
    for direction in DIRECTIONS:
        per = _series(points, lambda p: p["speed_m_s"], lambda p: small(p) and p["density_kg_m3"] == FRESH_KG_M3
                      and p["viscosity_m2_s"] is None and p["direction"] in ("quiet", direction))
        for name in CONTROLLERS:
            flow[name][direction] = per[name]
    at = lambda series, x: next((p for v, p in series if v == x), None)      # noqa: E731
    rows, summary = [], {"figures": [FIGURE, *FIGURES.values()], "hold_rule": (
        f"a point holds while its Pos is at most {HOLD_POS_FACTOR:g}x the controller's own Pos at the reference "
        "(d_lat 0 in the large pool; quiet fresh water in the small pool)")}
    for name in CONTROLLERS:
        ref4, ref = at(lateral[name], 0.0), at(density[name], FRESH_KG_M3)
        rows += [_row("fig4", p, ref4, d_lat_m=d, theta_lat_deg=theta_lat_deg(d)) for d, p in lateral[name]]
        rows += [_row("fig5 density", p, ref, density_kg_m3=rho) for rho, p in density[name]]
        rows += [_row("fig5 viscosity", p, ref, viscosity_m2_s=nu) for nu, p in viscosity[name]]
        rows += [_row("fig6", p, ref, direction=d if s else "quiet", speed_m_s=s)
                 for d in DIRECTIONS for s, p in flow[name][d] if s or d == next(iter(DIRECTIONS))]
        doubles = {}
        for d, series in flow[name].items():
            over = [s for s, p in series if s and _holds(p, ref) is False]
            doubles[d] = over[0] if over else None
        summary[name] = {
            "lateral": {"at_zero": ref4 and _metrics(ref4), "holds_d_lat_m": _holding_range(lateral[name], 0.0),
                        "points": {f"{d:g}": _metrics(p) for d, p in lateral[name]}},
            "density": {"holds_kg_m3": _holding_range(density[name], FRESH_KG_M3),
                        "points": {f"{rho:g}": _metrics(p) for rho, p in density[name]}},
            "viscosity": {"holds_m2_s": _holding_range(viscosity[name], FRESH_M2_S),
                          "points": {f"{nu:g}": _metrics(p) for nu, p in viscosity[name]}},
            "flow": {"quiet": ref and _metrics(ref), "pos_doubles_at_m_s": doubles,
                     "points": {d: {f"{s:g}": _metrics(p) for s, p in series if s}
                                for d, series in flow[name].items()}},
            "missing": next((p["missing"] for p in points if p["controller"] == name and p["missing"]), None),
            "swims": sum(p["runs"] for p in points if p["controller"] == name),
            "left_pool_or_sank": sum(p["off"] for p in points if p["controller"] == name),
            "diverged": sum(p["diverged"] for p in points if p["controller"] == name),
        }
    summary["swim_published"] = SWIM
    return {"rows": rows + _swim_rows(), "summary": summary, "lateral": lateral, "density": density,
            "viscosity": viscosity, "flow": flow}


# -- the figures -------------------------------------------------------------------------------

def _curve(ax, series: list, metric: str, name: str, x_scale: float = 1.0, labelled: bool = True, **style) -> None:
    xy = [(x * x_scale, p[metric]) for x, p in series if p[metric] is not None]
    if not xy:
        return
    ax.plot(*zip(*xy), markersize=4, label=CONTROLLERS[name] if labelled else None, **{**STYLE[name], **style})
    off = [(x * x_scale, p[metric]) for x, p in series if p[metric] is not None and (p["left_pool"] or p["sank"])]
    if off:
        ax.plot(*zip(*off), "o", markerfacecolor="none", markeredgecolor="m", markersize=10, markeredgewidth=1.2)


def _swim_level(ax, values: dict, metric: str, label: str, style: str = ":") -> None:
    if metric in values:
        ax.axhline(values[metric], color="tab:purple", linestyle=style, linewidth=1.2, label=label)


def _lateral_row(axes, numbers: dict) -> None:
    fig4 = SWIM["fig4"]
    for ax, metric in zip(axes, GOAL_METRICS):
        for name in CONTROLLERS:
            _curve(ax, numbers["lateral"][name], metric, name)
        for d in (fig4["holds_left_m"], fig4["holds_right_m"]):
            ax.axvline(d, color="k", linestyle="-.", linewidth=1.0,
                       label="SWIM generalises up to" if d < 0 else None)
        for d in (-fig4["training_offset_m"], fig4["training_offset_m"]):
            ax.axvline(d, color="tab:red", linestyle="--", linewidth=0.8,
                       label="SWIM training offset +-0.375 m" if d < 0 else None)
        edge = fig4["goal_ahead_m"] * math.tan(math.radians(fig4["training_angle_deg"]))
        for d in (-edge, edge):
            ax.axvline(d, color="tab:green", linestyle=":", linewidth=1.0,
                       label="SWIM training angle +-14 deg" if d < 0 else None)
        _swim_level(ax, fig4["table3_5m_static"], metric, "SWIM 5 m static mean (Table 3)")
        ax.set_xlabel("d_lat (m), + = right of the line")
        ax.set_ylabel(LABELS[metric])
        top = ax.secondary_xaxis("top", functions=(lambda d: np.degrees(np.arctan2(d, fig4["goal_ahead_m"])),
                                                    lambda t: fig4["goal_ahead_m"] * np.tan(np.radians(t))))
        top.set_xlabel("theta_lat (deg)")
    axes[0].legend(loc="best", fontsize="x-small")


def _fluid_rows(density_axes, viscosity_axes, numbers: dict) -> None:
    fig5 = SWIM["fig5"]
    for ax, metric in zip(density_axes, GOAL_METRICS):
        ax.axvspan(*fig5["density_succeeds_kg_m3"], color="tab:green", alpha=0.12, label="SWIM succeeds")
        for name in CONTROLLERS:
            _curve(ax, numbers["density"][name], metric, name)
        swim = fig5["table3_3m_static"]
        if metric in swim:
            ax.plot([fig5["water_kg_m3"]], [swim[metric]], "*", color="tab:purple", markersize=11,
                    label="SWIM in water (Table 3)")
        ax.set_xlabel("water density (kg/m^3)")
        ax.set_ylabel(LABELS[metric])
    for ax, metric in zip(viscosity_axes, GOAL_METRICS):
        ax.axvspan(*fig5["viscosity_succeeds_m2_s"], color="tab:green", alpha=0.12, label="SWIM succeeds (all tried)")
        for name in CONTROLLERS:
            _curve(ax, numbers["viscosity"][name], metric, name)
        ax.axvline(FRESH_M2_S, color="C0", linestyle=":", linewidth=1.0, label="fresh water")
        ax.set_xscale("log")
        ax.set_xlabel("kinematic viscosity (m^2/s)")
        ax.set_ylabel(LABELS[metric])
    density_axes[0].legend(loc="best", fontsize="x-small")
    viscosity_axes[0].legend(loc="best", fontsize="x-small")


def _flow_row(axes, numbers: dict) -> None:
    fig6 = SWIM["fig6"]
    for ax, metric in zip(axes, GOAL_METRICS):
        for k, direction in enumerate(DIRECTIONS):
            for name in CONTROLLERS:
                _curve(ax, numbers["flow"][name][direction], metric, name, x_scale=100.0, labelled=False,
                       color=f"C{k}")
        ax.axvline(100.0 * fig6["stable_up_to_m_s"], color="k", linestyle="-.", linewidth=1.0,
                   label="SWIM stable up to")
        if metric in fig6["quiet"]:
            ax.plot([0.0], [fig6["quiet"][metric]], "*", color="tab:purple", markersize=11,
                    label="SWIM quiet water (Table 3)")
        _swim_level(ax, fig6["dynamic_mean"], metric, "SWIM mean over its flows (Table 3)")
        ax.set_xlabel("inflow speed (cm/s)")
        ax.set_ylabel(LABELS[metric])
    handles = [plots.plt.Line2D([], [], color=f"C{k}", label=d) for k, d in enumerate(DIRECTIONS)]
    handles += [plots.plt.Line2D([], [], label=CONTROLLERS[n], **{**STYLE[n], "color": "0.2"}) for n in CONTROLLERS]
    axes[0].legend(handles=handles, loc="best", fontsize="x-small")
    axes[1].legend(loc="best", fontsize="x-small")


def _suptitle(fig, what: str) -> None:
    fig.suptitle(f"{STROKE}: {what}; SWIM's published points in purple and black, "
                 "magenta ring: a swim left the pool or sank below its floor", fontsize="medium")


def plot(numbers: dict, path: Path) -> None:
    path = Path(path)
    fig, axes = plots.figure(4, 4, width_in=18.0, height_in=3.6)
    _lateral_row(axes[0], numbers)
    _fluid_rows(axes[1], axes[2], numbers)
    _flow_row(axes[3], numbers)
    _suptitle(fig, "SWIM Figs. 4 (row 1), 5 (rows 2-3) and 6 (row 4)")
    plots.save(fig, path)
    fig, axes = plots.figure(1, 4, width_in=18.0, height_in=4.0)
    _lateral_row(axes[0], numbers)
    _suptitle(fig, "one goal 3 m ahead in the large pool, moved sideways (SWIM Fig. 4)")
    plots.save(fig, path.parent / FIGURES["fig4"])
    fig, axes = plots.figure(2, 4, width_in=18.0, height_in=3.6)
    _fluid_rows(axes[0], axes[1], numbers)
    _suptitle(fig, "the small pool's goals in other water (SWIM Fig. 5, section 4.4.3)")
    plots.save(fig, path.parent / FIGURES["fig5"])
    fig, axes = plots.figure(1, 4, width_in=18.0, height_in=4.0)
    _flow_row(axes[0], numbers)
    _suptitle(fig, "the small pool's goals under a uniform inflow (SWIM Fig. 6)")
    plots.save(fig, path.parent / FIGURES["fig6"])


# -- the report ---------------------------------------------------------------------------------

def _range(pair, unit: str, fmt: str = "g") -> str:
    if pair is None:
        return "nowhere"
    if pair[0] == pair[1]:
        return f"only at {pair[0]:{fmt}} {unit}"
    return f"from {pair[0]:{fmt}} to {pair[1]:{fmt}} {unit}"


def _scores(m: dict | None) -> str:
    return "no swims" if m is None else f"Pos {m['pos_m']:.2f} m, Prog {m['prog']:.2f}, Dev {m['dev_m']:.2f} m"


def _at(series: list, x) -> dict | None:
    return next((p for v, p in series if v == x and p["pos_m"] is not None), None)


def _lateral_words(numbers: dict, name: str) -> str:
    series, fig4 = numbers["lateral"][name], SWIM["fig4"]
    mine = numbers["summary"][name]["lateral"]
    words = f"straight ahead {_scores(mine['at_zero'])}"
    for d in (fig4["holds_left_m"], fig4["holds_right_m"]):
        if _at(series, d) is not None:
            words += f"; at SWIM's limit d_lat {d:+g} m {_scores(_at(series, d))}"
    holds = _range(mine["holds_d_lat_m"], "m", "+g")
    return words + f"; Pos within {HOLD_POS_FACTOR:g}x its straight-ahead value {holds}"


def _density_words(numbers: dict, name: str) -> str:
    series = numbers["density"][name]
    mine = numbers["summary"][name]["density"]
    words = f"holds {_range(mine['holds_kg_m3'], 'kg/m^3')}"
    sank = [rho for rho, p in series if p["sank"]]
    if sank:
        floor = bench.pool("small").depth_m
        words += f"; sinks below the pool's {floor:g} m floor at {', '.join(f'{x:g}' for x in sank)} kg/m^3"
    water, densest = _at(series, FRESH_KG_M3), series[-1][1] if series else None
    if water is not None and densest is not None and densest["pos_m"] is not None and series[-1][0] > FRESH_KG_M3:
        words += (f"; Dev {water['dev_m']:.2f} m in fresh water, {densest['dev_m']:.2f} m at "
                  f"{series[-1][0]:g} kg/m^3")
    return words


def _viscosity_words(numbers: dict, name: str) -> str:
    series = numbers["viscosity"][name]
    mine = numbers["summary"][name]["viscosity"]
    words = f"holds {_range(mine['holds_m2_s'], 'm^2/s', '.2g')}"
    water, thickest = _at(series, FRESH_M2_S), series[-1][1] if series else None
    if water is not None and thickest is not None and thickest["pos_m"] is not None and series[-1][0] > FRESH_M2_S:
        words += (f"; from fresh water to {series[-1][0]:g} m^2/s Prog {water['prog']:.2f} -> {thickest['prog']:.2f}, "
                  f"Dev {water['dev_m']:.2f} -> {thickest['dev_m']:.2f} m")
    return words


def _flow_words(numbers: dict, name: str) -> str:
    flow = numbers["summary"][name]["flow"]
    doubles = ", ".join(f"{d} at {v:g} m/s" if v is not None else f"{d} not within the speeds tried"
                        for d, v in flow["pos_doubles_at_m_s"].items())
    return f"quiet water {_scores(flow['quiet'])}; Pos more than doubles {doubles}"


def describe(numbers: dict) -> Outcome:
    s = numbers["summary"]
    swum = [n for n in CONTROLLERS if s[n]["swims"] > s[n]["diverged"] and not s[n]["missing"]]
    sentences = []
    for title, words in (("Fig. 4 (large pool, one goal 3 m ahead)", _lateral_words),
                         ("Fig. 5, density (small pool)", _density_words),
                         ("Fig. 5, viscosity (small pool)", _viscosity_words),
                         ("Fig. 6, inflow (small pool)", _flow_words)):
        sentences.append(f"{title}: " + "; ".join(f"{CONTROLLERS[n]}: {words(numbers, n)}" for n in swum) + ".")
    for name in CONTROLLERS:
        mine = s[name]
        if name not in swum:
            sentences.append(f"The {CONTROLLERS[name]} did not swim: {mine['missing'] or 'every swim blew up'}.")
            continue
        blew = f", {mine['diverged']} blew up" if mine["diverged"] else ""
        sentences.append(f"The {CONTROLLERS[name]}: {mine['left_pool_or_sank']} of {mine['swims']} swims left the pool "
                         f"or sank below its floor{blew}.")
    fig4 = SWIM["fig4"]
    ours = (" ".join(sentences) + f" SWIM: goals from d_lat {fig4['holds_left_m']:g} to +{fig4['holds_right_m']:g} m; "
            "densities 920-1500 kg/m^3; viscosities 1e-3 to 5e-2 m^2/s (all tried); stable up to about 0.75 m/s. "
            "Figures: " + ", ".join(s["figures"]) + ".")
    lag = [f"{CONTROLLERS[n]} Prog {s[n]['lateral']['at_zero']['prog']:.2f}" for n in swum
           if s[n]["lateral"]["at_zero"] is not None]
    differs = (
        "SWIM publishes Figs. 4 and 6 as plots and Fig. 5 as renders: the per-point values are not in its text, so "
        "beside ours stand only what it states: the limits above, Table 3's means (3 m static, 5 m static, and 3 m "
        "dynamic averaged over flows whose speeds it does not give) and its trends (low density sinks, high density "
        "degrades heading, viscosity slows progress and steadies the line). Its success criterion is not given; ours "
        f"is Pos within {HOLD_POS_FACTOR:g}x the controller's own at the reference" + (
            f"; in the large pool the straight-ahead reference already lags ({', '.join(lag)}), so Fig. 4's rule "
            "compares with a slow swim" if lag else "") + ". SWIM does not name the pool of its density and viscosity "
        "tests; ours use the small pool's goals, as Fig. 6 does. SWIM's viscosities are its SPH "
        "solver's, 1e-3 m^2/s already ~1100x real water's (its text also says 'up to 20x of water', which the "
        "50x range tried does not match); our thin plates feel viscosity only through Yang's skin "
        "friction (eta A v, eta = rho nu), their pressure drag and lift do not depend on it. SWIM's pool has walls "
        "and a floor; our plates have neither: a swim that leaves the pool or sinks below its floor swims on and is "
        "counted. SWIM does not say where across its 2 m wide large pool its start lies (a goal 1.25 m off a centred "
        "start is outside it), so our lateral sweep's pool is widened to keep each goal 0.5 m inside. Vel is not "
        "measured: our strokes are key poses, not a captured motion. Ours is trained on our own layered controller "
        "on the thin plates; SWIM's on a captured freestyle in SPH water.")
    setting = (f"{STROKE}. Fig. 4: large pool, one goal 3 m ahead, 8 s, d_lat from {min(D_LAT_M):g} to "
               f"+{max(D_LAT_M):g} m (quick: {len(QUICK_D_LAT_M)} offsets). Fig. 5: small pool, its three goals "
               "(quick: goal 0), densities 500-2500 kg/m^3 at fresh water's viscosity and kinematic viscosities "
               "1e-3 to 5e-2 m^2/s at fresh water's density. Fig. 6: small pool, inflows of 0.25-1.5 m/s (quick: "
               "0.5, 1, 1.5) along, against, across and diagonal to the line. Each point: the shipped residual "
               "(deterministic, in its training environment) and the layered heuristic, from SWIM's start (seed 0) "
               f"and, in the full run, {STARTS - 1} jittered starts; thin plates.")
    return Outcome(ours, setting, differs)
