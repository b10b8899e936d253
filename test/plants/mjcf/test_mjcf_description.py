"""The ``mjcf:`` description section: model inline or from a file, URDF, absent meshes, names
checked against the compiled model, and every bad input as one line."""
import numpy as np
import pytest
import yaml

from cablelab.bags import BagWriter
from cablelab.cli import main
from cablelab.description import load_description
from cablelab.errors import CablelabError
from cablelab.plants.mjcf.examples import ARM3, text

ARM_XML = text(ARM3)


def _desc(**section):
    return yaml.safe_dump({"plant": "mjcf", "mjcf": section}, sort_keys=False)


def _one_line_error(src) -> str:
    with pytest.raises(CablelabError) as exc:
        load_description(src)
    msg = str(exc.value)
    assert "\n" not in msg
    return msg


def test_inline_model_compiles_and_names_are_kept():
    d = load_description(_desc(model=ARM_XML, joints=["shoulder", "elbow"], payload_body="tool"))
    assert d.mjcf.joints == ("shoulder", "elbow") and d.mjcf.payload_body == "tool"
    assert d.mjcf.compiled().nv == 3


def test_model_file_is_read_relative_to_the_description_and_inlined(tmp_path):
    (tmp_path / "models").mkdir()
    (tmp_path / "models" / "arm.xml").write_text(ARM_XML)
    f = tmp_path / "machine.yaml"
    f.write_text(_desc(model_file="models/arm.xml", payload_body="tool"))
    d = load_description(str(f))
    assert d.mjcf.model == ARM_XML
    again = yaml.safe_load(d.to_yaml())            # published: the model travels inline
    assert "model_file" not in again["mjcf"] and again["mjcf"]["model"] == ARM_XML
    assert load_description(d.to_yaml()).mjcf.model == ARM_XML


def test_both_model_and_model_file_is_one_line_error():
    msg = _one_line_error(_desc(model=ARM_XML, model_file="arm.xml"))
    assert "mjcf" in msg and "not both" in msg


@pytest.mark.parametrize("key,value,unknown,known", [
    ("joints", ["shoulder", "wrist"], "wrist", "base_yaw, shoulder, elbow"),
    ("payload_body", "gripper", "gripper", "base, upper, fore, tool"),
    ("tendons", ["cable_1"], "cable_1", "none"),
])
def test_unknown_names_name_the_unknown_and_the_known(key, value, unknown, known):
    msg = _one_line_error(_desc(model=ARM_XML, **{key: value}))
    assert f"mjcf.{key}" in msg and repr(unknown) in msg and known in msg, msg


def test_model_that_does_not_compile_gives_mujocos_message_with_the_file(tmp_path):
    f = tmp_path / "broken.xml"
    f.write_text(ARM_XML.replace('axis="0 1 0"', 'axis="0 1 0" type="spiral"', 1))
    desc = tmp_path / "d.yaml"
    desc.write_text(_desc(model_file="broken.xml"))
    msg = _one_line_error(str(desc))
    assert str(f) in msg and "spiral" in msg, msg


def test_absent_mesh_files_load_from_the_inertials_with_a_warning():
    xml = ARM_XML.replace('<geom type="box" size="0.03 0.03 0.03" pos="0.03 0 0"/>',
                          '<geom type="mesh" mesh="gripper"/>').replace(
        "<actuator>", '<asset><mesh name="gripper" file="no/such/gripper.stl"/></asset><actuator>')
    d = load_description(_desc(model=xml))
    assert d.mjcf.warnings and "gripper.stl" in d.mjcf.warnings[0]
    m = d.mjcf.compiled()
    assert m.ngeom == load_description(_desc(model=ARM_XML)).mjcf.compiled().ngeom - 1
    np.testing.assert_allclose(m.body_mass, [0, 3.0, 2.0, 1.2, 0.3])


URDF = """<robot name="pendulum">
  <link name="base"/>
  <link name="arm">
    <inertial><origin xyz="0 0 -0.5"/><mass value="2"/>
      <inertia ixx="0.01" iyy="0.01" izz="0.01" ixy="0" ixz="0" iyz="0"/></inertial>
    <visual><geometry><mesh filename="package://pendulum/meshes/arm.dae"/></geometry></visual>
  </link>
  <joint name="hinge" type="continuous"><parent link="base"/><child link="arm"/>
    <axis xyz="0 1 0"/></joint>
</robot>"""


def test_urdf_is_accepted_and_its_inverse_dynamics_is_the_pendulum():
    """Oracle: a point-like pendulum, tau = (I + m l^2) qdd + m g l sin q."""
    from cablelab.plants.mjcf.inverse import inverse_dynamics

    d = load_description(_desc(model=URDF))
    m = d.mjcf.compiled(9.81)
    q = np.array([[0.3], [-1.0]])
    qdd = np.array([[2.0], [-0.5]])
    tau = inverse_dynamics(m, q, np.zeros_like(q), qdd)
    expect = (0.01 + 2 * 0.25) * qdd + 2 * 9.81 * 0.5 * np.sin(q)
    np.testing.assert_allclose(tau, expect, rtol=1e-9)


def test_bag_whose_joints_are_not_in_the_model_is_one_line_error(tmp_path, capsys):
    path = tmp_path / "bag"
    t = np.arange(400) * 0.002
    with BagWriter(path) as w:
        w.write_description(_desc(model=ARM_XML))
        w.write_joint_states("/mjcf/joint_states", t, ["base_yaw", "shoulder", "elbow", "wrist"],
                             np.zeros((400, 4)), None, np.zeros((400, 4)))
    assert main(["compare", str(path)]) == 2
    err = capsys.readouterr().err.strip()
    assert "\n" not in err and "'wrist'" in err and "not in the model" in err, err


def test_example_joints_are_the_shipped_arms():
    from cablelab.plants.mjcf.mjcf import dof_joints
    from cablelab.plants.mjcf.plant import EXAMPLE_JOINTS

    assert tuple(dof_joints(load_description(_desc(model=ARM_XML)).mjcf.compiled())) == EXAMPLE_JOINTS
