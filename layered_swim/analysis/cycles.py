"""Stroke cycles from a measured signal, and quantities resampled over the normalised cycle.

A cycle starts each time a marker signal that rises and falls once per stroke (for a prone
stroke, how far the left hand reaches ahead of the pelvis; see ``stroke_metrics``) rises through
its midline. The crossing, where the signal is steep, pins the phase far better than the
signal's maximum, which sits on a plateau in strokes with a glide. Hysteresis and a minimum
separation keep noise or a second, smaller bump from splitting a cycle in two. Pure numpy.
"""
from __future__ import annotations

import numpy as np

PROFILE_POINTS = 101          # samples over the normalised cycle, 0 %, 1 %, ..., 100 %
HYSTERESIS_STD = 0.2          # half-width of the trigger band round the midline
MIN_SEPARATION_PERIODS = 0.5  # crossings closer than this fraction of the expected period are noise


def cycle_starts(time_s, signal, period_hint_s: float) -> np.ndarray:
    """Cycle start times: when ``signal`` rises through its mean (interpolated between samples).
    A Schmitt trigger decides which rises count: the signal must have dipped HYSTERESIS_STD
    standard deviations below the mean and then climb as far above it, so noise wobbling round
    the mean counts once; a start also needs MIN_SEPARATION_PERIODS * ``period_hint_s`` since the
    previous one."""
    t, x = np.asarray(time_s, dtype=float), np.asarray(signal, dtype=float)
    mid, band = x.mean(), HYSTERESIS_STD * x.std()
    starts, armed, rise = [], False, None
    for i in range(1, len(x)):
        if x[i - 1] < mid <= x[i]:
            rise = t[i - 1] + (mid - x[i - 1]) / (x[i] - x[i - 1]) * (t[i] - t[i - 1])   # latest rise so far
        if x[i] < mid - band:
            armed = True
        elif armed and x[i] > mid + band and rise is not None:
            if not starts or rise - starts[-1] >= MIN_SEPARATION_PERIODS * period_hint_s:
                starts.append(rise)
            armed = False
    return np.array(starts)


def resample_cycles(time_s, values, starts, points: int = PROFILE_POINTS) -> np.ndarray:
    """``values`` (T, ...) linearly interpolated at ``points`` evenly spaced phases of every
    cycle [starts[k], starts[k + 1]]: shape (cycles, points, ...)."""
    t = np.asarray(time_s, dtype=float)
    v = np.asarray(values, dtype=float)
    flat = v.reshape(len(t), -1)
    phase = np.linspace(0.0, 1.0, points)
    out = np.empty((len(starts) - 1, points, flat.shape[1]))
    for k, (a, b) in enumerate(zip(starts[:-1], starts[1:])):
        at = a + phase * (b - a)
        out[k] = np.column_stack([np.interp(at, t, flat[:, j]) for j in range(flat.shape[1])])
    return out.reshape((len(starts) - 1, points) + v.shape[1:])


def cycle_means(profiles: np.ndarray) -> np.ndarray:
    """Time average of each resampled cycle (cycles, points, ...) -> (cycles, ...): the points
    are evenly spaced in time within a cycle, so the trapezoid rule over phase is the mean."""
    phase = np.linspace(0.0, 1.0, profiles.shape[1])
    return np.trapezoid(profiles, phase, axis=1)
