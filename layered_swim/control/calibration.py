"""The per-cycle layer's calibration table (Yang 4.3), read from ``strokes/calibration/<stroke>.yaml``
at a grid of weights and tempos: each yaw sequence's turn per cycle, inverted to pick the weight
that turns the swimmer through the wanted angle; each pitch and roll sequence's held attitude
(a pitch or roll sequence does not keep turning the body cycle after cycle: the water and the
buoyancy hold it at an offset, reached within a cycle), inverted to pick the weight that holds
the wanted offset; and the stroke's pace, its steady speed, roll, pitch and depth over a wider
range of tempos. ``layered-swim calibrate``
measures it (``layered_swim/analysis/calibrate.py``). A table made from a different version of
the stroke file is stale: loading it is an error that says how to remake it.
"""
from __future__ import annotations

import math
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
import yaml
from pydantic import Field, model_validator

from layered_swim.config import ConfigError, Degrees, Strict, between, load
from layered_swim.control.stroke import Sequence, Stroke
from layered_swim.outputs import write_text

SEQUENCE_AXIS = {"yaw_left": ("yaw", 1.0), "yaw_right": ("yaw", -1.0), "pitch_up": ("pitch", 1.0),
                 "pitch_down": ("pitch", -1.0), "roll_left": ("roll", 1.0), "roll_right": ("roll", -1.0)}
TURN_SEQUENCES = ("yaw_left", "yaw_right")


class CalibrationError(ConfigError):
    """The stroke's table is missing, malformed or stale: the per-cycle layer cannot steer it."""


def _increasing(values: list[float], field: str) -> None:
    if not all(b > a for a, b in zip(values, values[1:])):
        raise ValueError(f"{field} must increase")


class PaceSpec(Strict):
    """The unperturbed stroke swum straight at each tempo: its steady speed, its own cycle-mean
    shoulder roll and body pitch (what steering counts as level), and the depth its centre of
    mass ends at."""

    tempos: list[between(0.05, 5.0)] = Field(min_length=1)
    speed_m_s: list[between(-5.0, 5.0)]
    roll_deg: list[between(-90.0, 90.0)]
    pitch_deg: list[between(-90.0, 90.0)]
    depth_m: list[between(-5.0, 50.0)]

    @model_validator(mode="after")
    def _shapes(self) -> "PaceSpec":
        _increasing(self.tempos, "pace.tempos")
        n = len(self.tempos)
        if any(len(values) != n for values in (self.speed_m_s, self.roll_deg, self.pitch_deg, self.depth_m)):
            raise ValueError(f"pace: speed_m_s, roll_deg, pitch_deg and depth_m need one value per tempo ({n})")
        return self


class CalibrationSpec(Strict):
    """The file as ``save_table`` writes it."""

    stroke: str
    stroke_sha256: str
    weights: list[between(0.0, 10.0)] = Field(min_length=2)
    tempos: list[between(0.05, 5.0)] = Field(min_length=1)
    pace: PaceSpec
    turn_deg_per_cycle: dict[Sequence, list[list[Degrees]]]
    attitude_deg: dict[Sequence, list[list[Degrees]]] = {}

    @model_validator(mode="after")
    def _shapes(self) -> "CalibrationSpec":
        _increasing(self.weights, "weights")
        _increasing(self.tempos, "tempos")
        n = len(self.tempos)
        for key, table in (("turn_deg_per_cycle", self.turn_deg_per_cycle), ("attitude_deg", self.attitude_deg)):
            for name, rows in table.items():
                if (name in TURN_SEQUENCES) != (key == "turn_deg_per_cycle"):
                    raise ValueError(f"{key}.{name}: yaw sequences belong in turn_deg_per_cycle, "
                                     "pitch and roll sequences in attitude_deg")
                if len(rows) != n or any(len(row) != len(self.weights) for row in rows):
                    raise ValueError(f"{key}.{name} needs {n} rows of {len(self.weights)} numbers")
        return self


@dataclass(frozen=True)
class Pace:
    """The unperturbed stroke at each of ``tempos`` (increasing): steady speed, cycle-mean shoulder
    roll (left up > 0) and body pitch (nose up > 0), and the depth of its centre of mass at the end."""

    tempos: tuple[float, ...]
    speed_m_s: tuple[float, ...]
    roll_rad: tuple[float, ...]
    pitch_rad: tuple[float, ...]
    depth_m: tuple[float, ...]

    def roll_at(self, tempo: float) -> float:
        """The unperturbed stroke's mean roll: the level the per-cycle layer steers back to."""
        return float(np.interp(tempo, self.tempos, self.roll_rad))

    def pitch_at(self, tempo: float) -> float:
        """The unperturbed stroke's mean pitch: what the per-cycle layer counts as level."""
        return float(np.interp(tempo, self.tempos, self.pitch_rad))

    def tempo_for_speed(self, speed_m_s: float) -> float:
        """The tempo that swims ``speed_m_s`` steadily (read off the rising part of the table; the end
        tempos beyond its range)."""
        return float(np.interp(speed_m_s, np.maximum.accumulate(self.speed_m_s), self.tempos))

    def speed_at(self, tempo: float) -> float:
        return float(np.interp(tempo, self.tempos, self.speed_m_s))


@dataclass(frozen=True)
class CalibrationTable:
    stroke: str
    stroke_sha256: str
    weights: tuple[float, ...]
    tempos: tuple[float, ...]
    pace: Pace
    turn_rad: dict[str, np.ndarray]            # per yaw sequence (n_tempos, n_weights), in its own direction
    # per pitch or roll sequence (n_tempos, n_weights): the change of the cycle-mean pitch (nose up > 0)
    # or shoulder roll (left up > 0) it holds, whichever way its name says
    attitude_rad: dict[str, np.ndarray] = field(default_factory=dict)

    def _at(self, rows: np.ndarray, tempo: float) -> np.ndarray:
        if len(self.tempos) == 1:
            return rows[0]
        return np.array([np.interp(tempo, self.tempos, rows[:, k]) for k in range(len(self.weights))])

    def turn_at(self, sequence: str, tempo: float) -> np.ndarray:
        return self._at(self.turn_rad[sequence], tempo)

    def weight_for(self, sequence: str, wanted_rad: float, tempo: float) -> float:
        """Smallest weight whose calibrated turn reaches ``wanted_rad`` (>= 0), capped at the grid's end."""
        return self._inverse(self.turn_at(sequence, tempo), wanted_rad)

    def _inverse(self, effects: np.ndarray, wanted: float) -> float:
        effects = np.maximum.accumulate(effects)   # a dip means saturation
        if wanted <= effects[0]:
            return 0.0
        if wanted >= effects[-1]:
            return float(self.weights[-1])
        i = int(np.searchsorted(effects, wanted, side="left"))      # first grid weight that reaches it
        w0, w1, e0, e1 = self.weights[i - 1], self.weights[i], effects[i - 1], effects[i]
        return float(w0 + (w1 - w0) * (wanted - e0) / (e1 - e0))

    def weights_for(self, wanted_yaw_rad: float, tempo: float) -> dict[str, float]:
        """A wanted signed heading turn (+ left) -> the weight of the yaw sequence turning that way."""
        out = {}
        for sequence in TURN_SEQUENCES:
            amount = SEQUENCE_AXIS[sequence][1] * wanted_yaw_rad
            if amount > 0 and sequence in self.turn_rad:
                out[sequence] = self.weight_for(sequence, amount, tempo)
        return out

    def _holding(self, axis: str, tempo: float, sign: float) -> tuple[str, np.ndarray] | None:
        """The sequence of ``axis`` that holds the largest offset of ``sign``, and its offsets (made
        positive) at each weight; a sequence that holds its axis the other way than its name says
        (one authored for another version of the stroke) is used for the way it does."""
        best = None
        for sequence, rows in self.attitude_rad.items():
            if SEQUENCE_AXIS[sequence][0] == axis:
                effects = sign * self._at(rows, tempo)
                if effects.max() > 0.0 and (best is None or effects.max() > best[1].max()):
                    best = (sequence, effects)
        return best

    def attitude_range(self, axis: str, tempo: float) -> tuple[float, float]:
        """The lowest and highest offsets of ``axis`` its sequences hold at ``tempo`` (0 where none)."""
        low, high = self._holding(axis, tempo, -1.0), self._holding(axis, tempo, 1.0)
        return (-float(low[1].max()) if low else 0.0), (float(high[1].max()) if high else 0.0)

    def attitude_weights(self, axis: str, offset_rad: float, tempo: float) -> dict[str, float]:
        """The weight of the sequence that holds ``axis`` (pitch or roll) at ``offset_rad`` from the
        unperturbed stroke's attitude (at most its calibrated largest)."""
        holding = self._holding(axis, tempo, math.copysign(1.0, offset_rad)) if offset_rad else None
        if holding is None:
            return {}
        weight = self._inverse(holding[1], abs(offset_rad))
        return {holding[0]: weight} if weight > 0.0 else {}


def calibration_path(stroke: Stroke, directory: Path | None = None) -> Path:
    """A stroke's table: ``calibration/<name>.yaml`` beside its stroke file, unless ``directory``."""
    return (directory or Path(stroke.source).parent / "calibration") / f"{stroke.name}.yaml"


def _degrees(table: dict[str, np.ndarray]) -> dict[str, list[list[float]]]:
    return {name: [[round(math.degrees(v), 3) for v in row] for row in rows] for name, rows in table.items()}


def save_table(table: CalibrationTable, path: Path) -> Path:
    path.parent.mkdir(parents=True, exist_ok=True)
    data = {
        "stroke": table.stroke,
        "stroke_sha256": table.stroke_sha256,
        "weights": list(table.weights),
        "tempos": list(table.tempos),
        "pace": {"tempos": list(table.pace.tempos), "speed_m_s": [round(s, 4) for s in table.pace.speed_m_s],
                 "roll_deg": [round(math.degrees(a), 3) for a in table.pace.roll_rad],
                 "pitch_deg": [round(math.degrees(a), 3) for a in table.pace.pitch_rad],
                 "depth_m": [round(d, 3) for d in table.pace.depth_m]},
        "turn_deg_per_cycle": _degrees(table.turn_rad),
        "attitude_deg": _degrees(table.attitude_rad),
    }
    header = (f"# Generated by `layered-swim calibrate --stroke {table.stroke}`; do not edit.\n"
              "# turn_deg_per_cycle[yaw sequence][tempo index][weight index], in the sequence's own direction;\n"
              "# attitude_deg[pitch or roll sequence][tempo index][weight index]: the cycle-mean pitch (nose up > 0)\n"
              "# or shoulder roll (left up > 0) it holds, less the unperturbed stroke's.\n")
    write_text(path, header + yaml.safe_dump(data, sort_keys=False, default_flow_style=None))
    return path


def load_table(stroke: Stroke, directory: Path | None = None) -> CalibrationTable:
    path = calibration_path(stroke, directory)
    remake = f"run `layered-swim calibrate --stroke {stroke.name}`"
    if not path.exists():
        raise CalibrationError(f"{path}: no calibration table for stroke '{stroke.name}'; {remake}")
    try:
        spec = load(CalibrationSpec, path)
    except ConfigError as err:
        raise CalibrationError(f"{err}; {remake}") from None
    if spec.stroke_sha256 != stroke.spec_sha256:
        raise CalibrationError(f"{path}: stale calibration table (stroke file {stroke.source} changed since); {remake}")
    if not math.isclose(spec.weights[-1], stroke.steering.max_weight):
        raise CalibrationError(f"{path}: calibrated up to weight {spec.weights[-1]:g}, but {stroke.source} field "
                               f"'steering.max_weight' is {stroke.steering.max_weight:g}; {remake}")
    return CalibrationTable(
        stroke=spec.stroke, stroke_sha256=spec.stroke_sha256, weights=tuple(spec.weights), tempos=tuple(spec.tempos),
        pace=Pace(tuple(spec.pace.tempos), tuple(spec.pace.speed_m_s),
                  tuple(math.radians(a) for a in spec.pace.roll_deg),
                  tuple(math.radians(a) for a in spec.pace.pitch_deg), tuple(spec.pace.depth_m)),
        turn_rad={name: np.radians(np.array(rows, dtype=float)) for name, rows in spec.turn_deg_per_cycle.items()},
        attitude_rad={name: np.radians(np.array(rows, dtype=float)) for name, rows in spec.attitude_deg.items()})
