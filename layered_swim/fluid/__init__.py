"""Fluid models behind one interface (``backend.py``), chosen by name."""
from layered_swim.fluid.backend import BACKENDS, FluidBackend, FluidWrenches, make_fluid, register_backend
from layered_swim.fluid.thin_plate import PlateFluid

register_backend("plate", PlateFluid)

__all__ = ["BACKENDS", "FluidBackend", "FluidWrenches", "PlateFluid", "make_fluid", "register_backend"]
