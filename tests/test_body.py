"""The body file: the Yang swimmer's numbers, its URDF in PyBullet, and errors for bad files."""
import pybullet
import pytest
import yaml
from pybullet_utils.bullet_client import BulletClient

from layered_swim.body.layout import joint_layout
from layered_swim.body.model import DEFAULT_BODY_FILE, load_body
from layered_swim.body.urdf import axis_joint_name, write_urdf
from layered_swim.config import ConfigError

ROOT_DOF = 6


def test_yang_swimmer_numbers():
    body = load_body(lung_air_l=2.0)
    assert len(body.segment_names) == 16
    assert body.segment_names[0] == "pelvis" and body.segment_names[3] == "head"
    assert ROOT_DOF + joint_layout(body).size == 39
    assert body.total_mass_kg == pytest.approx(89.57)
    lungs_m3 = (1.5 + 2.0) * 1e-3   # residual volume + inhaled air
    assert body.total_mass_kg / (body.total_volume_m3 - lungs_m3) == pytest.approx(1044.0)
    assert load_body(lung_air_l=3.0).total_volume_m3 - body.total_volume_m3 == pytest.approx(1e-3)


def test_urdf_loads_with_named_joints(tmp_path):
    body = load_body()
    expected = set()
    for joint in body.joints:
        if joint.type == "two_axis":
            expected |= {axis_joint_name(joint.name, axis) for axis in joint.axis_names}
        else:
            expected.add(joint.name)
    client = BulletClient(connection_mode=pybullet.DIRECT)
    try:
        uid = client.loadURDF(str(write_urdf(body, tmp_path / "swimmer.urdf")),
                              flags=pybullet.URDF_USE_INERTIA_FROM_FILE)
        infos = [client.getJointInfo(uid, j) for j in range(client.getNumJoints(uid))]
        names = {info[1].decode() for info in infos if info[2] != pybullet.JOINT_FIXED}
        links = {info[12].decode() for info in infos}
        masses = [client.getDynamicsInfo(uid, link)[0] for link in range(-1, len(infos))]
    finally:
        client.disconnect()
    assert names == expected
    assert set(body.segment_names[1:]) <= links
    assert sum(masses) == pytest.approx(body.total_mass_kg, rel=1e-5)


def write_body(tmp_path, edit):
    data = yaml.safe_load(DEFAULT_BODY_FILE.read_text())
    edit(data)
    path = tmp_path / "bad_body.yaml"
    path.write_text(yaml.safe_dump(data, sort_keys=False))
    return path


@pytest.mark.parametrize("edit, field", [
    (lambda d: d.pop("total_mass_kg"), "total_mass_kg"),
    (lambda d: d["segments"]["thigh_l"].update(mass_kg="heavy"), "segments.thigh_l.mass_kg"),
    (lambda d: d["segments"]["forearm_l"].update(joint="elbow_x"), "elbow_x"),
])
def test_malformed_body_file(tmp_path, edit, field):
    path = write_body(tmp_path, edit)
    with pytest.raises(ConfigError) as err:
        load_body(path)
    message = str(err.value)
    assert "\n" not in message
    assert str(path) in message and field in message
