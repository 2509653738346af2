"""What the water is: density, viscosity, surface height and current. How a fluid model turns that
into forces (the thin plates' induced-flow ratios, an SPH particle size) is its backend's business."""
from __future__ import annotations

import math
from dataclasses import dataclass, replace

import numpy as np

from layered_swim.config import ConfigError

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

    def with_(self, **changes) -> "Medium":
        return replace(self, **changes)


def water(fluid: str = "fresh_water", density_kg_m3: float | None = None, current_m_s=(0.0, 0.0, 0.0)) -> Medium:
    """A preset's water, optionally at another density, with a current."""
    medium = preset(fluid).with_(current_m_s=tuple(float(c) for c in current_m_s))
    return medium if density_kg_m3 is None else medium.with_(rho_kg_m3=float(density_kg_m3))


def preset(name: str) -> Medium:
    try:
        rho, eta = PRESETS_KG_M3_PA_S[name]
    except KeyError:
        raise ConfigError(f"unknown fluid preset '{name}' (available: {', '.join(PRESETS_KG_M3_PA_S)})") from None
    return Medium(rho_kg_m3=rho, eta_pa_s=eta)
