"""Automatic stroke choice (Yang et al. 2004, section 7, future work): the stroke that suits what
the target asks, switched between stroke cycles.

Each stroke keeps its own layered controller (its calibration, steering and rules). At the end
of every cycle of the stroke swimming now, ``StrokeChoice`` looks at the target:

- **hold**: a target that stays put (or creeps) within ``hold_within_m`` (or that the swimmer,
  arriving fast, would coast to within ``hold_coast_to_m`` of) is held by treading water, which
  stays where it is and turns on the spot; treading goes on until the target is ``hold_leave_m``
  away or starts moving;
- **dive**: a target deeper than ``dive_beyond_m`` is followed with the breaststroke, the one
  stroke that holds a depth (the others ride the surface);
- **reach**: a target that stays put farther than ``reach_beyond_m`` (a jump, a click) is swum to
  with the stroke that gets there soonest by its ``Ability`` (``soonest``), once the body swims
  (``reach_from_m_s``), until within ``reach_until_m``, where the approach and the hold take over
  (alone, the breaststroke took up to 24 s to reach a jump 8-10 m away, the butterfly at most 11);
- **sprint**: a moving target far ahead (``sprint_beyond_m``, within ``sprint_ahead_rad`` of the
  heading) is chased with the crawl, until it is near or off to the side (only far: from a
  standstill the crawl's first cycles wobble);
- **keep up**: a target that asks more speed through the water than the breaststroke swims
  comfortably (its speed less the water's, beyond ``keep_up_share`` of the breaststroke's full
  pace: a fast target, or a current to fight) is followed with the stroke that turns most per
  metre among those that swim that speed within ``keep_up_share`` of their own full pace, or
  with the fastest where none does (``Ability``: read off each stroke's calibration, so a stroke
  tuned again is ranked again); it goes back to the breaststroke below ``keep_up_leave_share``;
- **otherwise** breaststroke: the tighter turn and the slower pace, for bends and approaches.

Holding starts at once, mid-cycle, when a still target comes within reach (a stroke circling it
tightly may be in reach only between its cycle ends), and ends at once when the held target
jumps away. The new stroke starts a fresh cycle at the switch, and the pose eases from the old
stroke's to the new one's over ``blend_s``, so the joints never jump.
"""
from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Callable, NamedTuple

import numpy as np

from layered_swim.control.cycle_choice import Water
from layered_swim.control.layered import LayeredController
from layered_swim.control.steering import attitude_of, bearing_error
from layered_swim.control.targets import Target, target_speed_m_s, target_velocity_m_s
from layered_swim.geometry import ease
from layered_swim.state import BodyState

AUTO = "auto"
SPRINT, TURN, HOLD = "front_crawl", "breaststroke", "treading_water"
AUTO_STROKES = (TURN, SPRINT, HOLD, "butterfly", "backstroke")      # the first is the one it starts with


class Ability(NamedTuple):
    """What a stroke can do, from its calibration: its steady speed at full tempo, and how much its
    yaw sequences turn it per metre swum at full tempo (the weaker side, at its strongest weight);
    and whether it swims face down, seeing where it goes."""

    top_m_s: float
    turn_rad_per_m: float
    face_down: bool = True


def ability_of(controller: LayeredController) -> Ability:
    table = controller.chooser.table
    top_m_s = table.pace.speed_at(1.0)
    turn_rad = min(float(np.max(table.turn_at(name, 1.0))) for name in table.turn_rad)
    return Ability(top_m_s, turn_rad / (top_m_s * controller.stroke.period_s),
                   controller.stroke.start.posture == "prone")


class Ask(NamedTuple):
    """What the target asks of the swimmer now."""

    distance_m: float
    target_speed_m_s: float
    heading_error_rad: float
    pace_m_s: float = 0.0      # the speed through the water that keeps with it (its velocity less the water's)
    depth_m: float = 0.0
    speed_m_s: float = 0.0     # the swimmer's own horizontal speed through the water
    closing_m_s: float = 0.0   # how fast it nears the target (horizontally, over the ground)


@dataclass(frozen=True)
class StrokeChoice:
    hold_within_m: float = 1.0
    hold_leave_m: float = 2.0
    # Arriving fast, the swimmer coasts on once it treads water (about its closing speed times
    # hold_coast_s): holding starts where it would coast to within hold_coast_to_m.
    hold_coast_s: float = 1.5
    hold_coast_to_m: float = 0.5
    still_m_s: float = 0.2            # a target slower than this stays put
    sprint_beyond_m: float = 12.0
    sprint_until_m: float = 3.0
    sprint_ahead_rad: float = math.radians(30.0)
    sprint_keep_rad: float = math.radians(60.0)
    keep_up_share: float = 0.85
    keep_up_leave_share: float = 0.75
    # A target that moved faster than any swimmer has jumped (a station, the mouse): it asks no pace.
    jumped_beyond_m_s: float = 3.0
    dive_beyond_m: float = 1.0
    reach_beyond_m: float = 4.0
    reach_until_m: float = 2.0
    # What a change of stroke costs in reaching: the blend and a first cycle from the last one's pose.
    switch_cost_s: float = 2.0
    # Only from a body already swimming this fast: from treading water, upright and still, the
    # butterfly stalled nose-up and never got going; the breaststroke lays it down first. Slowest
    # jump of `follow jumping --seeds 10` (median, the breaststroke levelling off at tempo 1.0):
    # 14.2 s; from 0.4 m/s 15.1, 0.5 15.8; from 0.3 the butterfly stalled in one run of ten and
    # missed two stations.
    reach_from_m_s: float = 0.35
    blend_s: float = 0.5

    def holds(self, active: str, distance_m: float, target_speed_m_s: float, closing_m_s: float = 0.0) -> bool:
        """Whether to tread water at (or keep holding) the target: it stays put and is near (or
        will be, coasting at ``closing_m_s``)."""
        if target_speed_m_s >= self.still_m_s:
            return False
        if active == HOLD:
            return distance_m < self.hold_leave_m
        coasts_to_m = distance_m - self.hold_coast_s * max(0.0, closing_m_s)
        return distance_m < self.hold_within_m or coasts_to_m < self.hold_coast_to_m

    def choose(self, active: str, ask: Ask, abilities: dict[str, Ability] | None = None) -> str:
        """``abilities``: the strokes that may keep up with a fast target (none: only the
        breaststroke, crawl and treading water are chosen)."""
        if self.holds(active, ask.distance_m, ask.target_speed_m_s, ask.closing_m_s):
            return HOLD
        if ask.depth_m > self.dive_beyond_m:
            return TURN
        distance, error = ask.distance_m, abs(ask.heading_error_rad)
        if abilities and ask.target_speed_m_s < self.still_m_s:
            soonest = self.soonest(active, ask, abilities)
            going_on = soonest == active and distance > self.reach_until_m
            starting = distance > self.reach_beyond_m and ask.speed_m_s >= self.reach_from_m_s
            if soonest != TURN and (going_on or starting):
                return soonest
        if (distance > self.sprint_beyond_m and error < self.sprint_ahead_rad) or (
                active == SPRINT and distance > self.sprint_until_m and error < self.sprint_keep_rad):
            return SPRINT
        if abilities:
            keeping = active != TURN and active in abilities
            share = self.keep_up_leave_share if keeping else self.keep_up_share
            if ask.pace_m_s > share * abilities[TURN].top_m_s:
                return self.keeping_up(ask.pace_m_s, abilities)
        return TURN

    def soonest(self, active: str, ask: Ask, abilities: dict[str, Ability]) -> str:
        """The stroke that would reach the target soonest: the distance at its full pace plus the
        heading error at its full turn rate, plus ``switch_cost_s`` for any but ``active``. Only
        strokes that face down (on its back, the backstroke took 11-20 s to reach a jump of 8-10 m:
        it swims blind and turns least per metre), and only those whose tightest turn at full pace
        does not circle round the target (alone, the butterfly circles a reached station 2-3 m out);
        the breaststroke where none is left."""
        def time_s(name: str) -> float:
            a = abilities[name]
            swim_s = (ask.distance_m + abs(ask.heading_error_rad) / a.turn_rad_per_m) / a.top_m_s
            return swim_s + (0.0 if name == active else self.switch_cost_s)

        def reachable(a: Ability) -> bool:
            # Within the circle of its tightest turn on the target's side: d < 2 R |sin(error)|.
            return ask.distance_m * a.turn_rad_per_m >= 2.0 * abs(math.sin(ask.heading_error_rad))
        fit = [name for name, a in abilities.items() if a.face_down and reachable(a)]
        return min(fit, key=time_s) if fit else TURN

    def keeping_up(self, asked_m_s: float, abilities: dict[str, Ability]) -> str:
        """The stroke that turns most per metre among those fast enough for ``asked_m_s``, else the fastest."""
        others = {name: a for name, a in abilities.items() if name != TURN}
        fast = [name for name, a in others.items() if asked_m_s <= self.keep_up_share * a.top_m_s]
        if fast:
            return max(fast, key=lambda name: others[name].turn_rad_per_m)
        return max(others, key=lambda name: others[name].top_m_s)


class Switch(NamedTuple):
    """One change of stroke: when, and to which."""

    time_s: float
    stroke: str


class AutoStrokeController:
    """Several strokes' layered controllers, one swimming at a time, switched by ``choice``."""

    def __init__(self, controllers: dict[str, LayeredController], target: Target, *,
                 medium: Callable[[], Water], choice: StrokeChoice = StrokeChoice(), first: str = AUTO_STROKES[0]):
        """``medium()``: the water swum in now (its current and flow field, not the body's wake,
        and where its surface is)."""
        self.controllers, self.target, self.choice_rule, self.first = controllers, target, choice, first
        self.medium = medium
        # The strokes that may keep up with a fast target: the breaststroke's pace is the bar.
        self.abilities = {name: ability_of(c) for name, c in controllers.items() if name != HOLD}
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
        ask = Ask(float(np.linalg.norm(goal - position)), target_speed_m_s(self.target, state.time_s),
                  bearing_error(position, goal, heading), self._asked_m_s(state.time_s, position),
                  self.medium().surface_z_m - float(goal[2]),
                  self._through_water_m_s(state.com_vel_m_s, position, state.time_s), closing_m_s(state, goal))
        return self.choice_rule.choose(self.active, ask, self.abilities)

    def _asked_m_s(self, time_s: float, position_m: np.ndarray) -> float:
        """The horizontal speed through the water that keeps with the target: its velocity less the
        water's at ``position_m``."""
        velocity = target_velocity_m_s(self.target, time_s)
        if np.linalg.norm(velocity) > self.choice_rule.jumped_beyond_m_s:
            velocity = np.zeros(3)
        return self._through_water_m_s(velocity, position_m, time_s)

    def _through_water_m_s(self, velocity_m_s: np.ndarray, position_m: np.ndarray, time_s: float) -> float:
        """The horizontal speed of ``velocity_m_s`` less the water's at ``position_m``."""
        velocity = velocity_m_s - self.medium().current_at(position_m, time_s, waves=False)[0]
        return float(np.hypot(velocity[0], velocity[1]))

    def _hold_changes_now(self, state: BodyState) -> bool:
        """Whether holding should start or end now, mid-cycle: a still target come within reach is
        held at once (a stroke turning tightly round it may pass within ``hold_within_m`` only
        between its cycle ends), and a held target that jumps away is left at once."""
        if self._from_pose is not None:
            return False
        goal = self.target.position(state.time_s)
        distance_m = float(np.linalg.norm(goal - state.com_m))
        holds = self.choice_rule.holds(self.active, distance_m, target_speed_m_s(self.target, state.time_s),
                                       closing_m_s(state, goal))
        return holds != (self.active == HOLD)

    def _switch(self, name: str, time_s: float) -> None:
        self._from_pose = None if self._last_pose is None else self._last_pose.copy()
        self._switched_s = time_s
        self.active = name
        self.current.restart(time_s)
        if self.current.lung_air_l is not None and self.lung_air_l is not None:
            self.current.lung_air_l = self.lung_air_l        # the breath held goes on
        self.switches.append(Switch(time_s, name))


def closing_m_s(state: BodyState, goal_m: np.ndarray) -> float:
    """How fast the swimmer nears ``goal_m``, horizontally, over the ground."""
    away = goal_m[:2] - state.com_m[:2]
    distance_m = float(np.linalg.norm(away))
    return float(state.com_vel_m_s[:2] @ away) / distance_m if distance_m > 1e-9 else 0.0
