"""The per-cycle layer's calibration table (Yang 4.3): each perturbation sequence's turn per cycle
at a grid of weights and tempos, read from ``strokes/calibration/<stroke>.yaml`` and inverted
to pick the weight that turns the swimmer through the wanted angle; and the stroke's pace, its
steady speed, roll, pitch and depth over a wider range of tempos. ``layered-swim calibrate``
measures it (``layered_swim/analysis/calibrate.py``). A table made from a different version of
the stroke file is stale: loading it is an error that says how to remake it.
"""
from __future__ import annotations

import math
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import yaml
from pydantic import Field, model_validator

from layered_swim.config import ConfigError, Degrees, Strict, between, load
from layered_swim.control.stroke import Sequence, Stroke
from layered_swim.outputs import write_text

SEQUENCE_AXIS = {"yaw_left": ("yaw", 1.0), "yaw_right": ("yaw", -1.0), "pitch_up": ("pitch", 1.0),
                 "pitch_down": ("pitch", -1.0), "roll_left": ("roll", 1.0), "roll_right": ("roll", -1.0)}


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

    @model_validator(mode="after")
    def _shapes(self) -> "CalibrationSpec":
        _increasing(self.weights, "weights")
        _increasing(self.tempos, "tempos")
        n = len(self.tempos)
        for name, rows in self.turn_deg_per_cycle.items():
            if len(rows) != n or any(len(row) != len(self.weights) for row in rows):
                raise ValueError(f"turn_deg_per_cycle.{name} needs {n} rows of {len(self.weights)} numbers")
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
    turn_rad: dict[str, np.ndarray]            # per sequence (n_tempos, n_weights), in its own direction

    def turn_at(self, sequence: str, tempo: float) -> np.ndarray:
        rows = self.turn_rad[sequence]
        if len(self.tempos) == 1:
            return rows[0]
        return np.array([np.interp(tempo, self.tempos, rows[:, k]) for k in range(len(self.weights))])

    def weight_for(self, sequence: str, wanted_rad: float, tempo: float) -> float:
        """Smallest weight whose calibrated turn reaches ``wanted_rad`` (>= 0), capped at the grid's end."""
        turns = np.maximum.accumulate(self.turn_at(sequence, tempo))   # a dip means saturation
        if wanted_rad <= turns[0]:
            return 0.0
        if wanted_rad >= turns[-1]:
            return float(self.weights[-1])
        i = int(np.searchsorted(turns, wanted_rad, side="left"))      # first grid weight that reaches it
        w0, w1, t0, t1 = self.weights[i - 1], self.weights[i], turns[i - 1], turns[i]
        return float(w0 + (w1 - w0) * (wanted_rad - t0) / (t1 - t0))

    def weights_for(self, wanted: dict[str, float], tempo: float) -> dict[str, float]:
        """Wanted signed turns per axis -> one weight per sequence (the sequence turning that way)."""
        out = {}
        for sequence, (axis, sign) in SEQUENCE_AXIS.items():
            amount = sign * wanted.get(axis, 0.0)
            if amount > 0 and sequence in self.turn_rad:
                out[sequence] = self.weight_for(sequence, amount, tempo)
        return out


def calibration_path(stroke: Stroke, directory: Path | None = None) -> Path:
    """A stroke's table: ``calibration/<name>.yaml`` beside its stroke file, unless ``directory``."""
    return (directory or Path(stroke.source).parent / "calibration") / f"{stroke.name}.yaml"


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
        "turn_deg_per_cycle": {name: [[round(math.degrees(v), 3) for v in row] for row in rows]
                               for name, rows in table.turn_rad.items()},
    }
    header = (f"# Generated by `layered-swim calibrate --stroke {table.stroke}`; do not edit.\n"
              "# turn_deg_per_cycle[sequence][tempo index][weight index], in the sequence's own direction.\n")
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
        turn_rad={name: np.radians(np.array(rows, dtype=float)) for name, rows in spec.turn_deg_per_cycle.items()})
