"""Drag and lift coefficients of a fully immersed thin flat plate, aspect ratio 0.2.

Angle convention: ``a`` is the angle of attack between the flow and the plate
*surface* (a = 0 edge-on, a = 90 deg face-on), i.e. a = 90 deg - alpha with
Yang et al.'s alpha = acos(D . N).
"""

import numpy as np

# Source: Atkinson, ROWING model, "Hydrofoil: Flat plate, fully immersed, b/c=0.2,
# after Hoerner" (http://www.atkinsopht.com/row/liftdrag.htm), see
# layered_swim/reference.md, section 1. 42.5 deg appears twice: before
# and after stall.
HOERNER_AR02_A_DEG = np.array(
    [0, 1, 2, 3, 5, 7, 10, 15, 20, 25, 30, 33, 35, 37, 39, 41, 42.5, 42.5,
     45, 50, 60, 70, 80, 90], dtype=np.float64)
HOERNER_AR02_CL = np.array(
    [0, .03, .065, .105, .185, .265, .39, .61, .83, 1.04, 1.23, 1.33, 1.36,
     1.38, 1.37, 1.35, 1.30, 0.73, 0.71, 0.67, 0.56, 0.40, 0.21, 0], dtype=np.float64)
HOERNER_AR02_CD = np.array(
    [0, .0005, .001, .005, .015, .03, .07, .17, .31, .49, .71, .84, .93, 1.01,
     1.08, 1.15, 1.20, 0.66, 0.71, 0.80, 0.96, 1.09, 1.17, 1.20], dtype=np.float64)

STALL_DEG = 42.5
STALL_RAMP_WIDTH_DEG = 1.5


def smoothed_knots():
    """Piecewise-linear knots (a_deg, cl, cd) with the stall step replaced by a ramp.

    The vertical jump at 42.5 deg becomes a linear ramp from 41.75 to 43.25 deg
    (pre-stall value -> post-stall value), so the force landscape is continuous.
    Angles are strictly increasing.
    """
    half = 0.5 * STALL_RAMP_WIDTH_DEG
    stall = np.flatnonzero(HOERNER_AR02_A_DEG == STALL_DEG)
    a_deg = HOERNER_AR02_A_DEG.copy()
    a_deg[stall[0]] = STALL_DEG - half
    a_deg[stall[1]] = STALL_DEG + half
    # The ramp must stay strictly inside its neighbours (41 and 45 deg).
    assert np.all(np.diff(a_deg) > 0.0)
    return a_deg, HOERNER_AR02_CL.copy(), HOERNER_AR02_CD.copy()


def build_coefficient_table(step_deg=0.25):
    """Dense uniformly spaced table over 0..90 deg (inclusive) for O(1) lookup.

    Returns (angles_rad, cl, cd), float64 contiguous arrays. With the default
    step every knot lies on the grid, so linear interpolation of the dense
    table reproduces the smoothed piecewise-linear curve exactly.
    """
    n = int(round(90.0 / step_deg)) + 1
    a_deg = np.linspace(0.0, 90.0, n)
    k_deg, k_cl, k_cd = smoothed_knots()
    return (np.ascontiguousarray(np.deg2rad(a_deg)),
            np.ascontiguousarray(np.interp(a_deg, k_deg, k_cl)),
            np.ascontiguousarray(np.interp(a_deg, k_deg, k_cd)))


def plate_coefficients(a_rad):
    """(C_L, C_D) at angle(s) of attack a_rad, clamped to [0, pi/2]."""
    k_deg, k_cl, k_cd = smoothed_knots()
    a_deg = np.rad2deg(np.asarray(a_rad, dtype=np.float64))
    return np.interp(a_deg, k_deg, k_cl), np.interp(a_deg, k_deg, k_cd)
