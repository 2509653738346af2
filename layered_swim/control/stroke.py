"""The basic stroke layer: a cyclic pose control graph read from a stroke file.

Each joint axis is keyed on its own over one cycle (``{fraction of cycle: degrees}``); an axis
without keys holds the rest pose. Keys are joined by a periodic, overshoot-free cubic (PCHIP on
three tiled cycles) and tabulated once, so evaluating a pose in the loop is a table lookup.
A joint may copy another's keys (``mirror_of``) shifted by a fraction of the cycle, which is how
left and right arms alternate in front crawl.
"""
from __future__ import annotations

import hashlib
import json
from dataclasses import dataclass, replace
from pathlib import Path
from typing import Literal

import numpy as np
from numba import njit
from pydantic import Field, model_validator
from scipy.interpolate import PchipInterpolator

from layered_swim.config import (
    SHIPPED_DIR,
    ConfigError,
    Degrees,
    Strict,
    available_files,
    between,
    file_path,
    load,
    search_dirs,
)
from layered_swim.control.steering import SteeringGains
from layered_swim.geometry import ease
from layered_swim.state import JointLayout, Start

STROKES_DIR = SHIPPED_DIR / "strokes"      # the top-level strokes/ in a checkout
TABLE_SAMPLES = 1024


class JointKeys(Strict):
    """Keys for one joint: per axis a mapping cycle fraction -> degrees, or a mirror."""

    model_config = Strict.model_config | {"extra": "allow"}
    mirror_of: str | None = None
    phase_shift: float = Field(0.0, ge=-1.0, le=1.0)

    def axis_keys(self) -> dict[str, dict[float, float]]:
        return dict(self.__pydantic_extra__ or {})


class StartSpec(Strict):
    posture: Literal["prone", "supine", "upright"] = "prone"
    depth_m: float = Field(0.0, ge=-1.0, le=10.0)     # pelvis centre below the surface
    speed_m_s: float = Field(0.0, ge=0.0, le=3.0)


# The steering sequences, each calibrated (turn per cycle against weight and tempo).
SEQUENCE_NAMES = ("pitch_up", "pitch_down", "yaw_left", "yaw_right", "roll_left", "roll_right")
PITCH_UP = "pitch_up"
PITCH_DOWN = "pitch_down"     # also levels off a stroke set off standing up (``steering.level_off_pitch_down_weight``)
# Lying down from upright (a lying stroke started from treading water): not calibrated, taken at
# weight 1 in place of the pitch correction by a stroke that starts pitched up by more than
# ``steering.level_off_beyond_deg`` beyond any climb toward the target, until it lies.
LEVEL_OFF = "level_off"
# Under water (the point steered for deeper than ``steering.under_water_below_m``): not calibrated,
# taken at weight 1 on top of the rest; a stroke that lifts its head to breathe leaves that out.
UNDER_WATER = "under_water"
# Rolled onto the side it should not face (a supine stroke face down): not calibrated, a cycle of it
# alone, at tempo 1, in place of all else while the chest faces the other way.
ROLL_OVER = "roll_over"
UNCALIBRATED_SEQUENCES = (LEVEL_OFF, UNDER_WATER, ROLL_OVER)
ALL_SEQUENCES = SEQUENCE_NAMES + UNCALIBRATED_SEQUENCES
Sequence = Literal[ALL_SEQUENCES]


class PerturbationSpec(Strict):
    """Per-joint offsets (degrees) relative to the basic stroke, keyed over the cycle, or the
    left-right mirror of another sequence (``mirror_of: yaw_left``)."""

    description: str = ""
    mirror_of: Sequence | None = None
    phase_shift: float = Field(0.0, ge=-1.0, le=1.0)   # with mirror_of: e.g. 0.5 when arms alternate
    keys: dict[str, JointKeys] = {}


class RuleSpec(Strict):
    enabled: bool = True
    gain: float = Field(30.0, ge=0.0, le=200.0)   # rad/s of offset per unit of the rule's gradient
    max_deg: float = Field(35.0, gt=0.0, le=90.0)
    # Also act while the water hinders (slice the palm, pull the arm in): for a recovery under
    # water. A crawl's hand only hinders from entry to catch, where slicing turns the palm away
    # just before the pull, so its rules act only while the water helps.
    hindering: bool = True


class RulesSpec(Strict):
    """Continuous-layer rules (Yang 4.4): palm orientation and arm reach."""

    palm: RuleSpec = RuleSpec()
    reach: RuleSpec = RuleSpec(gain=2.0, max_deg=20.0)


class SteeringSpec(Strict):
    """How the per-cycle layer steers this stroke: the share of each error it corrects in one
    cycle, tempo down to ``min_tempo`` (below it the stroke stops working) or up to ``turn_tempo``
    in a turn, and gliding for ``glide_cycles`` when closer than ``glide_within_m``, with
    ``glide_moving_joints`` still stroking (a crawl's legs keep kicking in a glide, or they sink)."""

    yaw_fraction: float = Field(SteeringGains.yaw_fraction, ge=0.0, le=1.0)
    pitch_fraction: float = Field(SteeringGains.pitch_fraction, ge=0.0, le=1.0)
    roll_fraction: float = Field(SteeringGains.roll_fraction, ge=0.0, le=1.0)
    # Pitching toward the target's depth, count it reached within this (a surface stroke that rides
    # shallower than a path cannot dive to it, and held its pitch-down sequence on for nothing).
    depth_within_m: float = Field(SteeringGains.depth_within_m, ge=0.0, le=10.0)
    # Pitch and roll errors within this are the stroke's own attitude: no correction, and a held
    # offset eases back to none (the crawl rides a few degrees off its calibrated pitch as it turns).
    attitude_within_deg: float = Field(0.0, ge=0.0, le=90.0)
    # Share of a pitch or roll error (beyond that) corrected at once, on top of the held offset.
    attitude_proportional: float = Field(SteeringGains.attitude_proportional, ge=0.0, le=2.0)
    min_tempo: float = Field(0.5, ge=0.1, le=1.0)
    # Full tempo from this far from the target, the slowest within 0.2 m, in between in proportion:
    # a stroke much faster at full tempo than the paths' 0.5 m/s (the backstroke, 1.37 m/s) ran past
    # its target and waited, over and over, when it swam flat out from 0.6 m off.
    full_tempo_beyond_m: float = Field(0.6, gt=0.2, le=20.0)     # TempoControl.far_m, beyond its near_m
    glide_within_m: float = Field(0.0, ge=0.0, le=10.0)
    glide_cycles: float = Field(1.0, gt=0.0, le=1.0)     # a glide's length in cycles
    # At least this tempo while turning more than 30 deg toward a target, unless more than
    # turn_tempo_until_ahead_s ahead of a moving one along its path (none: the tempo it has anyway).
    turn_tempo: float | None = Field(None, ge=0.5, le=1.5)
    turn_tempo_until_ahead_s: float = Field(0.0, ge=-10.0, le=10.0)
    # At turn_tempo too while behind a moving target along its path and farther than this from it
    # (none: never): at the target's pace the gap stays.
    catch_up_beyond_m: float | None = Field(None, gt=0.0, le=100.0)
    # Behind a moving target at the surface, swim at its pace plus the gap over this many seconds,
    # up to turn_tempo (none: at its pace, faster only by distance).
    close_gap_s: float | None = Field(None, gt=0.0, le=60.0)
    close_gap_beyond_m: float = Field(0.0, ge=0.0, le=20.0)     # ... only the gap beyond this
    # ... the gap as it will be this long from now at the speed gained on the target over the last
    # cycle (0: as it is now)
    close_gap_ahead_s: float = Field(0.0, ge=0.0, le=10.0)
    # At least this tempo while the point steered for lies more than 0.3 m below (none: any): a
    # stroke that lies nose-up when slow cannot pitch down far enough to dive at its pace.
    dive_tempo: float | None = Field(None, ge=0.5, le=1.5)
    # On a moving target's known path: aim lead_straight_s ahead of it where it runs straight (while
    # the target is under water or its path dives within 20 s: lead_straight_diving_s, none: the
    # same), up to lead_bend_s where it bends, and wait (slowest tempo, or glide) when more than
    # wait_ahead_s ahead of it.
    lead_straight_s: float = Field(1.5, ge=0.5, le=10.0)
    lead_straight_diving_s: float | None = Field(None, ge=0.5, le=10.0)
    lead_bend_s: float = Field(3.0, ge=0.5, le=10.0)
    wait_ahead_s: float = Field(0.5, ge=0.0, le=10.0)
    # ... and only within this of the path (farther off, swim back to it; a stroke that follows
    # loosely waits from farther).
    wait_within_m: float = Field(1.0, gt=0.0, le=100.0)
    # ... and, waiting, at least this tempo while turning more than 30 deg (none: the slowest): a
    # stroke whose slowest tempo is too slow to turn on lying down stands up there (the backstroke).
    wait_turn_tempo: float | None = Field(None, ge=0.1, le=1.5)
    # ... and at least the tempo whose steady speed is this share of the target's pace (none: the
    # slowest): a stroke that stalls at its slowest tempo (the breaststroke) is left standing.
    wait_pace: float | None = Field(None, gt=0.0, le=1.0)
    # ... and only within this of the depth it steers for (none: at any depth): a stroke that rides
    # up at its slowest tempo (the breaststroke) dives on instead of waiting above a diving path.
    wait_depth_within_m: float | None = Field(None, gt=0.0, le=10.0)
    # ... and, waiting where the path runs straight, head weave_deg off it, to one side and then the
    # other, turning back beyond weave_within_m out, at weave_tempo at least (none: straight on at
    # the slowest tempo): a stroke faster at its slowest tempo than its target (the backstroke) ran ahead.
    weave_deg: float | None = Field(None, gt=0.0, lt=90.0)
    weave_within_m: float = Field(0.6, gt=0.0, le=10.0)
    weave_tempo: float | None = Field(None, ge=0.1, le=1.5)
    # Steer upstream of the aim by the sideways drift measured over the last cycles (a current
    # across the path); the goal task's swims, which the shipped residuals learnt on, never do.
    aim_off: bool = False
    glide_moving_joints: list[str] = []
    # The largest weight the per-cycle layer gives a sequence (its offsets times this; the pose stays
    # inside the joints' ranges); `calibrate` measures turns up to it.
    max_weight: float = Field(1.0, ge=0.25, le=3.0, multiple_of=0.25)
    # Weights above 1 only for a heading turn wanted within this (a wider one takes cycles anyway).
    over_weight_within_deg: float = Field(180.0, gt=0.0, le=180.0)
    # The tempo falls from full with the target 30 deg off the heading to min_tempo this far off.
    wide_turn_deg: float = Field(90.0, gt=30.0, le=180.0)
    # Starting pitched nose up by more than this beyond any climb toward the target (standing up
    # from treading water), a lying stroke swims at level_off_tempo until it lies, taking its
    # ``level_off`` sequence, where it has one, instead of correcting pitch.
    level_off_beyond_deg: float = Field(35.0, gt=0.0, le=90.0)
    level_off_tempo: float = Field(1.0, ge=0.1, le=1.5)    # the tempo of those level-off cycles
    # ... and its pitch_down sequence at this weight in them, instead of the pitch correction (none:
    # the correction, which holds pitch_down to the weights it was calibrated at, lying)
    level_off_pitch_down_weight: float | None = Field(None, gt=0.0, le=3.0)
    # Mid-swim, after a cycle whose mean pitch was more than this nose up, or whose mean shoulder
    # roll was more than recover_beyond_roll_deg either way, a plain cycle (no sequence) at
    # level_off_tempo (none: never).
    recover_beyond_pitch_deg: float | None = Field(None, gt=0.0, le=90.0)
    recover_beyond_roll_deg: float | None = Field(None, gt=0.0, le=90.0)
    breathe: bool = False           # breathe out to sink and in to rise toward the target's depth
    # ... breathing out below the resting breath too (false: only in, to rise back from a push;
    # a crawl that emptied its lungs to dive sank legs first, nose up)
    breathe_out: bool = True
    # ... taking the depth error this many seconds ahead at the rate it closes (0: the error alone),
    # while the target lies deeper than under_water_below_m (where set)
    breathe_damping_s: float = Field(0.0, ge=0.0, le=20.0)
    # ... and there holds this much air at the target's depth (none: the resting breath)
    under_water_air_l: float | None = Field(None, ge=0.0, le=8.0)
    # Its ``under_water`` sequence at weight 1 while the point it steers for lies deeper than this
    # (none: never): under water a swimmer does not lift its head to breathe, and that lift rose the
    # breaststroke from 3 m with empty lungs.
    under_water_below_m: float | None = Field(None, gt=0.0, le=20.0)
    # ... and while it does, every control step its net pitch weight (+: pitch_down) moves by this
    # much per metre the pelvis lies above the target's depth under_water_depth_ahead_s on, plus
    # under_water_pitch_per_m_s per m/s it rises faster than that target (none: never;
    # control/depth_hold.py)
    under_water_pitch_per_m: float | None = Field(None, gt=0.0, le=20.0)
    under_water_pitch_per_m_s: float = Field(0.0, ge=0.0, le=20.0)
    under_water_depth_ahead_s: float = Field(0.0, ge=0.0, le=10.0)
    # ... and its cycle-by-cycle pitch correction steers to this pitch there, not to the pitch its
    # pace table gives at the surface (none: that one)
    under_water_level_pitch_deg: float | None = Field(None, ge=-45.0, le=45.0)
    # ... and corrects this share of its heading error a cycle there, not yaw_fraction (none: that
    # one): its yaw sequences, sized by the surface's table, turn it further under water
    under_water_yaw_fraction: float | None = Field(None, ge=0.0, le=1.0)

    @model_validator(mode="after")
    def _lead_ordered(self):
        straight_s = max(self.lead_straight_s, self.lead_straight_diving_s or 0.0)
        if self.lead_bend_s < straight_s:
            raise ValueError(f"lead_bend_s ({self.lead_bend_s:g} s) must be at least lead_straight_s and "
                             f"lead_straight_diving_s ({straight_s:g} s): a bend is aimed at no nearer")
        return self


class TrimSpec(Strict):
    """A posture for water far from the body's own density (``density_ratio``: the water's over the
    body's at its resting breath), added to every key pose: nothing in water near the body's
    density, all of ``joints`` at or beyond ``light_full`` / ``dense_full``, eased in between.
    In dense water the slowest tempo may ease toward ``dense_min_tempo`` too, and glides may hold
    every joint (``dense_still_glide``, from half the trim on): a body that rides high and level
    there swims on at tempos, and kicks on through glides, that leave it sinking nose-up in fresh
    water, so without these it cannot slow down for a slow target."""

    joints: dict[str, dict[str, Degrees]] = {}
    light_from: float = Field(0.97, gt=0.0, le=1.0)
    light_full: float = Field(0.93, gt=0.0, le=1.0)
    dense_from: float = Field(1.6, ge=1.0, le=10.0)
    dense_full: float = Field(2.4, ge=1.0, le=10.0)
    dense_min_tempo: float | None = Field(None, ge=0.1, le=1.0)
    dense_still_glide: bool = False

    @model_validator(mode="after")
    def _ordered(self):
        if not (self.light_full < self.light_from and self.dense_from < self.dense_full):
            raise ValueError("expected light_full < light_from and dense_from < dense_full")
        return self

    def weight(self, density_ratio: float) -> float:
        """How much of the trim to use, 0 to 1."""
        if density_ratio < self.light_from:
            share = (self.light_from - density_ratio) / (self.light_from - self.light_full)
        elif density_ratio > self.dense_from:
            share = (density_ratio - self.dense_from) / (self.dense_full - self.dense_from)
        else:
            return 0.0
        return ease(min(1.0, share))


class StrokeSpec(Strict):
    name: str
    description: str = ""
    period_s: between(0.2, 20.0)                   # human stroke cycles take 0.6 to 3 s
    interpolation: Literal["smooth", "linear"] = "smooth"
    start: StartSpec = StartSpec()
    rest_pose: dict[str, dict[str, Degrees]] = {}
    keys: dict[str, JointKeys] = {}
    pd_gain_scale: dict[str, between(0.01, 100.0)] = {}
    perturbations: dict[Sequence, PerturbationSpec] = {}
    rules: RulesSpec = RulesSpec()
    steering: SteeringSpec = SteeringSpec()
    trim: TrimSpec = TrimSpec()


@dataclass(frozen=True)
class CyclicTable:
    """A pose-sized quantity over one cycle: values and their rate per unit phase."""

    values: np.ndarray       # (TABLE_SAMPLES + 1, n), last row = first
    rates: np.ndarray

    def at(self, phase: float) -> tuple[np.ndarray, np.ndarray]:
        return _between_rows(self.values, self.rates, *_place(phase))

    def added(self, pose: np.ndarray, rate: np.ndarray, weight: float,
              phase: float) -> tuple[np.ndarray, np.ndarray]:
        """``pose + weight * value`` and ``rate + weight * its rate`` at ``phase`` (a weighted
        perturbation on a pose), as new arrays."""
        return _plus_between_rows(pose, rate, weight, self.values, self.rates, *_place(phase))


def _place(phase: float) -> tuple[int, float]:
    """The table row at or before ``phase`` (in cycles, any real number) and how far on to the next."""
    x = (phase % 1.0) * TABLE_SAMPLES
    i = min(int(x), TABLE_SAMPLES - 1)
    return i, x - i


@njit(cache=True, inline="always")
def _mixed(table, i, k, w):
    """Column k of rows i and i + 1 mixed by ``w``: numpy's ``a * (1 - w) + b * w``, the same bits."""
    return table[i, k] * (1.0 - w) + table[i + 1, k] * w


@njit(cache=True)
def _between_rows(values, rates, i, w):
    """Rows i and i + 1 of both tables mixed by ``w``, element by element (the controller asks it
    several times a control step)."""
    n = values.shape[1]
    pose, rate = np.empty(n), np.empty(n)
    for k in range(n):
        pose[k] = _mixed(values, i, k, w)
        rate[k] = _mixed(rates, i, k, w)
    return pose, rate


@njit(cache=True)
def _plus_between_rows(pose, rate, weight, values, rates, i, w):
    """``pose + weight * between`` (and the rates alike), ``between`` as ``_between_rows`` gives it."""
    n = values.shape[1]
    new_pose, new_rate = np.empty(n), np.empty(n)
    for k in range(n):
        new_pose[k] = pose[k] + weight * _mixed(values, i, k, w)
        new_rate[k] = rate[k] + weight * _mixed(rates, i, k, w)
    return new_pose, new_rate


@dataclass(frozen=True)
class Stroke:
    name: str
    description: str
    period_s: float
    start: StartSpec
    basic: CyclicTable                       # pose over one cycle, rad
    perturbations: dict[str, CyclicTable]    # offsets over one cycle at weight 1, rad
    rules: RulesSpec
    steering: SteeringSpec
    glide_moving: np.ndarray                 # (n,) bool: pose coordinates that keep stroking in a glide
    pd_gain_scale: dict[str, float]
    source: str
    spec_sha256: str                         # of the parsed file less its steering: calibration tables check it
    trim_spec: TrimSpec
    trim_rad: np.ndarray                     # (n,) the full trim's offsets

    def trimmed(self, density_ratio: float) -> "Stroke":
        """This stroke for water ``density_ratio`` times the body's density: its key poses moved by
        the share of the trim that water asks for (none near the body's own density), and in dense
        water its slowest tempo and glides as the trim says."""
        trim = self.trim_spec
        weight = trim.weight(density_ratio)
        if weight == 0.0:
            return self
        steering, glide_moving = self.steering, self.glide_moving
        if density_ratio > 1.0:
            if trim.dense_min_tempo is not None:
                min_tempo = steering.min_tempo + weight * (trim.dense_min_tempo - steering.min_tempo)
                steering = steering.model_copy(update={"min_tempo": min_tempo})
            if trim.dense_still_glide and weight >= 0.5:
                glide_moving = np.zeros_like(glide_moving)
        return replace(self, basic=CyclicTable(self.basic.values + weight * self.trim_rad, self.basic.rates),
                       steering=steering, glide_moving=glide_moving)

    @property
    def table(self) -> np.ndarray:
        return self.basic.values

    def pose(self, phase: float) -> tuple[np.ndarray, np.ndarray]:
        """Pose (rad) and its rate per unit phase at ``phase`` in cycles (any real number)."""
        return self.basic.at(phase)

    def start_state(self) -> Start:
        """The file's start: posture, depth and speed, at the origin heading +x."""
        return Start(self.start.posture, self.start.depth_m, self.start.speed_m_s)


def _cyclic_curve(keys: dict[float, float], shift: float, smooth: bool, where: str):
    times = np.array(sorted(keys), dtype=float)
    if np.any(times < 0) or np.any(times >= 1):
        raise ConfigError(f"{where}: key times must be fractions of the cycle in [0, 1)")
    values = np.radians([keys[t] for t in times])
    times = (times + shift) % 1.0
    order = np.argsort(times)
    times, values = times[order], values[order]
    samples = np.linspace(0.0, 1.0, TABLE_SAMPLES + 1)
    if len(times) == 1:
        return np.full_like(samples, values[0]), np.zeros_like(samples)
    tiled_t = np.concatenate([times - 1.0, times, times + 1.0])
    tiled_v = np.tile(values, 3)
    if smooth:
        curve = PchipInterpolator(tiled_t, tiled_v)
        return curve(samples), curve.derivative()(samples)
    value = np.interp(samples, tiled_t, tiled_v)
    slope = np.gradient(value, samples)
    return value, slope


def _keyed_table(keys: dict[str, JointKeys], base: np.ndarray, layout: JointLayout, joints: set[str],
                 smooth: bool, field: str) -> CyclicTable:
    """Tabulate per-joint keys over one cycle on top of ``base`` (unkeyed axes keep it)."""
    table = np.tile(base, (TABLE_SAMPLES + 1, 1))
    rates = np.zeros_like(table)
    for joint, joint_keys in keys.items():
        where = f"{field}.{joint}"
        source_keys = joint_keys
        if joint_keys.mirror_of is not None:
            mirrored = keys.get(joint_keys.mirror_of)
            if mirrored is None or mirrored.mirror_of is not None:
                raise ConfigError(f"{where}': mirror_of '{joint_keys.mirror_of}' must name a keyed joint "
                                  "that is not itself a mirror")
            if joint_keys.axis_keys():
                raise ConfigError(f"{where}': a mirrored joint takes no keys of its own")
            source_keys = mirrored
        for axis, axis_keys in source_keys.axis_keys().items():
            k = _coord(layout, joints, joint, axis, f"{where}.{axis}'")
            if not isinstance(axis_keys, dict) or not axis_keys:
                raise ConfigError(f"{where}.{axis}': expected a mapping of cycle fraction to degrees")
            try:
                parsed = {float(t): float(v) for t, v in axis_keys.items()}
            except (TypeError, ValueError):
                raise ConfigError(f"{where}.{axis}': keys and values must be numbers") from None
            if not all(np.isfinite(list(parsed)) & (np.abs(list(parsed.values())) <= 360.0)):
                raise ConfigError(f"{where}.{axis}': keys must be finite and angles within +-360 degrees")
            table[:, k], rates[:, k] = _cyclic_curve(parsed, joint_keys.phase_shift, smooth, f"{where}.{axis}'")
    return CyclicTable(table, rates)


def _swap_side(joint: str) -> str:
    for a, b in (("_l", "_r"), ("_r", "_l")):
        if joint.endswith(a):
            return joint[: -len(a)] + b
    return joint


def mirrored_keys(keys: dict[str, JointKeys], phase_shift: float = 0.0) -> dict[str, JointKeys]:
    """Left-right mirror, ``phase_shift`` cycles later: _l and _r joints swap keys (their axes are
    mirrored already); on midline joints the axes named ``*_left`` change sign."""
    out = {}
    for joint, joint_keys in keys.items():
        midline = _swap_side(joint) == joint
        axes = {axis: ({t: -v for t, v in values.items()} if midline and axis.endswith("_left") else values)
                for axis, values in joint_keys.axis_keys().items()}
        mirror_of = _swap_side(joint_keys.mirror_of) if joint_keys.mirror_of else None
        shift = (joint_keys.phase_shift + (0.0 if mirror_of else phase_shift)) % 1.0   # a mirror follows its source
        out[_swap_side(joint)] = JointKeys.model_validate({**axes, "mirror_of": mirror_of, "phase_shift": shift})
    return out


def _first_out_of_range(poses_rad: np.ndarray, layout: JointLayout) -> int | None:
    """The first pose coordinate that leaves its range of motion anywhere in ``poses_rad``
    (rows: poses), or None."""
    outside = ((poses_rad < layout.lower_rad - 1e-9) | (poses_rad > layout.upper_rad + 1e-9)).any(axis=0)
    return int(np.argmax(outside)) if outside.any() else None


def build_stroke(spec: StrokeSpec, layout: JointLayout, source: str) -> Stroke:
    joints = {name.split(".")[0] for name in layout.names}
    rest = np.zeros(layout.size)
    for joint, axes in spec.rest_pose.items():
        for axis, deg in axes.items():
            rest[_coord(layout, joints, joint, axis, f"{source}: field 'rest_pose.{joint}.{axis}'")] = np.radians(deg)
    smooth = spec.interpolation == "smooth"
    basic = _keyed_table(spec.keys, rest, layout, joints, smooth, f"{source}: field 'keys")
    k = _first_out_of_range(basic.values, layout)
    if k is not None:
        lo, hi = np.degrees(layout.lower_rad[k]), np.degrees(layout.upper_rad[k])
        raise ConfigError(f"{source}: field 'keys.{layout.names[k]}': angles leave the range of motion "
                          f"[{lo:.0f}, {hi:.0f}] deg")
    perturbations = {}
    for name, seq in spec.perturbations.items():
        field = f"{source}: field 'perturbations.{name}"
        keys = seq.keys
        if seq.mirror_of is not None:
            original = spec.perturbations.get(seq.mirror_of)
            if original is None or original.mirror_of is not None or seq.keys:
                raise ConfigError(f"{field}': mirror_of '{seq.mirror_of}' must name a sequence with keys of its "
                                  f"own, and a mirrored sequence takes none")
            keys = mirrored_keys(original.keys, seq.phase_shift)
        perturbations[name] = _keyed_table(keys, np.zeros(layout.size), layout, joints, smooth, f"{field}.keys")
    for joint in spec.pd_gain_scale:
        if joint not in joints:
            raise ConfigError(f"{source}: field 'pd_gain_scale.{joint}': unknown joint")
    if spec.steering.under_water_below_m is not None and UNDER_WATER not in spec.perturbations:
        raise ConfigError(f"{source}: field 'steering.under_water_below_m': the stroke has no {UNDER_WATER} sequence")
    for name in ("under_water_pitch_per_m", "under_water_level_pitch_deg", "under_water_yaw_fraction"):
        if getattr(spec.steering, name) is not None and spec.steering.under_water_below_m is None:
            raise ConfigError(f"{source}: field 'steering.{name}': needs steering.under_water_below_m "
                              f"(it acts only under water)")
    if spec.steering.level_off_pitch_down_weight is not None and PITCH_DOWN not in spec.perturbations:
        raise ConfigError(f"{source}: field 'steering.level_off_pitch_down_weight': the stroke has no "
                          f"{PITCH_DOWN} sequence")
    for joint in spec.steering.glide_moving_joints:
        if joint not in joints:
            raise ConfigError(f"{source}: field 'steering.glide_moving_joints': unknown joint '{joint}'")
    glide_moving = np.array([name.split(".")[0] in spec.steering.glide_moving_joints for name in layout.names])
    trim = np.zeros(layout.size)
    for joint, axes in spec.trim.joints.items():
        for axis, deg in axes.items():
            trim[_coord(layout, joints, joint, axis, f"{source}: field 'trim.joints.{joint}.{axis}'")] = np.radians(deg)
    k = _first_out_of_range(basic.values + trim, layout)
    if k is not None:
        raise ConfigError(f"{source}: field 'trim.joints': {layout.names[k]} with its trim leaves the range of motion")
    # What calibration measures: it swims without the rules, and the steering settings only read
    # its table, so both stay out; so does the trim, nothing in the water calibration swims in,
    # and the level-off, under-water and roll-over sequences, which steering takes only at a start
    # standing up, below the surface or turned over.
    exclude = {"steering": True, "rules": True, "trim": True, "perturbations": set(UNCALIBRATED_SEQUENCES)}
    digest = hashlib.sha256(json.dumps(spec.model_dump(mode="json", exclude=exclude),
                                       sort_keys=True).encode()).hexdigest()
    return Stroke(spec.name, spec.description, spec.period_s, spec.start, basic, perturbations, spec.rules,
                  spec.steering, glide_moving, dict(spec.pd_gain_scale), source, digest, spec.trim, trim)


def _coord(layout: JointLayout, joints: set[str], joint: str, axis: str, where: str) -> int:
    if joint not in joints:
        raise ConfigError(f"{where}: unknown joint '{joint}' (joints: {', '.join(sorted(joints))})")
    try:
        return layout.index(f"{joint}.{axis}")
    except KeyError:
        axes = [n.split(".")[1] for n in layout.names if n.startswith(joint + ".")]
        raise ConfigError(f"{where}: joint '{joint}' has no axis '{axis}' (axes: {', '.join(axes)})") from None


def available_strokes(directory: Path | None = None) -> list[str]:
    return available_files(directory or search_dirs("strokes"))


def stroke_path(name_or_path: str, directory: Path | None = None) -> Path:
    return file_path(name_or_path, directory or search_dirs("strokes"), "stroke")


def load_stroke(name_or_path: str, layout: JointLayout, directory: Path | None = None) -> Stroke:
    path = stroke_path(name_or_path, directory)
    return build_stroke(load(StrokeSpec, path), layout, str(path))
