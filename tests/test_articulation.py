"""Our kinematics and dynamics of the joint tree against PyBullet's own and against physics."""
import numpy as np
import pybullet
import pytest

from layered_swim.episode import Episode
from layered_swim.sim.articulation import ANGVEL, LINVEL, POS, QUAT, ROT, generalized_forces, mass_matrix_and_bias

GRAVITY_M_S2 = 9.81


@pytest.fixture(scope="module")
def swimming():
    """A front crawl 1.3 s in: every joint moving."""
    episode = Episode("front_crawl", integrator="bullet")   # checked against PyBullet's own state
    episode.run(1.3)
    yield episode.sim
    episode.close()


def test_forward_kinematics_matches_pybullet(swimming):
    world = swimming.world
    _, _, frames, _ = world.kinematics()
    links = pybullet.getLinkStates(world.uid, world._joints, 1, 1, physicsClientId=world._cid)
    theirs = frames[1:]
    np.testing.assert_allclose(theirs[:, POS], [s[0] for s in links], atol=1e-12)
    np.testing.assert_allclose(theirs[:, LINVEL], [s[6] for s in links], atol=1e-12)
    np.testing.assert_allclose(theirs[:, ANGVEL], [s[7] for s in links], atol=1e-12)
    # A quaternion and its negative are the same orientation.
    quat = np.array([s[1] for s in links])
    sign = np.sign(np.sum(quat * theirs[:, QUAT], axis=1))
    np.testing.assert_allclose(theirs[:, QUAT] * sign[:, None], quat, atol=1e-12)
    rows = theirs[:, ROT].reshape(-1, 3, 3)
    np.testing.assert_allclose(rows @ np.transpose(rows, (0, 2, 1)), np.broadcast_to(np.eye(3), rows.shape), atol=1e-12)


def test_mass_matrix_gives_the_kinetic_energy(swimming):
    """1/2 qd.M.qd equals the bodies' kinetic energy summed box by box."""
    world = swimming.world
    tree = world.tree
    _, qd, frames, subspace = world.kinematics()
    mass, _ = mass_matrix_and_bias(tree.index, tree.params, frames, subspace, GRAVITY_M_S2)
    assert np.allclose(mass, mass.T, atol=1e-12)
    assert np.linalg.eigvalsh(mass).min() > 0.0
    np.testing.assert_allclose(mass[3:6, 3:6], np.eye(3) * tree.mass_kg.sum(), rtol=1e-12)
    kinetic_j = 0.0
    for i in range(tree.n_bodies):
        rot = frames[i, ROT].reshape(3, 3)
        spin = rot.T @ frames[i, ANGVEL]
        kinetic_j += 0.5 * tree.mass_kg[i] * frames[i, LINVEL] @ frames[i, LINVEL]
        kinetic_j += 0.5 * spin @ (tree.inertia_kg_m2[i] * spin)
    assert 0.5 * qd @ mass @ qd == pytest.approx(kinetic_j, rel=1e-10)


def test_bias_at_rest_is_the_weight(swimming):
    """With every rate zero the bias is gravity alone: it cancels the generalised forces of the
    bodies' weights, and on the base it is the whole weight, upwards."""
    world = swimming.world
    tree = world.tree
    _, _, frames, subspace = world.kinematics()
    still = frames.copy()
    still[:, LINVEL] = 0.0
    still[:, ANGVEL] = 0.0
    _, bias = mass_matrix_and_bias(tree.index, tree.params, still, subspace, GRAVITY_M_S2)
    rows = np.arange(tree.n_bodies)
    weight = np.zeros((tree.n_bodies, 3))
    weight[:, 2] = -GRAVITY_M_S2 * tree.mass_kg
    load = generalized_forces(tree.index, still, subspace, rows, weight, np.zeros_like(weight), still[:, POS])
    np.testing.assert_allclose(bias + load, 0.0, atol=1e-9)
    assert bias[5] == pytest.approx(GRAVITY_M_S2 * tree.mass_kg.sum(), rel=1e-12)


def _rates_after_one_step(world, act) -> np.ndarray:
    state = world.client.saveState()
    try:
        world.read_state()
        act()
        world.step()
        return world.kinematics()[1].copy()
    finally:
        world.client.restoreState(state)
        world.client.removeState(state)
        world.read_state()


def test_segment_wrenches_as_generalised_forces_match_pybullet(swimming):
    """Pushing each segment through its generalised forces moves the body as PyBullet's own
    per-link external forces do."""
    world = swimming.world
    rng = np.random.default_rng(7)
    n = len(world.segment_links)
    force, torque = rng.normal(0.0, 20.0, (n, 3)), rng.normal(0.0, 2.0, (n, 3))
    state = world.read_state()
    at = state.pos_m + rng.normal(0.0, 0.05, (n, 3))

    def pybullet_forces():
        pybullet.getLinkStates(world.uid, world._joints, 0, 1, physicsClientId=world._cid)  # fresh link frames
        for link, f, t, p in zip(world.segment_links, force, torque, at):
            pybullet.applyExternalForce(world.uid, link, f.tolist(), p.tolist(), pybullet.WORLD_FRAME,
                                        physicsClientId=world._cid)
            pybullet.applyExternalTorque(world.uid, link, t.tolist(), pybullet.WORLD_FRAME, physicsClientId=world._cid)

    theirs = _rates_after_one_step(world, pybullet_forces)
    ours = _rates_after_one_step(world, lambda: world.apply_wrenches(force, torque, at))
    unpushed = _rates_after_one_step(world, lambda: None)
    assert np.abs(theirs - unpushed).max() > 0.1
    np.testing.assert_allclose(ours, theirs, atol=1e-9)
