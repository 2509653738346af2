"""``validate strokes``' figure: force and speed over one cycle, ours beside the published
curves' shapes. The published shapes are drawn schematically from what the papers describe (no
digitised data is shipped): Yang et al. 2004 Fig. 7, the force on the left hand over a
breaststroke cycle, smooth and one hump over the pull; a front crawl's intracycle speed, two
peaks a cycle (one per arm's pull) of +-15-20 % (Craig & Pendergast 1979). A schematic is placed
at our curve's phase and scale: it compares shapes, not timing or size."""
from __future__ import annotations

from pathlib import Path

import numpy as np

from layered_swim.analysis import plots

PULL_SHARE = 0.45                 # the schematic hand-force hump spans this share of the cycle
CRAWL_FLUCTUATION = 0.175         # +-17.5 %: the middle of Craig & Pendergast's +-15-20 %
PEAK_HAND_TARGET_N = (70.0, 200.0)


def hump(phase, centre: float, width: float) -> np.ndarray:
    """A smooth single hump (raised cosine) of height 1 centred on ``centre`` (phases in 0-1, wrapping)."""
    d = (np.asarray(phase, dtype=float) - centre + 0.5) % 1.0 - 0.5
    return np.where(np.abs(d) < width / 2, 0.5 * (1.0 + np.cos(2.0 * np.pi * d / width)), 0.0)


def two_peaks(phase, mean: float, first_peak: float, fluctuation: float) -> np.ndarray:
    """A speed with two equal peaks a cycle, ``first_peak`` the phase of one: mean (1 +- fluctuation)."""
    return mean * (1.0 + fluctuation * np.cos(4.0 * np.pi * (np.asarray(phase, dtype=float) - first_peak)))


def _phase(profile: dict) -> np.ndarray:
    return np.linspace(0.0, 1.0, len(profile["mean"]))


def _hand_force(ax, profile: dict) -> None:
    plots.band(ax, profile, "ours: left hand, breaststroke", color="C0")
    mean, phase = np.asarray(profile["mean"]), _phase(profile)
    peak = int(np.argmax(mean))
    ax.plot(100 * phase, mean[peak] * hump(phase, phase[peak], PULL_SHARE), "--", color="k",
            label="Yang et al. 2004 Fig. 7 (schematic): smooth, one hump over the pull")
    ax.set_ylabel("force of the water on the hand (N)")
    ax.set_title("hand force over a breaststroke cycle")


def _crawl_speed(ax, profile: dict) -> None:
    plots.band(ax, profile, "ours: front crawl", color="C1")
    mean, phase = np.asarray(profile["mean"]), _phase(profile)
    half = len(mean) // 2
    ax.plot(100 * phase, two_peaks(phase, float(mean.mean()), phase[int(np.argmax(mean[:half]))], CRAWL_FLUCTUATION),
            "--", color="k", label="published (schematic): two peaks, +-15-20 % (Craig & Pendergast 1979)")
    ax.set_ylabel("forward speed (m/s)")
    ax.set_title("intracycle speed of the front crawl")


def validation_figure(profiles: dict, path: Path) -> None:
    """Four panels from each stroke's free-swim profiles (mean and SD over the normalised cycle)."""
    fig, axes = plots.figure(2, 2, width_in=13.0, height_in=4.0)
    (force_ax, speed_ax), (all_speed_ax, all_force_ax) = axes
    if profiles.get("breaststroke"):
        _hand_force(force_ax, profiles["breaststroke"]["hand_l_force_n"])
    if profiles.get("front_crawl"):
        _crawl_speed(speed_ax, profiles["front_crawl"]["forward_speed_m_s"])
    for stroke, p in profiles.items():
        if not p:
            continue
        speed = np.asarray(p["forward_speed_m_s"]["mean"])
        if abs(speed.mean()) > 0.1:          # treading water holds its place: no speed to speak of
            all_speed_ax.plot(100 * _phase(p["forward_speed_m_s"]), 100.0 * (speed / speed.mean() - 1.0), label=stroke)
        hand = np.maximum(p["hand_l_force_n"]["mean"], p["hand_r_force_n"]["mean"])
        all_force_ax.plot(100 * _phase(p["hand_l_force_n"]), hand, label=stroke)
    all_speed_ax.set_ylabel("forward speed minus its mean (% of the mean)")
    all_speed_ax.set_title("speed over the cycle, every travelling stroke")
    for bound in PEAK_HAND_TARGET_N:
        all_force_ax.axhline(bound, color="0.4", linestyle=":", linewidth=0.9)
    all_force_ax.set_ylabel("larger of the two hands' mean force (N)")
    all_force_ax.set_title("hand force over the cycle; dotted: the 70-200 N peak target")
    for ax in axes.ravel():
        ax.set_xlim(0.0, 100.0)
        ax.set_xlabel(plots.CYCLE_LABEL)
        if ax.get_legend_handles_labels()[0]:
            ax.legend(loc="upper left", fontsize="x-small")
    fig.suptitle("validate strokes: ours (mean +- SD over cycles) beside the published curves' shapes "
                 "(schematics placed at our phase and scale)")
    plots.save(fig, path)
