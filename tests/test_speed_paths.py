"""The physics step's fast paths give numpy's own bits: the compiled single-quaternion rotation
and cross product, and the one-call wrench + stable PD loads."""
import numpy as np

from layered_swim.body.layout import joint_layout
from layered_swim.body.model import load_body
from layered_swim.geometry import cross, quat_rotate, unit_vector
from layered_swim.sim.simulation import PRONE_QUAT_XYZW
from layered_swim.sim.world import World


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
