"""The hopping leg in 3D (visualization_msgs/MarkerArray) along a simulated hopping run: the body
sits where the simulator's MuJoCo model puts its body (xpos after mj_kinematics), both links are
L long (003 eq. 2: the knee at L sin(theta) beside the guide, cos(theta) = leg length / 2L), the
foot stands on the ground in stance and meets it at every touch-down (the flight leg is the
length the simulator's touch-down guard uses), decoded from the message bytes. The foot along a
record (contact switch + height, what a bag holds) follows the simulator's to the lift-off
location error (one sample)."""
import math

import mujoco
import numpy as np
from rosbags.typesys import Stores, get_typestore

from cablelab.markers import MarkerEncoder
from cablelab.plants.leg.hybrid import STANCE, LegParams
from cablelab.plants.leg.markers import foot_heights, sim_markers
from cablelab.plants.leg.sim import LegSim

TS = get_typestore(Stores.ROS2_JAZZY)


def _run(n=3000):
    p = LegParams()
    sim = LegSim(p, p.z_td + 0.03)
    rows = []
    enc = MarkerEncoder(sim_markers(sim))
    for _ in range(n):
        before = sim.phase
        t_d = sim.events[-1].t if sim.events else 0.0
        sim.step(3.0 * math.sin(2 * math.pi * (sim.t - t_d) / 0.3) if sim.phase == STANCE else 0.0)
        mujoco.mj_kinematics(sim.model, sim.data)
        msg = TS.deserialize_cdr(enc.encode([sim.t], [sim_markers(sim)])[0], "visualization_msgs/msg/MarkerArray")
        rows.append((sim.z, sim.phase, before, sim.data.xpos[1].copy(), {m.ns: m for m in msg.markers}))
    return p, sim, rows


def _pts(m):
    return np.array([[q.x, q.y, q.z] for q in m.points])


def test_links_foot_and_body_follow_the_simulated_hops():
    p, sim, rows = _run()
    assert sum(e.kind == "touchdown" for e in sim.events) >= 3          # it hops
    feet = []
    for z, phase, before, xpos, by in rows:
        assert all(m.header.frame_id == "world" for m in by.values())
        body = by["body"].pose.position
        np.testing.assert_allclose([body.x, body.y, body.z], xpos, atol=1e-12)
        hip, knee, foot = _pts(by["links"])
        np.testing.assert_allclose(hip, xpos, atol=1e-12)
        np.testing.assert_allclose([np.linalg.norm(knee - hip), np.linalg.norm(foot - knee)], p.L, atol=1e-9)
        theta = math.acos((hip[2] - foot[2]) / (2 * p.L))
        np.testing.assert_allclose(knee[0], p.L * math.sin(theta), atol=1e-9)
        np.testing.assert_allclose(_pts(by["spring"]), [hip, foot], atol=1e-12)
        if phase == STANCE:
            assert foot[2] == 0.0 and abs(theta - math.acos(z / (2 * p.L))) < 1e-9
        else:
            assert foot[2] > -1e-12                                     # never below the ground
        feet.append((phase, before, foot[2]))
    # touch-down: the foot of the last flight sample was within one step of travel of the ground
    for (ph0, _, f0), (ph1, _, _) in zip(feet[:-1], feet[1:]):
        if ph0 != STANCE and ph1 == STANCE:
            assert f0 < 2.0 * 1e-3                                       # |zd| < 2 m/s, dt = 1 ms
    # the spring's colour: redder in stance (compressed) than at the top of a flight
    red = [(by["spring"].color.r - by["spring"].color.b, phase) for _, phase, _, _, by in rows]
    assert max(r for r, ph in red if ph == STANCE) > max(r for r, ph in red if ph != STANCE)


def test_foot_from_a_record_follows_the_simulator():
    p, sim, rows = _run()
    z = np.array([r[0] for r in rows])
    contact = np.array([float(r[1] == STANCE) for r in rows])
    sim_foot = np.array([_pts(r[4]["links"])[2, 2] for r in rows])
    np.testing.assert_allclose(foot_heights(z, contact, p.z_td), sim_foot, atol=2e-3)
    assert np.ptp(sim_foot) > 5e-3                                      # the foot really leaves the ground


def test_overlay_bag_draws_the_recorded_hops(tmp_path):
    """compare --out of a simulated hopping run: at about 30 Hz, the body at the recorded encoder
    height of each stamp, the foot on the ground whenever the contact switch is closed."""
    from pathlib import Path

    import cablelab.plants.leg as leg_pkg
    from cablelab.bags import open_bag
    from cablelab.cli import main
    from cablelab.plants.leg.sim import open_loop, simulate, write_bag

    p = LegParams()
    write_bag(tmp_path / "hops", simulate(p, p.z_td + 0.03, 0.0, 6.0, open_loop(3.0, 0.3)),
              (Path(leg_pkg.__file__).parent / "data" / "leg.yaml").read_text())
    assert main(["compare", str(tmp_path / "hops"), "--out", str(tmp_path / "ov"), "--json"]) == 0
    bag = open_bag(tmp_path / "ov")
    js = bag.joint_state("/leg/joint_states", ["body"])
    contact = bag.joint_state("/leg/contact", ["contact"])
    t_ns, raws = bag.raw("/leg/markers")
    t = np.asarray(t_ns) * 1e-9
    assert 25.0 < len(t) / (t[-1] - t[0]) < 35.0
    phases = set()
    for k in range(len(raws)):
        by = {m.ns: m for m in TS.deserialize_cdr(raws[k], "visualization_msgs/msg/MarkerArray").markers}
        j = int(np.argmin(np.abs(js.t - t[k])))
        assert abs(js.t[j] - t[k]) < 1e-6
        assert by["body"].pose.position.z == js.position[j, 0]
        foot = _pts(by["links"])[2, 2]
        if contact.position[j, 0] > 0.5:
            assert foot == 0.0
        phases.add(contact.position[j, 0] > 0.5)
        assert foot > -1e-12
    assert phases == {True, False}
