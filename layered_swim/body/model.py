"""The body file (YAML) and the resolved body the simulation uses.

``load_body`` validates the file and returns a ``Body``: per-segment arrays (mass, box half
extents, displaced volume, buoyancy ellipsoid) in segment order, and the joints with their
axes, ranges and PD gains. Everything is SI; degrees exist only in the file.
"""
from __future__ import annotations

from dataclasses import dataclass, replace
from importlib import resources
from pathlib import Path
from typing import Literal

import numpy as np
from pydantic import field_validator, model_validator

from layered_swim.config import ConfigError, Degrees, Strict, Vec3, between, load
from layered_swim.state import Segments

DEFAULT_BODY_FILE = resources.files("layered_swim.body") / "swimmer.yaml"
AXES_PER_JOINT_TYPE = {"ball": 3, "hinge": 1, "two_axis": 2}


class JointAxisSpec(Strict):
    axis: Vec3
    min_deg: Degrees
    max_deg: Degrees

    @model_validator(mode="after")
    def _check(self) -> "JointAxisSpec":
        if np.linalg.norm(self.axis.as_tuple()) < 1e-9:
            raise ValueError("axis must not be zero")
        if not self.min_deg < self.max_deg:
            raise ValueError(f"min_deg ({self.min_deg}) must be below max_deg ({self.max_deg})")
        return self


class PDSpec(Strict):
    kp: between(0.0, 1e5, above=True)
    kd: between(0.0, 1e4)
    max_torque_nm: between(0.0, 1e4, above=True)


class JointSpec(Strict):
    type: Literal["ball", "hinge", "two_axis"]
    pd: PDSpec
    axes: dict[str, JointAxisSpec]

    @model_validator(mode="after")
    def _check(self) -> "JointSpec":
        wanted = AXES_PER_JOINT_TYPE[self.type]
        if len(self.axes) != wanted:
            raise ValueError(f"a {self.type} joint needs {wanted} axes, got {len(self.axes)}")
        return self


class SizeSpec(Vec3):
    @model_validator(mode="after")
    def _positive(self) -> "SizeSpec":
        if min(self.as_tuple()) <= 0:
            raise ValueError("box sizes must be positive")
        return self


Density = between(100.0, 5000.0)          # foam to stone, kg/m3


class SegmentSpec(Strict):
    mass_kg: between(0.0, 300.0, above=True)
    density_kg_m3: Density
    size_m: SizeSpec
    parent: str | None = None
    joint: str | None = None
    joint_at_m: Vec3 | None = None
    center_m: Vec3 = Vec3(x=0.0, y=0.0, z=0.0)

    @model_validator(mode="after")
    def _check(self) -> "SegmentSpec":
        has = [self.parent is not None, self.joint is not None, self.joint_at_m is not None]
        if any(has) and not all(has):
            raise ValueError("a child segment needs parent, joint and joint_at_m together")
        return self


class LungSpec(Strict):
    segment: str
    residual_volume_l: between(0.0, 10.0)
    default_air_l: between(0.0, 10.0)
    max_air_l: between(0.0, 10.0) = 5.5      # the most air a breath adds above the residual volume


class BodySpec(Strict):
    name: str
    total_mass_kg: between(0.0, 500.0, above=True)
    mean_density_kg_m3: Density
    lungs: LungSpec
    gimbal_mass_kg: between(0.0, 10.0, above=True)
    segments: dict[str, SegmentSpec]
    joints: dict[str, JointSpec]

    @field_validator("segments")
    @classmethod
    def _tree(cls, segments: dict[str, SegmentSpec]) -> dict[str, SegmentSpec]:
        roots = [name for name, seg in segments.items() if seg.parent is None]
        if len(roots) != 1:
            raise ValueError(f"exactly one segment must have no parent, found {roots}")
        seen: set[str] = set()
        for name, seg in segments.items():
            if seg.parent is not None and seg.parent not in seen:
                raise ValueError(f"segment '{name}': parent '{seg.parent}' must be listed before it")
            seen.add(name)
        return segments

    @model_validator(mode="after")
    def _references(self) -> "BodySpec":
        used = [seg.joint for seg in self.segments.values() if seg.joint is not None]
        for joint in used:
            if joint not in self.joints:
                raise ValueError(f"joint '{joint}' is used by a segment but not defined under joints")
        unused = set(self.joints) - set(used)
        if unused:
            raise ValueError(f"joints not used by any segment: {sorted(unused)}")
        if len(set(used)) != len(used):
            raise ValueError("each joint may connect only one segment")
        if self.lungs.segment not in self.segments:
            raise ValueError(f"lungs.segment '{self.lungs.segment}' is not a segment")
        return self


@dataclass(frozen=True)
class Joint:
    name: str
    type: str                 # ball | hinge | two_axis
    parent: str
    child: str
    axis_names: tuple[str, ...]
    axes: np.ndarray          # (k, 3) unit vectors in the parent frame at the zero pose
    lower_rad: np.ndarray     # (k,)
    upper_rad: np.ndarray     # (k,)
    kp: float
    kd: float
    max_torque_nm: float
    joint_at_m: np.ndarray    # (3,) in the parent's link frame

    @property
    def dof(self) -> int:
        return len(self.axis_names)


@dataclass(frozen=True)
class Body:
    name: str
    segment_names: tuple[str, ...]     # root first, parents before children
    parents: tuple[str | None, ...]
    mass_kg: np.ndarray                # (n,) box mass (gimbal mass already taken out)
    half_extents_m: np.ndarray         # (n, 3)
    center_m: np.ndarray               # (n, 3) box centre in the segment's link frame
    volume_m3: np.ndarray              # (n,) displaced volume, lung air included
    semi_axes_m: np.ndarray            # (n, 3) equal-volume buoyancy ellipsoid
    joints: tuple[Joint, ...]          # in segment order
    gimbal_mass_kg: float
    lung_air_l: float
    lung_segment: str
    max_lung_air_l: float
    source: str

    @property
    def total_mass_kg(self) -> float:
        gimbals = sum(1 for j in self.joints if j.type == "two_axis")
        return float(self.mass_kg.sum() + gimbals * self.gimbal_mass_kg)

    @property
    def mass_fraction(self) -> np.ndarray:
        """Each box's share of the boxes' mass: weights for the centre of mass of the segments."""
        return self.mass_kg / self.mass_kg.sum()

    @property
    def segments(self) -> Segments:
        """The segments by name with their mass shares, as every ``BodyState`` carries them."""
        return Segments(self.segment_names, self.mass_fraction)

    @property
    def total_volume_m3(self) -> float:
        return float(self.volume_m3.sum())

    def density_ratio(self, rho_kg_m3: float) -> float:
        """The water's density over the body's (as it holds its breath now): above 1 it floats."""
        return rho_kg_m3 * self.total_volume_m3 / self.total_mass_kg

    def index(self, segment: str) -> int:
        return self.segment_names.index(segment)

    def breathing(self, air_l: float) -> "Body":
        """The same body holding ``air_l`` of air above the residual volume: its lung segment
        displaces the difference, its buoyancy ellipsoid grows with it."""
        i = self.index(self.lung_segment)
        volume = self.volume_m3.copy()
        volume[i] += (air_l - self.lung_air_l) * 1e-3
        semi = self.semi_axes_m.copy()
        semi[i] = equal_volume_semi_axes(self.half_extents_m[i], volume[i])
        return replace(self, volume_m3=volume, semi_axes_m=semi, lung_air_l=float(air_l))

    def joint(self, name: str) -> Joint:
        for joint in self.joints:
            if joint.name == name:
                return joint
        raise KeyError(name)


def load_body(path: str | Path | None = None, lung_air_l: float | None = None) -> Body:
    """Read and resolve a body file (the packaged Yang swimmer by default)."""
    source = Path(str(path if path is not None else DEFAULT_BODY_FILE))
    spec = load(BodySpec, source)
    air_l = spec.lungs.default_air_l if lung_air_l is None else float(lung_air_l)
    if not np.isfinite(air_l) or air_l < 0 or air_l > 8:
        raise ConfigError(f"lung air volume must be between 0 and 8 L, got {lung_air_l}")
    return resolve_body(spec, air_l, str(source))


def resolve_body(spec: BodySpec, lung_air_l: float, source: str) -> Body:
    names = tuple(spec.segments)
    segs = [spec.segments[n] for n in names]
    raw_mass = np.array([s.mass_kg for s in segs])
    mass = raw_mass * spec.total_mass_kg / raw_mass.sum()
    # Keep the relative (Dempster) densities; scale them so the cadaveric body has the mean density.
    raw_volume = mass / np.array([s.density_kg_m3 for s in segs])
    volume = raw_volume * (spec.total_mass_kg / spec.mean_density_kg_m3) / raw_volume.sum()
    volume[names.index(spec.lungs.segment)] += (spec.lungs.residual_volume_l + lung_air_l) * 1e-3

    joints = []
    for name, seg in zip(names, segs):
        if seg.joint is None:
            continue
        jspec = spec.joints[seg.joint]
        axes = np.array([a.axis.as_tuple() for a in jspec.axes.values()], dtype=float)
        axes /= np.linalg.norm(axes, axis=1, keepdims=True)
        joints.append(Joint(
            name=seg.joint, type=jspec.type, parent=seg.parent, child=name,
            axis_names=tuple(jspec.axes),
            axes=axes,
            lower_rad=np.radians([a.min_deg for a in jspec.axes.values()]),
            upper_rad=np.radians([a.max_deg for a in jspec.axes.values()]),
            kp=jspec.pd.kp, kd=jspec.pd.kd, max_torque_nm=jspec.pd.max_torque_nm,
            joint_at_m=np.array(seg.joint_at_m.as_tuple()),
        ))
        if jspec.type == "two_axis":
            mass[names.index(name)] -= spec.gimbal_mass_kg
    if np.any(mass <= 0):
        raise ConfigError(f"{source}: gimbal_mass_kg leaves a segment with no mass")

    half = np.array([s.size_m.as_tuple() for s in segs]) / 2
    return Body(
        name=spec.name, segment_names=names, parents=tuple(s.parent for s in segs),
        mass_kg=mass, half_extents_m=half,
        center_m=np.array([s.center_m.as_tuple() for s in segs]),
        volume_m3=volume, semi_axes_m=equal_volume_semi_axes(half, volume),
        joints=tuple(joints), gimbal_mass_kg=spec.gimbal_mass_kg, lung_air_l=lung_air_l,
        lung_segment=spec.lungs.segment, max_lung_air_l=spec.lungs.max_air_l, source=source,
    )


def equal_volume_semi_axes(half_extents_m, volume_m3):
    """Ellipsoid semi-axes proportional to the box half extents with 4/3 pi abc = volume_m3.

    half_extents_m (..., 3), volume_m3 (...) -> (..., 3).
    """
    half = np.asarray(half_extents_m, dtype=np.float64)
    vol = np.asarray(volume_m3, dtype=np.float64)
    scale = np.cbrt(3.0 * vol / (4.0 * np.pi * np.prod(half, axis=-1)))
    return half * scale[..., None]
