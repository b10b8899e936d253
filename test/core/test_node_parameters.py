"""ROS parameters of every node of every plant: declared from typed specs (cablelab.ros.params)
with descriptors, validated before use (integers where numbers are expected accepted, range,
length, choices), listed by the node's ``--help``; bad values are one line naming the node, the
parameter, the value and what is allowed, never a traceback.

The validation is checked against an independent predicate written here from the spec's fields
(hypothesis draws valid and invalid values of every declared type and range, per node), the
issue's cases against real nodes built in-process with ``--ros-args -p`` overrides."""
from __future__ import annotations

import importlib
import math
import os
import sys

import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from robust_helpers import REPO, toy_plant_dir

EXAMPLES = int(os.environ.get("CABLELAB_FUZZ_EXAMPLES", "40"))
FUZZ = settings(max_examples=EXAMPLES, deadline=None, derandomize=not os.environ.get("CABLELAB_FUZZ_RANDOM"),
                suppress_health_check=list(HealthCheck))


def _toy_specs():
    """The toy plant's simulator parameters (its package imported from its folder, then forgotten
    again with its registration, so no other test sees a plant the registry does not find)."""
    from cablelab import effects, registry

    before = dict(effects._REGISTRY)
    sys.path.insert(0, str(toy_plant_dir()))
    try:
        return importlib.import_module("pendulum_plant.nodes.sim").PARAMETERS
    finally:
        sys.path.remove(str(toy_plant_dir()))
        registry._REGISTRY.pop("pendulum", None)
        effects._REGISTRY.clear()
        effects._REGISTRY.update(before)
        for name in [m for m in sys.modules if m == "pendulum_plant" or m.startswith("pendulum_plant.")]:
            del sys.modules[name]


def _all_specs():
    """(node id, specs) of every node of every registered plant, and of the toy plant."""
    from cablelab.registry import available_plants
    from cablelab.ros.runner import ROLES, node_module, parameters_of

    out = []
    for plant in available_plants():
        for package, role in {**ROLES, "control_loop": "control_loop"}.items():
            module = node_module(plant, role)
            if module is not None:
                out.append((f"{package} --plant {plant}", parameters_of(module)))
    out.append(("cable_sim_node --plant pendulum", _toy_specs()))
    return out


SPECS = _all_specs()
IDS = [n for n, _ in SPECS]


def valid(spec, value) -> bool:
    """Independent oracle: is ``value`` (as rclpy hands it over) allowed by ``spec``?"""
    from cablelab.ros import params

    def scalar(x):
        k = spec.scalar
        if k == "bool":
            return isinstance(x, bool)
        if k == "str":
            return isinstance(x, str) and (not spec.choices or x in spec.choices)
        if isinstance(x, bool) or not isinstance(x, (int, float)):
            return False
        if k == "int" and isinstance(x, float) and not (math.isfinite(x) and x == int(x)):
            return False
        if k == "int" and not params.INT64[0] <= int(x) <= params.INT64[1]:   # ROS integers are int64
            return False
        if isinstance(x, float) and math.isnan(x):
            return spec.nan
        if math.isinf(x):
            return False
        return ((spec.ge is None or x >= spec.ge) and (spec.gt is None or x > spec.gt)
                and (spec.le is None or x <= spec.le) and (spec.lt is None or x < spec.lt))

    if spec.convert is not None:
        value = spec.convert(value)
    if spec.is_array:
        return (isinstance(value, list) and len(value) > 0
                and (spec.length is None or len(value) in spec.length) and all(scalar(x) for x in value))
    return not isinstance(value, list) and scalar(value)


def test_every_node_has_specs_for_its_parameters():
    assert len(SPECS) >= 16
    for node, specs in SPECS:
        assert specs, f"{node}: no ROS parameter specs"
        names = [s.name for s in specs]
        assert len(names) == len(set(names)), node
        for s in specs:
            assert s.description, f"{node}: {s.name} has no description"
            assert valid(s, s.default) and s.check(s.default, node) is not None, f"{node}: default of {s.name}"


def _bounded_number(spec, kind):
    lo = spec.ge if spec.ge is not None else spec.gt
    hi = spec.le if spec.le is not None else spec.lt
    lo = -1e6 if lo is None else lo
    hi = (lo + 1e6) if hi is None else hi
    if kind == "int":
        return st.integers(int(math.ceil(lo)), int(math.floor(hi)))
    return st.floats(lo, hi, allow_nan=False)


@st.composite
def any_value(draw, spec):
    """A value of spec's type in or around its range, or of another type (rclpy's override types:
    bool, int, float, str, lists of one of them)."""
    kinds = st.one_of(st.booleans(), st.integers(-10 ** 7, 10 ** 7),
                      st.floats(allow_nan=True, allow_infinity=True),
                      st.sampled_from([0, 0.0, -1, -1.0, 1e-9, 1e9, float("nan")]),
                      st.text(max_size=8), st.sampled_from(list(spec.choices) or ["x"]))
    scalar_kind = spec.scalar if spec.scalar in ("int", "float") else None
    near = _bounded_number(spec, scalar_kind) if scalar_kind else kinds
    if scalar_kind == "float":
        near = st.one_of(near, st.integers(-100, 100))        # integer spellings of numbers
    if spec.scalar == "bool":
        near = st.booleans()
    if spec.scalar == "str":
        near = st.sampled_from(list(spec.choices) or ["", "a.yaml"])
    one = st.one_of(near, near, kinds)
    lists = st.lists(one, min_size=0, max_size=5)
    if spec.length:
        lists = st.one_of(lists, st.lists(near, min_size=spec.length[0], max_size=spec.length[0]))
    return draw(st.one_of(lists, one) if spec.is_array else st.one_of(one, one, lists))


@pytest.mark.parametrize("node, specs", SPECS, ids=IDS)
def test_random_parameter_values_are_validated(node, specs):
    """Hypothesis: for every parameter of the node, a valid value is accepted (as the declared
    type: an integer becomes the number it means) and anything else is a one-line error naming
    the node, the parameter and what is allowed."""
    from cablelab.errors import CablelabError

    @FUZZ
    @given(data=st.data())
    def run(data):
        for spec in specs:
            value = data.draw(any_value(spec), label=spec.name)
            if valid(spec, value):
                out = spec.check(value, node)
                items = out if spec.is_array else [out]
                expect = {"float": float, "int": int, "bool": bool, "str": str}[spec.scalar]
                assert all(type(x) is expect for x in items), (spec.name, value, out)
                if spec.scalar == "float":
                    src = spec.convert(value) if spec.convert else value
                    src = src if spec.is_array else [src]
                    assert all(a == b or (a != a and b != b) for a, b in zip(items, src))
            else:
                with pytest.raises(CablelabError) as exc:
                    spec.check(value, node)
                text = str(exc.value)
                assert "\n" not in text and text.startswith(f"{node}: parameter {spec.name}:="), text
                assert "expected" in text

    run()


def test_descriptor_carries_range_and_read_only():
    from cablelab.ros.runner import node_module, parameters_of

    specs = {s.name: s for s in parameters_of(node_module("cdpr", "sim"))}
    d = specs["rate"].descriptor()
    assert d.read_only
    assert d.floating_point_range[0].from_value == 1.0 and d.floating_point_range[0].to_value == 10000.0
    assert "Hz" in d.description and "in [1, 10000]" in d.additional_constraints
    seed = specs["seed"].descriptor()
    assert seed.integer_range[0].from_value == 0 and not seed.floating_point_range


# ----------------------------------------------------------------------------- real nodes

@pytest.fixture
def ros_with():
    """``ros_with("rate:=100", ...)``: rclpy initialised with those ``-p`` overrides (the node
    reads them as from the command line); shut down after the test."""
    import rclpy

    from cablelab.ros.launch import release_domain_id, reserve_domain_id

    d = reserve_domain_id(salt=4343)
    started = []

    def init(*overrides):
        args = ["test", "--ros-args"]
        for o in overrides:
            args += ["-p", o]
        rclpy.init(args=args, domain_id=d)
        started.append(1)

    try:
        yield init
    finally:
        rclpy.try_shutdown()
        release_domain_id(d)


def _make(plant, role):
    from cablelab.ros.runner import node_module

    return node_module(plant, role).make_node()


@pytest.mark.parametrize("plant, role, overrides, name, value", [
    ("cdpr", "sim", ("timestep:=0.001",), "timestep", 0.001),     # was ParameterNotDeclared 'rate'
    ("cdpr", "sim", ("rate:=100",), "rate", 100.0),               # integer spelling of a double
    ("axis", "sim", ("inertia:=2",), "inertia", 2.0),
    ("crane", "sim", ("viscous:=[1, 0, 0]",), "viscous", [1.0, 0.0, 0.0]),
    ("suspended", "controller", ("excitation:=y",), "excitation", "y"),
])
def test_integer_and_partial_overrides_work(ros_with, plant, role, overrides, name, value):
    ros_with(*overrides)
    node = _make(plant, role)
    try:
        p = node.get_parameter(name)
        assert p.value == value and type(p.value) is type(value)
        assert node.describe_parameter(name).read_only
        if plant == "cdpr":
            assert node.get_parameter("rate").value == 100.0
    finally:
        node.destroy_node()


@pytest.mark.parametrize("plant, role, override, expect", [
    ("cdpr", "sim", "rate:=0.0", "parameter rate:=0.0: expected a number in [1, 10000] [Hz]"),
    ("cdpr", "sim", "timestep:=1e-9", "parameter timestep:=1e-09: expected 0 (auto) or a step of at least"),
    ("cdpr", "sim", "seed:=-1", "parameter seed:=-1: expected an integer >= 0"),
    ("cdpr", "sim", "payload_mass:=-500", "parameter payload_mass:=-500: expected a number in [0, 100000] [kg]"),
    ("cdpr", "sim", "tension_noise:=-5", "parameter tension_noise:=-5: expected a number in [0, 100000] [N]"),
    ("cdpr", "sim", "payload_com:=[0.1]", "parameter payload_com:=[0.1]: expected 3 numbers"),
    ("cdpr", "sim", "tension_bias:=[1.0, 2.0]", "parameter tension_bias:=[1.0, 2.0]: expected 1 or 8 numbers"),
    ("cdpr", "estimator", "poll_period:=1.0", "parameter poll_period:=1.0: expected a number in [0, 0.1] [s]"),
    ("cdpr", "controller", "model:=III", "parameter model:=III: expected one of: II, I"),
    ("axis", "sim", "rate:=abc", "parameter rate:=abc: expected a number in [1, 10000]"),
    ("axis", "estimator", "forgetting:=1.5", "parameter forgetting:=1.5"),
    ("crane", "sim", "base_tilt:=[0.1]", "parameter base_tilt:=[0.1]: expected 2 numbers"),
    ("crane", "controller", "kp:=[1.0, 2.0]", "parameter kp:=[1.0, 2.0]: expected 3 numbers"),
    ("leg", "sim", "mass_scale:=-1.0", "parameter mass_scale:=-1.0"),
    ("leg", "controller", "mode:=fast", "parameter mode:=fast: expected one of: apex, open_loop"),
    ("suspended", "sim", "rate:=-100", "parameter rate:=-100"),
    ("suspended", "estimator", "rest_position:=[1.0]", "parameter rest_position:=[1.0]: expected 3 numbers"),
    ("cdpr", "sim", "fast_executor:=1", "parameter fast_executor:=1: expected a bool"),
    ("cdpr", "sim", "rt_priority:=120", "parameter rt_priority:=120: expected an integer in [0, 99]"),
])
def test_bad_parameter_is_one_line_naming_it(ros_with, plant, role, override, expect):
    from cablelab.errors import CablelabError

    ros_with(override)
    with pytest.raises(CablelabError) as exc:
        _make(plant, role).destroy_node()
    text = str(exc.value)
    assert "\n" not in text and expect in text, text
    assert text.split(":")[0] in ("cable_sim_node", "payload_estimator", "pd_feedforward")


def test_node_help_lists_the_plant_parameters(capsys):
    """``cable_sim_node --plant cdpr --help`` (and ``--ros-args --help``) lists every ROS
    parameter of the plant's node with type, default, range and description, from the specs."""
    from cablelab.ros.runner import node_module, parameters_of, plant_main

    for argv in (["--plant", "cdpr", "--help"], ["--plant", "cdpr", "--ros-args", "--help"]):
        with pytest.raises(SystemExit) as exc:
            plant_main("cable_sim_node", "sim", argv, "simulator")
        assert exc.value.code == 0
        out = capsys.readouterr().out
        for spec in parameters_of(node_module("cdpr", "sim")):
            line = next(ln for ln in out.splitlines() if ln.startswith(f"  {spec.name} ("))
            assert spec.allowed() in line and spec.default_text() in line
        assert "rate (double, default 100.0; a number in [1, 10000] [Hz], read-only)" in out
        assert "payload centre of mass" in out


def test_unparsable_ros_args_are_one_line(capsys):
    """rcl refuses a list mixing integers and numbers: one line with the fix, exit 2."""
    from cablelab.ros.runner import run_node

    code = run_node(lambda: None, ["--ros-args", "-p", "payload_com:=[0, 0.5, 1]"],
                    "cable_sim_node --plant cdpr")
    err = capsys.readouterr().err.strip().splitlines()
    assert code == 2 and len(err) == 1
    assert "bad --ros-args" in err[0] and "[0.0, 0.5, 1.0]" in err[0] and "payload_com" in err[0]


def test_docs_nodes_tables_match_the_specs():
    """docs/nodes.md holds the generated parameter tables (``python docs/parameter_tables.py``)."""
    from cablelab.ros.params import markdown_table

    text = (REPO / "docs" / "nodes.md").read_text()
    for node, specs in SPECS:
        if "pendulum" in node:
            continue
        marker = f"<!-- parameters: {node} -->"
        assert marker in text, f"docs/nodes.md lacks the table of {node}"
        block = text.split(marker, 1)[1].split("<!-- end parameters -->", 1)[0]
        assert block.strip() == markdown_table(specs), f"docs/nodes.md: table of {node} is stale"


def test_simulator_refuses_a_pulley_radius_the_geometry_cannot_hold(ros_with, tmp_path):
    import yaml

    from cablelab.bags import open_bag
    from cablelab.errors import CablelabError
    from robust_helpers import CDPR

    doc = yaml.safe_load(open_bag(CDPR).description_yaml)
    doc["cdpr"]["pulley_radius"] = 100
    f = tmp_path / "d.yaml"
    f.write_text(yaml.safe_dump(doc))
    ros_with(f"description:={f}")
    with pytest.raises(CablelabError) as exc:
        _make("cdpr", "sim").destroy_node()
    assert "description cdpr.pulley_radius: 100 m is larger than the geometry allows" in str(exc.value)


def test_pick_takes_over_another_nodes_specs_unchanged():
    """A node sharing another node's parameters (the CDPR control loop) declares the very same
    specs (name, default, description, range), in the order asked; an unknown name is an error."""
    from cablelab.ros.params import Param, pick

    specs = (Param("a", 1.0, "first", ge=0.0), Param("b", "x", "second", choices=("x", "y")),
             Param("c", [1.0], "third"))
    got = pick(specs, "c", "a")
    assert [s.name for s in got] == ["c", "a"] and got[0] is specs[2] and got[1] is specs[0]
    with pytest.raises(KeyError):
        pick(specs, "d")
