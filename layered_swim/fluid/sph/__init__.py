"""The SPH fluid backend (SPlisHSPlasH through the optional ``[sph]`` extra)."""
from layered_swim.fluid.sph.settings import SphSettings

__all__ = ["SphSettings"]
