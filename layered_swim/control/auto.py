"""Automatic stroke choice (Yang et al. 2004, section 7, future work): the stroke that suits what
the target asks, switched between stroke cycles.

Each stroke keeps its own layered controller (its calibration, steering and rules). At the end
of every cycle of the stroke swimming now, ``StrokeChoice`` looks at the target:

- **hold**: a target that stays put (or creeps) within ``hold_within_m`` is held by treading
  water, which stays where it is and turns on the spot; treading goes on until the target is
  ``hold_leave_m`` away or starts moving;
- **sprint**: a target far ahead (``sprint_beyond_m``, within ``sprint_ahead_rad`` of the
  heading) is chased with the crawl, the fastest stroke, until it is near or off to the side
  (only far: from a standstill the crawl's first cycles wobble, and a breaststroke reaches a
  jump 8-10 m away sooner);
- **otherwise** breaststroke: the tighter turn and the slower pace, for bends and approaches.

Holding starts at once, mid-cycle, when a still target comes within reach (a stroke circling it
tightly may be in reach only between its cycle ends), and ends at once when the held target
jumps away. The new stroke starts a fresh cycle at the switch, and the pose eases from the old
stroke's to the new one's over ``blend_s``, so the joints never jump.
"""
from __future__ import annotations

import math
from dataclasses import dataclass
from typing import NamedTuple

import numpy as np

from layered_swim.control.layered import LayeredController
from layered_swim.control.steering import attitude_of, bearing_error
from layered_swim.control.targets import Target, target_speed_m_s
from layered_swim.geometry import ease
from layered_swim.state import BodyState

AUTO = "auto"
SPRINT, TURN, HOLD = "front_crawl", "breaststroke", "treading_water"
AUTO_STROKES = (TURN, SPRINT, HOLD)      # the first is the one it starts with


@dataclass(frozen=True)
class StrokeChoice:
    hold_within_m: float = 1.0
    hold_leave_m: float = 2.0
    still_m_s: float = 0.2            # a target slower than this stays put
    sprint_beyond_m: float = 12.0
    sprint_until_m: float = 3.0
    sprint_ahead_rad: float = math.radians(30.0)
    sprint_keep_rad: float = math.radians(60.0)
    blend_s: float = 0.5

    def holds(self, active: str, distance_m: float, target_speed_m_s: float) -> bool:
        """Whether to tread water at (or keep holding) the target: it stays put and is near."""
        return target_speed_m_s < self.still_m_s and distance_m < (
            self.hold_leave_m if active == HOLD else self.hold_within_m)

    def choose(self, active: str, distance_m: float, target_speed_m_s: float, heading_error_rad: float) -> str:
        if self.holds(active, distance_m, target_speed_m_s):
            return HOLD
        error = abs(heading_error_rad)
        if (distance_m > self.sprint_beyond_m and error < self.sprint_ahead_rad) or (
                active == SPRINT and distance_m > self.sprint_until_m and error < self.sprint_keep_rad):
            return SPRINT
        return TURN


class Switch(NamedTuple):
    """One change of stroke: when, and to which."""

    time_s: float
    stroke: str


class AutoStrokeController:
    """Several strokes' layered controllers, one swimming at a time, switched by ``choice``."""

    def __init__(self, controllers: dict[str, LayeredController], target: Target,
                 choice: StrokeChoice = StrokeChoice(), first: str = AUTO_STROKES[0]):
        self.controllers, self.target, self.choice_rule, self.first = controllers, target, choice, first
        self.reset()

    def reset(self) -> None:
        self.active = self.first
        for controller in self.controllers.values():
            controller.reset()
        self.switches: list[Switch] = []
        self.lung_air_l: float | None = self.current.lung_air_l    # kept through strokes that do not breathe
        self._from_pose: np.ndarray | None = None
        self._last_pose: np.ndarray | None = None
        self._switched_s = 0.0

    @property
    def current(self) -> LayeredController:
        return self.controllers[self.active]

    # What the episode, the HUD and the app read of a controller: the active stroke's.
    @property
    def stroke(self):
        return self.current.stroke

    @property
    def choice(self):
        return self.current.choice

    @property
    def cycles_per_s(self) -> float:
        return self.current.cycles_per_s

    @property
    def layers(self):
        return self.current.layers

    @layers.setter
    def layers(self, layers) -> None:
        for controller in self.controllers.values():
            controller.layers = layers

    def phase(self, time_s: float) -> float:
        return self.current.phase(time_s)

    def desired(self, time_s: float, state: BodyState | None,
                flow_m_s: np.ndarray | None) -> tuple[np.ndarray, np.ndarray]:
        if state is not None and (self.current.cycle_ends(time_s) or self._hold_changes_now(state)):
            wanted = self._wanted(state)
            if wanted != self.active:
                self._switch(wanted, time_s)
        pose, rate = self.current.desired(time_s, state, flow_m_s)
        if self.current.lung_air_l is not None:
            self.lung_air_l = self.current.lung_air_l
        if self._from_pose is not None:
            progress = (time_s - self._switched_s) / self.choice_rule.blend_s
            if progress >= 1.0:
                self._from_pose = None
            else:
                eased = ease(progress)
                pose = self._from_pose + eased * (pose - self._from_pose)
                rate = eased * rate
        self._last_pose = pose
        return pose, rate

    def _wanted(self, state: BodyState) -> str:
        goal, position = self.target.position(state.time_s), state.com_m
        heading = attitude_of(state, self.current.stroke.start.posture).heading_rad
        return self.choice_rule.choose(self.active, float(np.linalg.norm(goal - position)),
                                       target_speed_m_s(self.target, state.time_s),
                                       bearing_error(position, goal, heading))

    def _hold_changes_now(self, state: BodyState) -> bool:
        """Whether holding should start or end now, mid-cycle: a still target come within reach is
        held at once (a stroke turning tightly round it may pass within ``hold_within_m`` only
        between its cycle ends), and a held target that jumps away is left at once."""
        if self._from_pose is not None:
            return False
        distance_m = float(np.linalg.norm(self.target.position(state.time_s) - state.com_m))
        holds = self.choice_rule.holds(self.active, distance_m, target_speed_m_s(self.target, state.time_s))
        return holds != (self.active == HOLD)

    def _switch(self, name: str, time_s: float) -> None:
        self._from_pose = None if self._last_pose is None else self._last_pose.copy()
        self._switched_s = time_s
        self.active = name
        self.current.restart(time_s)
        if self.current.lung_air_l is not None and self.lung_air_l is not None:
            self.current.lung_air_l = self.lung_air_l        # the breath held goes on
        self.switches.append(Switch(time_s, name))
