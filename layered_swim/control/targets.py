"""Targets for the swimmer to follow (Yang et al. 2004, section 5): a 3-D point that may move.

A target is fixed, set by the app's mouse (``MovableTarget``), or read from a trajectory file in
``trajectories/``. Trajectory files describe a horizontal parametric curve (figure eight,
circle, sinusoid, line) travelled at a constant speed at a constant depth, a polyline of timed
3-D waypoints, or stations: fixed points the target jumps between at given times (a mouse click,
a buoy moved). Curves and polylines are turned once into a table of points against a parameter
(arc length in metres for curves, time in seconds for polylines), so ``position()`` is a binary
search and a linear blend.

``foresight``: whether a swimmer may look ahead along the target's path. A trajectory's future is
known (the per-cycle layer aims where it will be); a fixed, mouse-moved or jumping target's is not.

World frame: z up, water surface at z = 0, a depth d is z = -d; the swimmer starts at the origin
heading +x. Angles in files are degrees measured counterclockwise from +x (seen from above).
"""
from __future__ import annotations

from pathlib import Path
from typing import Any, Literal, Protocol, runtime_checkable

import numpy as np
from pydantic import Field

from layered_swim.config import (
    SHIPPED_DIR,
    ConfigError,
    Coordinate_m,
    Point2,
    Strict,
    available_files,
    between,
    file_path,
    load_yaml,
    parse,
    search_dirs,
)

TRAJECTORIES_DIR = SHIPPED_DIR / "trajectories"     # the top-level trajectories/ in a checkout
CURVE_SAMPLES = 4096          # samples per closed curve (figure eight, circle)
MAX_SAMPLES = 200_000


@runtime_checkable
class Target(Protocol):
    def position(self, time_s: float) -> np.ndarray:
        """World position (3,) in metres at ``time_s`` seconds after the start."""
        ...

    def path_points(self, n: int = 400) -> np.ndarray:
        """(n, 3) points along the whole path, for drawing; (1, 3) for a point target."""
        ...


def _point(point: Any) -> np.ndarray:
    p = np.array(point, dtype=float).reshape(-1)
    if p.shape != (3,) or not np.all(np.isfinite(p)):
        raise ValueError(f"a target point must be 3 finite numbers, got {point!r}")
    return p


class FixedTarget:
    foresight = False

    def __init__(self, point: Any):
        self._point = _point(point)

    def position(self, time_s: float) -> np.ndarray:
        return self._point.copy()

    def path_points(self, n: int = 400) -> np.ndarray:
        return self._point[None, :].copy()


class MovableTarget(FixedTarget):
    """A point the app moves (with the mouse); ``position`` returns the last point set."""

    def set(self, point: Any) -> None:
        self._point = _point(point)


class TrajectoryTarget:
    """A point moving along a table ``points`` (N, 3) sampled at increasing parameter ``u`` (N,).

    The parameter advances at ``rate`` per second (the speed in m/s for curves, where ``u`` is
    arc length; 1 for polylines, where ``u`` is time), starting ``start_s`` seconds along. With
    ``loop`` it wraps from the end of the table to its start, otherwise it stops at the end.
    """

    foresight = True

    def __init__(self, points: np.ndarray, u: np.ndarray, rate: float, loop: bool, start_s: float = 0.0,
                 name: str = "", description: str = "", kind: str = "", spec: Strict | None = None,
                 source: str = ""):
        keep = np.concatenate([[True], np.diff(u) > 0])        # drop zero-length steps
        self._points, self._u = np.asarray(points, float)[keep], np.asarray(u, float)[keep]
        if len(self._u) < 2:
            raise ValueError("a trajectory needs at least two distinct samples")
        self._steps = np.diff(self._points, axis=0)
        self._du = np.diff(self._u)
        self._rate, self._period = float(rate), float(self._u[-1])
        self.loop, self.start_s = loop, float(start_s)
        self.name, self.description, self.kind, self.spec, self.source = name, description, kind, spec, source

    @property
    def duration_s(self) -> float:
        """Seconds for one pass along the whole path (one lap when looping)."""
        return self._period / self._rate

    def position(self, time_s: float) -> np.ndarray:
        u = self._rate * (time_s + self.start_s)
        u = u % self._period if self.loop else min(max(u, 0.0), self._period)
        i = min(max(int(np.searchsorted(self._u, u, side="right")) - 1, 0), len(self._du) - 1)
        return self._points[i] + ((u - self._u[i]) / self._du[i]) * self._steps[i]

    def path_points(self, n: int = 400) -> np.ndarray:
        u = np.linspace(0.0, self._period, max(int(n), 2))
        return np.stack([np.interp(u, self._u, self._points[:, k]) for k in range(3)], axis=1)


class StationTarget:
    """A point that stays at ``points[i]`` from ``times_s[i]`` until the next time, then jumps."""

    foresight = False

    def __init__(self, points: np.ndarray, times_s: np.ndarray, name: str = "", description: str = "",
                 spec: Strict | None = None, source: str = ""):
        self._points, self._times_s = np.asarray(points, float), np.asarray(times_s, float)
        self.name, self.description, self.kind, self.spec, self.source = name, description, "stations", spec, source

    @property
    def stations(self) -> list[tuple[float, np.ndarray]]:
        """(time it jumps there, point) for every station, in order."""
        return [(float(t), p.copy()) for t, p in zip(self._times_s, self._points)]

    def position(self, time_s: float) -> np.ndarray:
        i = max(int(np.searchsorted(self._times_s, time_s, side="right")) - 1, 0)
        return self._points[i].copy()

    def path_points(self, n: int = 400) -> np.ndarray:
        return self._points.copy()


def _moved_m(target: Target, time_s: float, over_s: float) -> np.ndarray:
    """How far the target moves over the next ``over_s`` where its path is known ahead, over the
    last ``over_s`` where it is not (a mouse, a jump)."""
    if getattr(target, "foresight", True):
        return target.position(time_s + over_s) - target.position(time_s)
    return target.position(time_s) - target.position(max(0.0, time_s - over_s))


def target_velocity_m_s(target: Target, time_s: float, over_s: float = 1.0) -> np.ndarray:
    """How the target moves now (see ``_moved_m``)."""
    return _moved_m(target, time_s, over_s) / over_s


def target_speed_m_s(target: Target, time_s: float, over_s: float = 1.0) -> float:
    """How fast the target moves now (see ``_moved_m``)."""
    return float(np.linalg.norm(_moved_m(target, time_s, over_s))) / over_s


# ---------------------------------------------------------------- file schemas

Length_m = between(0.0, 1e4, above=True)
Time_s = between(0.0, 1e5)            # a day at most
Heading_deg = between(-3600.0, 3600.0)


class Size2(Strict):
    x: Length_m            # total width along x, m
    y: Length_m            # total height along y, m


class Waypoint(Strict):
    t_s: Time_s
    x: Coordinate_m
    y: Coordinate_m
    z: between(-100.0, 10.0)   # height above the surface: a depth d is z = -d (deepest 100 m)


class _Common(Strict):
    name: str
    description: str = ""
    loop: bool = False
    start_s: Time_s = 0.0               # seconds along the path at time 0


class _Curve(_Common):
    speed_m_s: between(0.0, 5.0, above=True)   # twice the fastest human swimmer
    depth_m: between(0.0, 100.0)        # the whole curve lies at z = -depth_m


class FigureEightSpec(_Curve):
    """Lemniscate of Gerono: x = cx + w/2 sin p, y = cy + h/2 sin 2p. It starts at the crossing
    (the centre) heading into the +x lobe towards +y."""
    type: Literal["figure_eight"]
    size_m: Size2
    center_m: Point2


class CircleSpec(_Curve):
    type: Literal["circle"]
    radius_m: Length_m
    center_m: Point2
    counterclockwise: bool = True
    start_angle_deg: Heading_deg = -90.0      # where on the circle it starts, seen from the centre


class SinusoidSpec(_Curve):
    type: Literal["sinusoid"]
    start_m: Point2
    heading_deg: Heading_deg
    length_m: Length_m                  # along the heading
    amplitude_m: between(0.0, 1e4)      # to the left of the heading first
    wavelength_m: Length_m


class LineSpec(_Curve):
    type: Literal["line"]
    start_m: Point2
    heading_deg: Heading_deg
    length_m: Length_m


class PolylineSpec(_Common):
    """Timed 3-D waypoints, linear in time between them; the first is at t_s = 0. With ``loop``
    the target returns from the last waypoint to the first over ``closing_s`` seconds."""
    type: Literal["polyline"]
    waypoints: list[Waypoint] = Field(min_length=2)
    closing_s: between(0.0, 1e5, above=True) | None = None


class StationsSpec(Strict):
    """Fixed points the target jumps to at ``t_s`` (the first at 0) and holds until the next."""
    type: Literal["stations"]
    name: str
    description: str = ""
    stations: list[Waypoint] = Field(min_length=1)


SPECS: dict[str, type[Strict]] = {
    "figure_eight": FigureEightSpec, "circle": CircleSpec, "sinusoid": SinusoidSpec,
    "line": LineSpec, "polyline": PolylineSpec, "stations": StationsSpec,
}


# ---------------------------------------------------------------- building

def _direction(heading_deg: float) -> tuple[np.ndarray, np.ndarray]:
    a = np.radians(heading_deg)
    return np.array([np.cos(a), np.sin(a)]), np.array([-np.sin(a), np.cos(a)])


def _curve_xy(spec: _Curve) -> np.ndarray:
    """Dense (N, 2) horizontal samples of a parametric curve, in travel order."""
    if isinstance(spec, FigureEightSpec):
        p = np.linspace(0.0, 2 * np.pi, CURVE_SAMPLES + 1)
        return np.stack([spec.center_m.x + spec.size_m.x / 2 * np.sin(p),
                         spec.center_m.y + spec.size_m.y / 2 * np.sin(2 * p)], axis=1)
    if isinstance(spec, CircleSpec):
        sign = 1.0 if spec.counterclockwise else -1.0
        a = np.radians(spec.start_angle_deg) + sign * np.linspace(0.0, 2 * np.pi, CURVE_SAMPLES + 1)
        return np.stack([spec.center_m.x + spec.radius_m * np.cos(a),
                         spec.center_m.y + spec.radius_m * np.sin(a)], axis=1)
    start = np.array([spec.start_m.x, spec.start_m.y])
    forward, left = _direction(spec.heading_deg)
    if isinstance(spec, LineSpec):
        return start + np.outer([0.0, spec.length_m], forward)
    n = int(np.clip(512 * spec.length_m / spec.wavelength_m, 1024, MAX_SAMPLES))
    s = np.linspace(0.0, spec.length_m, n + 1)
    lateral = spec.amplitude_m * np.sin(2 * np.pi * s / spec.wavelength_m)
    return start + np.outer(s, forward) + np.outer(lateral, left)


def _check_timed_points(points: list[Waypoint], field: str, source: str) -> None:
    times = [w.t_s for w in points]
    if times[0] != 0.0:
        raise ConfigError(f"{source}: field '{field}.0.t_s': the first one must be at t_s 0")
    for i in range(1, len(times)):
        if times[i] <= times[i - 1]:
            raise ConfigError(f"{source}: field '{field}.{i}.t_s': times must increase "
                              f"({times[i]:g} after {times[i - 1]:g})")
    for i, w in enumerate(points):
        if w.z > 0.0:
            raise ConfigError(f"{source}: field '{field}.{i}.z': z is height above the surface "
                              f"(z = -depth) and must be <= 0, got {w.z:g}")


def _check_polyline(spec: PolylineSpec, source: str) -> None:
    _check_timed_points(spec.waypoints, "waypoints", source)
    if spec.loop and spec.closing_s is None:
        raise ConfigError(f"{source}: field 'closing_s': required when loop is true "
                          "(seconds from the last waypoint back to the first)")
    if not spec.loop and spec.closing_s is not None:
        raise ConfigError(f"{source}: field 'closing_s': only used when loop is true")


def build_trajectory(spec: Strict, source: str = "") -> TrajectoryTarget | StationTarget:
    if isinstance(spec, StationsSpec):
        _check_timed_points(spec.stations, "stations", source)
        return StationTarget(np.array([[w.x, w.y, w.z] for w in spec.stations]),
                             np.array([w.t_s for w in spec.stations]), spec.name, spec.description, spec, source)
    common = dict(loop=spec.loop, start_s=spec.start_s, name=spec.name, description=spec.description,
                  kind=spec.type, spec=spec, source=source)
    if isinstance(spec, PolylineSpec):
        _check_polyline(spec, source)
        points = np.array([[w.x, w.y, w.z] for w in spec.waypoints])
        times = np.array([w.t_s for w in spec.waypoints])
        if spec.loop:
            points = np.vstack([points, points[:1]])
            times = np.append(times, times[-1] + spec.closing_s)
        return TrajectoryTarget(points, times, 1.0, **common)
    xy = _curve_xy(spec)
    points = np.column_stack([xy, np.full(len(xy), -spec.depth_m)])
    arc = np.concatenate([[0.0], np.cumsum(np.linalg.norm(np.diff(points, axis=0), axis=1))])
    return TrajectoryTarget(points, arc, spec.speed_m_s, **common)


def parse_trajectory(data: Any, source: str | Path) -> Strict:
    """Validate a trajectory file's content; the ``type`` field picks the schema."""
    known = ", ".join(sorted(SPECS))
    if not isinstance(data, dict):
        raise ConfigError(f"{source}: expected a mapping at the top level, got {type(data).__name__}")
    if "type" not in data:
        raise ConfigError(f"{source}: field 'type': missing (known: {known})")
    kind = data["type"]
    if not isinstance(kind, str) or kind not in SPECS:
        raise ConfigError(f"{source}: field 'type': unknown trajectory type {kind!r} (known: {known})")
    return parse(SPECS[kind], data, source)


def available_trajectories(directory: Path | None = None) -> list[str]:
    return available_files(directory or search_dirs("trajectories"))


def trajectory_path(name_or_path: str | Path, directory: Path | None = None) -> Path:
    return file_path(name_or_path, directory or search_dirs("trajectories"), "trajectory")


def load_trajectory(name_or_path: str | Path, directory: Path | None = None) -> TrajectoryTarget | StationTarget:
    """A trajectory by bare name (``figure_eight``) or by path to a YAML file."""
    path = trajectory_path(name_or_path, directory)
    return build_trajectory(parse_trajectory(load_yaml(path), path), str(path))
