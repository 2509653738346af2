"""Cycle segmentation and per-cycle resampling on synthetic signals."""
import numpy as np
import pytest

from layered_swim.analysis.cycles import cycle_means, cycle_starts, resample_cycles

HZ = 120


def chirp(periods_s, noise=0.0, seed=0):
    """A marker with one sine period per entry of ``periods_s`` (each cycle its own length), a
    small second bump late in each cycle that stays above the midline, and optional noise.
    Returns time, signal and the true times at which it rises through its mean (the first
    cycle's crossing at t = 0 does not count: the signal has not been below the midline yet)."""
    periods = np.asarray(periods_s, dtype=float)
    edges = np.concatenate([[0.0], np.cumsum(periods)])
    t = np.arange(0.0, edges[-1], 1.0 / HZ)
    k = np.clip(np.searchsorted(edges, t, side="right") - 1, 0, len(periods) - 1)
    phase = (t - edges[k]) / periods[k]
    signal = np.sin(2 * np.pi * phase) + 0.3 * np.maximum(0.0, np.sin(6 * np.pi * phase)) * (phase > 0.6)
    mean = signal.mean()
    signal += noise * np.random.default_rng(seed).normal(size=len(t))
    return t, signal, edges[1:-1] + np.arcsin(mean) / (2 * np.pi) * periods[1:]


def test_starts_at_the_rising_crossings():
    t, x, truth = chirp([1.0, 1.1, 0.9, 1.05, 1.0, 0.95])
    np.testing.assert_allclose(cycle_starts(t, x, period_hint_s=1.0), truth, atol=1e-3)


def test_noise_and_bumps_do_not_split_cycles():
    t, x, truth = chirp([1.0] * 10, noise=0.08)
    starts = cycle_starts(t, x, period_hint_s=1.0)
    starts = starts[starts > 0.5]     # noise may dip the signal before t = 0's rise: that one is real
    assert len(starts) == len(truth)
    np.testing.assert_allclose(starts, truth, atol=0.05)   # noise 0.08 over a slope of 2 pi per s


def test_no_cycles_in_a_flat_signal():
    t = np.arange(0.0, 5.0, 1.0 / HZ)
    assert len(cycle_starts(t, np.zeros_like(t), 1.0)) == 0


def test_resample_and_mean():
    t = np.arange(0.0, 4.0, 1.0 / HZ)
    starts = np.array([0.5, 1.5, 2.75])
    values = np.column_stack([3.0 * t, np.sin(2 * np.pi * (t - 0.5))])   # a ramp, a sine locked to cycle 1
    profiles = resample_cycles(t, values, starts, points=11)
    assert profiles.shape == (2, 11, 2)
    np.testing.assert_allclose(profiles[0, :, 0], 3.0 * np.linspace(0.5, 1.5, 11), atol=1e-9)
    np.testing.assert_allclose(profiles[1, [0, -1], 0], [4.5, 8.25])
    means = cycle_means(resample_cycles(t, values, starts, points=401))
    assert means[0, 0] == pytest.approx(3.0)              # ramp from 1.5 to 4.5
    assert means[0, 1] == pytest.approx(0.0, abs=1e-4)    # one whole sine period
