"""``layered-swim validate sph``: the SPH water against what it must reproduce.

- Buoyancy of a held torso-sized box, fully and half submerged, against rho g V.
- A flat plate towed at 0.5-1.5 m/s at 0, 30, 60 and 90 deg against the thin-plate model
  (the project's own plate kernel on the same box at the same velocity).
- The draft of a free-floating box (density 500 kg/m^3: half its height under water).
- The towed swimmer's passive drag against Narita et al. 2017's 23.5 v^2 N.
- A current through the small pool (no swimmer): the water's mean velocity in the middle of the
  pool, near the floor, at mid-depth and near the surface, every 0.5 s against the current's.
- A diagnostic, not a correction: the broadside plate at 0.5 m/s towed at three depths in a
  deeper tank. Its excess over the plate model grows with the water pressure around it (a
  share of rho g d A that stays about the same), not with the flow: a moving box in SPH water
  meets a drag from the pressure level itself. It is not the free surface (a lid on the water
  leaves it as it is) and the excess rises further when a lid pressurises the whole tank.

Each case runs without and with the boundary correction (boxes shrunk by ``mesh_shrink_radii``
particle radii per side: SPH leaves a fluid-free skin about one radius thick on every wall, so
bodies come out too big). Per-step forces are noisy (sd ~15 %): every figure is the mean of
20 ms windows, reported with the windows' standard deviation.
"""
from __future__ import annotations

import math

import numpy as np

from layered_swim.analysis.drag import REFERENCE_PASSIVE_DRAG_N_S2_M2, glide_state
from layered_swim.body.model import load_body
from layered_swim.fluid.backend import FluidError
from layered_swim.fluid.coefficients import build_coefficient_table
from layered_swim.fluid.medium import Medium
from layered_swim.fluid.plate import _plate_wrenches
from layered_swim.fluid.sph import SphSettings
from layered_swim.fluid.sph.backend import HEADROOM_M, MAX_WATER_SPEED_M_S, boundary_boxes, start_request
from layered_swim.fluid.sph.worker import SphWorker
from layered_swim.sim.simulation import GRAVITY_M_S2

WINDOW_S = 0.02
G_M_S2 = GRAVITY_M_S2
TORSO_HALF_M = np.array([0.15, 0.175, 0.275])       # 0.30 x 0.35 x 0.55 m: pelvis to shoulders
PLATE_HALF_M = np.array([0.15, 0.15, 0.025])        # 0.30 x 0.30 m, thin along its local z
FLOAT_HALF_M = np.array([0.15, 0.15, 0.10])         # 0.30 x 0.30 x 0.20 m at 500 kg/m^3: 0.10 m draft
FLOAT_DENSITY_KG_M3 = 500.0
TOW_SPEEDS_M_S = (0.5, 1.0, 1.5)
TOW_ANGLES_DEG = (0.0, 30.0, 60.0, 90.0)
SWIMMER_SPEEDS_M_S = (1.0, 1.5)
RAMP_S = 0.1              # tows speed up over this long: an impulsive start throws particles out
TOW_S = 0.4               # each tow; forces are averaged over its second half
TOW_TANK_M = (2.2, 1.0, 0.6)                       # length, width, depth: the plate tows
DEEP_TANK_M = (2.2, 1.6, 1.0)                      # the diagnostic's, deep enough for 0.7 m
TOW_DEPTH_M = 0.3                                  # the plate's centre below the surface
DIAGNOSTIC_DEPTHS_M = (0.3, 0.5, 0.7)
DIAGNOSTIC_SPEED_M_S = 0.5
CURRENT_POOL_M = (3.0, 1.5, 0.5)                   # SWIM's small pool
CURRENT_M_S = (0.5, 0.0, 0.0)
CURRENT_S = 2.5
CURRENT_SAMPLE_S = 0.5
IDENTITY = np.array([0.0, 0.0, 0.0, 1.0])


class Tank:
    """A rectangular tank of SPH water with boxes in it, driven step by step (no PyBullet)."""

    def __init__(self, settings: SphSettings, medium: Medium, size_m, half_m, pos_m, quat_xyzw, shrink: bool,
                 current_m_s=(0.0, 0.0, 0.0)):
        self.half_m = boundary_boxes(half_m, settings) if shrink else np.atleast_2d(half_m)
        self.dt = settings.time_step_s
        length, width, depth = size_m
        water = Medium(medium.rho_kg_m3, medium.eta_pa_s, surface_z_m=0.0, current_m_s=tuple(current_m_s))
        self.worker = SphWorker(settings.solver_threads)
        self.startup = self.worker.request("start", start_request(
            settings, water, G_M_S2, [-length / 2, -width / 2, -depth], [length / 2, width / 2, HEADROOM_M],
            self.half_m, pos_m, quat_xyzw))

    def step(self, pos_m, quat_xyzw, linvel_m_s) -> np.ndarray:
        """One step with the boxes at this pose and velocity; the total force on them (3,)."""
        pos, quat = np.atleast_2d(pos_m), np.atleast_2d(quat_xyzw)
        force, _, _, _, max_speed, _ = self.worker.request("step", (pos, quat, np.atleast_2d(linvel_m_s),
                                                                 np.zeros_like(pos), False))
        if not max_speed < MAX_WATER_SPEED_M_S:
            raise FluidError(f"the SPH water blew up (a particle at {max_speed:.3g} m/s)")
        return force.sum(axis=0)

    def close(self) -> None:
        self.worker.close()


def windowed(values: np.ndarray, dt: float) -> tuple[float, float]:
    """Mean and standard deviation of WINDOW_S means of a per-step series."""
    per = max(1, int(round(WINDOW_S / dt)))
    usable = len(values) // per * per
    means = np.asarray(values[:usable]).reshape(-1, per).mean(axis=1)
    return float(means.mean()), float(means.std())


def held_box(settings: SphSettings, medium: Medium, centre_z_m: float, shrink: bool, seconds: float = 0.3) -> dict:
    """Vertical force on the torso box held still with its centre at ``centre_z_m``."""
    tank = Tank(settings, medium, (1.4, 1.2, 0.9), TORSO_HALF_M, [0.0, 0.0, centre_z_m], IDENTITY, shrink)
    try:
        lift = np.array([tank.step([0.0, 0.0, centre_z_m], IDENTITY, np.zeros(3))[2]
                         for _ in range(int(round(seconds / tank.dt)))])
    finally:
        tank.close()
    submerged = np.clip(-(centre_z_m - TORSO_HALF_M[2]), 0.0, 2 * TORSO_HALF_M[2])
    expected = medium.rho_kg_m3 * G_M_S2 * 4 * TORSO_HALF_M[0] * TORSO_HALF_M[1] * submerged
    mean, sd = windowed(lift, tank.dt)
    return {"lift_n": mean, "window_sd_n": sd, "rho_g_v_n": expected, "ratio": mean / expected}


def plate_model_drag(medium: Medium, speed_m_s: float, quat_xyzw: np.ndarray) -> float:
    """The thin-plate model's force against the tow on the same box (no buoyancy, still water)."""
    angles, cl, cd = build_coefficient_table()
    force, _ = _plate_wrenches(np.zeros((1, 3)), quat_xyzw[None], np.array([[speed_m_s, 0.0, 0.0]]), np.zeros((1, 3)),
                               PLATE_HALF_M[None], np.zeros((1, 3)), medium.rho_kg_m3, medium.eta_pa_s, 1e9,
                               angles, cl, cd, 1)
    return float(-force[0, 0])


def tow(tank: Tank, start_m: np.ndarray, quat_xyzw: np.ndarray, speed_m_s: float) -> np.ndarray:
    """Tow the tank's boxes along +x, ramping up to ``speed_m_s``; the drag (N, against the tow)
    over the second half of the tow."""
    position, drag = np.array(start_m, dtype=float), []
    steps = int(round(TOW_S / tank.dt))
    for k in range(steps):
        speed = speed_m_s * min(1.0, (k + 1) * tank.dt / RAMP_S)
        velocity = np.zeros_like(position)
        velocity[..., 0] = speed
        position = position + velocity * tank.dt
        drag.append(-tank.step(position, quat_xyzw, velocity)[0])
    return np.array(drag[steps // 2:])


def towed_plate(settings: SphSettings, medium: Medium, speed_m_s: float, angle_deg: float, shrink: bool,
                depth_m: float = TOW_DEPTH_M, tank_m=TOW_TANK_M) -> dict:
    """The plate, its face at ``angle_deg`` to the tow (90: broadside), its centre ``depth_m``
    below the surface, towed along +x from 0.5 m off the tank's back wall."""
    half_angle = math.radians(angle_deg) / 2
    quat = np.array([0.0, math.sin(half_angle), 0.0, math.cos(half_angle)])   # about y: local z (the normal) tilts to x
    start = np.array([-tank_m[0] / 2 + 0.5, 0.0, -depth_m])
    tank = Tank(settings, medium, tank_m, PLATE_HALF_M, start, quat, shrink)
    try:
        mean, sd = windowed(tow(tank, start, quat, speed_m_s), tank.dt)
    finally:
        tank.close()
    model = plate_model_drag(medium, speed_m_s, quat)
    return {"speed_m_s": speed_m_s, "angle_deg": angle_deg, "depth_m": depth_m, "drag_n": mean, "window_sd_n": sd,
            "plate_model_n": model, "ratio": mean / model if model > 1e-6 else None}


def pressure_share(drag_n: float, model_n: float, depth_m: float, face_m2: float, rho_kg_m3: float,
                   g_m_s2: float = G_M_S2) -> float:
    """The SPH drag's excess over the plate model as a share of the hydrostatic force on the
    face (rho g d A): the same share at every depth means the excess follows the pressure level."""
    return (drag_n - model_n) / (rho_kg_m3 * g_m_s2 * depth_m * face_m2)


def broadside_by_depth(settings: SphSettings, medium: Medium) -> list[dict]:
    """The diagnostic: the shrunk broadside plate at 0.5 m/s at each of DIAGNOSTIC_DEPTHS_M."""
    half = boundary_boxes(PLATE_HALF_M, settings)[0]
    face_m2 = 4 * half[0] * half[1]                      # the face the water meets
    rows = []
    for depth in DIAGNOSTIC_DEPTHS_M:
        row = towed_plate(settings, medium, DIAGNOSTIC_SPEED_M_S, 90.0, True, depth, DEEP_TANK_M)
        row["excess_share_of_rho_g_d_a"] = pressure_share(row["drag_n"], row["plate_model_n"], depth, face_m2,
                                                          medium.rho_kg_m3)
        rows.append(row)
    return rows


def flowing_pool(settings: SphSettings, medium: Medium, current_m_s=CURRENT_M_S,
                 seconds: float = CURRENT_S) -> list[dict]:
    """The small pool with a current and no swimmer (a small box held above the water): every
    CURRENT_SAMPLE_S, the water's mean velocity in the middle (0.2 m in from every wall) at
    three depths."""
    length, width, depth = CURRENT_POOL_M
    above = np.array([0.0, 0.0, 0.2])
    tank = Tank(settings, medium, CURRENT_POOL_M, np.array([0.05, 0.05, 0.05]), above, IDENTITY, False, current_m_s)
    rows, every = [], int(round(CURRENT_SAMPLE_S / tank.dt))
    try:
        for k in range(1, int(round(seconds / tank.dt)) + 1):
            tank.step(above, IDENTITY, np.zeros(3))
            if k % every == 0:
                x, v = tank.worker.request("particles")
                middle = (np.abs(x[:, 0]) < length / 2 - 0.2) & (np.abs(x[:, 1]) < width / 2 - 0.2)
                layers = {name: v[middle & (np.abs(x[:, 2] - z) < 0.05)].mean(axis=0).tolist()
                          for name, z in (("floor", 0.1 - depth), ("middle", -depth / 2), ("surface", -0.1))}
                rows.append({"time_s": round(k * tank.dt, 3), "current_m_s": list(current_m_s), **layers})
    finally:
        tank.close()
    return rows


def floating_box(settings: SphSettings, medium: Medium, shrink: bool, seconds: float = 1.0) -> dict:
    """A box of density 500 let go at the surface, free to move vertically: its draft."""
    mass = FLOAT_DENSITY_KG_M3 * float(np.prod(2 * FLOAT_HALF_M))
    z = 0.0                                     # centre at the surface: half submerged, the expected draft
    tank = Tank(settings, medium, (1.2, 1.2, 0.6), FLOAT_HALF_M, [0.0, 0.0, z], IDENTITY, shrink)
    v, heights = 0.0, []
    try:
        for _ in range(int(round(seconds / tank.dt))):
            force = tank.step([0.0, 0.0, z], IDENTITY, [0.0, 0.0, v])[2]
            v += (force / mass - G_M_S2) * tank.dt       # semi-implicit Euler, vertical only
            z += v * tank.dt
            heights.append(z)
    finally:
        tank.close()
    tail = np.array(heights[len(heights) // 2:])
    draft = FLOAT_HALF_M[2] - float(tail.mean())
    expected = 2 * FLOAT_HALF_M[2] * FLOAT_DENSITY_KG_M3 / medium.rho_kg_m3
    return {"draft_m": draft, "expected_m": expected, "ratio": draft / expected}


def towed_swimmer(settings: SphSettings, medium: Medium, speed_m_s: float, shrink: bool) -> dict:
    """The glide-posed swimmer (``validate drag``'s pose) towed along +x."""
    body = load_body()
    glide = glide_state(body)
    pos = glide.pos_m - np.array([glide.pos_m[:, 0].mean() + 0.4, 0.0, 0.0])
    tank = Tank(settings, medium, (3.4, 1.5, 0.7), body.half_extents_m, pos, glide.quat_xyzw, shrink)
    try:
        mean, sd = windowed(tow(tank, pos, glide.quat_xyzw, speed_m_s), tank.dt)
    finally:
        tank.close()
    reference = REFERENCE_PASSIVE_DRAG_N_S2_M2 * speed_m_s**2
    return {"speed_m_s": speed_m_s, "drag_n": mean, "window_sd_n": sd, "reference_n": reference,
            "ratio": mean / reference}


def validate_sph(settings: SphSettings = SphSettings(), medium: Medium = Medium(), progress=None) -> dict:
    """Every case, before (raw boxes) and after (shrunk) the correction."""
    say = progress or (lambda _: None)
    out = {"particle_radius_m": settings.particle_radius_m, "mesh_shrink_radii": settings.mesh_shrink_radii,
           "window_s": WINDOW_S}
    for label, shrink in (("before", False), ("after", True)):
        say(f"{label}: held box")
        out[label] = {
            "held_box_full": held_box(settings, medium, -0.5, shrink),
            "held_box_half": held_box(settings, medium, 0.0, shrink),
        }
        say(f"{label}: floating box")
        out[label]["floating_box"] = floating_box(settings, medium, shrink)
        say(f"{label}: towed plate")
        out[label]["towed_plate"] = [towed_plate(settings, medium, v, a, shrink)
                                     for a in TOW_ANGLES_DEG for v in TOW_SPEEDS_M_S]
        say(f"{label}: towed swimmer")
        out[label]["towed_swimmer"] = [towed_swimmer(settings, medium, v, shrink) for v in SWIMMER_SPEEDS_M_S]
    say("current through the small pool")
    out["current"] = flowing_pool(settings, medium)
    say("diagnostic: broadside plate towed at three depths")
    out["broadside_by_depth"] = broadside_by_depth(settings, medium)
    return out
