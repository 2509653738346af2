"""Flow dragged along by the swimmer (Yang et al. 2004, eq. 5)."""

import math

import numpy as np
from numba import njit


@njit(cache=True)
def _induced_flow(v, axis, r_min, r_max, axial):
    speed2 = v[0] * v[0] + v[1] * v[1] + v[2] * v[2]
    out = np.zeros(3)
    if speed2 == 0.0:
        return out
    along = v[0] * axis[0] + v[1] * axis[1] + v[2] * axis[2]
    cos_a = along / math.sqrt(speed2)
    sin2 = max(0.0, 1.0 - cos_a * cos_a)
    ratio = (r_max - r_min) * sin2 * math.sqrt(sin2) + r_min
    for j in range(3):
        out[j] = ratio * v[j]
    if axial:
        kept = out[0] * axis[0] + out[1] * axis[1] + out[2] * axis[2]
        for j in range(3):
            out[j] = kept * axis[j]
    return out


def induced_flow(swimmer_velocity_m_s, pelvis_long_axis, r_min, r_max):
    """Water velocity near the swimmer, V_F = ((r_max - r_min) sin^3(alpha) + r_min) V_S.

    alpha is the angle between V_S and the pelvis long axis (unit vector); |cos alpha|
    is used so moving backwards along the axis counts as along it. The sin^3 drop-off
    is that of a cylinder's drag coefficient (Hoerner). Zero velocity gives zero.
    """
    return _induced_flow(np.asarray(swimmer_velocity_m_s, dtype=np.float64),
                         np.asarray(pelvis_long_axis, dtype=np.float64), float(r_min), float(r_max), False)
