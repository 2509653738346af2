"""Fluid models behind one interface (``backend.py``), chosen by name."""
from importlib.util import find_spec

from layered_swim.config import ConfigError
from layered_swim.fluid.backend import BACKENDS, FluidBackend, FluidError, FluidWrenches, make_fluid, register_backend
from layered_swim.fluid.thin_plate import PlateFluid

SPH_INSTALL = "pip install -e '.[sph]'"


def _sph(body, medium, gravity_m_s2, settings=None):
    """SPlisHSPlasH, imported only when asked for (an optional extra)."""
    if find_spec("pysplishsplash") is None:
        raise ConfigError(f"--backend sph needs the SPH extra: {SPH_INSTALL}")
    from layered_swim.fluid.sph.backend import SphBackend
    return SphBackend(body, medium, gravity_m_s2, settings)


register_backend("plate", PlateFluid)
register_backend("sph", _sph)

__all__ = ["BACKENDS", "FluidBackend", "FluidError", "FluidWrenches", "PlateFluid", "make_fluid", "register_backend"]
