"""Generate the URDF for a resolved ``Body`` (never edited by hand).

Link frames sit at their joint with axes parallel to the zero ("standing") pose; each box and
its inertia sit at the segment's ``center_m``. Two-axis joints (wrists, ankles) become two
revolute joints through a small gimbal link. Each link has a collision shape (see ``_link``), but
the swimmer is in open water and no contact, self-contact included, is modelled.
"""
from __future__ import annotations

from pathlib import Path
from xml.sax.saxutils import quoteattr

import numpy as np

from layered_swim.body.model import Body


def _vec(v) -> str:
    return " ".join(f"{float(x):.6g}" for x in v)


def _box_inertia(mass: float, half: np.ndarray) -> tuple[float, float, float]:
    sx, sy, sz = (2 * half) ** 2
    return mass * (sy + sz) / 12, mass * (sx + sz) / 12, mass * (sx + sy) / 12


def _link(name: str, mass: float, inertia, center, geometry: str) -> str:
    ixx, iyy, izz = inertia
    xyz = _vec(center)
    shape = f'<origin xyz="{xyz}"/><geometry>{geometry}</geometry>'
    # PyBullet's STABLE_PD_CONTROL, which the tests check our stable PD against, returns NaN for
    # links without a collision shape, so every link gets one; the world filters out all contacts.
    return (f"<link name={quoteattr(name)}><inertial><origin xyz=\"{xyz}\"/><mass value=\"{mass:.6g}\"/>"
            f'<inertia ixx="{ixx:.6g}" iyy="{iyy:.6g}" izz="{izz:.6g}" ixy="0" ixz="0" iyz="0"/>'
            f"</inertial><visual>{shape}</visual><collision>{shape}</collision></link>")


def _joint(name: str, kind: str, parent: str, child: str, origin, axis=None, limits=None,
           max_torque: float = 0.0) -> str:
    parts = [f"<joint name={quoteattr(name)} type=\"{kind}\">",
             f"<parent link={quoteattr(parent)}/><child link={quoteattr(child)}/>",
             f'<origin xyz="{_vec(origin)}"/>']
    if axis is not None:
        parts.append(f'<axis xyz="{_vec(axis)}"/>')
    if limits is not None:
        parts.append(f'<limit lower="{limits[0]:.6g}" upper="{limits[1]:.6g}" '
                     f'effort="{max_torque:.6g}" velocity="100"/>')
    parts.append("</joint>")
    return "".join(parts)


def gimbal_link_name(joint_name: str) -> str:
    return f"{joint_name}_gimbal"


def axis_joint_name(joint_name: str, axis_name: str) -> str:
    return f"{joint_name}_{axis_name}"


def body_to_urdf(body: Body) -> str:
    gimbal_r = 0.02  # radius of the sphere whose inertia the gimbal link gets
    gimbal_inertia = (0.4 * body.gimbal_mass_kg * gimbal_r**2,) * 3
    parts = ['<?xml version="1.0"?>', f"<robot name={quoteattr(body.name)}>"]
    for i, name in enumerate(body.segment_names):
        half = body.half_extents_m[i]
        parts.append(_link(name, body.mass_kg[i], _box_inertia(body.mass_kg[i], half),
                           body.center_m[i], f'<box size="{_vec(2 * half)}"/>'))
    for joint in body.joints:
        if joint.type == "ball":
            # The axis is unused by spherical joints; naming one silences the URDF importer's warning.
            parts.append(_joint(joint.name, "spherical", joint.parent, joint.child, joint.joint_at_m, (1, 0, 0)))
        elif joint.type == "hinge":
            parts.append(_joint(joint.name, "revolute", joint.parent, joint.child, joint.joint_at_m,
                                joint.axes[0], (joint.lower_rad[0], joint.upper_rad[0]), joint.max_torque_nm))
        else:
            gimbal = gimbal_link_name(joint.name)
            parts.append(_link(gimbal, body.gimbal_mass_kg, gimbal_inertia, (0, 0, 0),
                               f'<sphere radius="{gimbal_r}"/>'))
            parts.append(_joint(axis_joint_name(joint.name, joint.axis_names[0]), "revolute", joint.parent,
                                gimbal, joint.joint_at_m, joint.axes[0],
                                (joint.lower_rad[0], joint.upper_rad[0]), joint.max_torque_nm))
            parts.append(_joint(axis_joint_name(joint.name, joint.axis_names[1]), "revolute", gimbal,
                                joint.child, (0, 0, 0), joint.axes[1],
                                (joint.lower_rad[1], joint.upper_rad[1]), joint.max_torque_nm))
    parts.append("</robot>")
    return "\n".join(parts)


def write_urdf(body: Body, path: str | Path) -> Path:
    path = Path(path)
    path.write_text(body_to_urdf(body))
    return path
