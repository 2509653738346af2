"""The fluid is a choice: a backend is one class plus one registry entry, and swims through `run`."""
import json

import numpy as np
import pytest

from layered_swim.config import ConfigError
from layered_swim.fluid import BACKENDS, FluidBackend, FluidWrenches, make_fluid
from layered_swim.fluid.buoyancy import buoyancy_wrenches
from layered_swim.fluid.medium import Medium
from layered_swim.runs import run_swim
from layered_swim.spec import SwimSpec

SECONDS = 2.0


class StillWater(FluidBackend):
    """Buoyancy and nothing else: water that neither drags nor pushes."""

    name = "still"

    def wrenches(self, state):
        m, body = self.medium, self.body
        force, torque = buoyancy_wrenches(state.pos_m, state.quat_xyzw, body.semi_axes_m, body.volume_m3,
                                          m.rho_kg_m3, self.gravity_m_s2, m.surface_z_m)
        return FluidWrenches(force, torque, np.tile(m.current, (len(force), 1)), force)


def test_a_trivial_backend_drives_a_swim_through_run(tmp_path, monkeypatch):
    monkeypatch.setitem(BACKENDS, "still", StillWater)        # the one registry entry
    run_swim(SwimSpec(stroke="breaststroke", seconds=SECONDS, backend="still"), tmp_path / "still")
    run_swim(SwimSpec(stroke="breaststroke", seconds=SECONDS), tmp_path / "plate")
    still, plate = (np.load(tmp_path / name / "log.npz") for name in ("still", "plate"))
    # Water that pushes nothing sideways gives the limbs nothing to push on: the centre of mass
    # keeps about the stroke's 0.5 m/s start speed (PyBullet's articulated step keeps momentum to a
    # few per cent, not exactly). The plates give the same stroke thrust.
    assert still["com_vel_m_s"][:, 0].max() <= 0.55
    assert still["com_vel_m_s"][-1, 0] > 0.3
    assert plate["com_vel_m_s"][:, 0].max() > 0.6
    np.testing.assert_array_equal(still["fluid_force_n"][1:, :, :2], 0.0)
    np.testing.assert_array_equal(still["fluid_force_n"][1:], still["buoyancy_force_n"][1:])
    config = json.loads((tmp_path / "still" / "config.json").read_text())
    assert config["fluid_backend"] == {"name": "still", "settings": {}}
    plate_config = json.loads((tmp_path / "plate" / "config.json").read_text())
    assert plate_config["fluid_backend"]["name"] == "plate"
    assert plate_config["fluid_backend"]["settings"]["r_min"] == 0.68


def test_unknown_backend_is_a_one_line_config_error():
    from layered_swim.body.model import load_body

    with pytest.raises(ConfigError, match="unknown fluid backend 'sph2'.*plate"):
        make_fluid("sph2", load_body(), Medium(), 9.81)


def test_the_water_holds_only_what_water_is():
    assert set(Medium.__dataclass_fields__) == {"rho_kg_m3", "eta_pa_s", "surface_z_m", "current_m_s", "flow"}


def test_the_plates_see_only_the_velocity_through_the_water():
    """A uniform current changes nothing relative to the water (issue 37 asked why the strokes
    seemed to swim faster through a head-on current): the plates' force and torque on a body moving
    at v in a current c are those on the same body moving at v - c in still water, its added mass
    included (its acceleration is the same in both frames)."""
    from dataclasses import replace

    from layered_swim.body.model import load_body
    from layered_swim.episode import Episode

    episode = Episode("breaststroke")
    try:
        episode.run(1.0)
        before, state = episode.sim.state, None
        episode.run(1.0 / 480)
        state = episode.sim.state
    finally:
        episode.close()
    current = np.array([-0.3, 0.2, 0.0])
    body = load_body()
    results = []
    for water, shift in ((current, np.zeros(3)), (np.zeros(3), current)):
        fluid = make_fluid("plate", body, Medium(current_m_s=tuple(water)), 9.81)
        for s in (before, state):        # two steps: the added mass reads the acceleration between them
            out = fluid.wrenches(replace(s, linvel_m_s=s.linvel_m_s - shift))
        results.append(out)
        fluid.close()
    (moving, still) = results
    np.testing.assert_allclose(moving.force_n, still.force_n, rtol=1e-9, atol=1e-9)
    np.testing.assert_allclose(moving.torque_nm, still.torque_nm, rtol=1e-9, atol=1e-9)
    np.testing.assert_allclose(moving.flow_m_s - current, still.flow_m_s, atol=1e-12)
