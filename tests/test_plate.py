import math

import numpy as np
import pytest

from layered_swim.fluid.coefficients import build_coefficient_table, plate_coefficients, smoothed_knots
from layered_swim.fluid.plate import plate_wrenches, rectangle_submerged_fraction

RHO = 1000.0
ETA = 1.0e-3
TABLE = build_coefficient_table()
IDENTITY = [0.0, 0.0, 0.0, 1.0]


def one_box(half, pos=(0.0, 0.0, -5.0), quat=IDENTITY, linvel=(0.0, 0.0, 0.0),
            angvel=(0.0, 0.0, 0.0), flow=(0.0, 0.0, 0.0), surface_z=0.0, patches_per_edge=1):
    f, t = plate_wrenches([pos], [quat], [linvel], [angvel], [half], [flow], RHO, ETA,
                          surface_z, TABLE, patches_per_edge)
    return f[0], t[0]


# ---------------------------------------------------------------- coefficients

def test_coefficients_table_values():
    cl, cd = plate_coefficients(np.deg2rad([0.0, 30.0, 90.0]))
    np.testing.assert_allclose(cl, [0.0, 1.23, 0.0], atol=1e-12)
    np.testing.assert_allclose(cd, [0.0, 0.71, 1.20], atol=1e-12)


def test_coefficients_smoothed_stall():
    cl, cd = plate_coefficients(np.deg2rad([41.0, 41.75, 42.5, 43.25, 45.0]))
    np.testing.assert_allclose(cl, [1.35, 1.30, 0.5 * (1.30 + 0.73), 0.73, 0.71], atol=1e-12)
    np.testing.assert_allclose(cd, [1.15, 1.20, 0.5 * (1.20 + 0.66), 0.66, 0.71], atol=1e-12)
    # Continuous: no jump across the ramp.
    a = np.deg2rad(np.linspace(41.0, 45.0, 4001))
    cl, cd = plate_coefficients(a)
    assert np.max(np.abs(np.diff(cl))) < 1e-3
    assert np.max(np.abs(np.diff(cd))) < 1e-3


def test_coefficient_angles_monotone_and_dense_table_uniform():
    a_deg, _, _ = smoothed_knots()
    assert np.all(np.diff(a_deg) > 0.0)
    angles, cl, cd = TABLE
    assert angles[0] == 0.0 and angles[-1] == pytest.approx(math.pi / 2)
    np.testing.assert_allclose(np.diff(angles), np.deg2rad(0.25), rtol=1e-9)
    # Linear interpolation of the dense table reproduces the knot curve.
    x = np.random.default_rng(1).uniform(0.0, math.pi / 2, 500)
    ref_cl, ref_cd = plate_coefficients(x)
    np.testing.assert_allclose(np.interp(x, angles, cl), ref_cl, atol=1e-12)
    np.testing.assert_allclose(np.interp(x, angles, cd), ref_cd, atol=1e-12)


# ---------------------------------------------------------------- face-on, surface

def test_face_on():
    # 0.1 x 0.2 x 1.0 m box moving along +x at 2 m/s: only the +x face (0.2 m^2) faces
    # the flow; the -x face is a back face and the others see V . N = 0.
    f, t = one_box([0.05, 0.1, 0.5], linvel=[2.0, 0.0, 0.0])
    np.testing.assert_allclose(f, [-0.5 * 1000 * 0.2 * 4 * 1.2, 0.0, 0.0], atol=1e-12)
    np.testing.assert_allclose(f, [-480.0, 0.0, 0.0], atol=1e-9)
    np.testing.assert_allclose(t, 0.0, atol=1e-12)


def test_back_face_gives_nothing_reverse_flips():
    f, _ = one_box([0.05, 0.1, 0.5], linvel=[-2.0, 0.0, 0.0])
    np.testing.assert_allclose(f, [480.0, 0.0, 0.0], atol=1e-9)
    # Moving water instead of body: same relative flow, same force.
    f2, _ = one_box([0.05, 0.1, 0.5], flow=[2.0, 0.0, 0.0])
    np.testing.assert_allclose(f2, [480.0, 0.0, 0.0], atol=1e-9)


def test_above_surface_zero():
    f, t = one_box([0.05, 0.1, 0.5], pos=[0.0, 0.0, 0.6], linvel=[2.0, 0.0, -1.0])
    assert np.all(f == 0.0) and np.all(t == 0.0)


def test_half_submerged_vertical_face():
    # The +x face spans z in [-0.5, 0.5]: half of it is in the water.
    f, t = one_box([0.05, 0.1, 0.5], pos=[0.0, 0.0, 0.0], linvel=[2.0, 0.0, 0.0])
    np.testing.assert_allclose(f, [-240.0, 0.0, 0.0], atol=1e-9)
    np.testing.assert_allclose(t, 0.0, atol=1e-12)


# ---------------------------------------------------------------- edge-on, 30 deg

def test_edge_on_limit_is_friction():
    # Horizontal plate 1.0 x 0.2 x 0.002 m moving along its long edge (+x) at 2 m/s and
    # sinking at w = 1e-11 m/s so that its bottom face is (barely) front-facing.
    w = 1e-11
    f, _ = one_box([0.5, 0.1, 0.001], linvel=[2.0, 0.0, -w])
    # Bottom face, 0.2 m^2: friction eta A v = 1e-3 * 0.2 * 2 along -x; angle of attack
    # a = asin(w / |V|) ~ 3e-10 deg, C_D = 0.0005/deg * a, C_L = 0.03/deg * a.
    v2 = 4.0 + w * w
    a_deg = math.degrees(math.asin(w / math.sqrt(v2)))
    drag = 0.5 * 1000 * 0.2 * v2 * 0.0005 * a_deg
    lift = 0.5 * 1000 * 0.2 * v2 * 0.03 * a_deg
    d = np.array([-2.0, 0.0, w]) / math.sqrt(v2)
    lift_dir = np.array([w, 0.0, 2.0]) / math.sqrt(v2)
    bottom = -1e-3 * 0.2 * 2.0 * np.array([1.0, 0.0, 0.0]) + drag * d + lift * lift_dir
    # End face +x, 0.2 x 0.002 m: face-on at 2 m/s, plus friction from the sinking.
    end = np.array([-0.5 * 1000 * 0.0004 * 4 * 1.2, 0.0, 1e-3 * 0.0004 * w])
    np.testing.assert_allclose(f, bottom + end, rtol=1e-9, atol=1e-15)
    # The bottom face's own force is its friction, -4e-4 N x, to within 1e-8 N.
    assert abs(bottom[0] + 4e-4) < 1e-10 and abs(bottom[2]) < 1e-8


def test_angle_of_attack_30():
    # Horizontal plate (long edge x, short edge y, normal z); water at 2 m/s hitting
    # the bottom face at 30 deg within the x-z plane.
    c30, s30 = math.cos(math.radians(30)), 0.5
    hz = 0.005
    flow = [-2.0 * c30, 0.0, 2.0 * s30]
    f, t = one_box([0.5, 0.1, hz], flow=flow)
    # Bottom face, 0.2 m^2, q^2 = 4: drag 284 N along the flow, lift 492 N perpendicular,
    # toward the downstream (+z) side: L = (sin30, 0, cos30).
    drag = 0.5 * 1000 * 0.2 * 4 * 0.71
    lift = 0.5 * 1000 * 0.2 * 4 * 1.23
    assert drag == pytest.approx(284.0) and lift == pytest.approx(492.0)
    bottom = (drag * np.array([-c30, 0.0, s30]) + lift * np.array([s30, 0.0, c30])
              + 1e-3 * 0.2 * np.array([-2.0 * c30, 0.0, 0.0]))
    # End face +x (0.2 x 0.01 m, long edge y): the z part of the flow is along its short
    # edge, so it sees face-on flow of 2 cos30 (q^2 = 3) plus friction from the z part.
    a_end = 0.2 * 2 * hz
    end = (np.array([-0.5 * 1000 * a_end * 3.0 * 1.2, 0.0, 0.0])
           + 1e-3 * a_end * np.array([0.0, 0.0, 1.0]))
    np.testing.assert_allclose(f, bottom + end, rtol=1e-12, atol=1e-9)
    # Torques about the centre: bottom at (0, 0, -hz), end face at (0.5, 0, 0).
    t_ref = np.cross([0.0, 0.0, -hz], bottom) + np.cross([0.5, 0.0, 0.0], end)
    np.testing.assert_allclose(t, t_ref, rtol=1e-12, atol=1e-9)


def test_spanwise_flow_no_pressure():
    # Plate 1.0 x 0.2 x 0.01 m; water along the short edge (y) of the big faces.
    half = [0.5, 0.1, 0.005]
    f, _ = one_box(half, flow=[0.0, -2.0, 0.0])
    # Only the +y end face (1.0 x 0.01 m) is front-facing, face-on.
    np.testing.assert_allclose(f, [0.0, -0.5 * 1000 * 0.01 * 4 * 1.2, 0.0], atol=1e-9)
    # Add a small normal component: the bottom face feels only the normal 0.1 m/s as
    # pressure (face-on, q^2 = 0.01); the 2 m/s spanwise part only as friction.
    f, _ = one_box(half, flow=[0.0, -2.0, 0.1])
    bottom = np.array([0.0, -1e-3 * 0.2 * 2.0, 0.5 * 1000 * 0.2 * 0.01 * 1.2])
    end = np.array([0.0, -0.5 * 1000 * 0.01 * 4 * 1.2, 1e-3 * 0.01 * 0.1])
    np.testing.assert_allclose(f, bottom + end, rtol=1e-12, atol=1e-12)


# ---------------------------------------------------------------- rotation

def test_spin_with_translation_friction_opposes_spin():
    # Box moving face-on at 2 m/s and spinning at 2 rad/s about z: the +x face centre
    # slides along +y at w hx = 0.1 m/s (spanwise for that face), adding friction only.
    f, t = one_box([0.05, 0.1, 0.5], linvel=[2.0, 0.0, 0.0], angvel=[0.0, 0.0, 2.0])
    fy = -1e-3 * 0.2 * 0.1
    np.testing.assert_allclose(f, [-480.0, fy, 0.0], rtol=1e-12, atol=1e-12)
    np.testing.assert_allclose(t, [0.0, 0.0, 0.05 * fy], rtol=1e-12, atol=1e-15)


def test_pure_spin_face_centres_give_nothing():
    # At face centres a spin about the segment centre is tangential: no front faces.
    f, t = one_box([0.1, 0.1, 0.5], angvel=[0.0, 0.0, 2.0])
    assert np.all(f == 0.0) and np.all(t == 0.0)


def test_pure_spin_with_patches_opposes_spin():
    # 2 x 2 patches per face; spin 2 rad/s about the long axis z of a 0.2 x 0.2 x 1.0 box.
    # On each side face the two patches on the advancing half (offset 0.05 m) see
    # face-on flow 0.1 m/s: pressure 0.5*1000*0.05*0.01*1.2 = 0.3 N at lever arm 0.05 m,
    # plus friction 1e-3*0.05*0.2 = 1e-5 N tangential at lever arm 0.1 m.
    f, t = one_box([0.1, 0.1, 0.5], angvel=[0.0, 0.0, 2.0], patches_per_edge=2)
    per_patch = -(0.05 * 0.3 + 0.1 * 1e-5)
    np.testing.assert_allclose(f, 0.0, atol=1e-12)
    np.testing.assert_allclose(t, [0.0, 0.0, 8 * per_patch], rtol=1e-12, atol=1e-12)


def test_patches_same_for_uniform_flow():
    rng = np.random.default_rng(5)
    q = rng.normal(size=4)
    args = dict(half=[0.05, 0.1, 0.3], quat=q / np.linalg.norm(q), linvel=[1.0, -0.5, 0.3],
                flow=[0.2, 0.1, 0.0])
    f1, t1 = one_box(**args)
    f3, t3 = one_box(**args, patches_per_edge=3)
    np.testing.assert_allclose(f3, f1, rtol=1e-12, atol=1e-12)
    np.testing.assert_allclose(t3, t1, rtol=1e-10, atol=1e-12)


# ---------------------------------------------------------------- independent reference

def _quat_matrix(q):
    x, y, z, w = q / np.linalg.norm(q)
    return np.array([[1 - 2 * (y * y + z * z), 2 * (x * y - z * w), 2 * (x * z + y * w)],
                     [2 * (x * y + z * w), 1 - 2 * (x * x + z * z), 2 * (y * z - x * w)],
                     [2 * (x * z - y * w), 2 * (y * z + x * w), 1 - 2 * (x * x + y * y)]])


def _reference_box(pos, q, v, w, half, flow):
    """Straightforward per-face numpy version, with lift written as the component of
    the downstream normal perpendicular to D (what Yang's eq. 3 must reduce to)."""
    R = _quat_matrix(q)
    f_tot = np.zeros(3)
    t_tot = np.zeros(3)
    for k in range(3):
        others = [j for j in range(3) if j != k]
        jf = others[0] if half[others[0]] >= half[others[1]] else others[1]
        js = others[1] if jf == others[0] else others[0]
        area = 4 * half[jf] * half[js]
        for sign in (1, -1):
            n = sign * R[:, k]
            r = half[k] * n
            V = flow - (v + np.cross(w, r))
            if V @ n >= 0:
                continue
            n_in = -n
            S = R[:, js]
            v_nf = V - (V @ S) * S
            D = v_nf / np.linalg.norm(v_nf)
            a = math.pi / 2 - math.acos(np.clip(D @ n_in, -1, 1))
            cl, cd = plate_coefficients(a)
            lvec = n_in - (n_in @ D) * D
            L = lvec / np.linalg.norm(lvec)
            vt = V - (V @ n) * n
            f = 0.5 * RHO * area * (v_nf @ v_nf) * (cd * D + cl * L) + ETA * area * vt
            f_tot += f
            t_tot += np.cross(r, f)
    return f_tot, t_tot


def test_matches_reference_and_lift_points_downstream():
    rng = np.random.default_rng(42)
    n = 16
    pos = rng.normal(size=(n, 3)) * 0.3 + [0.0, 0.0, -3.0]
    q = rng.normal(size=(n, 4))
    q /= np.linalg.norm(q, axis=1)[:, None]
    v = rng.normal(size=(n, 3))
    w = rng.normal(size=(n, 3)) * 3
    half = rng.uniform(0.01, 0.3, size=(n, 3))
    flow = rng.normal(size=(n, 3)) * 0.3
    f, t = plate_wrenches(pos, q, v, w, half, flow, RHO, ETA, 0.0, TABLE)
    for i in range(n):
        fr, tr = _reference_box(pos[i], q[i], v[i], w[i], half[i], flow[i])
        np.testing.assert_allclose(f[i], fr, rtol=1e-9, atol=1e-9)
        np.testing.assert_allclose(t[i], tr, rtol=1e-9, atol=1e-9)
    # Deterministic.
    f2, t2 = plate_wrenches(pos, q, v, w, half, flow, RHO, ETA, 0.0, TABLE)
    assert np.array_equal(f, f2) and np.array_equal(t, t2)


# ---------------------------------------------------------------- submerged fraction

def test_rectangle_fraction_edge_cases():
    assert rectangle_submerged_fraction(0.1, 0.0, 0.0) == 0.0      # horizontal, above
    assert rectangle_submerged_fraction(-0.1, 0.0, 0.0) == 1.0     # horizontal, below
    assert rectangle_submerged_fraction(0.0, 0.0, 0.0) == 0.5
    assert rectangle_submerged_fraction(0.0, 0.5, 0.0) == 0.5      # vertical, half out
    assert rectangle_submerged_fraction(0.0, 0.0, 0.5) == 0.5
    assert rectangle_submerged_fraction(-0.25, 0.5, 0.0) == pytest.approx(0.75)
    assert rectangle_submerged_fraction(0.6, 0.5, 0.0) == 0.0
    assert rectangle_submerged_fraction(-0.6, 0.5, 0.0) == 1.0
    # a = b = 1, c = -1: P(u1 + u2 < 1) = 1 - 1/8.
    assert rectangle_submerged_fraction(-1.0, 1.0, 1.0) == pytest.approx(7.0 / 8.0)
    # a = 1, b = 0.5, c = 0.5: P(u1 + u2/2 < -0.5); on the flank (-1.5, -0.5] the CDF is
    # (x + 1.5)^2 / (8 * 1 * 0.5), at x = -0.5: 0.25.
    assert rectangle_submerged_fraction(0.5, 1.0, 0.5) == pytest.approx(0.25)


def test_rectangle_fraction_symmetry_and_continuity():
    for a, b in [(0.3, 0.1), (0.2, 0.2), (0.0, 0.4), (1e-300, 0.3), (0.5, 1e-12)]:
        for c in np.linspace(-0.8, 0.8, 33):
            assert (rectangle_submerged_fraction(c, a, b)
                    + rectangle_submerged_fraction(-c, a, b)) == pytest.approx(1.0, abs=1e-14)
    # b -> 0 approaches the uniform (vertical face) case continuously.
    for c in np.linspace(-0.6, 0.6, 25):
        assert rectangle_submerged_fraction(c, 0.5, 1e-9) == pytest.approx(
            rectangle_submerged_fraction(c, 0.5, 0.0), abs=1e-8)
    # Monotone non-increasing in c.
    cs = np.linspace(-1.0, 1.0, 2001)
    vals = np.array([rectangle_submerged_fraction(c, 0.4, 0.25) for c in cs])
    assert np.all(np.diff(vals) <= 1e-15)


def test_rectangle_fraction_monte_carlo():
    rng = np.random.default_rng(7)
    u = rng.uniform(-1.0, 1.0, size=(2, 400_000))
    for c, a, b in [(0.05, 0.3, 0.1), (-0.2, 0.25, 0.25), (0.0, 0.4, 0.05), (0.3, 0.2, 0.15)]:
        mc = np.mean(c + a * u[0] + b * u[1] < 0.0)
        sigma = math.sqrt(max(mc * (1 - mc), 1e-12) / u.shape[1])
        assert abs(rectangle_submerged_fraction(c, a, b) - mc) < 5 * sigma + 1e-12
