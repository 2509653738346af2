"""The per-cycle layer's choice toward a target (Yang 4.3 + section 5): ``TargetChooser`` picks
each cycle's weights and tempo (a ``CycleChoice``), with ``TempoControl`` (how hard to swim) and
``Lead`` (where to aim on a moving target's path).

At each cycle start: where is the target relative to the swimmer (heading error and depth), how
much of the heading error to turn this cycle, and which weight the calibration table says turns
that much; and for pitch and roll, which the water holds at an offset rather than letting them
turn on, the offset to hold: last cycle's moved by a share of the error left between the cycle's
mean attitude and the wanted one (the stroke's own, pitched toward the target's depth), an
integral control that neither oscillates nor leaves a steady error. The cycle's tempo
slows the stroke near the target so the swimmer does not overshoot a slow target (but not below
a moving target's own pace), and the rules are told how much more thrust is wanted.
"""
from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Callable, Protocol

import numpy as np

from layered_swim.control.calibration import CalibrationTable
from layered_swim.control.layered import CycleChoice
from layered_swim.control.steering import (
    MeanAttitude,
    SteeringGains,
    attitude_errors,
    attitude_of,
    bearing_error,
    beyond,
    glide_pitch,
    held_offset,
    turn_error,
    turned_over,
)
from layered_swim.control.stroke import LEVEL_OFF, PITCH_DOWN, ROLL_OVER, UNDER_WATER
from layered_swim.control.targets import Target, target_speed_m_s
from layered_swim.state import BodyState


@dataclass(frozen=True)
class TempoControl:
    """Full tempo beyond ``far_m`` from the target, ``min_tempo`` within ``near_m``; also
    ``min_tempo`` while the target is more than ``wide_turn_rad`` off the heading (swimming slower
    tightens the turn: speed falls faster than the turn rate). With ``keep_pace``, never slower
    than the tempo whose steady speed (the calibration's pace) is a moving target's own, unless
    ahead of it: slowing below it near the target only let it get away again.

    ``turn_tempo``: at least this tempo while the target is more than ``easy_turn_rad`` off the
    heading and the swimmer is at most ``turn_tempo_until_ahead_s`` ahead of it along its path (a
    stroke whose turn per cycle holds as its tempo rises turns more per second: the re-authored
    crawl and breaststroke, whose slow cycles could not follow the figure-eight's bends). A glide
    lasts ``glide_cycles`` of a cycle: a crawl's kick keeps it moving through a glide, and a
    whole cycle of it overshot a slow target.

    ``catch_up_beyond_m``: behind a moving target along its path and farther than this from it, at
    least ``turn_tempo`` (the stroke's fastest): at the target's pace the swimmer only keeps the gap
    (the figure-eight starts 2 m behind its target, and the breaststroke, at 0.83 m/s against
    0.5, took 10 s to close it).

    ``close_gap_s``: behind a moving target along its way, swim at its pace plus the gap over this
    many seconds (up to ``turn_tempo``, the stroke's fastest), not its pace alone: tempo by distance
    alone left the breaststroke trailing its target by 0.45 m on a straight line (steering costs it
    speed that the calibration's pace does not know of), and a current against it further. Only
    the gap beyond ``close_gap_beyond_m``: closing every gap, however small, the crawl followed the
    figure-eight in still water further off (0.74 m against 0.67; beyond 1 m, 0.66). The gap
    closed is the one ``close_gap_ahead_s`` from now at the speed the swimmer gained on the target
    over its last cycle: its speed follows its tempo a cycle late, and closing the gap as it was,
    the backstroke swung from 1.3 s behind its target to 1.5 s ahead across the figure-eight's
    crossing and waited again.

    ``wait_turn_tempo``: waiting for a moving target, at least this tempo while it is more than
    ``easy_turn_rad`` off the heading (None: the slowest): the backstroke's slowest tempo (0.55)
    swims its straights at ~0.7 m/s, nearer a 0.5 m/s target's pace than 0.65 (0.9 m/s), but
    turning that slowly it stands up.

    ``wait_pace``: waiting for a moving target, at least the tempo whose steady speed is this share
    of the target's pace (None: the slowest): at its slowest the breaststroke stalls nose-up, and
    once the target passes it must start again from standing.

    ``dive_tempo``: at least this tempo while the point steered for lies more than ``dive_below_m``
    below the centre of mass (a stroke that lies nose-up when slow cannot pitch down far enough to
    dive there: the breaststroke lies at 21 deg at tempo 0.7 and its pitch-down sequence takes it
    only to -8 deg; at full tempo it lies at 9 deg and pitches to -14), but not while well ahead of
    the target along its path (the breaststroke dived at full tempo 1-2 m past a diving target)."""

    min_tempo: float = 0.5
    keep_pace: bool = True
    glide_within_m: float = 0.0
    glide_cycles: float = 1.0
    turn_tempo: float | None = None
    turn_tempo_until_ahead_s: float = 0.0
    near_m: float = 0.2
    far_m: float = 0.6
    easy_turn_rad: float = math.radians(30.0)
    wide_turn_rad: float = math.radians(90.0)
    catch_up_beyond_m: float | None = None
    dive_tempo: float | None = None
    dive_below_m: float = 0.3
    close_gap_s: float | None = None
    close_gap_beyond_m: float = 0.0
    close_gap_ahead_s: float = 0.0
    wait_turn_tempo: float | None = None
    wait_pace: float | None = None
    weave_tempo: float | None = None

    def closing_speed_m_s(self, pace_m_s: float, behind_m: float, gaining_m_s: float = 0.0) -> float:
        """The speed to swim at behind a target moving at ``pace_m_s`` by ``behind_m`` along its
        way, gaining on it at ``gaining_m_s``: its pace, plus the gap beyond ``close_gap_beyond_m``
        as it will be ``close_gap_ahead_s`` from now, closed over ``close_gap_s`` (its pace alone
        with none)."""
        if self.close_gap_s is None:
            return pace_m_s
        behind_then_m = behind_m - gaining_m_s * self.close_gap_ahead_s
        return pace_m_s + max(0.0, behind_then_m - self.close_gap_beyond_m) / self.close_gap_s

    def drive(self, distance_m: float, heading_error_rad: float = 0.0) -> float:
        """How hard to swim, 0 (slowest) to 1 (full tempo)."""
        near = (distance_m - self.near_m) / (self.far_m - self.near_m)
        straight = (self.wide_turn_rad - abs(heading_error_rad)) / (self.wide_turn_rad - self.easy_turn_rad)
        return min(1.0, max(0.0, min(near, straight)))

    def tempo_for(self, drive: float) -> float:
        return float(self.min_tempo + (1.0 - self.min_tempo) * drive)

    def turning_tempo(self, tempo: float, heading_error_rad: float, ahead_of_target_s: float) -> float:
        if (self.turn_tempo is not None and abs(heading_error_rad) > self.easy_turn_rad
                and ahead_of_target_s <= self.turn_tempo_until_ahead_s):
            return max(tempo, self.turn_tempo)
        return tempo

    def waiting_tempo(self, tempo: float, heading_error_rad: float, pace_tempo: float | None = None,
                      weaving: bool = False) -> float:
        """``tempo`` while waiting, raised to ``wait_turn_tempo`` for a turn wider than ``easy_turn_rad``,
        with ``wait_pace`` to ``pace_tempo`` (the tempo whose steady speed is that share of the
        target's pace), and ``weaving`` to ``weave_tempo``."""
        if self.wait_turn_tempo is not None and abs(heading_error_rad) > self.easy_turn_rad:
            tempo = max(tempo, self.wait_turn_tempo)
        if self.wait_pace is not None and pace_tempo is not None:
            tempo = max(tempo, pace_tempo)
        if weaving and self.weave_tempo is not None:
            tempo = max(tempo, self.weave_tempo)
        return tempo

    def catching_up_tempo(self, tempo: float, distance_m: float, ahead_of_target_s: float) -> float:
        """``tempo``, raised to ``turn_tempo`` behind a moving target farther than ``catch_up_beyond_m``."""
        if (self.catch_up_beyond_m is not None and self.turn_tempo is not None and ahead_of_target_s <= 0.0
                and distance_m > self.catch_up_beyond_m):
            return max(tempo, self.turn_tempo)
        return tempo

    def diving_tempo(self, tempo: float, below_m: float, well_ahead: bool = False) -> float:
        """``tempo``, raised to ``dive_tempo`` for a point to swim to ``below_m`` below, unless the
        swimmer is ``well_ahead`` of its target along the path."""
        if self.dive_tempo is not None and below_m > self.dive_below_m and not well_ahead:
            return max(tempo, self.dive_tempo)
        return tempo


STEP_S = 0.5    # the target's direction and speed are read from its move over this long
# A path runs straight (for weaving) where it turns less than this over a lead's bend_s, and over each
# multiple of it up to WEAVE_STRAIGHT_BENDS times.
WEAVE_STRAIGHT_RAD = math.radians(20.0)
WEAVE_STRAIGHT_BENDS = 2


class Water(Protocol):
    """What a swimmer reads of the water swum in (a ``fluid.medium.Medium``)."""

    surface_z_m: float

    def current_at(self, points_m: np.ndarray, time_s: float, waves: bool = True) -> np.ndarray: ...


class InWater:
    """``target`` as seen from water moving at ``current_m_s`` from ``now_s`` on: its path less the
    water's move since ``now_s`` (a Galilean change of frame, exact for a uniform current). Steered
    in this frame, a swimmer crabs across a current by as much as it carries it, before any drift
    shows, and keeps a target's pace through the water, not over the ground."""

    def __init__(self, target: Target, current_m_s: np.ndarray, now_s: float):
        self.target, self.current_m_s, self.now_s = target, current_m_s, now_s
        self.foresight = getattr(target, "foresight", True)

    def position(self, time_s: float) -> np.ndarray:
        return self.target.position(time_s) - self.current_m_s * (time_s - self.now_s)

    def path_points(self, n: int = 400) -> np.ndarray:
        return self.target.path_points(n)


def _step_m(target: Target, time_s: float) -> np.ndarray:
    return target.position(time_s + STEP_S) - target.position(time_s)


def bend_rad(target: Target, time_s: float, over_s: float) -> float:
    """How far the target's direction of travel turns from ``time_s`` to ``over_s`` later."""
    now, later = _step_m(target, time_s), _step_m(target, time_s + over_s)
    norms = float(np.linalg.norm(now) * np.linalg.norm(later))
    return math.acos(max(-1.0, min(1.0, float(now @ later) / norms))) if norms > 1e-12 else 0.0


def weave_aim(aim_m: np.ndarray, position_m: np.ndarray, place_m: np.ndarray, direction: np.ndarray,
              side: float, angle_rad: float, within_m: float) -> tuple[np.ndarray, float]:
    """``aim_m`` moved across a straight path (through ``place_m`` along the horizontal unit
    ``direction``) so that the swimmer heads about ``angle_rad`` off it toward ``side`` (+1: the
    path's left), and the side: turned back once the swimmer is more than ``within_m`` out on it."""
    normal = np.array([-direction[1], direction[0]])
    across_m = float(np.dot(np.asarray(position_m, float)[:2] - np.asarray(place_m, float)[:2], normal))
    if side * across_m > within_m:
        side = -side
    reach_m = float(np.linalg.norm(np.asarray(aim_m, float)[:2] - np.asarray(position_m, float)[:2]))
    moved = np.array(aim_m, dtype=float)
    moved[:2] += normal * side * reach_m * math.tan(angle_rad)
    return moved, side


def behind_along_m(target: Target, time_s: float, position_m: np.ndarray) -> float:
    """How far ``position_m`` lies behind the target along its way, horizontally (< 0 ahead; 0 for a
    target standing still)."""
    step = _step_m(target, time_s)[:2]
    norm = float(np.linalg.norm(step))
    return float((target.position(time_s) - position_m)[:2] @ step) / norm if norm > 1e-9 else 0.0


def gain_along_m_s(target: Target, time_s: float, velocity_m_s: np.ndarray) -> float:
    """How fast a swimmer moving at ``velocity_m_s`` closes on the target along its way, horizontally:
    its speed along the target's direction of travel less the target's speed (0 for a target
    standing still)."""
    step = _step_m(target, time_s)[:2]
    norm = float(np.linalg.norm(step))
    return float(np.asarray(velocity_m_s)[:2] @ step) / norm - norm / STEP_S if norm > 1e-9 else 0.0


# Close a gap only on a path that stays at the surface: within this of it now, and no deeper
# than now by DIVE_M over the next LEVEL_AHEAD_S. Closing up before a dive left the breaststroke
# less room to get down (deep dive, 30 starts: 1.15 m of mean distance against 0.87).
SURFACE_WITHIN_M = 0.5
LEVEL_AHEAD_S = 20.0
DIVE_M = 0.3


def stays_at_surface(target: Target, time_s: float, surface_z_m: float) -> bool:
    """Whether ``target`` is near the surface now and its path does not dive over ``LEVEL_AHEAD_S``."""
    depth_m = surface_z_m - float(target.position(time_s)[2])
    deepest_m = max(surface_z_m - float(target.position(time_s + t)[2]) for t in np.linspace(0.0, LEVEL_AHEAD_S, 21))
    return depth_m <= SURFACE_WITHIN_M and deepest_m <= depth_m + DIVE_M


@dataclass(frozen=True)
class Lead:
    """How far ahead in time to aim at a moving target. Where its path runs straight, a short
    look keeps a sideways error (a cross current's drift) corrected hard, but one shorter than a
    cycle's travel snakes (strokes set their own: ``steering.lead_straight_s``); where the path
    bends, a long one starts the turn early, as turning takes cycles."""

    straight_s: float = 1.5
    bend_s: float = 3.0         # strokes set their own (``steering.lead_bend_s``): the turns they can make
    # Where the target is under water or its path dives soon (``stays_at_surface``), aim this far
    # ahead where the path runs straight (None: ``straight_s``).
    diving_straight_s: float | None = None
    depth_ahead_s: float = 1.5      # the depth steered for is the target's this far ahead
    full_bend_rad: float = math.radians(60.0)   # the path's change of direction over bend_s that earns all of it
    search_s: float = 6.0       # how far along the path, either way from the target, to look for the swimmer
    wait_ahead_s: float = 0.5   # ahead of the target by more than this along its path: slow down
    # ... but only this close to the path: far off it (a current carried the swimmer across a
    # corner), "ahead" is its nearest point on the path, and waiting there let the water carry it
    # on (the crawl ended 15-35 m off a square in a 0.3 m/s cross current). There it swims back.
    wait_within_m: float = 1.0
    # ... and within this of the depth it steers for (None: at any depth; waiting at its slowest
    # tempo, the breaststroke rose nose-up from 1.5 m above a diving path it was ahead on, and lost the dive).
    wait_depth_within_m: float | None = None
    # A stroke that glides near its target (``TempoControl.glide_within_m``) glides only when this
    # far ahead of it along its path: gliding as soon as near, the crawl glided while still behind
    # and trailed its target by about the glide distance (figure-eight 0.76 m; this alone 0.66 m).
    glide_ahead_s: float = 0.2
    # Steer upstream of the aim by the sideways drift the last cycles measured (``Drift``): a
    # current across the path otherwise holds the swimmer a metre or two downstream of it.
    aim_off: bool = False
    # Waiting on a straight stretch, head this far off the path, to one side and then the other,
    # turning back beyond weave_within_m out (None: straight on). A stroke still faster than its
    # target at its slowest tempo (the backstroke: ~0.7 m/s against 0.5) ran 1-3 m ahead of it.
    weave_rad: float | None = None
    weave_within_m: float = 0.6

    def place_on_path_s(self, target: Target, time_s: float, position_m: np.ndarray) -> tuple[float, float]:
        """When the target passes (or passed) nearest the swimmer, within ``search_s`` of now:
        where along the path the swimmer is, in the target's time, and how far across from the
        path it is there (horizontally). Nearest in 3-D: a swimmer over a diving path, not yet
        down, is not ahead on it; but it is on it, to wait there."""
        times_s = time_s + np.linspace(-self.search_s, self.search_s, 121)
        points = [target.position(t) - position_m for t in times_s]
        nearest = int(np.argmin([float(np.linalg.norm(p)) for p in points]))
        return float(times_s[nearest]), math.hypot(points[nearest][0], points[nearest][1])

    def aim(self, target: Target, time_s: float, position_m: np.ndarray,
            diving: bool = False) -> tuple[np.ndarray, float, float]:
        """The point to steer for, how many seconds the swimmer is ahead of the target along its
        path (< 0 behind) and how far off the path it is. Behind, it aims ahead of the target;
        ahead (it cut a corner or a current carried it), it aims ahead of its own place on the
        path, not back at the target: swimming back to a target that comes toward it only circles it.
        ``diving``: the target is under water or its path dives soon."""
        place_s, off_path_m = self.place_on_path_s(target, time_s, position_m)
        from_s = max(time_s, place_s)
        aim_m = np.array(target.position(from_s + self.seconds(target, from_s, diving)), dtype=float)
        # ... but at the depth the target itself reaches depth_ahead_s from now: a swimmer ahead along
        # a diving path held the path's depth there and left a hold early, and one behind dived late.
        aim_m[2] = target.position(time_s + self.depth_ahead_s)[2]
        return aim_m, place_s - time_s, off_path_m

    def waits(self, ahead_of_target_s: float, off_path_m: float, depth_off_m: float = 0.0) -> bool:
        """Whether to wait for the target: well ahead of it along its path, and on the path, at
        the depth it steers for (``depth_off_m`` from it)."""
        return (ahead_of_target_s > self.wait_ahead_s and off_path_m <= self.wait_within_m
                and (self.wait_depth_within_m is None or depth_off_m <= self.wait_depth_within_m))

    def seconds(self, target: Target, time_s: float, diving: bool = False) -> float:
        """How far ahead to aim: ``straight_s`` (diving: ``diving_straight_s``) where the path runs
        straight, up to ``bend_s`` where it bends by ``full_bend_rad`` or more."""
        straight_s = self.diving_straight_s if diving and self.diving_straight_s is not None else self.straight_s
        bend = bend_rad(target, time_s, self.bend_s)
        return straight_s + (self.bend_s - straight_s) * min(1.0, bend / self.full_bend_rad)

    def weaves(self, target: Target, place_s: float) -> bool:
        """Whether a waiting swimmer at ``place_s`` along the path weaves: the stroke does, and the
        path runs straight there (it turns less than ``WEAVE_STRAIGHT_RAD`` over the next
        ``WEAVE_STRAIGHT_BENDS`` times ``bend_s``: weaving up to a zigzag's corner, the backstroke
        stood up in the turn there and stalled for good in 2 of 10 starts)."""
        return (self.weave_rad is not None and float(np.linalg.norm(_step_m(target, place_s)[:2])) > 1e-9
                and all(bend_rad(target, place_s, k * self.bend_s) < WEAVE_STRAIGHT_RAD
                        for k in range(1, WEAVE_STRAIGHT_BENDS + 1)))


class Drift:
    """The water's sideways push, as a swimmer sees it: how fast the centre of mass moved across
    its heading over each cycle (the chord of the cycle's track against the mean of its start and
    end headings, which a steady turn leaves at zero), smoothed over cycles. Along the heading a
    current only changes the pace, which the tempo control answers; across it, it sets the
    swimmer off the path."""

    SMOOTHING = 0.5       # the newest cycle's share
    # Steering acts only on the drift beyond this: in still water a stroke's turns and glides
    # read as up to ~0.1 m/s of it, and aiming off on that cost the breaststroke 0.1-0.4 m on
    # the figure-eight and the deep dive.
    DEADZONE_M_S = 0.1
    STRAIGHT_COS = math.cos(math.radians(45.0))   # a cycle that turned less than this is read

    def __init__(self):
        self.reset()

    def reset(self) -> None:
        self.m_s = np.zeros(2)
        self._last: tuple[float, np.ndarray, np.ndarray] | None = None

    def update(self, time_s: float, position_m: np.ndarray, heading_rad: float, current_m_s: np.ndarray) -> None:
        """``current_m_s``: the water's velocity as far as the swimmer knows it (and steers for
        already): the drift is what is left."""
        forward = np.array([math.cos(heading_rad), math.sin(heading_rad)])
        # A cycle that turned hard (on the spot, after a jump) says nothing of the water: kept out.
        if self._last is not None and time_s > self._last[0] and float(forward @ self._last[2]) > self.STRAIGHT_COS:
            then_s, then_m, then_forward = self._last
            velocity = (position_m[:2] - then_m[:2]) / (time_s - then_s) - current_m_s[:2]
            mean = then_forward + forward
            norm = math.hypot(mean[0], mean[1])
            along = mean / norm if norm > 1e-6 else forward
            across = velocity - float(velocity @ along) * along
            self.m_s = self.m_s + self.SMOOTHING * (across - self.m_s)
        self._last = (time_s, np.array(position_m, dtype=float), forward)

    def aimed_off(self, position_m: np.ndarray, aim_m: np.ndarray, speed_m_s: float) -> np.ndarray:
        """``aim_m`` moved upstream by what the drift (less ``DEADZONE_M_S``) carries the swimmer
        while it swims there at ``speed_m_s``, at most half the way there (a crab angle up to ~27 deg)."""
        delta = aim_m[:2] - position_m[:2]
        distance = math.hypot(delta[0], delta[1])
        size = math.hypot(self.m_s[0], self.m_s[1])
        drift = self.m_s * (max(0.0, size - self.DEADZONE_M_S) / size) if size > 0.0 else self.m_s
        shift = drift * distance / max(speed_m_s, 0.3)
        size = math.hypot(shift[0], shift[1])
        if size > 0.5 * distance:
            shift *= 0.5 * distance / size
        return np.array([aim_m[0] - shift[0], aim_m[1] - shift[1], aim_m[2]])


class TargetChooser:
    """The layered controller's ``CycleChooser`` when it steers toward ``target``: each cycle's
    weights from the calibration ``table``, its tempo from ``tempo`` and its aim from ``lead``."""

    def __init__(self, target: Target, table: CalibrationTable, posture: str,
                 gains: SteeringGains = SteeringGains(), tempo: TempoControl = TempoControl(), lead: Lead = Lead(),
                 level_off_beyond_rad: float | None = None, level_off_tempo: float = 1.0,
                 level_off_sequence: bool = True, level_off_pitch_down_weight: float | None = None,
                 roll_over_sequence: bool = False,
                 recover_beyond_rad: tuple[float | None, float | None] = (None, None),
                 water: Callable[[], Water] | None = None, under_water_below_m: float | None = None,
                 under_water_level_pitch_rad: float | None = None, under_water_yaw_fraction: float | None = None):
        """``level_off_beyond_rad``: starting (cycle 0) pitched nose up by more than this beyond
        any climb toward the target, swim at ``level_off_tempo`` every cycle until neither the
        pitch as a cycle starts nor the last cycle's mean is (None: never), taking the stroke's
        ``level_off`` sequence (``level_off_sequence``: where it has one), or its pitch-down
        sequence at ``level_off_pitch_down_weight``, instead of a pitch correction.
        ``roll_over_sequence``: turned over (a supine stroke face down), swim a cycle of the
        stroke's ``roll_over`` sequence alone, at tempo 1 (False: the stroke has none).
        ``recover_beyond_rad``: (pitch, roll); after a cycle whose mean pitch was more than the first
        nose up, or whose mean shoulder roll was more than the second either way, swim a plain
        cycle at ``level_off_tempo`` (None: never).
        ``water()``: the water swum in now; a target on a known path is then steered for in the
        frame of the water's steady current where the swimmer is (``InWater``).
        ``under_water_below_m``: the stroke's ``under_water`` sequence at weight 1, on top of the
        rest, while the point steered for lies deeper than this below the surface (None: never);
        there the pitch correction steers to ``under_water_level_pitch_rad`` plus the glide angle
        (None: to the pace table's pitch, which is the surface's), and the heading correction takes
        ``under_water_yaw_fraction`` of the error a cycle (None: the gains' ``yaw_fraction``)."""
        self.target, self.table, self.posture, self.lead = target, table, posture, lead
        self.water = water
        self.gains, self.tempo_control = gains, tempo
        self.level_off_beyond_rad, self.level_off_tempo = level_off_beyond_rad, level_off_tempo
        self.level_off_sequence = level_off_sequence
        self.level_off_pitch_down_weight = level_off_pitch_down_weight
        self.roll_over_sequence = roll_over_sequence
        self.recover_beyond_rad = recover_beyond_rad
        self.under_water_below_m = under_water_below_m
        self.under_water_level_pitch_rad = under_water_level_pitch_rad
        self.under_water_yaw_fraction = under_water_yaw_fraction
        self._levelling = False
        self._last_error_rad = 0.0      # the last cycle's heading error, as steered
        self.held_rad = {"pitch": 0.0, "roll": 0.0}     # the attitude offsets the sequences hold
        self.drift = Drift()
        self._weave_side = 1.0          # the side of the path a waiting swimmer weaves to (+1: its left)
        self._cycle_start: tuple[float, np.ndarray] | None = None      # the last cycle's start: time, position

    def __call__(self, cycle: int, state: BodyState, last_cycle: MeanAttitude | None) -> CycleChoice:
        position = state.com_m
        # Aim ahead along the target's path (and keep its pace) only where it is known (not a mouse
        # or a jump); that path as the water carrying the swimmer sees it.
        foresight = getattr(self.target, "foresight", True)
        current = self._current_m_s(position, state.time_s)
        path = InWater(self.target, current, state.time_s) if foresight and current.any() else self.target
        at_surface = foresight and stays_at_surface(path, state.time_s, self._surface_z_m())
        if foresight:
            target, ahead_of_target_s, off_path_m = self.lead.aim(path, state.time_s, position, not at_surface)
        else:
            target, ahead_of_target_s, off_path_m = self.target.position(state.time_s), 0.0, 0.0
        # Ahead of the target along its path: wait for it at the slowest tempo (turning at full tempo
        # instead carried the breaststroke further out of the figure-eight), gliding where the stroke
        # glides to wait (gliding, the breaststroke's depth drifted 0.27 m off a diving target's);
        # far off the path it swims back instead.
        waiting = foresight and self.lead.waits(ahead_of_target_s, off_path_m, abs(float(target[2] - position[2])))
        place_s = state.time_s + ahead_of_target_s
        weaving = waiting and self.lead.weaves(path, place_s)
        if cycle == 0:
            self._weave_side = 1.0
            self._cycle_start = None
        velocity = self._last_cycle_velocity_m_s(state)
        if weaving:
            step = _step_m(path, place_s)[:2]
            target, self._weave_side = weave_aim(target, position, path.position(place_s), step / np.linalg.norm(step),
                                                 self._weave_side, self.lead.weave_rad, self.lead.weave_within_m)
        # Heading and pitch as the cycle starts (the same phase every cycle, and current); pitch and
        # roll to steer averaged over the last cycle.
        att = attitude_of(state, self.posture, facing=cycle == 0)     # a spell may start standing up
        mean = last_cycle if last_cycle is not None else MeanAttitude(att.pitch_rad, att.roll_rad)
        if cycle == 0:
            self.held_rad = {"pitch": 0.0, "roll": 0.0}
            self._last_error_rad = 0.0
        if self.lead.aim_off and foresight:      # on a known path (a jump's or the mouse's target has none)
            if cycle == 0:
                self.drift.reset()
            self.drift.update(state.time_s, position, att.heading_rad, current)
            target = self.drift.aimed_off(position, target, self.table.pace.speed_at(1.0))
        heading_error = bearing_error(position, target, att.heading_rad)
        distance = float(np.linalg.norm(self.target.position(state.time_s) - position))
        # Started standing up (from treading water), it levels off until it lies; climbing steeply
        # to a target far above (sunk in light water) does not count: there the pitch is the climb.
        # Only at a start: mid-swim, a push that pitches it up is for the pitch correction.
        climb_rad = max(0.0, glide_pitch(position, target, self.gains))
        # Levelling goes on while the last cycle's mean is still pitched up too: the pitch swings
        # within a cycle, and the breaststroke stopped levelling on a dip to 35 deg and stood up again.
        pitch_rad = att.pitch_rad if cycle == 0 or last_cycle is None else max(att.pitch_rad, last_cycle.pitch_rad)
        self._levelling = (cycle == 0 or self._levelling) and self.level_off_beyond_rad is not None and (
            pitch_rad - climb_rad > self.level_off_beyond_rad)
        drive = 0.0 if waiting else self.tempo_control.drive(distance, heading_error)
        # Levelling off, kick at the level-off tempo even for a target behind: a fast kick lies it down sooner.
        tempo = self.level_off_tempo if self._levelling else self.tempo_control.tempo_for(drive)
        # The target's pace where the swimmer is along its path (only a known path has one).
        pace_m_s = target_speed_m_s(path, state.time_s + max(0.0, ahead_of_target_s), STEP_S) if foresight else 0.0
        if self.tempo_control.keep_pace and not waiting and foresight:
            tempo = max(tempo, min(1.0, self.table.pace.tempo_for_speed(pace_m_s)))
            if self.tempo_control.close_gap_s is not None and at_surface:
                gaining = 0.0 if velocity is None else gain_along_m_s(path, state.time_s, velocity - current)
                closing = self.tempo_control.closing_speed_m_s(pace_m_s, behind_along_m(path, state.time_s, position),
                                                               gaining)
                fastest = self.tempo_control.turn_tempo or 1.0
                tempo = max(tempo, min(fastest, self.table.pace.tempo_for_speed(closing)))
        if waiting:
            pace_tempo = None
            if self.tempo_control.wait_pace is not None:
                pace_tempo = min(1.0, self.table.pace.tempo_for_speed(self.tempo_control.wait_pace * pace_m_s))
            tempo = self.tempo_control.waiting_tempo(tempo, heading_error, pace_tempo, weaving)
        else:
            tempo = self.tempo_control.turning_tempo(tempo, heading_error, ahead_of_target_s)
            if foresight:
                tempo = self.tempo_control.catching_up_tempo(tempo, distance, ahead_of_target_s)
        if not self._levelling:
            tempo = self.tempo_control.diving_tempo(tempo, float(position[2] - target[2]),
                                                    well_ahead=ahead_of_target_s > self.lead.wait_ahead_s)
        self._last_error_rad = turn_error(att, position, target, self._last_error_rad)
        under_water = self._under_water(target)    # the yaw share, the pitch level and the sequence go by it
        yaw = self._yaw_fraction(bool(under_water)) * self._last_error_rad
        near = (distance < self.tempo_control.glide_within_m
                and (not foresight or ahead_of_target_s > self.lead.glide_ahead_s))
        glide = ((near or (waiting and self.tempo_control.glide_within_m > 0))
                 and abs(heading_error) < self.tempo_control.easy_turn_rad)
        if self.roll_over_sequence and turned_over(state.quat("thorax"), self.posture):
            # Face down, the backstroke's stroke drove it on at ~0.5 m/s whichever way it faced and
            # its yaw sequences did not turn it: it stayed so for the rest of a swim, 4-11 m off.
            return CycleChoice({ROLL_OVER: 1.0}, 1.0)
        if self._stood_or_rolled(last_cycle):
            # Turning slowly, the backstroke stood up or rolled onto its side and stalled there for
            # tens of seconds with every sequence at full weight; a plain cycle at speed rights it
            # (the held offsets wait, as through a glide).
            return CycleChoice(under_water, self.level_off_tempo, thrust_demand=drive)
        weights = {}        # a glide holds its first pose: no sequence, and the held offsets wait
        if not glide:
            weights = (self.table.weights_for(yaw, tempo)
                       | self._attitude_weights(mean, position, target, tempo, bool(under_water)))
        if abs(yaw) > self.gains.over_weight_within_rad:
            weights = {name: min(1.0, w) for name, w in weights.items()}
        if self._levelling and self.level_off_sequence:
            weights[LEVEL_OFF] = 1.0
        if self._levelling and self.level_off_pitch_down_weight is not None:
            weights[PITCH_DOWN] = self.level_off_pitch_down_weight
        weights |= under_water
        # Near the target, or turning hard, the rules stop seeking more thrust (Yang 4.4: more force
        # only where more is wanted); else they speed the swimmer past a slow target.
        return CycleChoice(weights, tempo, glide, self.tempo_control.glide_cycles if glide else 1.0,
                           thrust_demand=drive)

    def _last_cycle_velocity_m_s(self, state: BodyState) -> np.ndarray | None:
        """The centre of mass's mean velocity over the cycle that ends now (None at the first)."""
        start, self._cycle_start = self._cycle_start, (state.time_s, state.com_m.copy())
        if start is None or state.time_s <= start[0]:
            return None
        return (state.com_m - start[1]) / (state.time_s - start[0])

    def _stood_or_rolled(self, last_cycle: MeanAttitude | None) -> bool:
        """Whether the last cycle's mean attitude was past ``recover_beyond_rad``."""
        pitch_rad, roll_rad = self.recover_beyond_rad
        return last_cycle is not None and (
            (pitch_rad is not None and last_cycle.pitch_rad > pitch_rad)
            or (roll_rad is not None and abs(last_cycle.roll_rad) > roll_rad))

    def _yaw_fraction(self, under_water: bool) -> float:
        """The share of the heading error corrected this cycle. Under water a yaw weight turns the
        breaststroke 1.5-2 times as far as the surface's table says, and correcting 75 % of the
        error a cycle there swung its heading +-60 deg every ~9 s, and each hard turn rolled it
        and moved its depth."""
        if self.under_water_yaw_fraction is not None and under_water:
            return self.under_water_yaw_fraction
        return self.gains.yaw_fraction

    def _under_water(self, aim_m: np.ndarray) -> dict[str, float]:
        """The under-water sequence's weight, by the depth of the point steered for (glides too)."""
        if self.under_water_below_m is None or self._surface_z_m() - float(aim_m[2]) <= self.under_water_below_m:
            return {}
        return {UNDER_WATER: 1.0}

    def _surface_z_m(self) -> float:
        return self.water().surface_z_m if self.water is not None else 0.0

    def _current_m_s(self, position_m: np.ndarray, time_s: float) -> np.ndarray:
        """The water's steady horizontal velocity at ``position_m`` (zero with no water to read)."""
        if self.water is None:
            return np.zeros(3)
        velocity = self.water().current_at(position_m, time_s, waves=False)[0]
        return np.array([velocity[0], velocity[1], 0.0])

    def _attitude_weights(self, mean: MeanAttitude, position_m: np.ndarray, target_m: np.ndarray,
                          tempo: float, under_water: bool) -> dict[str, float]:
        """The pitch and roll sequences' weights: each axis's held offset moved by its fraction of
        the error, plus the proportional share of it (levelling off, the level-off sequence does
        the pitching)."""
        level = MeanAttitude(self.table.pace.pitch_at(tempo), self.table.pace.roll_at(tempo))
        if self.under_water_level_pitch_rad is not None and under_water:
            # The surface's pitch at a slow tempo is nose-up (+21 deg at 0.7): under water that climbs.
            level = MeanAttitude(self.under_water_level_pitch_rad, level.roll_rad)
        errors = attitude_errors(mean, position_m, target_m, self.posture, level, self.gains)
        fractions = {"pitch": self.gains.pitch_fraction, "roll": self.gains.roll_fraction}
        weights = {}
        levels_pitch = self.level_off_sequence or self.level_off_pitch_down_weight is not None
        for axis, error in errors.items():
            if fractions[axis] > 0.0 and not (axis == "pitch" and self._levelling and levels_pitch):
                low, high = self.table.attitude_range(axis, tempo)
                within = self.gains.attitude_within_rad
                self.held_rad[axis] = held_offset(self.held_rad[axis], error, fractions[axis], low, high, within)
                now = self.held_rad[axis] + self.gains.attitude_proportional * beyond(error, within)
                weights.update(self.table.attitude_weights(axis, min(high, max(low, now)), tempo))
        return weights
