"""Buoyancy of segments represented by ellipsoids (Yang et al. 2004, sec. 3.2, Fig. 6).

The ellipsoid x = c + R diag(a) u, |u| <= 1, gives each segment's submerged fraction
and centre of buoyancy; the displaced volume itself is the segment's real volume.
Below the surface <=> n . u < surface_z - c_z with n_i = a_i R[2, i]. With s = |n|,
m = n / s and h = (surface_z - c_z) / s, the unit ball is cut by the plane m . u = h:

* submerged fraction f(h) = 1 - (1 - h)^2 (2 + h) / 4 for -1 < h < 1 (0 below, 1 above);
* centroid of the submerged part t_bar m, t_bar = -3 (1 - h)^2 / (4 (2 - h))
  (integral of t (1 - t^2) over (1 - t^2) on [-1, h]).

Affine maps preserve volume ratios and centroids, so both carry over to the ellipsoid.
"""

import math

import numpy as np
from numba import njit

from layered_swim.geometry import quat_to_rows


@njit(cache=True)
def _submerged(pos, quat, semi, surface_z, exact):
    n = pos.shape[0]
    frac = np.empty(n)
    cob = np.empty((n, 3))
    R = np.empty(9)        # rotation matrix, row-major
    for i in range(n):
        quat_to_rows(quat[i], R, True)
        n0 = semi[i, 0] * R[6]
        n1 = semi[i, 1] * R[7]
        n2 = semi[i, 2] * R[8]
        s = math.sqrt(n0 * n0 + n1 * n1 + n2 * n2)
        d = surface_z - pos[i, 2]
        if s > 0.0:
            h = d / s
        else:
            # Flat horizontal ellipsoid: all in or all out (half if exactly at the surface).
            h = 1.0 if d > 0.0 else (-1.0 if d < 0.0 else 0.0)
        t_bar = 0.0
        if exact:
            if h >= 1.0:
                f = 1.0
            elif h <= -1.0:
                f = 0.0
            else:
                f = 1.0 - (1.0 - h) * (1.0 - h) * (2.0 + h) / 4.0
                t_bar = -3.0 * (1.0 - h) * (1.0 - h) / (4.0 * (2.0 - h))
        else:
            f = min(max(0.5 * (1.0 + h), 0.0), 1.0)
        frac[i] = f
        cob[i, 0] = pos[i, 0]
        cob[i, 1] = pos[i, 1]
        cob[i, 2] = pos[i, 2]
        if t_bar != 0.0 and s > 0.0:
            # Centre of buoyancy c + R diag(a) (t_bar m), m = n / s.
            k = t_bar / s
            u0 = k * n0 * semi[i, 0]
            u1 = k * n1 * semi[i, 1]
            u2 = k * n2 * semi[i, 2]
            for j in range(3):
                cob[i, j] += R[3 * j] * u0 + R[3 * j + 1] * u1 + R[3 * j + 2] * u2
    return frac, cob


@njit(cache=True)
def _buoyancy_wrenches(pos, quat, semi, volume, rho, g, surface_z, exact):
    frac, cob = _submerged(pos, quat, semi, surface_z, exact)
    n = pos.shape[0]
    force = np.zeros((n, 3))
    torque = np.zeros((n, 3))
    for i in range(n):
        fz = rho * g * volume[i] * frac[i]
        force[i, 2] = fz
        # (cob - pos) x (0, 0, fz)
        torque[i, 0] = (cob[i, 1] - pos[i, 1]) * fz
        torque[i, 1] = -(cob[i, 0] - pos[i, 0]) * fz
    return force, torque


def _f64(x):
    return np.ascontiguousarray(x, dtype=np.float64)


def buoyancy_wrenches(pos_m, quat_xyzw, semi_axes_m, volume_m3, rho_kg_m3, gravity_m_s2,
                      surface_z_m, exact=True):
    """Buoyant force and torque on n segments.

    pos_m (n,3): ellipsoid centre = segment centre of mass (world); quat_xyzw (n,4):
    orientation (ellipsoid semi-axes lie along the local axes); semi_axes_m (n,3);
    volume_m3 (n,): displaced volume when fully submerged; gravity_m_s2: magnitude g
    (its sign is ignored); surface_z_m: water surface height.

    exact=True: exact submerged fraction of the ellipsoid, force rho g V f straight up
    (+z) applied at the exact centre of buoyancy, hence torque (cob - pos) x force, which
    rights a tilted segment.
    exact=False: Yang et al.'s approximation, fraction (1 + h) / 2 clamped to [0, 1]
    (h = cos(theta) of their Fig. 6 in the unit-sphere picture), applied at the
    ellipsoid centre, so the torque is zero.

    Returns force_n (n,3), torque_nm (n,3) about each centre.
    """
    return _buoyancy_wrenches(_f64(pos_m), _f64(quat_xyzw), _f64(semi_axes_m), _f64(volume_m3),
                              float(rho_kg_m3), abs(float(gravity_m_s2)), float(surface_z_m),
                              bool(exact))


def submerged_fraction_and_centre(pos_m, quat_xyzw, semi_axes_m, surface_z_m, exact=True):
    """Submerged volume fraction (n,) and centre of buoyancy (n,3) of each ellipsoid.

    exact=False gives Yang et al.'s fraction with the centre of buoyancy at the centre.
    """
    return _submerged(_f64(pos_m), _f64(quat_xyzw), _f64(semi_axes_m), float(surface_z_m),
                      bool(exact))
