"""What the water is: density, viscosity, surface height, a uniform current and, optionally, a flow
that varies from place to place (``flow_field.py``). How a fluid model turns that into forces (the
thin plates' induced-flow ratios, an SPH particle size) is its backend's business."""
from __future__ import annotations

import math
from dataclasses import dataclass, replace

import numpy as np

from layered_swim.config import ConfigError
from layered_swim.fluid.flow_field import FlowField

# Data sheet section 5 (25 C values).
PRESETS_KG_M3_PA_S = {
    "fresh_water": (997.05, 0.890e-3),
    "seawater": (1023.3, 0.956e-3),
}


@dataclass(frozen=True)
class Medium:
    rho_kg_m3: float = PRESETS_KG_M3_PA_S["fresh_water"][0]
    eta_pa_s: float = PRESETS_KG_M3_PA_S["fresh_water"][1]
    surface_z_m: float = 0.0
    current_m_s: tuple[float, float, float] = (0.0, 0.0, 0.0)
    flow: FlowField | None = None     # added to the current

    def __post_init__(self):
        checks = {
            "density": (self.rho_kg_m3, 1.0, 20000.0),
            "viscosity": (self.eta_pa_s, 0.0, 100.0),
        }
        for name, (value, lo, hi) in checks.items():
            if not (math.isfinite(value) and lo <= value <= hi):
                raise ConfigError(f"{name} must be a number in [{lo}, {hi}], got {value}")
        if len(self.current_m_s) != 3 or not all(math.isfinite(c) and abs(c) <= 5 for c in self.current_m_s):
            raise ConfigError(f"current must be three finite numbers of at most 5 m/s, got {self.current_m_s}")

    @property
    def current(self) -> np.ndarray:
        return np.asarray(self.current_m_s, dtype=float)

    def current_at(self, points_m: np.ndarray, time_s: float, waves: bool = True) -> np.ndarray:
        """(n, 3) water velocity at (n, 3) points: the current plus the flow field's (without
        ``waves``, its steady part)."""
        points = np.atleast_2d(np.asarray(points_m, float))
        uniform = np.tile(self.current, (len(points), 1))
        return uniform if self.flow is None else uniform + self.flow.velocity_m_s(points, time_s, waves)

    def to_json(self) -> dict:
        """The water as a run's resolved config records it (the flow field as its file's content)."""
        return {**{name: getattr(self, name) for name in ("rho_kg_m3", "eta_pa_s", "surface_z_m", "current_m_s")},
                "flow": None if self.flow is None else self.flow.to_json()}

    def with_(self, **changes) -> "Medium":
        return replace(self, **changes)


def water(fluid: str = "fresh_water", density_kg_m3: float | None = None, current_m_s=(0.0, 0.0, 0.0),
          flow: FlowField | None = None) -> Medium:
    """A preset's water, optionally at another density, with a current and a flow field."""
    medium = preset(fluid).with_(current_m_s=tuple(float(c) for c in current_m_s), flow=flow)
    return medium if density_kg_m3 is None else medium.with_(rho_kg_m3=float(density_kg_m3))


def preset(name: str) -> Medium:
    try:
        rho, eta = PRESETS_KG_M3_PA_S[name]
    except KeyError:
        raise ConfigError(f"unknown fluid preset '{name}' (available: {', '.join(PRESETS_KG_M3_PA_S)})") from None
    return Medium(rho_kg_m3=rho, eta_pa_s=eta)
