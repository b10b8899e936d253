"""A user's own model and topics: URDF on a remapped ``/joint_states``, measured tendon tensions
through the tendon Jacobian (sign: a tension pulls its tendon shorter)."""
import numpy as np
import pytest
import yaml

from cablelab import workbench
from cablelab.bags import BagWriter
from cablelab.model import KNOWN_OUTPUT
from cablelab.plants.mjcf.sim import Hidden, record, truth_model

URDF = """<robot name="double">
  <link name="base"/>
  <link name="l1"><inertial><origin xyz="0.25 0 0"/><mass value="1.5"/>
    <inertia ixx="0.002" iyy="0.03" izz="0.03" ixy="0" ixz="0" iyz="0"/></inertial>
    <visual><geometry><mesh filename="package://double/meshes/l1.stl"/></geometry></visual></link>
  <link name="l2"><inertial><origin xyz="0.2 0 0"/><mass value="0.8"/>
    <inertia ixx="0.001" iyy="0.01" izz="0.01" ixy="0" ixz="0" iyz="0"/></inertial></link>
  <joint name="j1" type="continuous"><parent link="base"/><child link="l1"/><axis xyz="0 1 0"/></joint>
  <joint name="j2" type="continuous"><parent link="l1"/><child link="l2"/>
    <origin xyz="0.5 0 0"/><axis xyz="0 1 0"/></joint>
</robot>"""

# the same machine as MJCF with motors, for the truth simulator (MuJoCo's URDF import has none)
URDF_MJCF = """<mujoco><compiler angle="radian"/><option timestep="0.002"/>
  <worldbody><body name="l1"><joint name="j1" axis="0 1 0"/>
    <inertial pos="0.25 0 0" mass="1.5" diaginertia="0.002 0.03 0.03"/>
    <body name="l2" pos="0.5 0 0"><joint name="j2" axis="0 1 0"/>
      <inertial pos="0.2 0 0" mass="0.8" diaginertia="0.001 0.01 0.01"/></body></body></worldbody>
  <actuator><motor joint="j1"/><motor joint="j2"/></actuator></mujoco>"""


def _write(path, desc: dict, topic: str, t, names, q, eff, extra=None):
    with BagWriter(path) as w:
        w.write_description(yaml.safe_dump(desc, sort_keys=False))
        w.write_joint_states(topic, t, names, q, None, eff)
        for args in extra or ():
            w.write_joint_states(*args)
    return str(path)


def test_urdf_on_a_remapped_joint_states_topic(tmp_path):
    t, q, e, joints = record(truth_model(URDF_MJCF), duration=8.0, seed=5)
    desc = {"plant": "mjcf", "mjcf": {"model": URDF, "topics": {"joint_states": "/joint_states"}}}
    bag = _write(tmp_path / "urdf", desc, "/joint_states", t, joints, q, e)
    plant, d, ds = workbench.load(bag)
    assert ds.channels == ("j1", "j2")
    assert not any("l1.stl" in w for w in ds.signals["load_warnings"])   # URDF visuals: ignored
    nrmse = workbench.compare(ds, workbench.build_model(plant, d)).channels
    assert all(m["nrmse"] < 0.02 for m in nrmse.values()), nrmse


TENDON_MJCF = """<mujoco><compiler angle="radian"/><option timestep="0.002"/>
  <worldbody><site name="anchor" pos="0.3 0 0.6"/>
    <body name="arm"><joint name="hinge" axis="0 1 0"/>
      <inertial pos="0.3 0 0" mass="2" diaginertia="0.01 0.06 0.06"/>
      <site name="tip" pos="0.6 0 0"/></body></worldbody>
  <tendon><spatial name="cable"><site site="anchor"/><site site="tip"/></spatial></tendon>
  <actuator><motor joint="hinge"/></actuator></mujoco>"""


def test_measured_tendon_tension_enters_through_the_tendon_jacobian(tmp_path):
    """Truth: a cable pulls the arm with a known tension (applied as a tendon force in the
    simulation); the joint motor supplies the rest. With the tension measured, the channel
    ``effort - ten_J^T T`` equals MuJoCo's inverse dynamics of the arm without the cable."""
    import mujoco

    spec = mujoco.MjSpec.from_string(TENDON_MJCF)
    act = spec.add_actuator(name="winch", target="cable")
    act.trntype = mujoco.mjtTrn.mjTRN_TENDON
    truth = spec.compile()
    truth.opt.integrator = mujoco.mjtIntegrator.mjINT_EULER
    d = mujoco.MjData(truth)
    n = 3000
    tt = np.arange(n) * truth.opt.timestep
    tension = 20.0 + 5.0 * np.sin(2.0 * tt)
    q, eff = np.empty(n), np.empty(n)
    ref = 0.4 * np.sin(1.3 * tt) - 0.2
    for k in range(n):
        mujoco.mj_step1(truth, d)
        d.ctrl[1] = -tension[k]                 # a pulling (shortening) tendon force
        d.ctrl[0] = 300 * (ref[k] - d.qpos[0]) - 30 * d.qvel[0] + d.qfrc_bias[0]
        q[k] = d.qpos[0]
        mujoco.mj_step2(truth, d)
        eff[k] = d.actuator_force[0]            # the joint motor alone
    desc = {"plant": "mjcf", "mjcf": {"model": TENDON_MJCF, "tendons": ["cable"]}}
    bag = _write(tmp_path / "tendon", desc, "/mjcf/joint_states", tt, ["hinge"], q[:, None],
                 eff[:, None], [("/mjcf/cable_tensions", tt, ["cable"], None, None, tension[:, None])])
    plant, dd, ds = workbench.load(bag)
    resid = ds.y[ds.valid, 0] - ds.signals[KNOWN_OUTPUT][ds.valid, 0]
    assert np.sqrt(np.mean(resid**2)) < 0.01 * np.sqrt(np.mean(ds.y[ds.valid, 0] ** 2))
    # without the tension the channel would be off by the cable's torque (tens of N m)
    moment = np.abs(ds.signals["ten_J"][ds.valid, 0, 0] * ds.signals["tension"][ds.valid, 0])
    assert moment.mean() > 1.0


def test_csv_import_onto_the_models_joints(tmp_path, capsys):
    """``cablelab import --plant mjcf``: CSV columns onto the joints the description's model has;
    the bag carries the model inline (model_file read), and the nominal model fits it."""
    from cablelab.cli import main
    from cablelab.plants.mjcf.examples import ARM3

    t, q, e, joints = record(truth_model(ARM3.read_text()), duration=6.0, seed=4)
    csv = tmp_path / "arm.csv"
    np.savetxt(csv, np.column_stack([t, q, e]), delimiter=",", comments="",
               header="t,q0,q1,q2,e0,e1,e2")
    desc = tmp_path / "arm.yaml"
    desc.write_text(yaml.safe_dump({"plant": "mjcf", "mjcf": {"model_file": str(ARM3)}}))
    spec = ",".join(["time=t"] + [f"position.{j}=q{k}" for k, j in enumerate(joints)]
                    + [f"effort.{j}=e{k}" for k, j in enumerate(joints)])
    assert main(["import", str(csv), "--plant", "mjcf", "--description", str(desc), "--map", spec,
                 "-o", str(tmp_path / "bag")]) == 0
    capsys.readouterr()
    plant, d, ds = workbench.load(str(tmp_path / "bag"))
    assert d.mjcf.model == ARM3.read_text() and ds.channels == tuple(joints)
    nrmse = workbench.compare(ds, workbench.build_model(plant, d)).channels
    assert all(m["nrmse"] < 0.02 for m in nrmse.values()), nrmse


def test_payload_estimate_on_a_window():
    """The estimator's fit on a 4 s window of the example arm carrying 1.2 kg at 5 cm."""
    from cablelab.description import load_description
    from cablelab.plants.mjcf.estimation import payload_estimate
    from cablelab.plants.mjcf.examples import ARM3
    from cablelab.plants.mjcf.sim import description_yaml

    xml = ARM3.read_text()
    t, q, e, _ = record(truth_model(xml, Hidden(payload=("tool", 1.2, (0.05, 0.0, 0.0)))),
                        duration=4.0, seed=2)
    est = payload_estimate(t, q, e, load_description(description_yaml(xml, payload_body="tool")))
    assert est.m == pytest.approx(1.2, rel=0.02)
    assert est.com[0] == pytest.approx(0.05, abs=0.005)


def test_feedforward_is_exact_on_the_model_and_carries_the_payload():
    """Computed torque with kp = kd = 0 gives MuJoCo's inverse dynamics at the reference
    acceleration; with a payload set, the generalised force of a model compiled with that payload
    (MjSpec child body, the oracle)."""
    import mujoco

    from cablelab.description import load_description
    from cablelab.plants.mjcf.control import Feedforward
    from cablelab.plants.mjcf.examples import ARM3
    from cablelab.plants.mjcf.inverse import inverse_dynamics
    from cablelab.plants.mjcf.sim import description_yaml

    xml = ARM3.read_text()
    sec = load_description(description_yaml(xml, payload_body="tool")).mjcf
    law = Feedforward(sec, 9.81, 0.0, 0.0)
    q, qd, qdd = np.array([0.2, -0.5, 0.9]), np.array([0.1, 0.3, -0.2]), np.array([1.0, -2.0, 0.5])
    np.testing.assert_allclose(law.command(q, qd, q, qd, qdd),
                               inverse_dynamics(sec.compiled(9.81), q[None], qd[None], qdd[None])[0], atol=1e-9)
    law.set_payload(0.8, (0.05, 0.01, 0.0))
    truth = truth_model(xml, Hidden(payload=("tool", 0.8, (0.05, 0.01, 0.0))), euler=False)
    np.testing.assert_allclose(law.command(q, qd, q, qd, qdd),
                               inverse_dynamics(truth, q[None], qd[None], qdd[None])[0], atol=1e-6)
