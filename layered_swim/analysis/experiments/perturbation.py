"""SWIM 2026, section 4.4.4: recovery after impulse pushes up to 2 mg and under continuous random
pushes up to 80 N. SWIM's swimmer reaches goals in 4-8 s episodes; recovering from a push needs
longer, so ours follows a target along a straight line for 30 s and is pushed on the pelvis.

The swimmer is the breaststroke with all three layers, standing in for SWIM's freestyle. That is
this experiment's choice, not a limit of the crawl: the front crawl follows moving targets for
minutes too (mean distance, median over 10 starts: the figure-eight 0.64 m in 120 s, a line in a
0.3 m/s cross current 1.32 m in 60 s; docs/results.md)."""
from __future__ import annotations

from pathlib import Path

import numpy as np

from layered_swim.analysis import plots
from layered_swim.analysis.experiments.runner import Outcome
from layered_swim.body.model import load_body
from layered_swim.control.targets import load_trajectory
from layered_swim.episode import Episode
from layered_swim.runs import swim
from layered_swim.sim.simulation import GRAVITY_M_S2
from layered_swim.tasks import FollowTarget

NAME = "perturbation"
TITLE = "Recovery after impulse and random pushes (SWIM 2026, section 4.4.4)"
PAPER = ("SWIM's policy withstands impulse perturbations up to about 2 mg and continuous random forces up to 80 N; "
         "backward and vertical pushes are the most disruptive.")
FIGURE = "perturbation.png"
CSV = "perturbation.csv"
STROKE = "breaststroke"
TRAJECTORY = "straight_line"
SECONDS = 30.0
PUSH_AT_S = 10.0
IMPULSE_S = 0.1                # SWIM does not say how long its impulses last; a 0.1 s shove
RANDOM_FROM_S = 5.0
RANDOM_HOLD_S = 0.5            # a random push keeps its direction this long
DIRECTIONS = {"backward": (-1.0, 0.0, 0.0), "forward": (1.0, 0.0, 0.0), "left": (0.0, 1.0, 0.0),
              "up": (0.0, 0.0, 1.0), "down": (0.0, 0.0, -1.0)}
IMPULSE_MG = (0.5, 1.0, 1.5, 2.0, 2.5, 3.0)
RANDOM_N = (20.0, 40.0, 60.0, 80.0, 100.0, 120.0)
BACK_ON_TRACK_M = 0.1          # within the unperturbed run's worst distance to the target plus this
SWIM_LIMITS = {"impulse_mg": 2.0, "random_n": 80.0}


def configs(quick: bool, seed: int) -> list[dict]:
    base = {"stroke": STROKE, "trajectory": TRAJECTORY, "seconds": SECONDS}
    impulses = (1.0, 2.0, 3.0) if quick else IMPULSE_MG
    directions = ("backward", "left", "up") if quick else tuple(DIRECTIONS)
    randoms = (40.0, 80.0, 120.0) if quick else RANDOM_N
    return ([{**base, "kind": "none"}]
            + [{**base, "kind": "impulse", "direction": d, "mg": k, "at_s": PUSH_AT_S, "for_s": IMPULSE_S}
               for d in directions for k in impulses]
            + [{**base, "kind": "random", "force_n": f, "from_s": RANDOM_FROM_S, "hold_s": RANDOM_HOLD_S, "seed": seed}
               for f in randoms])


def push(config: dict, weight_n: float):
    """The pelvis push of this run as an episode observer: sets the force for the next physics step."""
    if config["kind"] == "impulse":
        force = config["mg"] * weight_n * np.array(DIRECTIONS[config["direction"]])
        start, end = config["at_s"], config["at_s"] + config["for_s"]
        return lambda sim: sim.push(force if start <= sim.time_s < end else 0.0)
    if config["kind"] == "random":
        rng = np.random.default_rng(config["seed"])
        n = int(np.ceil((config["seconds"] - config["from_s"]) / config["hold_s"])) + 1
        directions = rng.normal(size=(n, 3))
        forces = config["force_n"] * directions / np.linalg.norm(directions, axis=1, keepdims=True)

        def on_step(sim) -> None:
            k = int((sim.time_s - config["from_s"]) // config["hold_s"])
            sim.push(forces[k] if k >= 0 else 0.0)
        return on_step
    return None


def run(config: dict) -> dict:
    body = load_body()
    weight_n = float(body.total_mass_kg * GRAVITY_M_S2)
    pusher = push(config, weight_n)
    episode = swim(Episode(config["stroke"], FollowTarget(load_trajectory(config["trajectory"]))), config["seconds"],
                   observers=[pusher] if pusher else [])
    a = episode.task.track()
    distance = np.linalg.norm(a["swimmer_m"] - a["target_m"], axis=1)
    return {"time_s": a["track_time_s"].tolist(), "distance_m": distance.tolist(), "weight_n": weight_n}


def recovery(time_s, distance_m, threshold_m: float, push_s: float) -> tuple[bool, float | None, float]:
    """(recovered, seconds from the push until the swimmer is back within ``threshold_m`` of the
    target after its largest excursion, that excursion). A push that never takes it beyond the
    threshold takes 0 s; one it never comes back from within the run is not recovered. Later
    wandering round the threshold does not count: the unpushed swimmer wanders as much."""
    t, d = np.asarray(time_s), np.asarray(distance_m)
    after = np.flatnonzero(t >= push_s)
    worst = after[np.argmax(d[after])]
    peak = float(d[worst])
    if peak <= threshold_m:
        return True, 0.0, peak
    back = np.flatnonzero((t > t[worst]) & (d <= threshold_m))
    return (True, float(t[back[0]] - push_s), peak) if len(back) else (False, None, peak)


def measure(configs: list[dict], results: list[dict]) -> dict:
    baseline = next(r for c, r in zip(configs, results) if c["kind"] == "none")
    t = np.array(baseline["time_s"])
    threshold = float(np.max(np.array(baseline["distance_m"])[t >= RANDOM_FROM_S])) + BACK_ON_TRACK_M
    quiet_mean = float(np.mean(np.array(baseline["distance_m"])[t >= RANDOM_FROM_S]))
    rows, impulses, randoms = [], {}, []      # impulses: direction -> [(mg, recovered, seconds, peak)]
    for c, r in zip(configs, results):
        d = np.array(r["distance_m"])
        if c["kind"] == "impulse":
            ok, secs, peak = recovery(r["time_s"], d, threshold, c["at_s"])
            impulses.setdefault(c["direction"], []).append((c["mg"], ok, secs, peak))
            rows.append({"kind": "impulse", "direction": c["direction"], "magnitude": c["mg"], "unit": "mg",
                         "recovered": ok, "recovery_s": secs, "peak_distance_m": peak, "mean_distance_m": None})
        elif c["kind"] == "random":
            mean = float(d[np.array(r["time_s"]) >= c["from_s"]].mean())
            randoms.append((c["force_n"], mean))
            rows.append({"kind": "random", "direction": "random", "magnitude": c["force_n"], "unit": "N",
                         "recovered": None, "recovery_s": None, "peak_distance_m": float(d.max()),
                         "mean_distance_m": mean})
    lost = {d: min([p[0] for p in pts if not p[1]], default=None) for d, pts in impulses.items()}
    summary = {"on_track_threshold_m": threshold, "not_back_from_mg": lost, "random": [
        {"force_n": f, "mean_distance_m": m} for f, m in randoms], "unpushed_mean_distance_m": quiet_mean}
    return {"rows": rows, "summary": summary, "impulses": impulses, "mass_kg": results[0]["weight_n"] / GRAVITY_M_S2,
            # at SWIM's impulse limit: direction -> (mg, recovered, seconds, peak)
            "at_limit": {d: next(p for p in pts if p[0] == SWIM_LIMITS["impulse_mg"]) for d, pts in impulses.items()
                         if any(p[0] == SWIM_LIMITS["impulse_mg"] for p in pts)}}


def plot(numbers: dict, path: Path) -> None:
    threshold, s = numbers["summary"]["on_track_threshold_m"], numbers["summary"]
    fig, axes = plots.figure(1, 3, height_in=4.0, width_in=15.0)
    rec_ax, peak_ax, rand_ax = axes[0]
    for direction, points in numbers["impulses"].items():
        mg = [p[0] for p in points]
        line, = peak_ax.plot(mg, [p[3] for p in points], "o-", label=direction)
        done = [(p[0], p[2]) for p in points if p[1]]
        if done:
            rec_ax.plot(*zip(*done), "o-", color=line.get_color(), label=direction)
        failed = [p[0] for p in points if not p[1]]
        if failed:
            rec_ax.plot(failed, [SECONDS - PUSH_AT_S] * len(failed), "x", color=line.get_color(), markersize=9,
                        markeredgewidth=2)
    rec_ax.axhline(SECONDS - PUSH_AT_S, color="C3", linestyle=":", linewidth=0.8, label="x: not back by the end")
    for ax in (rec_ax, peak_ax):
        ax.axvline(SWIM_LIMITS["impulse_mg"], color="0.5", linestyle="--", linewidth=0.8, label="SWIM withstands up to")
        ax.set_xlabel(f"impulse force, {IMPULSE_S:g} s on the pelvis (multiples of body weight mg)")
    rec_ax.set_ylabel("time from the push until back on track (s)")
    rec_ax.set_title("recovery after one push")
    rec_ax.legend(loc="best", fontsize="small")
    peak_ax.axhline(threshold, color="k", linewidth=0.6, label="on track (unperturbed worst + 0.1 m)")
    peak_ax.set_yscale("log")
    peak_ax.set_ylabel("largest distance to the target after the push (m)")
    peak_ax.set_title("how far the push throws the swimmer off")
    peak_ax.legend(loc="best", fontsize="small")
    forces = [0.0] + [r["force_n"] for r in s["random"]]
    rand_ax.plot(forces, [s["unpushed_mean_distance_m"]] + [r["mean_distance_m"] for r in s["random"]], "o-", color="k")
    rand_ax.axvline(SWIM_LIMITS["random_n"], color="0.5", linestyle="--", linewidth=0.8, label="SWIM withstands up to")
    rand_ax.set_xlabel(f"random push on the pelvis, new direction every {RANDOM_HOLD_S:g} s (N)")
    rand_ax.set_ylabel(f"mean distance to the target after {RANDOM_FROM_S:g} s (m)")
    rand_ax.set_title("continuous random pushes")
    rand_ax.legend(loc="best", fontsize="small")
    fig.suptitle(f"{STROKE} following a target at 0.5 m/s (all layers), pushed on the pelvis")
    plots.save(fig, path)


def describe(numbers: dict) -> Outcome:
    impulses, at_limit, s = numbers["impulses"], numbers["at_limit"], numbers["summary"]
    threshold, lost, quiet_mean = s["on_track_threshold_m"], s["not_back_from_mg"], s["unpushed_mean_distance_m"]
    randoms = [(r["force_n"], r["mean_distance_m"]) for r in s["random"]]
    random_off = [f for f, m in randoms if m > threshold]
    ours = ("Impulses: " + "; ".join(
        f"{d} - " + (f"back on track after every push up to {max(p[0] for p in impulses[d]):g} mg" if lost[d] is None
                     else f"not back by the end from {lost[d]:g} mg on")
        for d in impulses) + ". At 2 mg: " + ", ".join(
        f"{d} never off track ({p[3]:.1f} m at worst)" if p[3] <= threshold else
        f"{d} {p[3]:.1f} m off at worst, " + (f"back in {p[2]:.1f} s" if p[1] else "not back")
        for d, p in at_limit.items()) + f". Random pushes: mean distance to the target {quiet_mean:.2f} m unpushed, "
        + ", ".join(f"{m:.2f} m at {f:g} N" for f, m in randoms)
        + (f"; on average off track (beyond {threshold:.2f} m) from {min(random_off):g} N." if random_off
           else f"; on average on track (within {threshold:.2f} m) up to {randoms[-1][0]:g} N."))
    setting = (f"{STROKE}, all three layers, following `{TRAJECTORY}` (0.5 m/s) for {SECONDS:g} s. "
               "Impulses: a force of "
               f"k mg (m = {numbers['mass_kg']:.1f} kg) on the pelvis for {IMPULSE_S:g} s at t = {PUSH_AT_S:g} s. "
               f"Random pushes: constant magnitude from t = {RANDOM_FROM_S:g} s, "
               "direction drawn uniformly on the sphere "
               f"every {RANDOM_HOLD_S:g} s (seeded). On track = within the unperturbed run's largest distance to the "
               f"target after {RANDOM_FROM_S:g} s ({threshold - BACK_ON_TRACK_M:.2f} m) "
               f"plus {BACK_ON_TRACK_M:g} m; the "
               "recovery time runs from the push to the first return on track after the largest excursion.")
    ranked = sorted(at_limit, key=lambda d: at_limit[d][3], reverse=True)
    differs = ("SWIM reports freestyle goal reaching; here breaststroke following a line stands in (the "
               "experiment's choice: its pushes were tuned on it), and SWIM does not say "
               "how long its impulses last (ours: 0.1 s). SWIM finds backward and vertical pushes the most disruptive; "
               "ranked by how far a 2 mg push throws ours off: " + ", ".join(
                   f"{d} {at_limit[d][3]:.1f} m" for d in ranked) + ".")
    return Outcome(ours, setting, differs)
