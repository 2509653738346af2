"""One interface for every fluid model, and the registry that picks one by name.

A backend turns the body's state (time included) into one force and one torque per segment, and
says what the controller and the log read: the water velocity at each segment (the rules read it
at the hands) and, where the model can separate it, the buoyancy part of the force. The
simulation calls ``wrenches`` once per physics step and never looks inside.

A new fluid is one module with a ``FluidBackend`` subclass plus one ``register_backend`` call
(``plate`` is registered in ``layered_swim/fluid/__init__.py``).
"""
from __future__ import annotations

from typing import Callable, NamedTuple

import numpy as np

from layered_swim.body.model import Body
from layered_swim.config import ConfigError
from layered_swim.fluid.medium import Medium
from layered_swim.state import BodyState


class FluidError(RuntimeError):
    """The fluid model failed (a solver process died, the water blew up, the swimmer left it)."""


class FluidWrenches(NamedTuple):
    """What the water does to the body in one step, per segment, world frame."""

    force_n: np.ndarray                   # (n, 3) at each segment's centre of mass, buoyancy included
    torque_nm: np.ndarray                 # (n, 3) about each segment's centre of mass
    flow_m_s: np.ndarray                  # (n, 3) water velocity at each segment
    buoyancy_force_n: np.ndarray | None   # (n, 3) the buoyancy part of force_n; None where inseparable


class FluidBackend:
    """A fluid model for one body. Subclasses implement ``wrenches``; the rest have defaults."""

    name = "fluid"

    def __init__(self, body: Body, medium: Medium, gravity_m_s2: float):
        self.body = body
        self.medium = medium
        self.gravity_m_s2 = gravity_m_s2

    def wrenches(self, state: BodyState) -> FluidWrenches:
        raise NotImplementedError

    def set_medium(self, medium: Medium) -> None:
        """The water changes mid-swim (the app's density and current keys)."""
        self.medium = medium

    # Whether ``breathe`` changes what the water does: the SPH pool's boxes displace what their
    # geometry does, whatever the lungs hold.
    breathes = True

    def breathe(self, air_l: float) -> None:
        """The swimmer now holds ``air_l`` of air (above the residual volume): its buoyancy changes."""
        self.body = self.body.breathing(air_l)

    def settings(self) -> dict:
        """The model's own settings, JSON-able, for the run's resolved config."""
        return {}

    def report(self) -> dict:
        """What the model says about the swim so far, JSON-able, for the run's summary."""
        return {}

    def domain_xy_m(self, state: BodyState) -> tuple[np.ndarray, np.ndarray] | None:
        """The horizontal extent (lower and upper corner) of the water for a swim starting at
        ``state``; None where the water has no walls (the plates)."""
        return None

    def container(self, state: BodyState) -> tuple[np.ndarray, np.ndarray, float] | None:
        """Walls the body touches for a swim starting at ``state``: the box's lower and upper corner,
        and how far the start must rise for its lowest point to clear the floor; None in open water."""
        return None

    def particles(self) -> tuple[np.ndarray, np.ndarray] | None:
        """Water to draw: particle positions (k, 3) and speeds (k,); None where the model has none."""
        return None

    def reset(self) -> None:
        """Forget any state of the water before a new episode (the plates keep none but the added
        mass's last step)."""

    def close(self) -> None:
        """Release what the backend holds (processes, files)."""


BackendFactory = Callable[..., FluidBackend]
BACKENDS: dict[str, BackendFactory] = {}


def register_backend(name: str, factory: BackendFactory) -> None:
    """Make ``factory(body, medium, gravity_m_s2[, settings])`` available as ``--backend name``
    (``settings``: the backend's own settings object, passed only when the caller gives one)."""
    BACKENDS[name] = factory


def make_fluid(name: str, body: Body, medium: Medium, gravity_m_s2: float, settings=None) -> FluidBackend:
    try:
        factory = BACKENDS[name]
    except KeyError:
        raise ConfigError(f"unknown fluid backend {name!r} (available: {', '.join(sorted(BACKENDS))})") from None
    return factory(body, medium, gravity_m_s2) if settings is None else factory(body, medium, gravity_m_s2, settings)
