"""Thin-plate hydrodynamic forces on the faces of box segments (Yang et al. 2004, eqs. 1-4).

Every box has six faces (+-x, +-y, +-z of its local frame). A face the water flows
into (V . N < 0, V = water velocity relative to the face, N = outward normal) gets

* drag + lift (eq. 1): 0.5 rho A |V_NF|^2 (C_D(a) D + C_L(a) L), where V_NF is V with
  its component along the face's short edge removed (spanwise flow makes no pressure
  force) and D = V_NF / |V_NF|;
* friction (eq. 2): eta A |V_t| along V_t = V - (V . N) N.

Both are scaled by the face's submerged area fraction. Faces with V . N >= 0 give
nothing. The flow is evaluated at the face centre (or at patch centres when a face is
split into patches_per_edge^2 patches; see plate_wrenches).
"""

import math

import numpy as np
from numba import njit

from layered_swim.geometry import quat_to_rows


@njit(cache=True)
def _uniform_sum_cdf_nonpos(x, a, b):
    """CDF at x <= 0 of a*u1 + b*u2, u1, u2 independent uniform on [-1, 1], a, b >= 0."""
    p = max(a, b)
    q = min(a, b)
    if p == 0.0:
        return 0.5 if x == 0.0 else 0.0
    if x <= -(p + q):
        return 0.0
    if x <= q - p:
        # Rising quadratic flank of the trapezoid; t in (0, 2q] so q > 0 here and t/q <= 2.
        t = x + p + q
        return t * (t / q) / (8.0 * p)
    return 0.5 + x / (2.0 * p)


@njit(cache=True)
def rectangle_submerged_fraction(c_z, a, b):
    """Exact fraction of a rectangle's area below the water surface.

    c_z: height of the rectangle's centre relative to the surface (negative = below);
    a, b: |z components| of its two half-edge vectors. The point c + u1 e1 + u2 e2 is
    uniform over the rectangle for u1, u2 uniform on [-1, 1], so the fraction is
    P(a u1 + b u2 < -c_z), the CDF of a trapezoidal density. Continuous in all
    arguments; a = 0 and/or b = 0 (vertical edges / horizontal face) are handled
    without division by zero (a horizontal face exactly at the surface counts half).
    """
    x = -c_z
    if x <= 0.0:
        return _uniform_sum_cdf_nonpos(x, a, b)
    return 1.0 - _uniform_sum_cdf_nonpos(-x, a, b)


@njit(cache=True)
def _plate_wrenches(pos, quat, linvel, angvel, half, flow, rho, eta, surface_z,
                    angles, cl_tab, cd_tab, patches_per_edge):
    n = pos.shape[0]
    force = np.zeros((n, 3))
    torque = np.zeros((n, 3))
    n_tab = angles.shape[0]
    inv_step = (n_tab - 1) / angles[n_tab - 1]
    R = np.empty(9)        # rotation matrix, row-major: body axis c is column c
    kp = patches_per_edge
    inv_kp = 1.0 / kp
    for i in range(n):
        quat_to_rows(quat[i], R, True)
        wx, wy, wz = angvel[i, 0], angvel[i, 1], angvel[i, 2]
        fx_tot = 0.0
        fy_tot = 0.0
        fz_tot = 0.0
        tx_tot = 0.0
        ty_tot = 0.0
        tz_tot = 0.0
        for k in range(3):
            # The two in-plane axes in increasing index order (ties -> lower index is long).
            j1 = 1 if k == 0 else 0
            j2 = 1 if k == 2 else 2
            if half[i, j1] >= half[i, j2]:
                jf = j1
                js = j2
            else:
                jf = j2
                js = j1
            hf = half[i, jf]
            hs = half[i, js]
            area = 4.0 * hf * hs * inv_kp * inv_kp
            if area <= 0.0:
                continue
            fax, fay, faz = R[jf], R[3 + jf], R[6 + jf]
            sax, say, saz = R[js], R[3 + js], R[6 + js]
            # Patch half-edge heights for the submerged fraction.
            hz_f = abs(hf * inv_kp * faz)
            hz_s = abs(hs * inv_kp * saz)
            for sign in (1.0, -1.0):
                nx = sign * R[k]
                ny = sign * R[3 + k]
                nz = sign * R[6 + k]
                hk = half[i, k]
                for pf in range(kp):
                    uf = ((2 * pf + 1) * inv_kp - 1.0) * hf
                    for ps in range(kp):
                        us = ((2 * ps + 1) * inv_kp - 1.0) * hs
                        # Patch centre relative to the segment centre.
                        rx = hk * nx + uf * fax + us * sax
                        ry = hk * ny + uf * fay + us * say
                        rz = hk * nz + uf * faz + us * saz
                        # Water velocity relative to the patch.
                        vx = flow[i, 0] - (linvel[i, 0] + wy * rz - wz * ry)
                        vy = flow[i, 1] - (linvel[i, 1] + wz * rx - wx * rz)
                        vz = flow[i, 2] - (linvel[i, 2] + wx * ry - wy * rx)
                        vn = vx * nx + vy * ny + vz * nz
                        if vn >= 0.0:
                            continue
                        frac = rectangle_submerged_fraction(pos[i, 2] + rz - surface_z,
                                                            hz_f, hz_s)
                        if frac <= 0.0:
                            continue
                        # Friction, eq. 2: eta * A * (in-plane relative flow).
                        c_fric = eta * area
                        gx = c_fric * (vx - vn * nx)
                        gy = c_fric * (vy - vn * ny)
                        gz = c_fric * (vz - vn * nz)
                        # Chordwise flow: drop the component along the short edge.
                        vs = vx * sax + vy * say + vz * saz
                        ax = vx - vs * sax
                        ay = vy - vs * say
                        az = vz - vs * saz
                        q2 = ax * ax + ay * ay + az * az
                        if q2 > 1e-30:
                            qn = math.sqrt(q2)
                            dx = ax / qn
                            dy = ay / qn
                            dz = az / qn
                            # Angle of attack a = 90 deg - acos(D . N_in), N_in = -N.
                            cos_alpha = min(max(-(dx * nx + dy * ny + dz * nz), 0.0), 1.0)
                            a = math.asin(cos_alpha)
                            xt = a * inv_step
                            it = int(xt)
                            if it > n_tab - 2:
                                it = n_tab - 2
                            t = xt - it
                            cl = cl_tab[it] + t * (cl_tab[it + 1] - cl_tab[it])
                            cd = cd_tab[it] + t * (cd_tab[it + 1] - cd_tab[it])
                            c_p = 0.5 * rho * area * q2
                            gx += c_p * cd * dx
                            gy += c_p * cd * dy
                            gz += c_p * cd * dz
                            # Eq. 3 with F oriented so F . V >= 0: L then points to the
                            # plate's downstream side.
                            o = 1.0 if (vx * fax + vy * fay + vz * faz) >= 0.0 else -1.0
                            ffx = o * fax
                            ffy = o * fay
                            ffz = o * faz
                            ux = dy * ffz - dz * ffy
                            uy = dz * ffx - dx * ffz
                            uz = dx * ffy - dy * ffx
                            un = math.sqrt(ux * ux + uy * uy + uz * uz)
                            if un > 1e-12 and cl != 0.0:
                                ux /= un
                                uy /= un
                                uz /= un
                                lx = dy * uz - dz * uy
                                ly = dz * ux - dx * uz
                                lz = dx * uy - dy * ux
                                ln = math.sqrt(lx * lx + ly * ly + lz * lz)
                                c_l = c_p * cl / ln
                                gx += c_l * lx
                                gy += c_l * ly
                                gz += c_l * lz
                        gx *= frac
                        gy *= frac
                        gz *= frac
                        fx_tot += gx
                        fy_tot += gy
                        fz_tot += gz
                        tx_tot += ry * gz - rz * gy
                        ty_tot += rz * gx - rx * gz
                        tz_tot += rx * gy - ry * gx
        force[i, 0] = fx_tot
        force[i, 1] = fy_tot
        force[i, 2] = fz_tot
        torque[i, 0] = tx_tot
        torque[i, 1] = ty_tot
        torque[i, 2] = tz_tot
    return force, torque


def _f64(x):
    return np.ascontiguousarray(x, dtype=np.float64)


def plate_wrenches(pos_m, quat_xyzw, linvel_m_s, angvel_rad_s, half_extents_m, flow_m_s,
                   rho_kg_m3, eta_pa_s, surface_z_m, table, patches_per_edge=1):
    """Hydrodynamic force and torque on n box segments.

    pos_m (n,3): box centre = segment centre of mass (world); quat_xyzw (n,4): box
    orientation; linvel_m_s (n,3): velocity of the centre; angvel_rad_s (n,3): world
    angular velocity; half_extents_m (n,3): half sizes along the local axes;
    flow_m_s (n,3): water velocity at each segment; rho_kg_m3, eta_pa_s: water density
    and dynamic viscosity; surface_z_m: water surface height; table: the tuple from
    coefficients.build_coefficient_table().

    patches_per_edge: each face is split into patches_per_edge^2 equal patches, each
    treated as its own plate. With 1 (Yang's model) the flow is sampled at face centres
    only, where a spin about the segment centre is purely tangential, so a segment
    spinning in still water gets no torque except via friction; >= 2 resolves that
    rotational drag at proportional extra cost.

    Returns force_n (n,3) and torque_nm (n,3) about each segment centre.
    """
    angles_rad, cl, cd = table
    return _plate_wrenches(_f64(pos_m), _f64(quat_xyzw), _f64(linvel_m_s), _f64(angvel_rad_s),
                           _f64(half_extents_m), _f64(flow_m_s), float(rho_kg_m3),
                           float(eta_pa_s), float(surface_z_m), angles_rad, cl, cd,
                           int(patches_per_edge))
