"""Stroke metrics from a logged run: pure functions of the recorded arrays.

Everything is measured over the window after the swimmer has settled into its stroke
(``SETTLE_S``); a run shorter than that is measured whole, and the summary says so.
Axes: world z up with the surface at z = 0, the swim starts heading +x.
"""
from __future__ import annotations

import numpy as np

from layered_swim.geometry import quat_rotate

SETTLE_S = 5.0
_UP = np.array([0.0, 0.0, 1.0])
_LATERAL = np.array([0.0, 1.0, 0.0])   # a segment's local +y: the swimmer's left


def head_top_height_m(pos_m, quat_xyzw, half_extents_z) -> np.ndarray:
    """Height above the surface of the head box's top (its local +z face centre)."""
    pos_m, quat_xyzw = np.asarray(pos_m, dtype=float), np.asarray(quat_xyzw, dtype=float)
    return pos_m[..., 2] + quat_rotate(quat_xyzw, _UP * float(half_extents_z))[..., 2]


def roll_deg(quat_xyzw) -> np.ndarray:
    """Tilt of a segment's lateral axis out of the horizontal plane: roll about the direction
    of travel, positive when the left side rises."""
    lateral_z = quat_rotate(np.asarray(quat_xyzw, dtype=float), _LATERAL)[..., 2]
    return np.degrees(np.arcsin(np.clip(lateral_z, -1.0, 1.0)))


def per_cycle_peak(time_s, values, cycles_per_s) -> np.ndarray:
    """Maximum of ``values`` in each stroke cycle that lies wholly inside the samples (cycle k
    spans phases [k, k + 1]); with no whole cycle, the maximum over all samples."""
    phase = np.asarray(time_s, dtype=float) * cycles_per_s
    tol = 1e-9  # samples sit on cycle boundaries up to rounding
    first, last = int(np.ceil(phase[0] - tol)), int(np.floor(phase[-1] + tol))
    peaks = [values[(phase >= k - tol) & (phase <= k + 1 + tol)].max() for k in range(first, last)]
    return np.array(peaks) if peaks else np.array([np.max(values)])


def summary(time_s, com_pos_m, pelvis_pos_m, thorax_quat_xyzw, head_top_m, cycles_per_s: float,
            stroke: str, settle_s: float = SETTLE_S) -> dict:
    """The run's headline numbers. Arrays are per log sample: time_s (T,), positions (T, 3),
    thorax orientation (T, 4), head-top height (T,)."""
    time_s = np.asarray(time_s, dtype=float)
    window = time_s >= settle_s
    note = None
    if window.sum() < 2:
        window = np.ones_like(time_s, dtype=bool)
        note = f"run shorter than the {settle_s:g} s settle time: metrics cover the whole run"
    t = time_s[window]
    duration_s = t[-1] - t[0]
    com = np.asarray(com_pos_m, dtype=float)[window]
    pelvis = np.asarray(pelvis_pos_m, dtype=float)[window]
    mean_speed = (com[-1, 0] - com[0, 0]) / duration_s
    roll = np.abs(roll_deg(np.asarray(thorax_quat_xyzw, dtype=float)[window]))
    return {
        "stroke": stroke,
        "seconds": float(time_s[-1]),
        "mean_speed_m_s": float(mean_speed),
        "stroke_rate_cpm": float(60.0 * cycles_per_s),
        "distance_per_cycle_m": float(mean_speed / cycles_per_s),
        "peak_shoulder_roll_deg": float(per_cycle_peak(t, roll, cycles_per_s).mean()),
        "mean_head_height_m": float(np.mean(np.asarray(head_top_m, dtype=float)[window])),
        "horizontal_drift_m_s": float(np.linalg.norm(pelvis[-1, :2] - pelvis[0, :2]) / duration_s),
        "final_pelvis_depth_m": float(-np.asarray(pelvis_pos_m, dtype=float)[-1, 2]),
        "note": note,
    }
