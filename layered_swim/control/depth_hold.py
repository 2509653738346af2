"""Holding a depth under water: the pitch sequences' weight moved every control step.

The cycle layer picks its pitch weights once a cycle from the last cycle's mean pitch, sized by a
table calibrated at the surface. Under water the same weight pitches the body about twice as far
(``pitch_down`` at 1: 60 deg against the table's 23-30), with no surface to damp it, and a cycle's
delay made that correction swing the breaststroke between -60 and +40 deg. On top of it, while a
stroke takes its ``under_water`` sequence, this adds to the net pitch weight (+: more pitch-down)
by how far the pelvis lies above the target's depth a little ahead, and how much faster it rises
than the target (``steering.under_water_pitch_per_m``, ``..._per_m_s``).
"""
from __future__ import annotations

from dataclasses import dataclass

from layered_swim.control.stroke import PITCH_DOWN, PITCH_UP
from layered_swim.control.targets import Target, target_velocity_m_s

RATE_STEP_S = 0.5     # the target's sinking rate from its move over this long, centred on the time read


@dataclass(frozen=True)
class DepthHold:
    per_m: float             # weight per metre above the target's depth
    per_m_s: float = 0.0     # ... plus per m/s it rises faster than the target
    ahead_s: float = 0.0     # the target's depth and rate this far ahead

    def weight(self, above_m: float, rising_m_s: float) -> float:
        """The pitch weight to add (+: pitch-down), within +-1."""
        return min(1.0, max(-1.0, self.per_m * above_m + self.per_m_s * rising_m_s))

    def weight_toward(self, target: Target, time_s: float, pelvis_z_m: float, com_vz_m_s: float) -> float:
        """``weight`` for a pelvis at ``pelvis_z_m`` whose centre of mass rises at ``com_vz_m_s``."""
        at_s = time_s + self.ahead_s
        target_vz = float(target_velocity_m_s(target, at_s - RATE_STEP_S / 2, RATE_STEP_S)[2])
        return self.weight(pelvis_z_m - float(target.position(at_s)[2]), com_vz_m_s - target_vz)


def with_pitch_added(weights: dict[str, float], added: float) -> dict[str, float]:
    """``weights`` with ``added`` on their net pitch weight (pitch-down less pitch-up), taken by the
    one sequence that pitches that way, at most 1."""
    net = weights.get(PITCH_DOWN, 0.0) - weights.get(PITCH_UP, 0.0) + added
    out = {name: w for name, w in weights.items() if name not in (PITCH_DOWN, PITCH_UP)}
    if net > 0.0:
        out[PITCH_DOWN] = min(1.0, net)
    elif net < 0.0:
        out[PITCH_UP] = min(1.0, -net)
    return out
