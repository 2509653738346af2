import math

import numpy as np
import pytest

from layered_swim.body.model import equal_volume_semi_axes
from layered_swim.fluid.buoyancy import buoyancy_wrenches, submerged_fraction_and_centre
from layered_swim.fluid.induced_flow import induced_flow

RHO = 1000.0
G = 9.81
IDENTITY = [0.0, 0.0, 0.0, 1.0]


def quat_axis_angle(axis, angle_rad):
    axis = np.asarray(axis, dtype=float) / np.linalg.norm(axis)
    return np.r_[axis * math.sin(angle_rad / 2), math.cos(angle_rad / 2)]


def quat_matrix(q):
    x, y, z, w = np.asarray(q) / np.linalg.norm(q)
    return np.array([[1 - 2 * (y * y + z * z), 2 * (x * y - z * w), 2 * (x * z + y * w)],
                     [2 * (x * y + z * w), 1 - 2 * (x * x + z * z), 2 * (y * z - x * w)],
                     [2 * (x * z - y * w), 2 * (y * z + x * w), 1 - 2 * (x * x + y * y)]])


def one(pos, semi, quat=IDENTITY, volume=0.01, surface_z=0.0, exact=True):
    f, t = buoyancy_wrenches([pos], [quat], [semi], [volume], RHO, G, surface_z, exact)
    frac, cob = submerged_fraction_and_centre([pos], [quat], [semi], surface_z, exact)
    return f[0], t[0], frac[0], cob[0]


def test_sphere_half_submerged():
    r = 0.2
    f, t, frac, cob = one([1.0, 2.0, 0.0], [r, r, r], volume=0.02)
    assert frac == pytest.approx(0.5)
    np.testing.assert_allclose(cob, [1.0, 2.0, -3 * r / 8], atol=1e-15)
    np.testing.assert_allclose(f, [0.0, 0.0, 0.5 * RHO * G * 0.02], rtol=1e-14)
    np.testing.assert_allclose(t, 0.0, atol=1e-14)


def test_fully_submerged_and_fully_out():
    q = quat_axis_angle([1.0, 2.0, 3.0], 0.7)
    f, t, frac, cob = one([0.0, 0.0, -1.0], [0.3, 0.1, 0.05], quat=q, volume=0.004)
    assert frac == 1.0
    np.testing.assert_allclose(f, [0.0, 0.0, RHO * G * 0.004], rtol=1e-14)
    assert np.all(t == 0.0)
    f, t, frac, _ = one([0.0, 0.0, 0.31], [0.3, 0.1, 0.05], quat=q)
    assert frac == 0.0 and np.all(f == 0.0) and np.all(t == 0.0)


def test_sphere_cap_hand_value():
    # Sphere r = 0.2 with centre 0.05 below the surface: h = 0.25,
    # f = 1 - 0.75^2 * 2.25 / 4 = 0.68359375; centroid t = -3 * 0.75^2 / (4 * 1.75).
    r = 0.2
    _, _, frac, cob = one([0.0, 0.0, -0.05], [r, r, r])
    assert frac == pytest.approx(0.68359375, rel=1e-14)
    assert cob[2] == pytest.approx(-0.05 - r * 3 * 0.5625 / 7.0, rel=1e-14)


def test_rotated_ellipsoid_monte_carlo():
    semi = np.array([0.3, 0.1, 0.05])
    q = quat_axis_angle([0.3, -0.8, 0.5], 1.1)
    centre = np.array([0.2, -0.1, -0.03])
    _, _, frac, cob = one(centre, semi, quat=q)
    rng = np.random.default_rng(1234)
    n = 400_000
    u = rng.normal(size=(n, 3))
    u *= (rng.uniform(size=n) ** (1.0 / 3.0) / np.linalg.norm(u, axis=1))[:, None]
    x = centre + (u * semi) @ quat_matrix(q).T
    below = x[:, 2] < 0.0
    mc_frac = below.mean()
    assert 0.1 < mc_frac < 0.9
    assert abs(frac - mc_frac) < 5 * math.sqrt(mc_frac * (1 - mc_frac) / n)
    xs = x[below]
    sigma = xs.std(axis=0) / math.sqrt(len(xs))
    assert np.all(np.abs(cob - xs.mean(axis=0)) < 5 * sigma + 1e-12)


def test_tilted_ellipsoid_righting_torque():
    # Long axis x horizontal, tilted -20 deg about y so the +x end rises out of the water;
    # buoyancy acts nearer the submerged -x end, rotating +x back down: torque_y > 0.
    q = quat_axis_angle([0.0, 1.0, 0.0], math.radians(-20.0))
    assert quat_matrix(q)[2, 0] > 0.0
    f, t, frac, cob = one([0.0, 0.0, -0.02], [0.3, 0.1, 0.05], quat=q)
    assert 0.0 < frac < 1.0 and f[2] > 0.0
    assert cob[0] < 0.0
    assert t[1] > 0.0
    assert abs(t[0]) < 1e-12 and t[2] == 0.0
    np.testing.assert_allclose(t, np.cross(cob - [0.0, 0.0, -0.02], f), atol=1e-15)
    # Mirror tilt: opposite torque.
    _, t2, _, _ = one([0.0, 0.0, -0.02], [0.3, 0.1, 0.05],
                      quat=quat_axis_angle([0.0, 1.0, 0.0], math.radians(20.0)))
    assert t2[1] == pytest.approx(-t[1], rel=1e-12)


def test_yang_approximation():
    r = 0.2
    f, t, frac, cob = one([0.5, 0.0, -0.05], [r, r, r], volume=0.02, exact=False)
    assert frac == pytest.approx((1 + 0.25) / 2)
    np.testing.assert_allclose(f, [0.0, 0.0, 0.625 * RHO * G * 0.02], rtol=1e-14)
    assert np.all(t == 0.0)
    np.testing.assert_allclose(cob, [0.5, 0.0, -0.05])
    # Tilted ellipsoid: h is the plane offset over the support half-width s = |n|.
    q = quat_axis_angle([0.0, 1.0, 0.0], math.radians(30.0))
    semi = np.array([0.3, 0.1, 0.05])
    s = math.hypot(0.3 * math.sin(math.radians(30.0)), 0.05 * math.cos(math.radians(30.0)))
    _, t, frac, _ = one([0.0, 0.0, 0.04], semi, quat=q, exact=False)
    assert frac == pytest.approx(0.5 * (1 - 0.04 / s))
    assert np.all(t == 0.0)


def test_gravity_sign_ignored():
    a, _ = buoyancy_wrenches([[0, 0, -1]], [IDENTITY], [[0.1, 0.1, 0.1]], [0.01], RHO, 9.81, 0.0)
    b, _ = buoyancy_wrenches([[0, 0, -1]], [IDENTITY], [[0.1, 0.1, 0.1]], [0.01], RHO, -9.81, 0.0)
    assert np.array_equal(a, b)


def test_equal_volume_semi_axes():
    half = np.array([[0.05, 0.1, 0.5], [0.1, 0.1, 0.1]])
    vol = np.array([0.01, 0.004])
    semi = equal_volume_semi_axes(half, vol)
    np.testing.assert_allclose(4.0 / 3.0 * np.pi * np.prod(semi, axis=1), vol, rtol=1e-14)
    np.testing.assert_allclose(semi / half, (semi / half)[:, :1] * np.ones(3), rtol=1e-14)
    # A box's own volume (8 abc) gives semi-axes (6 / pi)^(1/3) times the half extents.
    semi = equal_volume_semi_axes([0.1, 0.2, 0.3], 8 * 0.1 * 0.2 * 0.3)
    np.testing.assert_allclose(semi, np.cbrt(6 / np.pi) * np.array([0.1, 0.2, 0.3]))


# ---------------------------------------------------------------- induced flow (eq. 5)

def test_induced_flow():
    axis = np.array([0.0, 0.0, 1.0])
    v = np.array([0.0, 0.0, 1.5])
    np.testing.assert_allclose(induced_flow(v, axis, 0.2, 0.8), 0.2 * v)
    np.testing.assert_allclose(induced_flow(-v, axis, 0.2, 0.8), -0.2 * v)
    side = np.array([1.5, 0.0, 0.0])
    np.testing.assert_allclose(induced_flow(side, axis, 0.2, 0.8), 0.8 * side)
    np.testing.assert_allclose(induced_flow(np.zeros(3), axis, 0.2, 0.8), 0.0)
    # 45 deg: sin^3 = 2^-1.5.
    v45 = np.array([1.0, 0.0, 1.0])
    np.testing.assert_allclose(induced_flow(v45, axis, 0.2, 0.8),
                               (0.6 * 2 ** -1.5 + 0.2) * v45, rtol=1e-14)
