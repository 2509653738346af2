"""The own integrator (sim/integrator.py) steps the body as PyBullet's multibody does: from the same
state and loads it lands on PyBullet's next state (to rounding; to ~1e-6 with a joint past its
limit, where Bullet's solve differs in detail); a swim stays on PyBullet's; a pool with walls is
stepped by PyBullet."""
import numpy as np
import pytest

from layered_swim.body.layout import joint_layout
from layered_swim.body.model import load_body
from layered_swim.config import ConfigError
from layered_swim.episode import Episode
from layered_swim.sim.simulation import PRONE_QUAT_XYZW, SimConfig
from layered_swim.sim.world import World
from layered_swim.spec import SwimSpec

PHYSICS_HZ = 480


def _worlds(pose):
    body = load_body()
    layout = joint_layout(body)
    worlds = [World(body, layout, PHYSICS_HZ, 9.81, integrator=kind) for kind in ("bullet", "own")]
    for world in worlds:
        world.reset((0.0, 0.0, -0.3), PRONE_QUAT_XYZW, pose, (1.0, 0.2, 0.0))
    return layout, worlds


def _knee_beyond_its_limit(layout):
    """A pose with the left knee 0.05 rad past its upper limit (PyBullet's limit row is active)."""
    body = load_body()
    knee = next(j for j in body.joints if j.name == "knee_l")
    pose = layout.zeros()
    pose[layout.index("knee_l.flexion")] = knee.upper_rad[0] + 0.05
    return pose


def _step_both(worlds, layout, target, loads_rng_seed=0, steps=1):
    rng = np.random.default_rng(loads_rng_seed)
    n = len(worlds[0].segment_links)
    force, torque = rng.normal(0.0, 20.0, (n, 3)), rng.normal(0.0, 2.0, (n, 3))
    for _ in range(steps):
        for world in worlds:
            state = world.read_state()
            world.set_targets(target, np.zeros_like(target))
            world.drive_and_step(force, torque, state.pos_m)
    return [(world.read_state().pos_m.copy(), world.kinematics()[1].copy()) for world in worlds]


def test_one_step_lands_on_pybullets_next_state_with_a_joint_past_its_limit():
    layout = joint_layout(load_body())
    pose = _knee_beyond_its_limit(layout)
    layout, worlds = _worlds(pose)
    try:
        (pos_b, qd_b), (pos_o, qd_o) = _step_both(worlds, layout, pose)
        np.testing.assert_allclose(qd_o, qd_b, atol=1e-5)
        np.testing.assert_allclose(pos_o, pos_b, atol=1e-7)
        # The limit pushed back: the knee's rate points inside its range (PD alone drives it further out).
        knee = worlds[1].tree.rates_of(1 + worlds[1].motor_indices[layout.motor_joint.index("knee_l")]).start
        assert qd_o[knee] < 0.0
    finally:
        for world in worlds:
            world.close()


def test_a_second_of_steps_stays_on_pybullets_states():
    layout = joint_layout(load_body())
    target = layout.zeros()
    target[layout.index("shoulder_l.flexion")] = 1.5
    target[layout.index("knee_r.flexion")] = 1.0
    layout, worlds = _worlds(layout.zeros())
    try:
        (pos_b, qd_b), (pos_o, qd_o) = _step_both(worlds, layout, target, steps=PHYSICS_HZ)
        np.testing.assert_allclose(pos_o, pos_b, atol=1e-4)
        np.testing.assert_allclose(qd_o, qd_b, atol=1e-3)
    finally:
        for world in worlds:
            world.close()


def test_a_swim_is_pybullets_to_rounding():
    tracks = {}
    for integrator in ("bullet", "own"):
        spec = SwimSpec.of("test", stroke="front_crawl", seconds=2.0, integrator=integrator)
        episode = spec.episode()
        try:
            episode.run(2.0)
            tracks[integrator] = episode.sim.state.com_m
        finally:
            episode.close()
    np.testing.assert_allclose(tracks["own"], tracks["bullet"], atol=1e-9)


def test_walls_hand_the_step_to_pybullet_and_back():
    layout, worlds = _worlds(joint_layout(load_body()).zeros())
    world = worlds[1]
    try:
        assert world.own
        world.set_pool(np.array([-3.0, -1.0, -1.0]), np.array([3.0, 1.0, 0.5]))
        assert not world.own
        _step_both([world], layout, layout.zeros(), steps=10)
        moved = world.read_state().pos_m.copy()
        world.set_pool(None, None)
        assert world.own
        np.testing.assert_array_equal(world.read_state().pos_m, moved)   # on from where PyBullet left it
    finally:
        for w in worlds:
            w.close()


def test_an_unknown_integrator_is_one_clear_error():
    with pytest.raises(ConfigError, match="integrator"):
        SimConfig(PHYSICS_HZ, 120, 9.81, "rk4")
    with pytest.raises(ConfigError, match="integrator"):
        SwimSpec.of("test", stroke="front_crawl", integrator="rk4")
    with pytest.raises(ConfigError, match="integrator"):
        Episode("front_crawl", integrator="rk4")


def test_the_trees_own_factorisation_solves_as_a_dense_one():
    """``ltl_factor`` keeps to the mass matrix's tree sparsity; the solve and stable PD through it
    agree with the dense Cholesky to rounding."""
    from layered_swim.sim.articulation import ltl_factor, ltl_solve, mass_matrix_and_bias, parent_rates
    from layered_swim.sim.pd import stable_pd_torques

    episode = Episode("front_crawl")
    try:
        episode.run(1.0)
        world = episode.sim.world
        tree = world.tree
        mass, bias = mass_matrix_and_bias(tree.index, tree.params, world._frames, world._subspace, 9.81)
        parent = parent_rates(tree.index)
        assert all(-1 <= p < k for k, p in enumerate(parent))
        outside = [(i, j) for i in range(tree.n_dof) for j in range(i)
                   if mass[i, j] != 0.0 and j not in _ancestors(parent, i)]
        assert not outside, f"mass matrix entries off the tree: {outside[:5]}"
        b = np.random.default_rng(0).normal(size=tree.n_dof)
        factor = mass.copy()
        ltl_factor(factor, parent)
        np.testing.assert_allclose(ltl_solve(factor, parent, b), np.linalg.solve(mass, b), rtol=1e-9, atol=1e-9)
        q, qd = world.kinematics()[:2]
        args = (tree.index, q, qd, world._target_q, world._target_qd, world._gains, world.dt_s)
        dense = stable_pd_torques(mass.copy(), bias, *args, np.zeros(0, dtype=np.int64))
        np.testing.assert_allclose(stable_pd_torques(mass.copy(), bias, *args, parent), dense, rtol=1e-9, atol=1e-9)
    finally:
        episode.close()


def _ancestors(parent, k):
    found, j = set(), parent[k]
    while j >= 0:
        found.add(j)
        j = parent[j]
    return found


def test_a_run_folder_from_before_the_own_integrator_replays_with_pybullet(tmp_path):
    import json

    from layered_swim.runs import repeatable, run_swim

    spec = SwimSpec.of("test", stroke="front_crawl", seconds=0.2)
    run_swim(spec, tmp_path / "run")
    config = json.loads((tmp_path / "run" / "config.json").read_text())
    assert config["swim"]["integrator"] == "own"
    assert repeatable(tmp_path / "run" / "config.json")[1].integrator == "own"
    del config["swim"]["integrator"]          # as written before the own integrator
    (tmp_path / "old.json").write_text(json.dumps(config))
    assert repeatable(tmp_path / "old.json")[1].integrator == "bullet"
