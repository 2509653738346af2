"""Added mass: the water a segment must accelerate along with itself (issue 36), integrated stably.

**Coefficients.** Each segment is its buoyancy ellipsoid (semi-axes a_1, a_2, a_3 along the box
axes, the segment's real displaced volume V; ``Body.semi_axes_m``). In potential flow (Lamb 1932,
arts. 114-115) with

    alpha_j = a_1 a_2 a_3 int_0^inf dl / ((a_j^2 + l) D(l)),  D(l) = sqrt(prod_i (a_i^2 + l))
            = (2/3) a_1 a_2 a_3 R_D(a_k^2, a_l^2, a_j^2)          (Carlson's symmetric integral)

its added mass along axis j and added moment of inertia about axis i ((i, j, k) in cyclic order) are

    m_j = k_j rho V,  k_j = alpha_j / (2 - alpha_j)
    I_i = (rho V / 5) (a_j^2 - a_k^2)^2 (alpha_k - alpha_j) / (2 (a_j^2 - a_k^2) + (a_j^2 + a_k^2) (alpha_j - alpha_k))

(a sphere: k = 1/2, no added inertia; a thin disk of radius R: 8/3 rho R^3 face-on and
16/45 rho R^5 about a diameter; a long elliptic cylinder: the 2-D strip's rho pi c^2 / 4 per span
for chord c = 2 a_j, face-on). Out of the water a segment carries none: every coefficient is
scaled by the ellipsoid's submerged volume fraction (the buoyancy's exact fraction).

**Force.** F = -R diag(m) R^T a and T = -R diag(I) R^T alpha: in the segment's body axes, each
component opposes the segment's linear (angular) acceleration relative to the water. The water
does not accelerate: the current is uniform and steady and the swimmer-induced flow stands for a
mean wake, not for water the body accelerates (that is this term). Velocity-dependent terms of
Kirchhoff's equations (the Munk moment, omega x the fluid's momentum) are left out: the plates
give the steady forces.

**Integration.** The force F_n applied during step n -> n+1 cannot use that step's acceleration
(it is not known before PyBullet steps), and an explicit force on last step's acceleration,
F_n = -m a_{n-1}, feeds on itself: for a free segment of mass s, a_n = (G - m a_{n-1}) / s
multiplies any error by -m/s each step, and a hand of ~0.5 kg carries ~1.1 kg of water palm-first.
Instead each axis solves the implicit equation (s + m) a = G, F = -m a = -m/(s + m) G, with the
other forces G inferred from the segment's own Newton-Euler equation over the last step,
G_{n-1} = s a_{n-1} - F_{n-1}:

    F_n = m / (s + m) (F_{n-1} - s a_{n-1})             (torques: the same with I, alpha)

s is the segment's own mass (or box moment of inertia about that axis). For a free body this is
exact one step late: any error is gone after one step. For segments joined into a body
(mobility Lambda = J M^-1 J^T from segment forces to accelerations, S and A the segments' own
and added inertias, block-diagonal), the error e_n = F_n - F* obeys
e_n = (I - (S + A)^-1 S (I + A Lambda)) e_{n-1}, whose eigenvalues are 1 - mu with
(A^-1 + Lambda) v = mu (A^-1 + S^-1) v. The body's mass matrix is M >= J^T S J (its kinetic
energy is its segments', and the wrist and ankle gimbals'), so
f^T Lambda f = max_u (2 f^T J u - u^T M u) <= max_w (2 f^T w - w^T S w) = f^T S^-1 f: Lambda <= S^-1,
and 0 < mu <= 1. The error shrinks every step, without changing sign, at any time step and any
ratio of added to own mass. A joint that holds a segment only slows the convergence (at worst
m/(s + m) per step); forces that follow the state (the PD torques, the plates) are part of G.
The one-step lag damps a little: a free box on a spring k obeys (s + m) x'' = -k x - (m k dt / s) x'.
``explicit=True`` keeps the unstable force, for the validation's contrast only.
"""
from __future__ import annotations

import math

import numpy as np
from numba import njit

from layered_swim.body.model import Body
from layered_swim.fluid.buoyancy import _submerged
from layered_swim.geometry import quat_to_rows
from layered_swim.state import BodyState

# Longest gap between two evaluations that still counts as the step before (the slowest physics
# rate is 120 Hz); anything else (a new episode, a state out of order) starts the memory afresh.
MAX_STEP_S = 0.05


def ellipsoid_integrals(semi_axes_m) -> np.ndarray:
    """Lamb's alpha_0, beta_0, gamma_0 of ellipsoids with semi-axes (..., 3); they sum to 2."""
    from scipy.special import elliprd

    a2 = np.square(np.asarray(semi_axes_m, dtype=np.float64))
    abc = np.prod(np.sqrt(a2), axis=-1)
    return np.stack([2.0 / 3.0 * abc * elliprd(a2[..., (j + 1) % 3], a2[..., (j + 2) % 3], a2[..., j])
                     for j in range(3)], axis=-1)


def ellipsoid_added_inertia(semi_axes_m, rho_kg_m3: float) -> np.ndarray:
    """Added mass along each axis (kg) then added moment of inertia about each axis (kg m^2) of
    fully submerged ellipsoids with semi-axes (..., 3) in still fluid of density ``rho_kg_m3``:
    (..., 6)."""
    a = np.asarray(semi_axes_m, dtype=np.float64)
    alpha = ellipsoid_integrals(a)
    rho_v = rho_kg_m3 * 4.0 / 3.0 * math.pi * np.prod(a, axis=-1)
    out = np.empty(a.shape[:-1] + (6,))
    for i in range(3):
        out[..., i] = alpha[..., i] / (2.0 - alpha[..., i]) * rho_v
        j, k = (i + 1) % 3, (i + 2) % 3
        bj, bk = a[..., j] ** 2, a[..., k] ** 2
        d = bj - bk
        den = 2.0 * d + (bj + bk) * (alpha[..., j] - alpha[..., k])
        # Axisymmetric about i (d = 0): turning moves no water. Near it both factors vanish together.
        small = np.abs(d) <= 1e-12 * (bj + bk)
        ratio = np.where(small, 0.0, d * d * (alpha[..., k] - alpha[..., j]) / np.where(small, 1.0, den))
        out[..., 3 + i] = rho_v / 5.0 * ratio
    return out


def own_inertia(body: Body) -> np.ndarray:
    """Each segment's own mass (three times) then its box's moments of inertia about its centre of
    mass along the box axes (as the URDF gives PyBullet): (n, 6)."""
    m = body.mass_kg
    h2 = np.square(body.half_extents_m)
    return np.column_stack([m, m, m, m * (h2[:, 1] + h2[:, 2]) / 3.0, m * (h2[:, 0] + h2[:, 2]) / 3.0,
                            m * (h2[:, 0] + h2[:, 1]) / 3.0])


@njit(cache=True)
def added_mass_step(pos, quat, linvel, angvel, memory, force, torque, inv_dt, own, added, semi, surface_z, explicit):
    """One step of the scheme (see the module's docstring), in place: ``force`` and ``torque``
    (n, 3), world frame, hold the last step's on entry and this step's on return; ``memory``
    (2, n, 3) the last step's velocity and angular velocity on entry, this step's on return.
    ``inv_dt`` 0: no last step to read (the first of a run), the water applies nothing."""
    n = pos.shape[0]
    frac, _ = _submerged(pos, quat, semi, surface_z, True)
    R = np.empty(9)                  # row-major: body axis c is column c
    acc = np.empty(3)
    prev = np.empty(3)
    out = np.empty(3)
    for i in range(n):
        if inv_dt <= 0.0 or frac[i] <= 0.0:
            for c in range(3):
                force[i, c] = 0.0
                torque[i, c] = 0.0
        else:
            quat_to_rows(quat[i], R, True)
            for part in range(2):        # 0: translation, 1: rotation
                for c in range(3):
                    if part == 0:
                        acc[c] = (linvel[i, c] - memory[0, i, c]) * inv_dt
                        prev[c] = force[i, c]
                    else:
                        acc[c] = (angvel[i, c] - memory[1, i, c]) * inv_dt
                        prev[c] = torque[i, c]
                for c in range(3):       # along body axis c: the world vectors' components R^T v
                    a_c = R[c] * acc[0] + R[3 + c] * acc[1] + R[6 + c] * acc[2]
                    p_c = R[c] * prev[0] + R[3 + c] * prev[1] + R[6 + c] * prev[2]
                    m = frac[i] * added[i, 3 * part + c]
                    if explicit:
                        out[c] = -m * a_c
                    else:
                        s = own[i, 3 * part + c]
                        out[c] = m / (s + m) * (p_c - s * a_c)
                target = force if part == 0 else torque
                for r in range(3):       # back to the world: R out
                    target[i, r] = R[3 * r] * out[0] + R[3 * r + 1] * out[1] + R[3 * r + 2] * out[2]
        for c in range(3):
            memory[0, i, c] = linvel[i, c]
            memory[1, i, c] = angvel[i, c]


class AddedMass:
    """The added-mass wrench of a body's segments, with the one step of memory the scheme needs."""

    def __init__(self, body: Body, rho_kg_m3: float, explicit: bool = False):
        self.own = np.ascontiguousarray(own_inertia(body))
        self.semi = np.ascontiguousarray(body.semi_axes_m, dtype=np.float64).copy()
        self.explicit = explicit
        self.rho_kg_m3 = float(rho_kg_m3)
        self._per_density = ellipsoid_added_inertia(self.semi, 1.0)
        # (n, 6): each segment's added masses, then added moments of inertia, fully submerged.
        self.added = self._per_density * self.rho_kg_m3
        self.reset()

    def set_density(self, rho_kg_m3: float) -> None:
        self.rho_kg_m3 = float(rho_kg_m3)
        self.added = self._per_density * self.rho_kg_m3

    def reshape(self, i: int, semi_axes_m) -> None:
        """Segment ``i``'s ellipsoid changed (the lungs filled or emptied)."""
        self.semi[i] = semi_axes_m
        self._per_density[i] = ellipsoid_added_inertia(self.semi[i], 1.0)
        self.added[i] = self._per_density[i] * self.rho_kg_m3

    def reset(self) -> None:
        """Forget the last step (a new episode): the next evaluation applies nothing."""
        self._time_s: float | None = None
        n = len(self.own)
        self.force_n = np.zeros((n, 3))      # written in place each step (read them before the next)
        self.torque_nm = np.zeros((n, 3))
        self.memory = np.zeros((2, n, 3))    # the last step's velocities

    def inverse_step_s(self, time_s: float) -> float | None:
        """What ``added_mass_step`` takes as ``inv_dt`` for a step at ``time_s`` (0: the first of a
        run, or after a jump in the clock), and remembers the time; None: the same time again
        (the last answer stands)."""
        last, self._time_s = self._time_s, time_s
        if last is not None and time_s == last:
            return None
        return 1.0 / (time_s - last) if last is not None and 0.0 < time_s - last <= MAX_STEP_S else 0.0

    def wrenches(self, state: BodyState, surface_z_m: float) -> tuple[np.ndarray, np.ndarray]:
        """The force and torque (n, 3), world frame, about each centre of mass, for the step from
        ``state``. Called once per physics step; called again at the same time it answers the same.
        (The plates make the same step inside their own compiled call.)"""
        inv_dt = self.inverse_step_s(state.time_s)
        if inv_dt is not None:
            added_mass_step(state.pos_m, state.quat_xyzw, state.linvel_m_s, state.angvel_rad_s, self.memory,
                            self.force_n, self.torque_nm, inv_dt, self.own, self.added, self.semi, float(surface_z_m),
                            self.explicit)
        return self.force_n, self.torque_nm
