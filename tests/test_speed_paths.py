"""The physics step's fast paths give numpy's own bits: the compiled single-quaternion rotation
and cross product, the one-call wrench + stable PD loads, the compiled hand rules, the goal
line's one-time position, the plates' one call with the added mass, and the controller's and the
environment's compiled helpers."""
import math

import numpy as np

from layered_swim.body.layout import joint_layout
from layered_swim.body.model import load_body
from layered_swim.control.rules import RULE_MEMORY_S, arm_indices, rule_offsets
from layered_swim.control.stroke import RulesSpec
from layered_swim.geometry import cross, quat_rotate, unit_vector
from layered_swim.sim.simulation import PRONE_QUAT_XYZW
from layered_swim.sim.world import World
from layered_swim.tasks import swim_benchmark as bench


def _numpy_rotate(q, v):
    u, w = q[..., :3], q[..., 3:4]
    t = 2.0 * np.cross(u, v)
    return v + w * t + np.cross(u, t)


def test_compiled_rotation_and_cross_are_numpys_bits():
    rng = np.random.default_rng(3)
    for _ in range(2000):
        q = rng.normal(size=4)
        q /= np.linalg.norm(q)
        v, rows = rng.normal(size=3) * rng.uniform(0.0, 50.0), rng.normal(size=(2, 3))
        assert quat_rotate(q, v).tobytes() == _numpy_rotate(q, v).tobytes()
        assert quat_rotate(q, rows).tobytes() == _numpy_rotate(q, rows).tobytes()
        assert cross(rows, v).tobytes() == np.cross(rows, v).tobytes()
        assert cross(v, rows[0]).tobytes() == np.cross(v, rows[0]).tobytes()
        assert unit_vector(v).tobytes() == (v / float(np.linalg.norm(v))).tobytes()
    many = rng.normal(size=(5, 4))          # the general path still broadcasts
    assert quat_rotate(many, rng.normal(size=(5, 3))).shape == (5, 3)


def test_one_call_loads_equal_wrenches_then_drive():
    body = load_body()
    layout = joint_layout(body)
    pending = []
    for fused in (False, True):
        world = World(body, layout, 480, gravity_m_s2=9.81)
        try:
            world.reset((0.0, 0.0, -0.3), PRONE_QUAT_XYZW, layout.zeros(), (0.5, 0.0, 0.0))
            world.set_targets(0.2 * np.ones(layout.size), np.ones(layout.size))
            state = world.read_state()
            force = np.random.default_rng(1).normal(size=state.pos_m.shape)
            torque = np.random.default_rng(2).normal(size=state.pos_m.shape)
            if fused:
                world.drive_with_wrenches(force, torque, state.pos_m)
            else:
                world.apply_wrenches(force, torque, state.pos_m)
                world.drive()
            pending.append(world._pending.copy())
        finally:
            world.close()
    assert pending[0].tobytes() == pending[1].tobytes()


def _dot3(a, b):
    """Dot products with 3-vectors (``b``), summed left to right: numpy's ``@`` goes through BLAS,
    whose kernel (and so its rounding) depends on the CPU (an AVX-512 machine's differed in the
    last bit)."""
    return a[..., 0] * b[0] + a[..., 1] * b[1] + a[..., 2] * b[2]


def _numpy_rules(previous, arms, rules, quat, linvel, flow_m_s, desired, dt_s, engagement):
    """The hand rules as numpy vector expressions (the compiled kernel's reference)."""
    pull, limit = np.zeros_like(previous), np.zeros_like(previous)
    for arm in arms:
        flow = flow_m_s[arm.hand] - linvel[arm.hand]
        speed = math.sqrt(_dot3(flow, flow))
        if speed < 0.05:
            continue
        flow_dir = flow / speed
        helpfulness, strength = _dot3(flow_dir, desired), min(speed, 1.0)
        if helpfulness > 0.0 or rules.palm.hindering:
            normal = _numpy_rotate(quat[arm.hand], np.array([0.0, 1.0, 0.0]))
            turning = np.cross(_numpy_rotate(quat[arm.forearm], arm.wrist_axes), normal)
            facing, along = _dot3(normal, flow_dir), _dot3(normal, desired)
            toward_flow, toward_desired = _dot3(turning, flow_dir), _dot3(turning, desired)
            gradient = 2.0 * abs(facing) * along * toward_flow + facing * abs(facing) * toward_desired
            pull[list(arm.palm_coords)] = rules.palm.gain * strength * gradient
            limit[list(arm.palm_coords)] = np.radians(rules.palm.max_deg)
        if helpfulness > 0.0 or rules.reach.hindering:
            pull[arm.elbow_coord] = -rules.reach.gain * helpfulness * strength
            limit[arm.elbow_coord] = np.radians(rules.reach.max_deg)
    return np.clip(previous * (1.0 - dt_s / RULE_MEMORY_S) + engagement * pull * dt_s, -limit, limit)


def test_compiled_hand_rules_are_numpys_bits():
    body = load_body()
    layout = joint_layout(body)
    arms, rules = arm_indices(body, layout), RulesSpec()
    rng = np.random.default_rng(5)
    n = len(body.segment_names)
    for k in range(500):
        quat = rng.normal(size=(n, 4))
        quat /= np.linalg.norm(quat, axis=1, keepdims=True)
        linvel, flow = rng.normal(size=(n, 3)), rng.normal(size=(n, 3)) * (k % 3)   # some steps in still water
        desired = rng.normal(size=3)
        desired /= np.linalg.norm(desired)
        previous = rng.normal(size=layout.size) * 0.3
        args, engagement = (previous, arms, rules, quat, linvel, flow, desired, 1.0 / 120.0), rng.uniform()
        assert rule_offsets(*args, engagement=engagement).tobytes() == _numpy_rules(*args, engagement).tobytes()


def test_the_goal_lines_one_time_position_is_the_arrays():
    task = bench.goal_tasks(bench.pool("small"))[2]
    for t_s in (0.0, 0.37, 1.9, task.duration_s, task.duration_s + 2.0):
        one = bench.goal_position(task, float(t_s))
        assert one.tobytes() == bench.goal_position(task, np.array([t_s]))[0].tobytes()
        assert bench.intermediate_goal(task, float(t_s), 0.5).tobytes() == \
            bench.intermediate_goal(task, np.array(t_s), 0.5).tobytes()


def test_the_plates_one_call_with_the_added_mass_equals_the_two_summed():
    from layered_swim.episode import Episode
    from layered_swim.fluid.added_mass import AddedMass
    from layered_swim.fluid.thin_plate import _fluid_wrenches

    episode = Episode("front_crawl")
    try:
        fluid = episode.sim.fluid
        twin = AddedMass(episode.body, fluid.medium.rho_kg_m3)
        for _ in range(30):
            state = episode.sim.state
            plates = _fluid_wrenches(state.pos_m, state.quat_xyzw, state.linvel_m_s, state.angvel_rad_s,
                                     fluid._segments, fluid._medium, fluid._coefficients, fluid._segment_current)
            added_force, added_torque = twin.wrenches(state, fluid.medium.surface_z_m)
            expected = (plates[0] + added_force, plates[1] + added_torque)
            episode.step()            # the simulation's own call, fused
            got = episode.sim.fluid_now
            assert got.force_n.tobytes() == expected[0].tobytes() and got.torque_nm.tobytes() == expected[1].tobytes()
        again = fluid.wrenches(episode.sim.state)      # asked twice at one time, the added mass stands
        assert fluid.wrenches(episode.sim.state).force_n.tobytes() == again.force_n.tobytes()
    finally:
        episode.close()


def test_the_controller_and_environments_compiled_helpers_are_numpys_bits():
    from layered_swim.control.stroke import TABLE_SAMPLES, CyclicTable
    from layered_swim.rl.env import _add_into
    from layered_swim.rl.observation import to_heading_frame
    from layered_swim.sim.world import _scatter
    from layered_swim.state import _clipped

    rng = np.random.default_rng(5)
    table = CyclicTable(rng.normal(size=(TABLE_SAMPLES + 1, 41)), rng.normal(size=(TABLE_SAMPLES + 1, 41)))
    for phase in rng.uniform(-3.0, 3.0, 300):
        x = (phase % 1.0) * TABLE_SAMPLES
        i = min(int(x), TABLE_SAMPLES - 1)
        w = x - i
        pose, rate = table.at(phase)
        assert pose.tobytes() == (table.values[i] * (1.0 - w) + table.values[i + 1] * w).tobytes()
        assert rate.tobytes() == (table.rates[i] * (1.0 - w) + table.rates[i + 1] * w).tobytes()
        base_pose, base_rate, weight = rng.normal(size=41), rng.normal(size=41), rng.uniform(-1.5, 1.5)
        added_pose, added_rate = table.added(base_pose, base_rate, weight, phase)
        assert added_pose.tobytes() == (base_pose + weight * pose).tobytes()
        assert added_rate.tobytes() == (base_rate + weight * rate).tobytes()
    for shape in ((3,), (16, 3), (4, 3)):
        v, heading = rng.normal(size=shape), rng.uniform(-4.0, 4.0)
        c, s = math.cos(heading), math.sin(heading)
        expected = np.stack([c * v[..., 0] + s * v[..., 1], -s * v[..., 0] + c * v[..., 1], v[..., 2]], axis=-1)
        assert to_heading_frame(v, heading).tobytes() == expected.tobytes()
    first, then = rng.normal(size=8), rng.normal(size=5)
    at, source = rng.permutation(13)[:10], rng.permutation(13)[:10]
    into, expected = np.zeros(13), np.zeros(13)
    _scatter(into, at, source, first, then)
    expected[at] = np.concatenate([first, then])[source]
    assert into.tobytes() == expected.tobytes()
    low = rng.normal(size=41) - 1.0
    high = low + rng.uniform(0.0, 2.0, 41)
    pose = rng.normal(size=41) * 2.0
    pose[:4], low[1], high[1] = (np.nan, -0.0, low[2], high[3]), 0.0, 1.0     # NaN, a signed zero, ties
    assert _clipped(pose, low, high).tobytes() == np.clip(pose, low, high).tobytes()
    force, torque, more_force, more_torque = (rng.normal(size=(16, 3)) for _ in range(4))
    expected_force, expected_torque = force + more_force, torque + more_torque
    _add_into(force, torque, more_force, more_torque)
    assert force.tobytes() == expected_force.tobytes() and torque.tobytes() == expected_torque.tobytes()
