"""A current in the SPH pool, as a recirculating flume does it (pure numpy, no solver).

The pool is open at both ends of every axis the current crosses (x, y or both). Water that
leaves through one end comes back in through the other, and a buffer of water at each open end,
``buffer_m`` deep, is moved rigidly at the current's velocity: it holds the water in like a wall
would, pushes it through at the current's speed, and the water's own arrangement is kept (no
emitted lattice, whose spacing differs from settled water's). The swimmer's side of the pool is
the box between the buffers.
"""
from __future__ import annotations

import numpy as np

BUFFER_RADII = 6            # each open end's rigidly driven water, in particle radii (>= the kernel's reach, 4)
SETTLE_S = 1.5              # a flowing pool settles at least this long: after 0.5 s its water still surged
                            # along the pool once (0.39-0.57 m/s for 0.5 m/s over the swim's first 2 s)


def open_axes(current_m_s) -> tuple[bool, bool]:
    """Which horizontal axes a current crosses: its pool is open at both ends of those."""
    return bool(current_m_s[0]), bool(current_m_s[1])


def water_box(pool_min_m, pool_max_m, axes: tuple[bool, bool], buffer_m: float) -> tuple[np.ndarray, np.ndarray]:
    """The water's box: the pool's, lengthened by a buffer at each open end (the swimmer's grates
    stay at the pool's faces)."""
    lo, hi = np.array(pool_min_m, dtype=float), np.array(pool_max_m, dtype=float)
    for axis, is_open in enumerate(axes):
        if is_open:
            lo[axis] -= buffer_m
            hi[axis] += buffer_m
    return lo, hi


def wrap(positions: np.ndarray, lo, hi, axes: tuple[bool, bool]) -> None:
    """Move water that left the box through an open end back in through the other (in place)."""
    for axis, is_open in enumerate(axes):
        if is_open:
            length = hi[axis] - lo[axis]
            column = positions[:, axis]
            column[column >= hi[axis]] -= length
            column[column < lo[axis]] += length


def in_buffers(positions: np.ndarray, lo, hi, axes: tuple[bool, bool], buffer_m: float) -> np.ndarray:
    """Which particles lie within ``buffer_m`` of an open end (the rigidly driven water)."""
    mask = np.zeros(len(positions), dtype=bool)
    for axis, is_open in enumerate(axes):
        if is_open:
            column = positions[:, axis]
            mask |= (column < lo[axis] + buffer_m) | (column > hi[axis] - buffer_m)
    return mask
