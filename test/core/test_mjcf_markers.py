"""Markers of any MuJoCo model (cablelab.mjcf_markers): on a small MJCF (box, capsule, ellipsoid,
plane, a wrapping cylinder, a spatial tendon from a body over a pulley site to a second body),
every geom marker sits at MuJoCo's geom_xpos turned by its geom_xmat (decoded from the message
bytes, the rotation through scipy) with the sizes written in the XML, and the tendon's lines end
at the site positions of MuJoCo's forward kinematics, the pulley site ending one branch and
starting the next, tangent points on the wrapping cylinder. One layout in every state (wrapping
or not), so one MarkerEncoder serves them all."""
import mujoco
import pytest
import numpy as np
from hypothesis import given, settings, strategies as st
from rosbags.typesys import Stores, get_typestore
from scipy.spatial.transform import Rotation

from cablelab.markers import MarkerEncoder, tension_colour
from cablelab.mjcf_markers import model_markers

TS = get_typestore(Stores.ROS2_JAZZY)
XML = """<mujoco><worldbody>
 <site name="anchor" pos="0 0 2"/>
 <site name="pul" pos="1 0 2.2"/>
 <geom name="floor" type="plane" size="0 0 1" rgba="0.5 0.5 0.5 1"/>
 <body name="drum" pos="0.03 0 1.65"><geom name="drum" type="cylinder" size="0.05 0.1" euler="90 0 0"/></body>
 <body name="a" pos="0 0 1"><freejoint/><geom name="box" type="box" size=".1 .2 .3"/>
   <site name="sa" pos="0 0 0.3"/></body>
 <body name="b" pos="1 0 1"><freejoint/><geom name="cap" type="capsule" size=".05 .2"/>
   <geom name="ell" type="ellipsoid" size=".03 .04 .05" pos="0 .1 0"/>
   <site name="sb" pos="0 0 0.2"/></body>
 <geom name="ghost" type="sphere" size="0.1" rgba="1 0 0 0"/>
</worldbody>
<tendon><spatial name="rope" width="0.01">
  <site site="sa"/><geom geom="drum"/><site site="anchor"/><site site="pul"/>
  <pulley divisor="2"/><site site="pul"/><site site="sb"/></spatial></tendon>
</mujoco>"""
SCALE = {"floor": (10.0, 10.0, 0.001), "drum": (0.1, 0.1, 0.2), "box": (0.2, 0.4, 0.6),
         "cap": (0.1, 0.1, 0.4), "ell": (0.06, 0.08, 0.1)}
MODEL = mujoco.MjModel.from_xml_string(XML)


def _state(pa, ra, pb, rb):
    d = mujoco.MjData(MODEL)
    d.qpos[:] = np.r_[pa, Rotation.from_rotvec(ra).as_quat(scalar_first=True),
                      pb, Rotation.from_rotvec(rb).as_quat(scalar_first=True)]
    mujoco.mj_forward(MODEL, d)
    return d


def _decode(frame, template):
    raw = MarkerEncoder(template).encode([1.5], [frame])[0]
    return TS.deserialize_cdr(raw, "visualization_msgs/msg/MarkerArray").markers


vec = st.lists(st.floats(-0.3, 0.3), min_size=3, max_size=3)


@settings(max_examples=25, deadline=None)
@given(pa=vec, ra=vec, pb=vec, rb=vec, force=st.floats(0.0, 200.0))
def test_geoms_and_tendon_follow_mujoco_kinematics(pa, ra, pb, rb, force):
    d = _state(np.r_[0, 0, 1] + pa, np.array(ra) * 3, np.r_[1, 0, 1] + pb, np.array(rb) * 3)
    template = model_markers(MODEL, _state([0, 0, 1], [0, 0, 0], [1, 0, 1], [0, 0, 0]))
    frame = model_markers(MODEL, d, tendon_force=[force], top=100.0)
    msgs = _decode(frame, template)
    assert all(m.header.frame_id == "world" for m in msgs)
    geoms = {m.id: m for m in msgs if m.ns == "geoms"}
    assert MODEL.geom("ghost").id not in geoms            # invisible (alpha 0): not drawn
    for name, scale in SCALE.items():
        g = MODEL.geom(name).id
        m = geoms[g]
        np.testing.assert_allclose([m.pose.position.x, m.pose.position.y, m.pose.position.z], d.geom_xpos[g],
                                   atol=1e-12)
        o = m.pose.orientation
        np.testing.assert_allclose(Rotation.from_quat([o.x, o.y, o.z, o.w]).as_matrix(),
                                   d.geom_xmat[g].reshape(3, 3), atol=1e-9)
        np.testing.assert_allclose([m.scale.x, m.scale.y, m.scale.z], scale, atol=1e-12)
    # capsule caps: 0.2 m along the capsule's axis on both sides of its centre
    g = MODEL.geom("cap").id
    caps = sorted((np.array([m.pose.position.x, m.pose.position.y, m.pose.position.z]) for m in msgs
                   if m.ns == "geom_caps"), key=lambda p: -p @ d.geom_xmat[g].reshape(3, 3)[:, 2])
    axis = d.geom_xmat[g].reshape(3, 3)[:, 2]
    np.testing.assert_allclose(caps, [d.geom_xpos[g] + 0.2 * axis, d.geom_xpos[g] - 0.2 * axis], atol=1e-12)
    # the tendon: segments of branch 1 (sa [-> drum tangents] -> anchor -> pul), branch 2 (pul -> sb)
    rope = [m for m in msgs if m.ns == "tendons"]
    assert len(rope) == 1 and rope[0].type == 5
    pts = np.array([[p.x, p.y, p.z] for p in rope[0].points]).reshape(-1, 2, 3)
    seg = pts[np.linalg.norm(pts[:, 1] - pts[:, 0], axis=1) > 1e-12]
    site = {n: d.site_xpos[MODEL.site(n).id] for n in ("sa", "anchor", "pul", "sb")}
    np.testing.assert_allclose(seg[-1], [site["pul"], site["sb"]], atol=1e-12)   # the second branch
    np.testing.assert_allclose(seg[-2, 1], site["pul"], atol=1e-12)              # the first ends there
    for a, b in zip(seg[:-1, 1], seg[1:-1, 0]):                                  # a path within a branch
        np.testing.assert_allclose(a, b, atol=1e-12)
    path = np.r_[seg[:1, 0], seg[:-1, 1]]      # branch 1: sa, [2 tangent points,] anchor, pul
    assert len(path) in (3, 5)
    np.testing.assert_allclose(path[[0, -2, -1]], [site["sa"], site["anchor"], site["pul"]], atol=1e-12)
    inner = path[1:-2]                          # on the drum: 0.05 m from its axis (world y)
    if len(inner):
        c = d.geom_xpos[MODEL.geom("drum").id]
        np.testing.assert_allclose(np.hypot(inner[:, 0] - c[0], inner[:, 2] - c[2]), 0.05, atol=1e-9)
    c = rope[0].color
    np.testing.assert_allclose([c.r, c.g, c.b], tension_colour(force, 100.0)[:3], atol=1e-6)


def test_one_layout_whether_the_tendon_wraps_or_not():
    """The drum is touched in one state and not in the other: same number of points (padding)."""
    touching = _state([0, 0, 1], [0, 0, 0], [1, 0, 1], [0, 0, 0])
    free = _state([-0.5, 0, 1], [0, 0, 0], [1, 0, 1], [0, 0, 0])
    n_wrap = [np.sum(dd.wrap_obj.reshape(-1)[:dd.ten_wrapnum[0]] >= 0) for dd in (touching, free)]
    assert n_wrap[0] != n_wrap[1]                      # the path really changes
    a, b = model_markers(MODEL, touching), model_markers(MODEL, free)
    assert [len(m.points) if m.points is not None else None for m in a] == \
        [len(m.points) if m.points is not None else None for m in b]
    msgs = _decode(b, a)
    pts = np.array([[p.x, p.y, p.z] for p in [m for m in msgs if m.ns == "tendons"][0].points])
    np.testing.assert_allclose(pts[0], free.site_xpos[MODEL.site("sa").id], atol=1e-12)


HANG = """<mujoco><option timestep="0.002"/><worldbody>
 <site name="top" pos="0 0 2"/>
 <body name="load" pos="0 0 1"><joint name="z" type="slide" axis="0 0 1" damping="40"/>
   <geom type="sphere" size="0.05" mass="{m}"/><site name="hook"/></body>
</worldbody>
<tendon><spatial name="rope" {attrs}><site site="top"/><site site="hook"/></spatial></tendon>
{act}</mujoco>"""


@pytest.mark.parametrize("attrs,act", [
    ('limited="true" range="0 1"', ""),                                    # taut at its limit
    ('stiffness="2000" springlength="0 0.9"', ""),                           # an elastic rope
    ("", '<actuator><motor tendon="rope" gear="2" ctrllimited="false"/></actuator>'),  # a winch
], ids=["limit", "spring", "actuator"])
def test_tendon_tension_carries_the_hanging_weight(attrs, act):
    """A 3 kg load hanging at rest on a rope: the rope's tension is its weight m g, whichever of
    the limit, the spring or an actuator (ctrl = -m g / gear: pulling) holds it."""
    from cablelab.mjcf_markers import tendon_tension

    m = 3.0
    model = mujoco.MjModel.from_xml_string(HANG.format(m=m, attrs=attrs, act=act))
    d = mujoco.MjData(model)
    if act:
        d.ctrl[0] = -m * 9.81 / 2
    for _ in range(3000):
        mujoco.mj_step(model, d)
    mujoco.mj_forward(model, d)
    assert abs(d.qvel[0]) < 1e-6
    np.testing.assert_allclose(tendon_tension(model, d), [m * 9.81], rtol=1e-3)
