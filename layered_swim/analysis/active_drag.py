"""Active drag as swimming science measures it: the velocity perturbation method (VPM) of
Kolmogorov & Duplishcheva 1992 (J. Biomech. 25(3): 311-318). Pure functions.

The swimmer swims the same stroke twice: freely at mean speed v1, and towing a small buoy of known
drag at mean speed v2, the buoy pulling back with mean force F_b. With the same useful power both
times and the swimmer's own drag going as D = k v^2:

    k v1^3 = k v2^3 + F_b v2   =>   D1 = k v1^2 = F_b v2 v1^2 / (v1^3 - v2^3)

Whole-body, so a limb recovering against the water and another pulling are not counted twice (the
sum of each segment's resistive force, ``stroke_metrics.propulsive_resistive_n``, does that; it is
reported apart as "resistive force summed over segments", never as active drag).

A simulated swimmer keeps its joint trajectories, not its power, under the extra load, so the
power it put out in each swim is measured too: ``power_ratio`` = P2 / P1 gives the same balance
with that ratio, k v1^3 (P2 / P1) = k v2^3 + F_b v2 (equal efficiency assumed), a check on the
method's equal-power assumption, not the method itself.
"""
from __future__ import annotations

import math

import numpy as np

from layered_swim.config import ConfigError

NARITA_ACTIVE_DRAG = (32.2, 3.3)      # D = 32.2 v^3.3 N, front crawl (Narita et al. 2017)


def vpm_active_drag_n(buoy_force_n: float, free_speed_m_s: float, towing_speed_m_s: float,
                      power_ratio: float = 1.0) -> float | None:
    """D1 = F_b v2 v1^2 / (v1^3 (P2/P1) - v2^3): the active drag at the free speed v1. None where
    the buoy did not slow the swimmer enough to read one (a denominator at or below zero)."""
    values = {"buoy force": buoy_force_n, "free speed": free_speed_m_s, "towing speed": towing_speed_m_s,
              "power ratio": power_ratio}
    for name, value in values.items():
        if not (isinstance(value, (int, float)) and math.isfinite(value) and value > 0.0):
            raise ConfigError(f"velocity perturbation method: the {name} must be a positive number, got {value}")
    denominator = free_speed_m_s**3 * power_ratio - towing_speed_m_s**3
    if denominator <= 0.0:
        return None
    return buoy_force_n * towing_speed_m_s * free_speed_m_s**2 / denominator


def narita_active_drag_n(speed_m_s: float) -> float:
    """Narita et al. 2017's active drag of front crawl at ``speed_m_s``: 32.2 v^3.3 N."""
    k, power = NARITA_ACTIVE_DRAG
    return k * abs(speed_m_s) ** power


def buoy_drag_n(drag_kg_m: float, speed_m_s: float) -> float:
    """A towed body of quadratic drag: F = k v^2."""
    return drag_kg_m * speed_m_s**2


def propelling_efficiency(active_drag_n: float | None, speed_m_s: float, joint_power_w: float) -> float | None:
    """Power to overcome the active drag over the net mechanical power of the joints: D1 v1 / P."""
    if active_drag_n is None or not joint_power_w > 0.0:
        return None
    return active_drag_n * speed_m_s / joint_power_w


def window_rate(time_s, total, start_s: float, end_s: float) -> float:
    """Mean rate of a running total (work in J, impulse in N s) between two times: its change over
    the span, the total read linearly between samples."""
    if not end_s > start_s:
        raise ConfigError(f"an empty time window ({start_s:g} to {end_s:g} s)")
    at = np.interp([start_s, end_s], np.asarray(time_s, dtype=float), np.asarray(total, dtype=float))
    return float((at[1] - at[0]) / (end_s - start_s))
