"""Water that moves differently from place to place: a flow built from primitives (Yang et al. 2004,
section 3.3), read from a ``water`` file (``waters/`` in a checkout).

The primitives are the plane potential flows (uniform, source, sink, vortex), the same at every
depth, and a travelling surface wave (linear deep-water theory) whose orbital velocity decays with
depth. Their velocities add. A source's, sink's or vortex's speed grows without bound at its
centre; within about ``core_radius_m`` it falls smoothly to zero instead (the Lamb-Oseen profile:
``1 - exp(-r^2 / r_c^2)`` times the potential flow's speed). Formulas: ``layered_swim/reference.md``
section "Flow primitives". The wave moves the water only: the surface the buoyancy sees stays flat.

World frame: z up, the surface at z = 0; angles in files are degrees counterclockwise from +x.
"""
from __future__ import annotations

import math
from pathlib import Path
from typing import Annotated, Any, Literal, Union

import numpy as np
from pydantic import Field

from layered_swim.config import (
    SHIPPED_DIR,
    ConfigError,
    Point2,
    Strict,
    available_files,
    between,
    file_path,
    load_yaml,
    parse,
    search_dirs,
)

WATER_DIR = SHIPPED_DIR / "waters"      # the top-level waters/ in a checkout
GRAVITY_M_S2 = 9.81
MAX_STEEPNESS = 0.3      # wave amplitude x wavenumber: linear theory holds well below breaking (~0.44)


class Vector3(Strict):
    x: between(-5.0, 5.0) = 0.0
    y: between(-5.0, 5.0) = 0.0
    z: between(-5.0, 5.0) = 0.0


class UniformSpec(Strict):
    type: Literal["uniform"]
    velocity_m_s: Vector3


class _Point(Strict):
    center_m: Point2
    core_radius_m: between(0.0, 100.0, above=True) = 0.5


class SourceSpec(_Point):
    """Water welling up at ``center_m`` and flowing out evenly: ``strength_m2_s`` square metres a
    second per metre of depth (the speed at r metres is strength / (2 pi r))."""
    type: Literal["source", "sink"]
    strength_m2_s: between(0.0, 100.0, above=True)


class VortexSpec(_Point):
    """Water circling ``center_m``, counterclockwise seen from above for a positive
    ``circulation_m2_s`` (the speed at r metres is circulation / (2 pi r))."""
    type: Literal["vortex"]
    circulation_m2_s: between(-100.0, 100.0)


class WaveSpec(Strict):
    """A deep-water wave travelling toward ``heading_deg``: surface amplitude ``amplitude_m``,
    crest to crest ``wavelength_m``; its period follows (sqrt(2 pi wavelength / g))."""
    type: Literal["wave"]
    amplitude_m: between(0.0, 5.0, above=True)
    wavelength_m: between(0.1, 500.0)
    heading_deg: between(-3600.0, 3600.0) = 0.0
    phase_deg: between(-3600.0, 3600.0) = 0.0


FlowSpec = Annotated[Union[UniformSpec, SourceSpec, VortexSpec, WaveSpec], Field(discriminator="type")]


class WaterSpec(Strict):
    """A ``water`` file: a name, what it is, and the flows that add up to its water's motion."""
    name: str
    description: str = ""
    flows: list[FlowSpec] = Field(min_length=1)


class FlowField:
    """The water's velocity anywhere and at any time from a ``WaterSpec``."""

    def __init__(self, spec: WaterSpec, source: str = ""):
        for i, flow in enumerate(spec.flows):
            if isinstance(flow, WaveSpec) and flow.amplitude_m * 2 * math.pi / flow.wavelength_m > MAX_STEEPNESS:
                raise ConfigError(f"{source or spec.name}: field 'flows.{i}.amplitude_m': a wave this steep "
                                  f"(amplitude x 2 pi / wavelength above {MAX_STEEPNESS}) is beyond linear "
                                  "wave theory")
        self.spec, self.source = spec, source
        self.name = spec.name

    def velocity_m_s(self, points_m: np.ndarray, time_s: float, waves: bool = True) -> np.ndarray:
        """(n, 3) water velocity at (n, 3) world points at ``time_s``; without ``waves``, the steady
        flow only (a wave's water circles: over a period it goes nowhere)."""
        points = np.atleast_2d(np.asarray(points_m, float))
        velocity = np.zeros_like(points)
        for flow in self.spec.flows:
            if isinstance(flow, UniformSpec):
                velocity += (flow.velocity_m_s.x, flow.velocity_m_s.y, flow.velocity_m_s.z)
            elif isinstance(flow, WaveSpec):
                if waves:
                    velocity += _wave(flow, points, time_s)
            else:
                velocity[:, :2] += _point_flow(flow, points)
        return velocity

    def to_json(self) -> dict:
        return self.spec.model_dump(mode="json")


def _point_flow(flow: SourceSpec | VortexSpec, points: np.ndarray) -> np.ndarray:
    offset = points[:, :2] - (flow.center_m.x, flow.center_m.y)
    r2 = np.maximum((offset ** 2).sum(axis=1), 1e-300)
    # Speed k / r outside the core, fading to zero at the centre: the velocity is k (1 - e^(-r^2/rc^2)) / r^2
    # times the offset (radial) or its perpendicular (circling).
    scale = (1.0 - np.exp(-r2 / flow.core_radius_m ** 2)) / r2
    if isinstance(flow, VortexSpec):
        return (flow.circulation_m2_s / (2 * math.pi)) * scale[:, None] * np.column_stack([-offset[:, 1], offset[:, 0]])
    sign = 1.0 if flow.type == "source" else -1.0
    return (sign * flow.strength_m2_s / (2 * math.pi)) * scale[:, None] * offset


def _wave(flow: WaveSpec, points: np.ndarray, time_s: float) -> np.ndarray:
    k = 2 * math.pi / flow.wavelength_m
    omega = math.sqrt(GRAVITY_M_S2 * k)
    heading = math.radians(flow.heading_deg)
    direction = np.array([math.cos(heading), math.sin(heading)])
    phase = k * (points[:, :2] @ direction) - omega * time_s + math.radians(flow.phase_deg)
    # Orbital speed a omega at the surface, e^(k z) of it at depth -z; above the surface as at it.
    speed = flow.amplitude_m * omega * np.exp(k * np.minimum(points[:, 2], 0.0))
    horizontal = speed * np.cos(phase)
    return np.column_stack([horizontal * direction[0], horizontal * direction[1], speed * np.sin(phase)])


def available_waters(directory: Path | None = None) -> list[str]:
    return available_files(directory or search_dirs("waters"))


def parse_water(data: Any, source: str | Path) -> WaterSpec:
    return parse(WaterSpec, data, source)


def load_water(name_or_path: str | Path, directory: Path | None = None) -> FlowField:
    """A water file by bare name (``river_bend``) or by path to a YAML file."""
    path = file_path(name_or_path, directory or search_dirs("waters"), "water")
    return FlowField(parse_water(load_yaml(path), path), str(path))
