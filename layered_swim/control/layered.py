"""The layered controller (Yang section 4): basic stroke + per-cycle perturbations + rules.

At the start of every stroke cycle a chooser (a ``CycleChooser``: ``cycle_choice.TargetChooser``
steering toward a target, or ``fixed_weights``) picks one weight per perturbation sequence (and
the cycle's tempo); the weights scale and blend the sequences' offsets into the basic pose
for that whole cycle. Every control step the continuous rules adjust the blended pose from the
water flowing past the hands. Layers can be switched off one by one (``Layers``). A stroke that
breathes to steer (``steering.breathe``) also sets the air in the lungs toward the target's depth
(``control/lungs.py``); the simulation hands it to the fluid. Under water a stroke may move its
pitch weights every step toward the target's depth (``control/depth_hold.py``).
"""
from __future__ import annotations

from dataclasses import dataclass, field
from typing import Protocol

import numpy as np

from layered_swim.config import ConfigError
from layered_swim.control.depth_hold import DepthHold, with_pitch_added
from layered_swim.control.lungs import LungControl
from layered_swim.control.rules import Arms, rule_offsets
from layered_swim.control.steering import MeanAttitude, elevation, forward_axis, shoulder_roll
from layered_swim.control.stroke import ALL_SEQUENCES, UNDER_WATER, Stroke
from layered_swim.control.targets import Target, target_velocity_m_s
from layered_swim.geometry import ease, unit_vector
from layered_swim.state import BodyState, JointLayout

BLEND_CYCLES = 0.15   # a new cycle's weights take over within this fraction of it
BREATH_RATE_STEP_S = 0.5   # the target's sinking rate, for the lungs, from its move over this long


@dataclass(frozen=True)
class Layers:
    cycle: bool = True
    palm: bool = True
    reach: bool = True

    @classmethod
    def parse(cls, text: str) -> "Layers":
        """``basic``, ``basic,cycle``, ``basic,cycle,rules`` or with ``palm``/``reach`` alone."""
        names = {n.strip() for n in text.split(",") if n.strip()}
        unknown = names - {"basic", "cycle", "rules", "palm", "reach"}
        if unknown or "basic" not in names:
            raise ConfigError(f"--layers must list 'basic' plus any of cycle, rules, palm, reach; got '{text}'")
        rules = "rules" in names
        return cls(cycle="cycle" in names, palm=rules or "palm" in names, reach=rules or "reach" in names)

    def describe(self) -> str:
        parts = ["basic"] + (["cycle"] if self.cycle else [])
        parts += (["rules"] if self.palm and self.reach
                  else (["palm"] if self.palm else []) + (["reach"] if self.reach else []))
        return ",".join(parts)


@dataclass
class CycleChoice:
    """What the per-cycle layer decided at the start of a cycle."""

    weights: dict[str, float] = field(default_factory=dict)
    tempo: float = 1.0
    glide: bool = False      # hold the cycle's first pose (but the stroke's glide_moving_joints)
    cycles: float = 1.0      # how much of a stroke cycle this choice lasts (a glide may be shorter)
    thrust_demand: float = 1.0   # 0..1: how much more force the rules should seek this cycle


class CycleChooser(Protocol):
    """The per-cycle layer's decision rule: called at each cycle start with the cycle's number, the
    body state and the pitch and shoulder roll averaged over the last cycle (None before one has ended)."""

    def __call__(self, cycle: int, state: BodyState, last_cycle: MeanAttitude | None) -> CycleChoice: ...


class LayeredController:
    def __init__(self, stroke: Stroke, layout: JointLayout, arms: Arms, chooser: CycleChooser,
                 layers: Layers = Layers(), target: Target | None = None, lungs: LungControl | None = None,
                 depth_hold: DepthHold | None = None):
        """``target``: where the rules push toward; without one, straight ahead (scripted weights).
        ``lungs``: breathe toward the target's depth (needs a target). ``depth_hold``: while the
        cycle takes the ``under_water`` sequence, move the pitch weights every step toward the
        target's depth (needs a target)."""
        self.stroke, self.layout, self.arms, self.chooser, self.layers = stroke, layout, arms, chooser, layers
        self.target = target
        self.lungs = lungs if target is not None else None
        self.depth_hold = depth_hold if target is not None else None
        self.reset()

    def reset(self) -> None:
        self._previous_weights: dict[str, float] = {}
        self.rule_offsets = np.zeros(self.layout.size)
        self._last_rule_time_s = None
        self.choice = CycleChoice()
        self.cycle = -1
        self.cycle_start_s = 0.0
        self._pitch_sum, self._roll_sum, self._attitude_n = 0.0, 0.0, 0
        self.last_cycle: MeanAttitude | None = None
        # The air the swimmer holds (None: it does not breathe to steer), and when it last changed.
        self.lung_air_l = self.lungs.rest_air_l if self.lungs is not None else None
        self._last_breath_s: float | None = None

    def restart(self, time_s: float) -> None:
        """Begin afresh at ``time_s``: its first cycle starts there (a stroke switched in)."""
        self.reset()
        self.cycle_start_s = time_s

    def cycle_ends(self, time_s: float) -> bool:
        """Whether the cycle under way is over at ``time_s`` (or none has begun)."""
        return self.cycle < 0 or (time_s - self.cycle_start_s) * self.cycles_per_s >= self.choice.cycles

    @property
    def cycles_per_s(self) -> float:
        return self.choice.tempo / self.stroke.period_s

    def phase(self, time_s: float) -> float:
        """The stroke's phase in cycles; a glide holds its cycle's start."""
        return float(self.cycle) if self.choice.glide else self._running_phase(time_s)

    def _running_phase(self, time_s: float) -> float:
        return self.cycle + (time_s - self.cycle_start_s) * self.cycles_per_s

    def _start_cycle(self, state: BodyState | None) -> None:
        if self.cycle >= 0:
            self.cycle_start_s += self.choice.cycles / self.cycles_per_s
        self.cycle += 1
        if self._attitude_n:
            self.last_cycle = MeanAttitude(self._pitch_sum / self._attitude_n, self._roll_sum / self._attitude_n)
        self._previous_weights = dict(self.choice.weights)   # fully blended in by the cycle's end
        self._pitch_sum, self._roll_sum, self._attitude_n = 0.0, 0.0, 0
        if state is not None:
            self.choice = self.chooser(self.cycle, state, self.last_cycle)
            if not self.layers.cycle:
                self.choice = CycleChoice(tempo=self.choice.tempo)

    def desired(self, time_s: float, state: BodyState | None,
                flow_m_s: np.ndarray | None) -> tuple[np.ndarray, np.ndarray]:
        while self.cycle_ends(time_s):
            self._start_cycle(state)
        phase = self.phase(time_s)
        pose, rate = self.stroke.pose(phase)
        if self.choice.glide:
            # Held but for the joints the stroke keeps moving through a glide (its kick).
            running, running_rate = self.stroke.pose(self._running_phase(time_s))
            moving = self.stroke.glide_moving
            pose = np.where(moving, running, pose)
            rate = np.where(moving, running_rate, 0.0)
        weights = self._blended_weights(time_s)
        if self.depth_hold is not None and state is not None and UNDER_WATER in self.choice.weights:
            weights = with_pitch_added(weights, self.depth_hold.weight_toward(
                self.target, time_s, float(state.pos("pelvis")[2]), float(state.com_vel_m_s[2])))
        for name, weight in weights.items():
            if weight:
                pose, rate = self.stroke.perturbations[name].added(pose, rate, weight, phase)
        if state is not None:
            forward = forward_axis(state.quat("pelvis"), self.stroke.start.posture)   # read once a step
            self._track_attitude(state, forward)
            if self.lungs is not None and self.layers.cycle:      # depth is steered, like the heading
                self._breathe(time_s, state)
            if self.layers.palm or self.layers.reach:
                dt_s = time_s - self._last_rule_time_s if self._last_rule_time_s is not None else 0.0
                self._last_rule_time_s = time_s
                desired = self.desired_direction(state, forward)
                self.rule_offsets = rule_offsets(self.rule_offsets, self.arms, self.stroke.rules, state.quat_xyzw,
                                                 state.linvel_m_s, flow_m_s, desired, dt_s, self.layers.palm,
                                                 self.layers.reach, self._engagement(forward, desired))
                pose = pose + self.rule_offsets
        return self.layout.clamp(pose), rate * self.cycles_per_s

    def desired_direction(self, state: BodyState, forward: np.ndarray) -> np.ndarray:
        """Unit vector from the centre of mass to the target (without one, ``forward``: the way the
        swimmer heads)."""
        if self.target is None:
            return forward
        return unit_vector(self.target.position(state.time_s) - state.com_m)

    def _blended_weights(self, time_s: float) -> dict[str, float]:
        """This cycle's weights, eased in from the last cycle's over BLEND_CYCLES: a sequence need
        not be zero at the cycle start (a mirror shifted half a cycle is not), so a switch of
        weights must not jump the pose."""
        progress = (time_s - self.cycle_start_s) * self.cycles_per_s / BLEND_CYCLES
        if progress >= 1.0 or not self._previous_weights:
            return self.choice.weights
        eased = ease(progress)
        # A fixed order: the offsets are summed in it, and a set's order changes with the hash seed.
        names = [n for n in ALL_SEQUENCES if n in self.choice.weights or n in self._previous_weights]
        return {n: self._previous_weights.get(n, 0.0)
                + eased * (self.choice.weights.get(n, 0.0) - self._previous_weights.get(n, 0.0))
                for n in names}

    def _engagement(self, forward: np.ndarray, desired: np.ndarray) -> float:
        """How much the rules push: fully when the target is ahead and the cycle has no turn,
        fading as the target moves abeam or the yaw weight grows. While turning, the per-cycle
        layer's left-right asymmetry is what is wanted, and rules that maximise both hands'
        thrust would even it out."""
        turning = max(self.choice.weights.get("yaw_left", 0.0), self.choice.weights.get("yaw_right", 0.0))
        return max(0.0, float(forward @ desired)) ** 2 * max(0.0, 1.0 - turning) ** 3 * self.choice.thrust_demand

    def _breathe(self, time_s: float, state: BodyState) -> None:
        dt_s = time_s - self._last_breath_s if self._last_breath_s is not None else 0.0
        self._last_breath_s = time_s
        target_vz_m_s = float(target_velocity_m_s(self.target, time_s, BREATH_RATE_STEP_S)[2])
        self.lung_air_l = self.lungs.next_air_l(self.lung_air_l, -float(state.pos("pelvis")[2]),
                                                -float(self.target.position(time_s)[2]), dt_s,
                                                target_vz_m_s - float(state.com_vel_m_s[2]))

    def _track_attitude(self, state: BodyState, forward: np.ndarray) -> None:
        """Accumulate the cycle's mean pitch and shoulder roll: a crawl rolls +-30 deg within a
        cycle, and a stroke's pitch swings with its phase, so steering reads the cycle average."""
        self._pitch_sum += elevation(forward)
        self._roll_sum += shoulder_roll(state.quat("thorax"))
        self._attitude_n += 1


def fixed_weights(weights: dict[str, float], from_cycle: int = 0, tempo: float = 1.0) -> CycleChooser:
    """A scripted chooser: ``weights`` from cycle ``from_cycle`` on (calibration, experiments)."""
    unknown = set(weights) - set(ALL_SEQUENCES)
    if unknown:
        raise ValueError(f"unknown perturbation sequences {sorted(unknown)}")

    def chooser(cycle: int, state: BodyState, last_cycle: MeanAttitude | None) -> CycleChoice:
        return CycleChoice(dict(weights) if cycle >= from_cycle else {}, tempo)
    return chooser
