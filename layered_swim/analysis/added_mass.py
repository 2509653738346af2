"""``layered-swim validate added-mass``: the plates' added mass against answers on paper.

One segment's box, alone, deep in still water with no gravity (so no weight and no buoyancy),
in PyBullet through the World, the plate backend with ``added_mass`` giving every fluid force:

* **on a spring**: along each box axis (and, a torsion spring, about each), started a little out
  of its rest point. A body of mass s carrying m of water oscillates with T = 2 pi sqrt((s + m) / k)
  (moments of inertia about an axis likewise); k is chosen so that T is 1 s. The amplitude is small
  (5 mm, 0.05 rad), so the plates' drag hardly damps it (a damped period differs by a fraction of
  a percent);
* **a hand on a forearm**, joined at the wrist by a ball joint whose PD (no damping) is the
  spring, flapped about each axis: the two boxes swing against each other and the forearm is free,
  so the answer is the linearised articulated body's, omega^2 = k (M^-1)_ee with
  M = sum_i J_i^T (S_i + A_i) J_i (own and added inertias, J_i each box's velocity from the nine
  rates). Here the water of each segment is not its alone to carry: the scheme converges over a few
  steps rather than one (see added_mass.py);
* **pushed from rest**: a constant force along the hand's palm normal. Its acceleration is
  (F + D) / (s + m) (D: the plates' drag, small this early), and the water's force is m times it;
* **the explicit force** (F_n = -m a_{n-1}, ``AddedMass.explicit``) on the hand's palm-first
  spring: a hand lighter than its water, so it blows up within tens of steps at every rate.

PyBullet's World wants at least one joint: a 1 g marker hangs at a lone box's centre on a held
ball joint, and its mass and water are counted in the answer.
"""
from __future__ import annotations

import math

import numpy as np

from layered_swim.body.layout import joint_layout
from layered_swim.body.model import Body, Joint, equal_volume_semi_axes, load_body
from layered_swim.fluid.added_mass import ellipsoid_added_inertia, own_inertia
from layered_swim.fluid.medium import Medium
from layered_swim.fluid.thin_plate import PlateFluid, PlateSettings
from layered_swim.geometry import quat_multiply
from layered_swim.sim.simulation import MAX_SPEED_M_S
from layered_swim.sim.world import World

SEGMENTS = ("hand_l", "foot_l", "forearm_l", "thigh_l", "thorax")   # flat plates, a bar, a prism, the trunk
RATES_HZ = (240, 480, 960)
PERIOD_S = 1.0                 # each spring is stiff enough for this period with the water's mass
PERIODS = 4                    # simulated
AMPLITUDE_M = 0.005
AMPLITUDE_RAD = 0.05
DEPTH_M = 3.0
TOLERANCE = 0.10               # the must-hold: the period within 10 % of the analytic one
MARKER_KG, MARKER_HALF_M = 0.001, 0.005
PUSH_N = 10.0
PUSH_S = 0.03                  # the pushed plate's window (its first step left out: see added_mass.py)
AXES = "xyz"


def one_box(segment: str, body: Body | None = None) -> Body:
    """``segment``'s box of the swimmer as a body of its own (mass, box, volume), with the marker."""
    body = body or load_body()
    i = body.index(segment)
    half = np.array([body.half_extents_m[i], [MARKER_HALF_M] * 3])
    volume = np.array([body.volume_m3[i], MARKER_KG / 1000.0])
    marker = Joint(name="marker", type="ball", parent="box", child="marker", axis_names=("x", "y", "z"),
                   axes=np.eye(3), lower_rad=np.full(3, -math.pi), upper_rad=np.full(3, math.pi), kp=0.05, kd=0.001,
                   max_torque_nm=10.0, joint_at_m=np.zeros(3))
    return Body(name=f"{segment}_box", segment_names=("box", "marker"), parents=(None, "box"),
                mass_kg=np.array([body.mass_kg[i], MARKER_KG]), half_extents_m=half, center_m=np.zeros((2, 3)),
                volume_m3=volume, semi_axes_m=equal_volume_semi_axes(half, volume), joints=(marker,),
                gimbal_mass_kg=body.gimbal_mass_kg, lung_air_l=0.0, lung_segment="box", max_lung_air_l=0.0,
                source=f"{body.source} ({segment} alone)")


def wrist_pair(body: Body | None = None, stiffness_nm_rad: float = 1.0) -> Body:
    """The swimmer's left forearm box (free) with its hand box on a ball joint at the wrist end, no
    gimbal, the joint's PD a spring of ``stiffness_nm_rad`` without damping."""
    body = body or load_body()
    f, h = body.index("forearm_l"), body.index("hand_l")
    half = body.half_extents_m[[f, h]]
    volume = body.volume_m3[[f, h]]
    wrist = Joint(name="wrist", type="ball", parent="forearm", child="hand", axis_names=("x", "y", "z"),
                  axes=np.eye(3), lower_rad=np.full(3, -math.pi), upper_rad=np.full(3, math.pi), kp=stiffness_nm_rad,
                  kd=0.0, max_torque_nm=100.0, joint_at_m=np.array([0.0, 0.0, -half[0, 2]]))
    return Body(name="wrist_pair", segment_names=("forearm", "hand"), parents=(None, "forearm"),
                mass_kg=body.mass_kg[[f, h]].copy(), half_extents_m=half,
                center_m=np.array([[0.0, 0.0, 0.0], [0.0, 0.0, -half[1, 2]]]), volume_m3=volume,
                semi_axes_m=equal_volume_semi_axes(half, volume), joints=(wrist,), gimbal_mass_kg=body.gimbal_mass_kg,
                lung_air_l=0.0, lung_segment="forearm", max_lung_air_l=0.0, source=f"{body.source} (wrist pair)")


def _wrist_mobility(pair: Body, rho_kg_m3: float, water: bool) -> np.ndarray:
    """(M^-1)[6:9, 6:9] of the pair at rest, aligned with the world: the wrist's compliance per unit
    stiffness. Rates: the forearm's velocity and angular velocity at its centre, then the wrist's."""
    inertia = own_inertia(pair) + (ellipsoid_added_inertia(pair.semi_axes_m, rho_kg_m3) if water else 0.0)
    wrist = pair.joints[0].joint_at_m
    hand = wrist + pair.center_m[1]

    def skew(r):
        return np.array([[0.0, -r[2], r[1]], [r[2], 0.0, -r[0]], [-r[1], r[0], 0.0]])

    eye, zero = np.eye(3), np.zeros((3, 3))
    forearm_j = np.block([[eye, zero, zero], [zero, eye, zero]])
    hand_j = np.block([[eye, -skew(hand), -skew(hand - wrist)], [zero, eye, eye]])
    mass = sum(j.T @ np.diag(d) @ j for j, d in ((forearm_j, inertia[0]), (hand_j, inertia[1])))
    return np.linalg.inv(mass)[6:9, 6:9]


def wrist_spring(axis: int, physics_hz: int, body: Body | None = None, periods: float = PERIODS) -> dict:
    """The hand flapping about its wrist's ``axis`` against the free forearm (see the module's docstring)."""
    medium = Medium()
    pair = wrist_pair(body)
    compliance = _wrist_mobility(pair, medium.rho_kg_m3, True)[axis, axis]
    k = (2.0 * math.pi / PERIOD_S) ** 2 / compliance
    pair = wrist_pair(body, k)
    tank = _Tank(pair, physics_hz, True, False, medium)
    try:
        start = tank.pose.copy()
        start[axis] = AMPLITUDE_RAD
        tank.world.reset((0.0, 0.0, -DEPTH_M), (0.0, 0.0, 0.0, 1.0), start)
        tank.world.set_targets(tank.pose, tank.pose)
        tank.fluid.reset()
        n = int(round(periods * PERIOD_S * physics_hz))
        t, d = np.empty(n), np.empty(n)
        zero = np.zeros(3)
        for step in range(n):
            state = tank.world.read_state()
            forearm, hand = state.quat_xyzw
            t[step] = state.time_s
            d[step] = _rotation_vector(quat_multiply(forearm * [-1.0, -1.0, -1.0, 1.0], hand))[axis]
            tank.step(zero, zero)
    finally:
        tank.close()
    analytic = 2.0 * math.pi / math.sqrt(k * compliance)
    dry = 2.0 * math.pi / math.sqrt(k * _wrist_mobility(pair, medium.rho_kg_m3, False)[axis, axis])
    simulated = _crossing_period(t, d)
    return {"segment": "hand_l on forearm_l", "motion": f"about wrist {AXES[axis]}", "physics_hz": physics_hz,
            "k": float(k), "analytic_s": analytic, "without_water_s": dry, "simulated_s": simulated,
            "ratio": simulated / analytic}


def _axis_angle(axis: np.ndarray, angle: float) -> np.ndarray:
    return np.array([*(axis * math.sin(angle / 2)), math.cos(angle / 2)])


def _rotation_vector(q: np.ndarray) -> np.ndarray:
    q = q if q[3] >= 0 else -q
    s = np.linalg.norm(q[:3])
    return np.zeros(3) if s < 1e-15 else q[:3] / s * 2.0 * math.atan2(s, q[3])


class _Tank:
    """The box (and marker) deep in still water without gravity, stepped like ``Simulation.step``:
    the fluid first, then the pushes, PD, PyBullet."""

    def __init__(self, box: Body, physics_hz: int, added_mass: bool = True, explicit: bool = False,
                 medium: Medium = Medium()):
        self.box = box
        layout = joint_layout(box)
        self.world = World(box, layout, physics_hz, 0.0)
        self.fluid = PlateFluid(box, medium, 0.0, PlateSettings(added_mass=added_mass))
        if explicit:
            self.fluid.added_mass.explicit = True
        self.pose = layout.zeros()

    def start(self, quat_xyzw=(0.0, 0.0, 0.0, 1.0)) -> None:
        self.world.reset((0.0, 0.0, -DEPTH_M), quat_xyzw, self.pose)
        self.world.set_targets(self.pose, self.pose)
        self.fluid.reset()

    def step(self, force_n: np.ndarray, torque_nm: np.ndarray):
        """One step with ``force_n``/``torque_nm`` on the box besides the water; the state before it
        and what the water did."""
        state = self.world.read_state()
        water = self.fluid.wrenches(state)
        force, torque = water.force_n.copy(), water.torque_nm.copy()
        force[0] += force_n
        torque[0] += torque_nm
        self.world.drive_with_wrenches(force, torque, state.pos_m)      # as the simulation's step does
        self.world.step()
        return state, water

    def close(self) -> None:
        self.world.close()


def _inertia_totals(box: Body, rho_kg_m3: float) -> tuple[np.ndarray, np.ndarray]:
    """Own and added inertia (6,) of box and marker together, the marker held to the box at its centre."""
    return own_inertia(box).sum(axis=0), ellipsoid_added_inertia(box.semi_axes_m, rho_kg_m3).sum(axis=0)


def _crossing_period(t: np.ndarray, d: np.ndarray) -> float:
    """Twice the mean time between successive zero crossings of d(t) (linear interpolation)."""
    s = np.sign(d)
    k = np.nonzero(s[:-1] * s[1:] < 0)[0]
    if len(k) < 3:
        return math.nan
    crossings = t[k] - d[k] * (t[k + 1] - t[k]) / (d[k + 1] - d[k])
    return float(2.0 * np.mean(np.diff(crossings)))


def spring(segment: str, axis: int, rotation: bool, physics_hz: int, added_mass: bool = True,
           explicit: bool = False, body: Body | None = None, periods: float = PERIODS) -> dict:
    """The box on a spring along (``rotation``: a torsion spring about) its axis ``axis``."""
    box = one_box(segment, body)
    medium = Medium()
    own, added = _inertia_totals(box, medium.rho_kg_m3)
    j = 3 * rotation + axis
    inertia = own[j] + (added[j] if added_mass else 0.0)
    k = inertia * (2.0 * math.pi / PERIOD_S) ** 2
    e = np.eye(3)[axis]
    tank = _Tank(box, physics_hz, added_mass, explicit, medium)
    try:
        if rotation:
            tank.start(_axis_angle(e, AMPLITUDE_RAD))
        else:
            tank.start()
        anchor = np.array([0.0, 0.0, -DEPTH_M]) - AMPLITUDE_M * e
        amplitude = AMPLITUDE_RAD if rotation else AMPLITUDE_M
        n = int(round(periods * PERIOD_S * physics_hz))
        t, d = np.empty(n), np.empty(n)
        diverged_at = None
        zero = np.zeros(3)
        for step in range(n):
            state = tank.world.read_state()
            if rotation:
                turn = _rotation_vector(state.quat_xyzw[0])      # from the rest orientation, the identity
                t[step], d[step] = state.time_s, turn @ e
                tank.step(zero, -k * turn)
            else:
                offset = state.pos_m[0] - anchor
                t[step], d[step] = state.time_s, offset @ e
                tank.step(-k * offset, zero)
            if not (abs(d[step]) < 100.0 * amplitude and np.abs(state.linvel_m_s).max() < MAX_SPEED_M_S):
                diverged_at = step      # what Simulation.step calls diverged (PyBullet caps speeds near 100 m/s)
                break
    finally:
        tank.close()
    own_j, added_j = float(own[j]), float(added[j])
    row = {"segment": segment, "motion": f"{'about' if rotation else 'along'} {AXES[axis]}", "physics_hz": physics_hz,
           "own": own_j, "added": added_j, "k": float(k),
           "analytic_s": 2.0 * math.pi * math.sqrt((own_j + added_j) / k),
           "without_water_s": 2.0 * math.pi * math.sqrt(own_j / k)}
    if diverged_at is not None:
        return {**row, "simulated_s": None, "ratio": None, "diverged_after_steps": diverged_at}
    simulated = _crossing_period(t, d)
    return {**row, "simulated_s": simulated, "ratio": simulated / row["analytic_s"], "diverged_after_steps": None}


def pushed_plate(physics_hz: int, segment: str = "hand_l", axis: int = 1, body: Body | None = None) -> dict:
    """The box pushed from rest by a constant force along its axis ``axis`` (the hand's palm normal)."""
    box = one_box(segment, body)
    medium = Medium()
    own, added = _inertia_totals(box, medium.rho_kg_m3)
    e = np.eye(3)[axis]
    tank = _Tank(box, physics_hz, True, False, medium)
    try:
        tank.start()
        n = max(4, int(round(PUSH_S * physics_hz)))
        velocity, water_force, added_force = [], [], []
        for _ in range(n + 1):
            state, water = tank.step(PUSH_N * e, np.zeros(3))
            velocity.append(state.linvel_m_s[:, axis] @ box.mass_kg / box.mass_kg.sum())
            water_force.append(float(water.force_n[:, axis].sum()))
            added_force.append(float(tank.fluid.added_mass.force_n[:, axis].sum()))
    finally:
        tank.close()
    dt = 1.0 / physics_hz
    # Step i's force acts from state i to state i + 1; the first step, with no last step to read,
    # carries no water (see added_mass.py), so it is left out.
    acc = np.diff(velocity) / dt
    acc, water_force, added_force = acc[1:], np.array(water_force[1:-1]), np.array(added_force[1:-1])
    drag = water_force - added_force
    mass = own[axis] + added[axis]
    expected = float(np.mean((PUSH_N + drag) / mass))
    simulated = float(np.mean(acc))
    return {"segment": segment, "along": AXES[axis], "physics_hz": physics_hz, "force_n": PUSH_N,
            "own_kg": float(own[axis]), "added_kg": float(added[axis]), "simulated_m_s2": simulated,
            "analytic_m_s2": expected, "ratio": simulated / expected, "without_water_m_s2": float(PUSH_N / own[axis]),
            "water_force_over_added_mass_times_a": float(np.mean(-added_force / (added[axis] * acc)))}


def validate_added_mass(segments=SEGMENTS, rates_hz=RATES_HZ) -> dict:
    """Every spring (each segment, each axis, along and about; the wrist about each axis) at each
    rate, the pushed hand at each rate, and the explicit force's blow-up at each rate."""
    body = load_body()
    springs = [spring(s, axis, rotation, hz, body=body) for hz in rates_hz for s in segments
               for rotation in (False, True) for axis in range(3)]
    springs += [wrist_spring(axis, hz, body=body) for hz in rates_hz for axis in range(3)]
    pushed = [pushed_plate(hz, body=body) for hz in rates_hz]
    explicit = [spring("hand_l", 1, False, hz, explicit=True, body=body) for hz in rates_hz]
    ok = all(abs(r["ratio"] - 1.0) <= TOLERANCE for r in springs + pushed)
    return {"tolerance": TOLERANCE, "period_s": PERIOD_S, "amplitude_m": AMPLITUDE_M, "amplitude_rad": AMPLITUDE_RAD,
            "springs": springs, "pushed": pushed, "explicit": explicit, "pass": bool(ok)}
