"""``cablelab excite`` on the mjcf plant (the arm3 example with a payload body): a motion of the
base alone leaves the shoulder's load torque constant, so the payload mass and the shoulder's
torque offset are confounded; the designed motion keeps every joint in its range, speed and
acceleration (checked on the written reference with numerical derivatives, independent of the
design's own), and its condition number for the pair is small. The limits come from the MJCF:
joint ranges, actuator ctrlrange x gear and forcerange."""
from pathlib import Path

import numpy as np
import pytest

import cablelab.plants.mjcf as pkg
from cablelab.description import load_description
from cablelab.excite import condition, design, get_exciter, model_for
from cablelab.plants.mjcf.excite import effort_limits
from cablelab.plants.mjcf.sim import description_yaml
from cablelab.registry import get_plant

XML = (Path(pkg.__file__).parent / "examples" / "arm3.xml").read_text()
PARAMS = ["m", "OF[shoulder]"]


def test_designed_arm_motion_separates_payload_and_offset_within_the_limits():
    desc = load_description(description_yaml(XML, payload_body="tool"))
    ex = get_exciter("mjcf")
    lim = ex.limits(desc)
    assert lim.joints == ("base_yaw", "shoulder", "elbow")
    # confounded: the base turns, shoulder and elbow hold still
    t = np.arange(0.0, 20.0, 0.05)
    q = np.zeros((len(t), 3))
    q[:, 0], q[:, 1], q[:, 2] = np.sin(0.5 * t), 0.3, -0.5
    qd, qdd = np.zeros_like(q), np.zeros_like(q)
    qd[:, 0], qdd[:, 0] = 0.5 * np.cos(0.5 * t), -0.25 * np.sin(0.5 * t)
    still = ex.motion_dataset(t, q, qd, qdd, desc)
    model, _ = model_for(get_plant("mjcf"), desc, PARAMS, still)
    before = condition(model, still, PARAMS)
    assert before > 1e6
    d = design("mjcf", desc, PARAMS, duration=20.0)
    assert d.condition_after < 100 and d.condition_after < before / 1e4
    # every limit, checked on the reference with its own numerical derivatives
    dt = d.t[1] - d.t[0]
    assert np.all(d.q >= lim.lower - 1e-9) and np.all(d.q <= lim.upper + 1e-9)
    v = np.gradient(d.q, dt, axis=0)
    a = np.gradient(v, dt, axis=0)
    assert np.all(np.abs(v) <= lim.speed * 1.01 + 1e-6)
    assert np.all(np.abs(a) <= lim.accel * 1.05 + 1e-3)
    assert np.ptp(d.q[:, 1]) > 0.5 and np.ptp(d.q[:, 2]) > 0.5      # the shoulder and elbow move


def test_effort_limits_from_ctrlrange_and_forcerange():
    xml = XML.replace('<motor name="shoulder_motor" joint="shoulder" gear="1" ctrllimited="false"/>',
                      '<motor name="shoulder_motor" joint="shoulder" gear="2" ctrllimited="true" '
                      'ctrlrange="-5 5"/>')
    xml = xml.replace('<motor name="elbow_motor" joint="elbow" gear="1" ctrllimited="false"/>',
                      '<motor name="elbow_motor" joint="elbow" gear="1" ctrllimited="false" '
                      'forcelimited="true" forcerange="-3 3"/>')
    desc = load_description(description_yaml(xml, payload_body="tool"))
    cap = effort_limits(desc.mjcf.compiled())
    assert cap[0] == np.inf and cap[1] == pytest.approx(10.0) and cap[2] == pytest.approx(3.0)
    # holding the arm out straight needs more than 3 N m at the elbow: the constraint says so
    lim = get_exciter("mjcf").limits(desc)
    q = np.tile([0.0, 0.0, 0.0], (5, 1))
    bad = lim.check(q, np.zeros_like(q), np.zeros_like(q))
    assert any(b.startswith("elbow: effort") for b in bad)
