"""The SPH backend's own knobs, checked on construction (one line naming the field on error)."""
from __future__ import annotations

import math
import os
from dataclasses import dataclass

from layered_swim.config import ConfigError

PHYSICS_STEP_S = 1.0 / 480      # the simulation's default step; the SPH steps once per physics step
MIN_SETTLE_S = 0.2              # shorter, the water started on a grid around the body's void blows up
MAX_PARTICLES = 2_000_000       # beyond this a 2-core machine takes hours per simulated second


@dataclass(frozen=True)
class SphSettings:
    """``pool_size_m``: length (x), width (y) and water depth; SWIM's small pool by default (the
    commands' ``--pool`` picks its large one, 5 x 2 x 0.7 m). The pool is axis-aligned, centred
    across the swimmer's start, its back wall ``wall_gap_m`` behind the rearmost point of the body.
    Viscosity None: the medium's (real water's 1e-6 m^2/s kinematic by default).
    ``mesh_shrink_radii``: the boundary boxes are shrunk by this many particle radii per side, the
    correction for SPH's fluid-free skin (validate sph)."""

    pool_size_m: tuple[float, float, float] = (3.0, 1.5, 0.5)
    wall_gap_m: float = 0.15
    particle_radius_m: float = 0.025
    time_step_s: float = PHYSICS_STEP_S
    viscosity_m2_s: float | None = None
    mesh_shrink_radii: float = 1.0
    settle_s: float = 0.5
    threads: int | None = None       # None: every core
    deterministic: bool = False      # one thread: bit-identical runs

    def __post_init__(self):
        if len(self.pool_size_m) != 3:
            raise ConfigError(f"SPH pool_size_m must be (length, width, depth), got {self.pool_size_m!r}")
        for name, value in zip(("pool length", "pool width", "water depth"), self.pool_size_m):
            _check(name, value, 0.1, 100.0)
        _check("particle_radius_m", self.particle_radius_m, 0.002, 0.2)
        _check("time_step_s", self.time_step_s, 1e-5, 0.01)
        _check("wall_gap_m", self.wall_gap_m, 0.0, 5.0)
        _check("mesh_shrink_radii", self.mesh_shrink_radii, 0.0, 3.0)
        _check("settle_s", self.settle_s, MIN_SETTLE_S, 10.0)
        if self.viscosity_m2_s is not None:
            _check("viscosity_m2_s", self.viscosity_m2_s, 0.0, 1.0)
        if self.threads is not None and not (isinstance(self.threads, int) and 1 <= self.threads <= 256):
            raise ConfigError(f"SPH threads must be an integer in 1..256, got {self.threads!r}")
        length, width, depth = self.pool_size_m
        particles = length * width * depth / (2 * self.particle_radius_m) ** 3
        if particles > MAX_PARTICLES:
            raise ConfigError(f"a {length:g} x {width:g} x {depth:g} m pool at particle radius "
                              f"{self.particle_radius_m:g} m is ~{particles:.3g} particles (at most {MAX_PARTICLES:g})")

    @property
    def solver_threads(self) -> int:
        return 1 if self.deterministic else (self.threads or os.cpu_count() or 1)


def _check(name: str, value, lo: float, hi: float) -> None:
    if not (isinstance(value, (int, float)) and math.isfinite(value) and lo <= value <= hi):
        raise ConfigError(f"SPH {name} must be a number in [{lo:g}, {hi:g}], got {value!r}")
