"""Figures for ``analyze`` and ``compare``: each draws from the plain analysis data (never from
a simulation) and writes one PNG. Every axis names its quantity and unit."""
from __future__ import annotations

from pathlib import Path

import matplotlib

from layered_swim.outputs import atomic_path

matplotlib.use("Agg")                  # headless: files only, no display
import matplotlib.pyplot as plt  # noqa: E402  (the backend must be chosen first)
import numpy as np  # noqa: E402

DPI = 110
MIN_ROLL_SPAN_DEG = 5.0
CYCLE_LABEL = "stroke cycle (%)"
LIMB_TITLES = {"hand_l": "left hand", "hand_r": "right hand", "foot_l": "left foot", "foot_r": "right foot"}


def figure(rows: int = 1, cols: int = 1, width_in: float = 9.0, height_in: float = 3.2, **kwargs):
    fig, axes = plt.subplots(rows, cols, figsize=(width_in, height_in * rows), squeeze=False, **kwargs)
    return fig, axes


def save(fig, path: str | Path) -> None:
    for ax in fig.axes:
        ax.grid(True, alpha=0.3)
    fig.tight_layout()
    with atomic_path(path) as tmp:
        fig.savefig(tmp, dpi=DPI)
    plt.close(fig)


def band(ax, profile: dict, label: str, scale: float = 1.0, **style) -> None:
    """Mean over the normalised cycle with a +-1 SD band across cycles."""
    mean, sd = np.asarray(profile["mean"]) * scale, np.asarray(profile["sd"]) * abs(scale)
    pct = np.linspace(0.0, 100.0, len(mean))
    line, = ax.plot(pct, mean, label=label, **style)
    ax.fill_between(pct, mean - sd, mean + sd, color=line.get_color(), alpha=0.2, linewidth=0)
    ax.set_xlim(0.0, 100.0)
    ax.set_xlabel(CYCLE_LABEL)


def _thrust_words(result: dict) -> str:
    return "along travel" if result["summary"]["thrust_axis"] == "forward" else "upward"


def _title(result: dict, what: str) -> str:
    return f"{result['stroke']}: {what} (mean +- SD over {result['summary']['cycles']} cycles)"


def speed_figure(result: dict, path: Path) -> None:
    ex, profiles = result["excerpt"], result["profiles"]
    fig, axes = figure(2, 1)
    top, bottom = axes[0, 0], axes[1, 0]
    top.plot(ex["time_s"], ex["forward_speed_m_s"], color="C0", label="forward speed")
    for start in ex["starts_s"]:
        top.axvline(start, color="0.5", linestyle="--", linewidth=0.8)
    top.set_xlabel("time (s)")
    top.set_ylabel("forward speed (m/s)", color="C0")
    marker = top.twinx()
    marker.plot(ex["time_s"], ex["cycle_marker_m"], color="C1", linewidth=0.9)
    marker.set_ylabel("cycle marker reach (m)", color="C1")
    top.set_title(f"{result['stroke']}: first analysed cycles; dashed lines = cycle starts "
                  "(marker rising through its mean)")
    band(bottom, profiles["forward_speed_m_s"], "forward speed")
    mean = result["summary"]["mean_speed_m_s"]["mean"]
    bottom.axhline(mean, color="k", linewidth=0.8, label=f"mean {mean:.2f} m/s")
    bottom.set_ylabel("forward speed (m/s)")
    bottom.set_title(_title(result, "centre-of-mass speed over the cycle"))
    bottom.legend(loc="best", fontsize="small")
    save(fig, path)


def limb_force_figure(result: dict, path: Path) -> None:
    fig, axes = figure(2, 2, height_in=3.0)
    for ax, name in zip(axes.ravel(), LIMB_TITLES):
        band(ax, result["profiles"][f"{name}_force_n"], "magnitude", color="0.35")
        band(ax, result["profiles"][f"{name}_thrust_n"], f"{_thrust_words(result)} (+ propulsive)", color="C0")
        ax.axhline(0.0, color="k", linewidth=0.6)
        ax.set_ylabel("hydrodynamic force (N)")
        ax.set_title(f"{LIMB_TITLES[name]}")
        ax.legend(loc="best", fontsize="small")
    fig.suptitle(_title(result, "force of the water on the hands and feet"))
    save(fig, path)


def propulsion_figure(result: dict, path: Path) -> None:
    profiles = result["profiles"]
    fig, axes = figure(2, 1)
    top, bottom = axes[0, 0], axes[1, 0]
    ahead, back = (("pushed ahead", "held back") if result["summary"]["thrust_axis"] == "forward"
                   else ("pushed up", "pushed down"))
    band(top, profiles["propulsive_force_n"], f"propulsive (segments {ahead})", color="C2")
    band(top, profiles["resistive_force_n"], f"resistive (segments {back})", scale=-1.0, color="C3")
    net = np.asarray(profiles["propulsive_force_n"]["mean"]) - np.asarray(profiles["resistive_force_n"]["mean"])
    top.plot(np.linspace(0.0, 100.0, len(net)), net, color="k", linewidth=1.0, label="net")
    top.axhline(0.0, color="k", linewidth=0.6)
    top.set_ylabel(f"force {_thrust_words(result)} (N)")
    top.set_title(_title(result, "hydrodynamic force summed over segments"))
    top.legend(loc="best", fontsize="small")
    band(bottom, profiles["joint_power_w"], "all joints", color="C4")
    power = result["summary"]["mechanical_power_w"]["mean"]
    bottom.axhline(power, color="k", linewidth=0.8, label=f"mean {power:.0f} W")
    bottom.set_ylabel("joint mechanical power (W)")
    bottom.set_title("mechanical power of the joint torques (torque x joint rate, summed)")
    bottom.legend(loc="best", fontsize="small")
    save(fig, path)


def attitude_figure(result: dict, path: Path) -> None:
    profiles = result["profiles"]
    fig, axes = figure(3, 1, height_in=2.6)
    roll, pitch, head = axes[:, 0]
    band(roll, profiles["shoulder_roll_deg"], "shoulders (thorax)")
    band(roll, profiles["hip_roll_deg"], "hips (pelvis)")
    low, high = roll.get_ylim()
    roll.set_ylim(min(low, -MIN_ROLL_SPAN_DEG), max(high, MIN_ROLL_SPAN_DEG))   # a level body reads as level
    roll.set_ylabel("roll (deg, left up > 0)")
    roll.set_title(_title(result, "body roll, pitch and head height"))
    roll.legend(loc="best", fontsize="small")
    band(pitch, profiles["pitch_deg"], "pelvis")
    pitch.set_ylabel("pitch (deg)")
    band(head, profiles["head_top_m"], "top of the head")
    head.axhline(0.0, color="C0", linewidth=0.8, linestyle=":", label="water surface")
    head.set_ylabel("height (m)")
    head.legend(loc="best", fontsize="small")
    save(fig, path)


COMPARE_PANELS = (("forward_speed_m_s", "forward speed (m/s)"),
                  ("hand_l_thrust_n", "left hand force along the thrust axis (N)"),
                  ("joint_power_w", "joint mechanical power (W)"), ("shoulder_roll_deg", "shoulder roll (deg)"))


def compare_figure(results: list[dict], path: Path) -> None:
    fig, axes = figure(2, 2, height_in=3.2, width_in=11.0)
    for ax, (name, label) in zip(axes.ravel(), COMPARE_PANELS):
        for result in results:
            band(ax, result["profiles"][name], result["stroke"])
        ax.set_ylabel(label)
        ax.legend(loc="best", fontsize="small")
    fig.suptitle("strokes side by side over the normalised cycle (mean +- SD across cycles)")
    save(fig, path)
