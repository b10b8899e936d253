"""The suspended platforms in 3D (visualization_msgs/MarkerArray): against the simulator's own
MuJoCo models at random states, the cables end at the truth plant's top and bottom sites (LiCAS,
four cables) or at S and the platform's attachment point (CRANEbot's rope), the arms pass through
the arm bodies' origins (xpos) to the last link's centre of mass (xipos); hanging at rest, the
cable tensions carry the weight hanging below them (subtree mass x g), decoded from the message
bytes."""
import mujoco
import numpy as np
import pytest
from hypothesis import given, settings, strategies as st
from rosbags.typesys import Stores, get_typestore

from cablelab.markers import MarkerEncoder
from cablelab.plants.suspended.markers import state_markers
from cablelab.plants.suspended.mjcf import arm_joint_names, build_truth, build_virtual
from cablelab.plants.suspended.params import parameter_set
from cablelab.plants.suspended.sim import initial_state, truth_start

TS = get_typestore(Stores.ROS2_JAZZY)


def _decode(frame):
    raw = MarkerEncoder(frame).encode([1.0], [frame])[0]
    msgs = TS.deserialize_cdr(raw, "visualization_msgs/msg/MarkerArray").markers
    assert all(m.header.frame_id == "world" for m in msgs)
    return msgs


def _pts(m):
    return np.array([[q.x, q.y, q.z] for q in m.points])


def _check_arms(p, model, data, msgs):
    arms = sorted((m for m in msgs if m.ns == "arms"), key=lambda m: m.id)
    for side, m in zip(("left", "right"), arms):
        pts = _pts(m)
        want = [data.xpos[model.body(f"{side}_link{i + 1}").id] for i in range(p.n_arm)]
        want.append(data.xipos[model.body(f"{side}_link{p.n_arm}").id])
        np.testing.assert_allclose(pts, want, atol=1e-9)


def _with_arms(model, p, x0, q_arm):
    d = mujoco.MjData(model)
    mujoco.mj_setState(model, d, x0, mujoco.mjtState.mjSTATE_FULLPHYSICS)
    for name, v in zip(arm_joint_names(p), q_arm):
        d.qpos[model.joint(name).qposadr[0]] = v
    mujoco.mj_forward(model, d)
    return d


angles = st.floats(-0.4, 0.4)


@settings(max_examples=10, deadline=None)
@given(sx=angles, sy=angles, yaw=angles, arm=st.lists(st.floats(-1.0, 1.0), min_size=12, max_size=12))
def test_licas_truth_cables_and_arms(sx, sy, yaw, arm):
    p = parameter_set("licas")
    model = build_truth(p)
    x0 = truth_start(model, p, sx, sy, 0.0)
    d = _with_arms(model, p, x0, arm[:2 * p.n_arm])
    d.qpos[3:7] = [np.cos(yaw / 2), 0, 0, np.sin(yaw / 2)]     # turn the platform as well
    mujoco.mj_forward(model, d)
    msgs = _decode(state_markers(p, model, d))
    cables = {m.id: _pts(m) for m in msgs if m.ns == "cables"}
    assert sorted(cables) == [1, 2, 3, 4]
    for i in range(4):
        np.testing.assert_allclose(cables[i + 1], [d.site_xpos[model.site(f"top{i}").id],
                                                   d.site_xpos[model.site(f"bot{i}").id]], atol=1e-9)
    _check_arms(p, model, d, msgs)


@settings(max_examples=10, deadline=None)
@given(j=st.lists(angles, min_size=6, max_size=6), arm=st.lists(st.floats(-1.0, 1.0), min_size=12, max_size=12))
def test_cranebot_virtual_rope_and_arms(j, arm):
    p = parameter_set("cranebot")
    model = build_virtual(p)
    x0 = initial_state(model, dict(zip(("J7", "J8", "J9", "J10", "J11", "J12"), j)))
    d = _with_arms(model, p, x0, arm[:2 * p.n_arm])
    msgs = _decode(state_markers(p, model, d))
    rope = [m for m in msgs if m.ns == "cables"]
    assert len(rope) == 1
    np.testing.assert_allclose(_pts(rope[0]), [d.site_xpos[model.site("S").id],
                                               d.site_xpos[model.site("platform").id]], atol=1e-9)
    _check_arms(p, model, d, msgs)


@pytest.mark.parametrize("variant,kind", [("licas", "truth"), ("cranebot", "virtual")])
def test_cables_carry_the_hanging_weight_at_rest(variant, kind):
    from cablelab.plants.suspended.markers import cable_tensions

    p = parameter_set(variant)
    model = build_truth(p) if kind == "truth" else build_virtual(p)
    x0 = truth_start(model, p) if kind == "truth" else initial_state(model)
    d = _with_arms(model, p, x0, np.zeros(2 * p.n_arm))
    for _ in range(3000):                       # 3 s: the arms settle on their servos
        mujoco.mj_step(model, d)
    mujoco.mj_forward(model, d)
    hanging = "platform" if kind == "truth" else "link10"
    weight = model.body_subtreemass[model.body(hanging).id] * 9.81
    ten = cable_tensions(p, model, d)
    assert ten.shape == ((4,) if variant == "licas" else (1,))
    np.testing.assert_allclose(ten.sum(), weight, rtol=0.02)
    assert np.all(ten > 0)


def test_overlay_bag_draws_the_recorded_platform(tmp_path):
    """compare --out of a simulated CRANEbot swing: the rope of each array ends at the recorded
    platform pose of its stamp, at about 30 Hz."""
    from cablelab.bags import open_bag
    from cablelab.cli import main
    from cablelab.plants.suspended.bag import description_yaml, write_run
    from cablelab.plants.suspended.sim import simulate

    p = parameter_set("cranebot")
    m = build_virtual(p)
    run = simulate(m, initial_state(m, {"J8": 0.2}), 8.0)[0]
    write_run(tmp_path / "swing", run, p.S, description_yaml("cranebot"))
    assert main(["compare", str(tmp_path / "swing"), "--out", str(tmp_path / "ov"), "--json"]) == 0
    bag = open_bag(tmp_path / "ov")
    pose = bag.pose("/suspended/platform_pose")
    t_ns, raws = bag.raw("/suspended/markers")
    t = np.asarray(t_ns) * 1e-9
    assert 25.0 < len(t) / (t[-1] - t[0]) < 35.0
    for k in range(0, len(raws), 20):
        msg = TS.deserialize_cdr(raws[k], "visualization_msgs/msg/MarkerArray")
        j = int(np.argmin(np.abs(pose.t - t[k])))
        assert abs(pose.t[j] - t[k]) < 1e-6
        rope = _pts([m for m in msg.markers if m.ns == "cables"][0])
        np.testing.assert_allclose(rope, [p.S, pose.position[j]], atol=1e-9)
