"""Where the face is against the surface: breathing and a face kept out of the water. Pure
functions of logged arrays (world z up, surface at z = 0).

The face is the centre of the head box's front (local +x, the way the face looks;
``body/swimmer.yaml``), about nose height: above the surface, a swimmer can breathe.
"""
from __future__ import annotations

import numpy as np

from layered_swim.geometry import quat_rotate

FACE_LOCAL = np.array([1.0, 0.0, 0.0])      # a segment's local +x: anterior


def face_height_m(head_pos_m, head_quat_xyzw, head_half_depth_m: float) -> np.ndarray:
    """Height above the surface of the centre of the head box's front face."""
    offset = quat_rotate(np.asarray(head_quat_xyzw, dtype=float), FACE_LOCAL * float(head_half_depth_m))
    return np.asarray(head_pos_m, dtype=float)[..., 2] + offset[..., 2]


def per_cycle_max(time_s, values, starts_s) -> np.ndarray:
    """Largest value within each cycle [starts[k], starts[k + 1])."""
    t, v = np.asarray(time_s, dtype=float), np.asarray(values, dtype=float)
    cycle = np.searchsorted(np.asarray(starts_s, dtype=float), t, side="right") - 1
    inside = (cycle >= 0) & (cycle < len(starts_s) - 1)
    out = np.full(len(starts_s) - 1, -np.inf)
    np.maximum.at(out, cycle[inside], v[inside])
    return out


def cycles_above_pct(time_s, height_m, starts_s) -> float:
    """Share of the cycles in which ``height_m`` rises above the surface at least once (%)."""
    peaks = per_cycle_max(time_s, height_m, starts_s)
    return float(100.0 * np.mean(peaks > 0.0))


def time_below_pct(time_s, height_m, start_s: float, end_s: float) -> float:
    """Share of the samples from ``start_s`` to ``end_s`` with ``height_m`` below the surface (%)."""
    t, h = np.asarray(time_s, dtype=float), np.asarray(height_m, dtype=float)
    inside = (t >= start_s) & (t <= end_s)
    return float(100.0 * np.mean(h[inside] < 0.0))
