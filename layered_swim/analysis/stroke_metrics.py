"""Per-cycle stroke metrics from a logged swim: pure functions of the recorded arrays.

``analyze_log`` cuts the settled part of a log into stroke cycles (``cycles.py``) and measures
each cycle; the helpers above it each compute one quantity and are tested on hand-made
trajectories. Axes: world z up, surface at z = 0. "Forward" is the horizontal direction the
centre of mass travelled over the analysed window; the thrust axis is forward for prone and supine
strokes and straight up for upright ones (treading water pushes the body up, not along).
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from layered_swim.analysis.cycles import cycle_means, cycle_starts, resample_cycles
from layered_swim.config import ConfigError
from layered_swim.control.steering import FORWARD_LOCAL
from layered_swim.geometry import quat_rotate
from layered_swim.state import lying
from layered_swim.tasks.metrics import roll_deg

PELVIS_LONG_AXIS_LOCAL = np.array([0.0, 0.0, 1.0])
LIMBS = ("hand_l", "hand_r", "foot_l", "foot_r")
CYCLE_MARKER = {"prone": "hand_l", "supine": "hand_l", "upright": "foot_l"}   # reaches furthest once per cycle
MIN_CYCLES = 2
EXCERPT_CYCLES = 6     # cycles shown as time series in the plot of how the swim was cut
UP = np.array([0.0, 0.0, 1.0])


def travel_direction(com_pos_m) -> np.ndarray:
    """Unit horizontal vector of the net displacement of the centre of mass (T, 3); +x when it
    did not move horizontally."""
    d = np.asarray(com_pos_m, dtype=float)[-1] - np.asarray(com_pos_m, dtype=float)[0]
    d[2] = 0.0
    norm = np.linalg.norm(d)
    return d / norm if norm > 1e-9 else np.array([1.0, 0.0, 0.0])


def pitch_deg(quat_xyzw, forward_local) -> np.ndarray:
    """Elevation of a segment's forward axis above the horizontal (head up > 0 for a prone or
    supine pelvis, leaning back > 0 for an upright one)."""
    forward = quat_rotate(np.asarray(quat_xyzw, dtype=float), np.asarray(forward_local, dtype=float))
    return np.degrees(np.arcsin(np.clip(forward[..., 2], -1.0, 1.0)))


def body_inclination_deg(segment_pos_m, seg: dict) -> np.ndarray:
    """Elevation of the line from between the feet to the head above the horizontal (head up > 0):
    the body's inclination as swimming science measures it (e.g. Zamparo et al. 2009)."""
    pos = np.asarray(segment_pos_m, dtype=float)
    line = pos[:, seg["head"]] - 0.5 * (pos[:, seg["foot_l"]] + pos[:, seg["foot_r"]])
    return np.degrees(np.arctan2(line[:, 2], np.linalg.norm(line[:, :2], axis=1)))


def heading_deg(quat_xyzw, forward_local) -> np.ndarray:
    """Compass direction of a segment's forward axis seen from above, counterclockwise from +x
    (a left turn increases it), unwrapped so a turn past 180 deg keeps counting."""
    forward = quat_rotate(np.asarray(quat_xyzw, dtype=float), np.asarray(forward_local, dtype=float))
    return np.degrees(np.unwrap(np.arctan2(forward[..., 1], forward[..., 0])))


def reach_along_body_m(marker_pos_m, pelvis_pos_m, pelvis_quat_xyzw) -> np.ndarray:
    """How far a segment lies along the pelvis long axis (towards the head) from the pelvis."""
    axis = quat_rotate(np.asarray(pelvis_quat_xyzw, dtype=float), PELVIS_LONG_AXIS_LOCAL)
    return np.sum((np.asarray(marker_pos_m, dtype=float) - np.asarray(pelvis_pos_m, dtype=float)) * axis, axis=-1)


def propulsive_resistive_n(force_n, axis) -> tuple[np.ndarray, np.ndarray]:
    """Per sample, the sums over segments of the forces' positive and (as magnitudes) negative
    parts along ``axis``: force_n (T, segments, 3) -> two (T,) arrays, both >= 0."""
    along = np.asarray(force_n, dtype=float) @ np.asarray(axis, dtype=float)
    return np.clip(along, 0.0, None).sum(axis=-1), np.clip(-along, 0.0, None).sum(axis=-1)


def speed_fluctuation_pct(speed_profiles) -> np.ndarray:
    """Intracycle speed fluctuation per cycle, +-percent of the cycle's mean speed: half the
    range over the mean, 100 (max - min) / (2 mean). speed_profiles (cycles, points)."""
    p = np.asarray(speed_profiles, dtype=float)
    return 100.0 * (p.max(axis=1) - p.min(axis=1)) / (2.0 * cycle_means(p))


def amplitude(profiles) -> np.ndarray:
    """Half the peak-to-peak range of each cycle (cycles, points) -> (cycles,)."""
    p = np.asarray(profiles, dtype=float)
    return 0.5 * (p.max(axis=1) - p.min(axis=1))


def mean_power_w(time_s, work_j, starts) -> np.ndarray:
    """Mean power over each cycle from a running total of work: its change over the cycle."""
    at = np.interp(starts, time_s, work_j)
    return np.diff(at) / np.diff(starts)


def propelling_efficiency(drag_n, speed_m_s, power_w):
    """Useful power (overcoming the active drag at the mean speed) over mechanical power."""
    return drag_n * speed_m_s / power_w


@dataclass(frozen=True)
class SwimmerInfo:
    segment_names: tuple[str, ...]
    posture: str              # prone | supine | upright: which segment marks cycles, which axis is thrust
    period_hint_s: float      # the controller's cycle period, to reject noise crossings
    settle_s: float           # analyse from here on


def _stats(values) -> dict:
    v = np.asarray(values, dtype=float)
    return {"mean": float(v.mean()), "sd": float(v.std(ddof=1)) if len(v) > 1 else 0.0}


def analyze_log(log: dict, info: SwimmerInfo) -> dict:
    """Cycles, per-cycle rows, means and spreads, and mean +- SD profiles over the normalised
    cycle. ``log`` holds the recorder's arrays including ``joint_work_j``."""
    t = np.asarray(log["time_s"], dtype=float)
    # A row without a finite fluid force (the last of a run that blew up) is never part of the window.
    keep = (t >= info.settle_s) & np.isfinite(log["fluid_force_n"]).all(axis=(1, 2))
    window = {name: np.asarray(values)[keep] for name, values in log.items()}
    t = window["time_s"]
    seg = {name: i for i, name in enumerate(info.segment_names)}
    pos, quat = window["segment_pos_m"], window["segment_quat_xyzw"]
    marker = reach_along_body_m(pos[:, seg[CYCLE_MARKER[info.posture]]], pos[:, seg["pelvis"]], quat[:, seg["pelvis"]])
    starts = cycle_starts(t, marker, info.period_hint_s)
    if len(starts) < MIN_CYCLES + 1:
        raise ConfigError(f"only {max(len(starts) - 1, 0)} whole stroke cycles after the {info.settle_s:g} s settle "
                          f"time (a cycle is one rise and fall of the {CYCLE_MARKER[info.posture]}'s reach along the "
                          f"body); at least {MIN_CYCLES} are needed: swim longer, or the stroke does not cycle")
    travels = lying(info.posture)     # along the body; an upright stroke holds itself up
    forward = travel_direction(window["com_pos_m"])
    series = _series(window, seg, info.posture, forward, forward if travels else UP)
    profiles = {name: resample_cycles(t, values, starts) for name, values in series.items()}
    rows = _cycle_rows(t, window, starts, forward, profiles, travels)
    summary = {name: _stats(values) for name, values in rows.items() if name != "start_s"}
    for limb in ("hand", "foot"):
        summary[f"peak_{limb}_force_n"] = _stats(np.maximum(rows[f"peak_{limb}_l_force_n"],
                                                            rows[f"peak_{limb}_r_force_n"]))
    speed = summary["mean_speed_m_s"]["mean"]
    drag = summary["resistive_force_n"]["mean"] if travels else None
    summary.update({
        "cycles": len(starts) - 1,
        "analysed_s": float(starts[-1] - starts[0]),
        "travel_direction": forward.tolist(),
        "thrust_axis": "forward" if travels else "up",
        "active_drag_n": drag,
        "active_drag_per_v2_kg_m": drag / speed**2 if travels else None,
        "propelling_efficiency": (propelling_efficiency(drag, speed, summary["mechanical_power_w"]["mean"])
                                  if travels else None),
    })
    return {
        "summary": summary,
        "cycles": [{k: float(v[i]) for k, v in rows.items()} for i in range(len(starts) - 1)],
        "profiles": {name: {"mean": p.mean(axis=0).tolist(), "sd": p.std(axis=0, ddof=1).tolist()}
                     for name, p in profiles.items()},
        "excerpt": _excerpt(t, series["forward_speed_m_s"], marker, starts),
    }


def _buoyancy_or_zero(buoyancy_n: np.ndarray, thrust_axis: np.ndarray) -> np.ndarray:
    """The logged buoyancy part of the fluid force. A backend that cannot separate it (SPH) logs
    NaN; along a horizontal thrust axis buoyancy adds nothing, so the whole force serves there."""
    if not np.isnan(buoyancy_n).any():
        return buoyancy_n
    if abs(float(np.asarray(thrust_axis, dtype=float)[2])) > 1e-6:
        raise ConfigError("this fluid backend does not separate buoyancy from the rest of the force, so an "
                          "upright stroke's vertical thrust cannot be analysed with it; use --backend plate")
    return np.zeros_like(buoyancy_n)


def _series(window: dict, seg: dict, posture: str, forward: np.ndarray, thrust_axis: np.ndarray) -> dict:
    """Every per-sample quantity that gets a profile over the cycle."""
    quat = window["segment_quat_xyzw"]
    hydro = window["fluid_force_n"] - _buoyancy_or_zero(window["buoyancy_force_n"], thrust_axis)
    propulsive, resistive = propulsive_resistive_n(hydro, thrust_axis)
    series = {
        "forward_speed_m_s": window["com_vel_m_s"] @ forward,
        "shoulder_roll_deg": roll_deg(quat[:, seg["thorax"]]),
        "hip_roll_deg": roll_deg(quat[:, seg["pelvis"]]),
        "pitch_deg": pitch_deg(quat[:, seg["pelvis"]], FORWARD_LOCAL[posture]),
        "head_top_m": window["head_top_m"],
        "propulsive_force_n": propulsive,
        "resistive_force_n": resistive,
        "joint_power_w": np.gradient(window["joint_work_j"], window["time_s"]),
    }
    if lying(posture) and {"head", "foot_l", "foot_r"} <= seg.keys():    # a level pelvis, legs hanging, is not level
        series["body_inclination_deg"] = body_inclination_deg(window["segment_pos_m"], seg)
    for name in LIMBS:
        series[f"{name}_thrust_n"] = hydro[:, seg[name]] @ thrust_axis
        series[f"{name}_force_n"] = np.linalg.norm(hydro[:, seg[name]], axis=1)
    return series


def _cycle_rows(t, window: dict, starts, forward, profiles: dict, travels: bool) -> dict:
    """One value per cycle for every per-cycle quantity (arrays of length cycles)."""
    means = {name: cycle_means(p) for name, p in profiles.items()}
    duration = np.diff(starts)
    com_at_starts = np.column_stack([np.interp(starts, t, window["com_pos_m"][:, k]) for k in range(3)])
    distance = np.diff(com_at_starts, axis=0) @ forward
    rows = {
        "start_s": starts[:-1], "duration_s": duration, "stroke_rate_cpm": 60.0 / duration,
        "distance_per_cycle_m": distance, "mean_speed_m_s": distance / duration,
        "shoulder_roll_deg": amplitude(profiles["shoulder_roll_deg"]),
        "hip_roll_deg": amplitude(profiles["hip_roll_deg"]),
        "pitch_deg": means["pitch_deg"], "head_top_m": means["head_top_m"],
        **({"body_inclination_deg": means["body_inclination_deg"]} if "body_inclination_deg" in means else {}),
        "propulsive_force_n": means["propulsive_force_n"], "resistive_force_n": means["resistive_force_n"],
        "mechanical_power_w": mean_power_w(t, window["joint_work_j"], starts),
        **{f"peak_{name}_force_n": profiles[f"{name}_force_n"].max(axis=1) for name in LIMBS},
    }
    if travels:    # an upright swimmer hardly travels: its speed fluctuation is noise over nothing
        rows["speed_fluctuation_pct"] = speed_fluctuation_pct(profiles["forward_speed_m_s"])
    return rows


def _excerpt(t, speed, marker, starts) -> dict:
    """The first few analysed cycles as time series, for the plot that shows how cycles were cut."""
    inside = (t >= starts[0]) & (t <= starts[min(EXCERPT_CYCLES, len(starts) - 1)])
    return {"time_s": t[inside].tolist(), "forward_speed_m_s": speed[inside].tolist(),
            "cycle_marker_m": marker[inside].tolist(), "starts_s": starts[: EXCERPT_CYCLES + 1].tolist()}
