"""Property-based fuzz of every node callback, in-process (no DDS traffic): hostile messages
(NaN/inf, wrong lengths, unknown joint names, empty, stamps out of order or negative, junk
descriptions) go to every ``on_*`` callback of the simulator, estimator and controller nodes of
each plant, followed by the node's periodic step. Every node keeps running (no exception leaves
a callback) and reports on /diagnostics: a status is published, and a rejected input makes it at
least WARN."""
from __future__ import annotations

import inspect
import os

import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from robust_helpers import CDPR, EMPS, REPO

EXAMPLES = int(os.environ.get("CABLELAB_FUZZ_EXAMPLES", "12"))
FUZZ = settings(max_examples=EXAMPLES, deadline=None, derandomize=not os.environ.get("CABLELAB_FUZZ_RANDOM"),
                suppress_health_check=list(HealthCheck))

def _node_factories():
    """Every node of every plant of the registry (``<plant package>.nodes.<role>``): nothing to
    keep in step when a plant or a node is added."""
    from cablelab.registry import available_plants
    from cablelab.ros.runner import ROLES, node_module

    out = []
    for plant in available_plants():
        for role in ROLES.values():
            if node_module(plant, role) is not None:
                out.append((plant, role))
    return out


NODES = _node_factories()
STEPS = ("tick", "on_timer", "process")
NAMES = ["joint", "slew", "luff", "hoist", "theta1", "theta2"] + [f"winch_{i}" for i in range(1, 10)] + \
        [f"cable_{i}" for i in range(1, 10)] + ["nope", ""]

FLOAT = st.one_of(st.floats(allow_nan=True, allow_infinity=True), st.sampled_from([0.0, 1.0, -1.0, 1e300, -50.0]))
ARRAY = st.lists(FLOAT, max_size=10)
NAME_LIST = st.lists(st.sampled_from(NAMES), max_size=10)


def _descriptions():
    from cablelab.bags import open_bag

    plants = REPO / "src" / "cablelab" / "cablelab" / "plants"
    return {"axis": open_bag(EMPS).description_yaml, "cdpr": open_bag(CDPR).description_yaml,
            "crane": open_bag(REPO / "bags" / "crane_control").description_yaml,
            "leg": (plants / "leg" / "data" / "leg.yaml").read_text(),
            "suspended": (plants / "suspended" / "data" / "licas.yaml").read_text(),
            "mjcf": _mjcf_description()}


def _mjcf_description() -> str:
    from cablelab.plants.mjcf.nodes.sim import default_description

    return default_description()


@st.composite
def stamp(draw, header):
    header.stamp.sec = draw(st.integers(-2 ** 31, 2 ** 31 - 1))
    header.stamp.nanosec = draw(st.integers(0, 999_999_999))
    return header


@st.composite
def message(draw, type_name: str, descriptions: dict):
    from builtin_interfaces.msg import Duration
    from geometry_msgs.msg import (InertiaStamped, PoseStamped, Quaternion, Transform, Twist,
                                   Vector3)
    from sensor_msgs.msg import JointState
    from std_msgs.msg import Float64MultiArray, String
    from trajectory_msgs.msg import (JointTrajectory, JointTrajectoryPoint, MultiDOFJointTrajectory,
                                     MultiDOFJointTrajectoryPoint)

    def vec():
        return Vector3(x=draw(FLOAT), y=draw(FLOAT), z=draw(FLOAT))

    def quat():
        return Quaternion(x=draw(FLOAT), y=draw(FLOAT), z=draw(FLOAT), w=draw(FLOAT))

    if type_name == "JointState":
        m = JointState(name=draw(NAME_LIST), position=draw(ARRAY), velocity=draw(ARRAY), effort=draw(ARRAY))
        draw(stamp(m.header))
    elif type_name == "PoseStamped":
        m = PoseStamped()
        m.pose.position.x, m.pose.position.y, m.pose.position.z = draw(FLOAT), draw(FLOAT), draw(FLOAT)
        m.pose.orientation = quat()
        draw(stamp(m.header))
    elif type_name == "Float64MultiArray":
        m = Float64MultiArray(data=draw(ARRAY))
    elif type_name == "String":
        other = draw(st.sampled_from(sorted(descriptions)))
        m = String(data=draw(st.one_of(st.text(max_size=60), st.just(descriptions[other]),
                                       st.sampled_from(["plant: cdpr", "{}", "plant: [1]", "- 1"]))))
    elif type_name == "JointTrajectory":
        pts = [JointTrajectoryPoint(positions=draw(ARRAY), velocities=draw(ARRAY), accelerations=draw(ARRAY),
                                    time_from_start=Duration(sec=draw(st.integers(-5, 5))))
               for _ in range(draw(st.integers(0, 2)))]
        m = JointTrajectory(joint_names=draw(NAME_LIST), points=pts)
        draw(stamp(m.header))
    elif type_name == "MultiDOFJointTrajectory":
        pts = []
        for _ in range(draw(st.integers(0, 2))):
            k = draw(st.integers(0, 2))
            pts.append(MultiDOFJointTrajectoryPoint(
                transforms=[Transform(translation=vec(), rotation=quat()) for _ in range(k)],
                velocities=[Twist(linear=vec(), angular=vec()) for _ in range(draw(st.integers(0, 2)))],
                accelerations=[Twist(linear=vec(), angular=vec()) for _ in range(draw(st.integers(0, 2)))]))
        m = MultiDOFJointTrajectory(joint_names=draw(NAME_LIST), points=pts)
        draw(stamp(m.header))
    elif type_name == "InertiaStamped":
        m = InertiaStamped()
        m.inertia.m = draw(FLOAT)
        m.inertia.com = vec()
        draw(stamp(m.header))
    elif type_name == "Imu":
        from sensor_msgs.msg import Imu

        m = Imu(orientation=quat(), angular_velocity=vec(), linear_acceleration=vec())
        m.orientation_covariance[0] = draw(st.sampled_from([0.0, -1.0]))
        draw(stamp(m.header))
    else:
        raise AssertionError(f"no strategy for {type_name}")
    return m


def _callbacks(node) -> dict:
    """``on_*`` methods with one message argument -> the message type's name."""
    out = {}
    for name, fn in inspect.getmembers(node, inspect.ismethod):
        if not name.startswith("on_"):
            continue
        params = list(inspect.signature(fn).parameters.values())
        if len(params) != 1:
            continue
        ann = params[0].annotation
        tname = ann if isinstance(ann, str) else getattr(ann, "__name__", "")
        if tname:
            out[name] = tname.split(".")[-1]
    return out


@pytest.fixture(scope="module")
def ros(tmp_path_factory):
    import rclpy

    from cablelab.ros.launch import release_domain_id, reserve_domain_id

    d = reserve_domain_id(salt=4242)
    rclpy.init(domain_id=d)
    try:
        yield
    finally:
        rclpy.try_shutdown()
        release_domain_id(d)


def test_every_plant_node_is_fuzzed():
    assert {("axis", "sim"), ("cdpr", "controller"), ("crane", "estimator")} <= set(NODES)


@pytest.mark.parametrize("plant, role", NODES, ids=[f"{p}.{r}" for p, r in NODES])
def test_node_survives_hostile_messages(ros, plant, role):
    from cablelab.ros.inputs import InputMonitor
    from cablelab.ros.runner import node_module

    descriptions = _descriptions()
    if plant not in descriptions:
        pytest.skip(f"no working description of plant {plant} for the fuzz test yet")
    node = node_module(plant, role).make_node()
    cls = type(node).__name__
    published = []
    node.diag.pub.publish = published.append
    try:
        cbs = _callbacks(node)
        assert cbs, f"{cls}: no callbacks found"
        if "on_description" in cbs:                     # a working node first, then the hostility
            from std_msgs.msg import String

            node.on_description(String(data=descriptions[plant]))
        steps = [getattr(node, s) for s in STEPS if callable(getattr(node, s, None))]
        names = sorted(cbs)
        # subscriptions taken as serialised bytes get their messages as bytes too, and garbage
        raw = {getattr(s.callback, "__name__", "") for s in node.subscriptions if s.raw}

        def sample(n):
            m = message(cbs[n], descriptions)
            if n in raw:
                from rclpy.serialization import serialize_message

                m = st.one_of(m, m.map(serialize_message), st.binary(max_size=200))
            return st.tuples(st.just(n), m)

        @FUZZ
        @given(seq=st.lists(st.sampled_from(names).flatmap(sample), min_size=1, max_size=6))
        def run(seq):
            for name, msg in seq:
                getattr(node, name)(msg)            # must not raise
            for step in steps:
                step()
            level, text, values = node.status()
            assert level in (0, 1, 2) and isinstance(text, str) and "\n" not in text
            inputs = getattr(node, "inputs", None)
            if isinstance(inputs, InputMonitor) and any(s.rejected for s in inputs.inputs.values()):
                assert level >= 1, (text, values)
            n = len(published)
            node.diag.publish()
            assert len(published) == n + 1 and published[-1].status[0].level == bytes([level])

        run()
    finally:
        node.destroy_node()


# ----------------------------------------------------------------------------- ROS parameters

@pytest.mark.parametrize("plant, role", NODES, ids=[f"{p}.{r}" for p, r in NODES])
def test_node_refuses_random_bad_parameters(ros, monkeypatch, plant, role):
    """Hypothesis: the real node built with one random invalid override of one of its declared
    parameters (wrong type, out of range, wrong length: strategies of test_node_parameters) stops
    with one line naming the node and the parameter, never a traceback or a node half built."""
    from rclpy.node import Node
    from rclpy.parameter import Parameter

    from cablelab.errors import CablelabError
    from cablelab.ros.runner import node_module, parameters_of
    from test_node_parameters import any_value, valid

    module = node_module(plant, role)
    specs = parameters_of(module)
    overrides = []
    init = Node.__init__

    def with_overrides(self, *a, **kw):
        kw["parameter_overrides"] = list(overrides)
        init(self, *a, **kw)

    monkeypatch.setattr(Node, "__init__", with_overrides)

    def homogeneous(v):          # what an override can hold (rcl refuses mixed lists itself)
        return not isinstance(v, list) or (v and len({type(x) for x in v}) == 1)

    @settings(max_examples=max(3, EXAMPLES // 2), deadline=None,
              derandomize=not os.environ.get("CABLELAB_FUZZ_RANDOM"), suppress_health_check=list(HealthCheck))
    @given(data=st.data())
    def run(data):
        spec = data.draw(st.sampled_from(specs))
        value = data.draw(any_value(spec).filter(lambda v: not valid(spec, v) and homogeneous(v)
                                                 and v is not None))
        overrides[:] = [Parameter(spec.name, value=value)]
        with pytest.raises(CablelabError) as exc:
            module.make_node().destroy_node()
        text = str(exc.value)
        assert "\n" not in text and f"parameter {spec.name}:=" in text, text

    run()
