"""The basic stroke layer: a cyclic pose control graph read from a stroke file.

Each joint axis is keyed on its own over one cycle (``{fraction of cycle: degrees}``); an axis
without keys holds the rest pose. Keys are joined by a periodic, overshoot-free cubic (PCHIP on
three tiled cycles) and tabulated once, so evaluating a pose in the loop is a table lookup.
A joint may copy another's keys (``mirror_of``) shifted by a fraction of the cycle, which is how
left and right arms alternate in front crawl.
"""
from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path
from typing import Literal

import numpy as np
from pydantic import Field, PositiveFloat, model_validator
from scipy.interpolate import PchipInterpolator

from layered_swim.config import ConfigError, Strict, load
from layered_swim.control.pose import JointLayout

STROKES_DIR = Path(__file__).resolve().parents[2] / "strokes"
TABLE_SAMPLES = 1024


class JointKeys(Strict):
    """Keys for one joint: per axis a mapping cycle fraction -> degrees, or a mirror."""

    model_config = Strict.model_config | {"extra": "allow"}
    mirror_of: str | None = None
    phase_shift: float = Field(0.0, ge=-1.0, le=1.0)

    def axis_keys(self) -> dict[str, dict[float, float]]:
        return dict(self.__pydantic_extra__ or {})


class StartSpec(Strict):
    posture: Literal["prone", "upright"] = "prone"
    depth_m: float = Field(0.0, ge=-1.0, le=10.0)     # pelvis centre below the surface
    speed_m_s: float = Field(0.0, ge=0.0, le=3.0)


class StrokeSpec(Strict):
    name: str
    description: str = ""
    period_s: PositiveFloat
    interpolation: Literal["smooth", "linear"] = "smooth"
    start: StartSpec = StartSpec()
    rest_pose: dict[str, dict[str, float]] = {}
    keys: dict[str, JointKeys] = {}
    pd_gain_scale: dict[str, PositiveFloat] = {}


@dataclass(frozen=True)
class Stroke:
    name: str
    description: str
    period_s: float
    start: StartSpec
    table: np.ndarray        # (TABLE_SAMPLES + 1, n) pose over one cycle, rad (last row = first)
    rate_table: np.ndarray   # (TABLE_SAMPLES + 1, n) d pose / d phase, rad per cycle
    pd_gain_scale: dict[str, float]
    source: str

    def pose(self, phase: float) -> tuple[np.ndarray, np.ndarray]:
        """Pose (rad) and its rate per unit phase at ``phase`` in cycles (any real number)."""
        x = (phase % 1.0) * TABLE_SAMPLES
        i = min(int(x), TABLE_SAMPLES - 1)
        w = x - i
        pose = self.table[i] * (1.0 - w) + self.table[i + 1] * w
        rate = self.rate_table[i] * (1.0 - w) + self.rate_table[i + 1] * w
        return pose, rate


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


def build_stroke(spec: StrokeSpec, layout: JointLayout, source: str) -> Stroke:
    joints = {name.split(".")[0] for name in layout.names}
    n = layout.size
    rest = np.zeros(n)
    for joint, axes in spec.rest_pose.items():
        for axis, deg in axes.items():
            rest[_coord(layout, joints, joint, axis, f"{source}: field 'rest_pose.{joint}.{axis}'")] = np.radians(deg)
    table = np.tile(rest, (TABLE_SAMPLES + 1, 1))
    rates = np.zeros_like(table)
    smooth = spec.interpolation == "smooth"
    for joint, keys in spec.keys.items():
        where = f"{source}: field 'keys.{joint}"
        source_keys = keys
        if keys.mirror_of is not None:
            if keys.mirror_of not in spec.keys or spec.keys[keys.mirror_of].mirror_of is not None:
                raise ConfigError(f"{where}': mirror_of '{keys.mirror_of}' must name a keyed joint that is not itself a mirror")
            if keys.axis_keys():
                raise ConfigError(f"{where}': a mirrored joint takes no keys of its own")
            source_keys = spec.keys[keys.mirror_of]
        for axis, axis_keys in source_keys.axis_keys().items():
            k = _coord(layout, joints, joint, axis, f"{where}.{axis}'")
            if not isinstance(axis_keys, dict) or not axis_keys:
                raise ConfigError(f"{where}.{axis}': expected a mapping of cycle fraction to degrees")
            try:
                parsed = {float(t): float(v) for t, v in axis_keys.items()}
            except (TypeError, ValueError):
                raise ConfigError(f"{where}.{axis}': keys and values must be numbers") from None
            if not all(np.isfinite(list(parsed)) & np.isfinite(list(parsed.values()))):
                raise ConfigError(f"{where}.{axis}': keys and values must be finite numbers")
            table[:, k], rates[:, k] = _cyclic_curve(parsed, keys.phase_shift, smooth, f"{where}.{axis}'")
    outside = (table < layout.lower_rad - 1e-9) | (table > layout.upper_rad + 1e-9)
    if outside.any():
        k = int(np.argwhere(outside.any(axis=0))[0, 0])
        lo, hi = np.degrees(layout.lower_rad[k]), np.degrees(layout.upper_rad[k])
        raise ConfigError(f"{source}: field 'keys.{layout.names[k]}': angles leave the range of motion "
                          f"[{lo:.0f}, {hi:.0f}] deg")
    for joint in spec.pd_gain_scale:
        if joint not in joints:
            raise ConfigError(f"{source}: field 'pd_gain_scale.{joint}': unknown joint")
    return Stroke(spec.name, spec.description, spec.period_s, spec.start, table, rates,
                  dict(spec.pd_gain_scale), source)


def _coord(layout: JointLayout, joints: set[str], joint: str, axis: str, where: str) -> int:
    if joint not in joints:
        raise ConfigError(f"{where}: unknown joint '{joint}' (joints: {', '.join(sorted(joints))})")
    try:
        return layout.index(f"{joint}.{axis}")
    except KeyError:
        axes = [n.split(".")[1] for n in layout.names if n.startswith(joint + ".")]
        raise ConfigError(f"{where}: joint '{joint}' has no axis '{axis}' (axes: {', '.join(axes)})") from None


def available_strokes(directory: Path = STROKES_DIR) -> list[str]:
    return sorted(p.stem for p in directory.glob("*.yaml"))


def stroke_path(name_or_path: str, directory: Path = STROKES_DIR) -> Path:
    candidate = Path(name_or_path)
    if candidate.suffix in (".yaml", ".yml"):
        return candidate
    path = directory / f"{name_or_path}.yaml"
    if not path.exists():
        raise ConfigError(f"unknown stroke '{name_or_path}' (available: {', '.join(available_strokes(directory))})")
    return path


def load_stroke(name_or_path: str, layout: JointLayout, directory: Path = STROKES_DIR) -> Stroke:
    path = stroke_path(name_or_path, directory)
    return build_stroke(load(StrokeSpec, path), layout, str(path))
