"""Flow dragged along by the swimmer (Yang et al. 2004, eq. 5)."""

import math

import numpy as np


def induced_flow(swimmer_velocity_m_s, pelvis_long_axis, r_min, r_max):
    """Water velocity near the swimmer, V_F = ((r_max - r_min) sin^3(alpha) + r_min) V_S.

    alpha is the angle between V_S and the pelvis long axis (unit vector); |cos alpha|
    is used so moving backwards along the axis counts as along it. The sin^3 drop-off
    is that of a cylinder's drag coefficient (Hoerner). Zero velocity gives zero.
    """
    v = np.asarray(swimmer_velocity_m_s, dtype=np.float64)
    speed2 = float(v @ v)
    if speed2 == 0.0:
        return np.zeros(3)
    cos_a = float(v @ np.asarray(pelvis_long_axis, dtype=np.float64)) / math.sqrt(speed2)
    sin2 = max(0.0, 1.0 - cos_a * cos_a)
    return ((r_max - r_min) * sin2 * math.sqrt(sin2) + r_min) * v
