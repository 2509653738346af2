"""Episode observers that measure what the recorder does not: a towed buoy (the velocity
perturbation method's known extra drag) and the joints' positive work. Each keeps a running total,
sampled at the log rate on the recorder's rows (after physics step k * physics_hz / log_hz), so a
mean over any window of cycles is its change over the window (``active_drag.window_rate``).

The buoy pulls through the simulation's push hook (``Simulation.push``, as the experiments'
pushes do): a force from outside the water, so the logged fluid force never holds it."""
from __future__ import annotations

import numpy as np

from layered_swim.config import ConfigError


class _Sampled:
    """A running total, sampled every ``physics_hz / log_hz`` physics steps."""

    def __init__(self, physics_hz: int, log_hz: int):
        if log_hz <= 0 or physics_hz % log_hz:
            raise ConfigError(f"log rate {log_hz} Hz must divide the physics rate {physics_hz} Hz")
        self.dt_s = 1.0 / physics_hz
        self._every, self._physics_hz = physics_hz // log_hz, physics_hz
        self._time_s: list[float] = []
        self._totals: dict[str, list[float]] = {}

    def _sample(self, steps: int, **totals: float) -> None:
        if steps % self._every == 0:
            self._time_s.append(steps / self._physics_hz)
            for name, value in totals.items():
                self._totals.setdefault(name, []).append(value)

    def arrays(self) -> dict[str, np.ndarray]:
        return {"time_s": np.array(self._time_s), **{k: np.array(v) for k, v in self._totals.items()}}


class TowedBuoy(_Sampled):
    """A buoy of drag ``drag_kg_m`` v^2 towed on a line from the pelvis: each physics step it pulls
    the pelvis back against the centre of mass's horizontal velocity v, with |F| = k |v|^2. Keeps
    ``impulse_ns``, the running integral of |F| (its mean force over a window is the buoy's F_b)."""

    def __init__(self, drag_kg_m: float, physics_hz: int, log_hz: int):
        if not (np.isfinite(drag_kg_m) and drag_kg_m > 0.0):
            raise ConfigError(f"the towed buoy's drag must be a positive number of kg/m, got {drag_kg_m}")
        super().__init__(physics_hz, log_hz)
        self.drag_kg_m = float(drag_kg_m)
        self._pull_n = 0.0           # the pull set at the last call, applied during the step just taken
        self._impulse_ns = 0.0

    def __call__(self, sim) -> None:
        self._impulse_ns += self._pull_n * self.dt_s
        velocity = np.array(sim.state.com_vel_m_s, dtype=float)
        velocity[2] = 0.0
        speed = float(np.linalg.norm(velocity))
        self._pull_n = self.drag_kg_m * speed**2
        sim.push(-self.drag_kg_m * speed * velocity, "pelvis")
        self._sample(sim.steps, impulse_ns=self._impulse_ns)


class JointWork(_Sampled):
    """The joints' net and positive mechanical work, every physics step as the recorder's
    ``joint_work_j`` (torque times the mean of the joint rates before and after the step). Positive
    work clips each joint's power at zero before summing (a ball joint's three components taken
    together), so a joint braking a limb never pays back another's work: ``net_j``, ``positive_j``."""

    def __init__(self, sim, log_hz: int):
        super().__init__(sim.config.physics_hz, log_hz)
        sizes = [3 if ball else 1 for ball in sim.layout.motor_is_ball]
        self._joint_starts = np.concatenate([[0], np.cumsum(sizes)[:-1]]).astype(int)
        self._rates = sim.world.joint_torques_and_rates()[1]
        self._net_j = self._positive_j = 0.0

    def __call__(self, sim) -> None:
        torque, rates = sim.world.joint_torques_and_rates()
        per_joint_w = np.add.reduceat(torque * 0.5 * (rates + self._rates), self._joint_starts)
        self._rates = rates
        self._net_j += self.dt_s * float(per_joint_w.sum())
        self._positive_j += self.dt_s * float(np.clip(per_joint_w, 0.0, None).sum())
        self._sample(sim.steps, net_j=self._net_j, positive_j=self._positive_j)
