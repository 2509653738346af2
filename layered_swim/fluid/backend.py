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

    def settings(self) -> dict:
        """The model's own settings, JSON-able, for the run's resolved config."""
        return {}

    def reset(self) -> None:
        """Forget any state of the water before a new episode (the plates keep none)."""

    def close(self) -> None:
        """Release what the backend holds (processes, files)."""


BackendFactory = Callable[[Body, Medium, float], FluidBackend]
BACKENDS: dict[str, BackendFactory] = {}


def register_backend(name: str, factory: BackendFactory) -> None:
    """Make ``factory(body, medium, gravity_m_s2)`` available as ``--backend name``."""
    BACKENDS[name] = factory


def make_fluid(name: str, body: Body, medium: Medium, gravity_m_s2: float) -> FluidBackend:
    try:
        factory = BACKENDS[name]
    except KeyError:
        raise ConfigError(f"unknown fluid backend {name!r} (available: {', '.join(sorted(BACKENDS))})") from None
    return factory(body, medium, gravity_m_s2)
