"""The joints' mechanical work, from the torques stable PD applied, closes the energy balance of
a swim: joint work = change of kinetic and potential energy - work of the water."""
import numpy as np
import pytest

from layered_swim.episode import Episode
from layered_swim.geometry import quat_rotate
from layered_swim.recorder import Recorder

SECONDS = 2.0


def mechanical_energy_j(body, state) -> float:
    """Kinetic (translation and rotation of each box) plus gravitational potential energy. The
    wrists' and ankles' 50 g gimbal links are left out: a few hundredths of a per cent here."""
    m, side = body.mass_kg, 2.0 * body.half_extents_m
    inertia = m[:, None] * (np.sum(side**2, axis=1, keepdims=True) - side**2) / 12.0
    local_w = quat_rotate(state.quat_xyzw * np.array([-1.0, -1.0, -1.0, 1.0]), state.angvel_rad_s)
    return float(np.sum(0.5 * m * np.sum(state.linvel_m_s**2, axis=1) + 0.5 * np.sum(inertia * local_w**2, axis=1)
                        + m * 9.81 * state.pos_m[:, 2]))


def test_joint_work_closes_the_energy_balance():
    episode = Episode("breaststroke")
    sim = episode.sim
    try:
        recorder = Recorder(sim, joint_work=True)
        start = mechanical_energy_j(sim.body, sim.state)
        water_j = 0.0
        for _ in range(int(SECONDS * sim.config.physics_hz)):
            before = sim.state
            episode.step()
            recorder(sim)
            force, torque = sim.fluid_now.force_n, sim.fluid_now.torque_nm   # what the water did in that step
            after = sim.state
            water_j += np.sum(force * (before.linvel_m_s + after.linvel_m_s) / 2
                              + torque * (before.angvel_rad_s + after.angvel_rad_s) / 2) / sim.config.physics_hz
        gained_j = mechanical_energy_j(sim.body, sim.state) - start
    finally:
        episode.close()
    joints_j = recorder.arrays()["joint_work_j"][-1]
    assert joints_j > 1000.0                      # the stroke does real work on the water
    # PyBullet's default body damping takes the rest (joint work slightly above the balance)
    assert joints_j == pytest.approx(gained_j - water_j, rel=0.03)
