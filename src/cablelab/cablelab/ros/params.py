"""Typed ROS parameters: one :class:`Param` per parameter of a node, declared and validated from it.

A node module lists its parameters once, as a tuple of :class:`Param` (name, default, description,
unit, allowed range or choices, array length, read-only); :meth:`PlantNode.declare_params
<cablelab.ros.plant_node.PlantNode.declare_params>` validates each value (the default or the
``-p name:=value`` / ``--params-file`` override) with :func:`check` and declares it with a
``rcl_interfaces/ParameterDescriptor`` built from the same spec (description, range,
``read_only``), so ``ros2 param describe`` and the node's ``--help`` (:func:`help_text`) say the
same thing, and docs/nodes.md holds the :func:`markdown_table` of every node.

Validation (ROS-free, used by the nodes and by the tests directly): integers are accepted where
numbers are (``-p rate:=100``), numbers must be finite and in range, arrays must have an allowed
length, text must be one of the choices; anything else is one line,
``<node>: parameter <name>:=<value>: expected <what>``.
"""
from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any, Callable

from ..errors import CablelabError

#: ROS type names (as ``ros2 param describe`` prints them) of the parameter kinds
ROS_TYPES = {"bool": "bool", "int": "integer", "float": "double", "str": "string",
             "float[]": "double array", "int[]": "integer array", "str[]": "string array"}
INT64 = (-2 ** 63, 2 ** 63 - 1)


def _kind_of(default: Any) -> str:
    if isinstance(default, bool):
        return "bool"
    if isinstance(default, int):
        return "int"
    if isinstance(default, float):
        return "float"
    if isinstance(default, str):
        return "str"
    if isinstance(default, (list, tuple)) and default:
        return _kind_of(default[0]) + "[]"
    raise TypeError(f"cannot infer a parameter kind from the default {default!r}")


def _fmt(x: float) -> str:
    return f"{x:g}" if isinstance(x, float) else str(x)


@dataclass(frozen=True)
class Param:
    """One ROS parameter of a node.

    Args:
        name: parameter name.
        default: value when not overridden; its Python type gives the kind (``float``,
            ``int``, ``bool``, ``str`` or a non-empty list of one of them).
        description: what it is (one sentence; the unit goes in ``unit``).
        unit: SI unit of a number (``"Hz"``, ``"kg"``, ``"s wall"``), empty for none.
        ge, gt, le, lt: bounds of a number (or of every element of a number array).
        length: allowed lengths of an array (``(3,)``; None = any non-empty).
        choices: allowed values of a text parameter.
        nan: NaN is allowed (it means "not given", e.g. taken from the description).
        read_only: read once at start-up (``ros2 param set`` is refused, since it would do nothing).
        convert: applied to an override before it is checked (e.g. YAML's bare ``y`` read as true).
        kind: ``float``, ``int``, ``bool``, ``str``, ``float[]``, ``int[]``, ``str[]``
            (inferred from ``default`` when empty).
    """

    name: str
    default: Any
    description: str
    unit: str = ""
    ge: float | None = None
    gt: float | None = None
    le: float | None = None
    lt: float | None = None
    length: tuple[int, ...] | None = None
    choices: tuple[str, ...] = ()
    nan: bool = False
    read_only: bool = True
    convert: Callable[[Any], Any] | None = None
    kind: str = ""

    def __post_init__(self):
        if not self.kind:
            object.__setattr__(self, "kind", _kind_of(self.default))

    @property
    def scalar(self) -> str:
        return self.kind.rstrip("[]")

    @property
    def is_array(self) -> bool:
        return self.kind.endswith("[]")

    def bounds_text(self) -> str:
        """The allowed range as text (``> 0``, ``in [0, 1]``), empty when unbounded."""
        lo = (f">= {_fmt(self.ge)}" if self.ge is not None else
              f"> {_fmt(self.gt)}" if self.gt is not None else "")
        hi = (f"<= {_fmt(self.le)}" if self.le is not None else
              f"< {_fmt(self.lt)}" if self.lt is not None else "")
        if self.ge is not None and self.le is not None:
            return f"in [{_fmt(self.ge)}, {_fmt(self.le)}]"
        return " and ".join(x for x in (lo, hi) if x)

    def allowed(self) -> str:
        """What the value must be, as text (``a number > 0``, ``3 numbers``, ``one of: a, b``)."""
        if self.choices:
            return "one of: " + ", ".join(self.choices)
        noun = {"float": "number", "int": "integer", "bool": "bool (true or false)",
                "str": "text"}[self.scalar]
        bounds = self.bounds_text()
        if self.is_array:
            count = (" or ".join(str(n) for n in self.length) if self.length else "one or more")
            plural = "s" if self.length != (1,) else ""
            text = f"{count} {noun}{plural}"
            if bounds:
                text += f", each {bounds}"
        elif noun == "text":
            text = noun
        else:
            text = f"a{'n' if noun[0] in 'aeiou' else ''} {noun}"
            if bounds:
                text += f" {bounds}"
        if self.nan:
            text += " (or NaN: not given)"
        return text + (f" [{self.unit}]" if self.unit else "")

    def default_text(self) -> str:
        if self.is_array:
            return "[" + ", ".join(repr(x) for x in self.default) + "]"
        if isinstance(self.default, bool):
            return str(self.default).lower()
        if isinstance(self.default, str):
            return repr(self.default)
        return repr(self.default)

    # ------------------------------------------------------------------ validation
    def _scalar(self, x: Any, who: str, shown: str):
        def bad():
            return CablelabError(f"{who}: parameter {self.name}:={shown}: expected {self.allowed()}")

        kind = self.scalar
        if kind == "bool":
            if not isinstance(x, bool):
                raise bad()
            return x
        if kind == "str":
            if not isinstance(x, str) or (self.choices and x not in self.choices):
                raise bad()
            return x
        if isinstance(x, bool) or not isinstance(x, (int, float)):
            raise bad()
        if kind == "int":
            if isinstance(x, float):
                if not (math.isfinite(x) and x.is_integer()):
                    raise bad()
                x = int(x)
        else:
            x = float(x)
            if math.isnan(x):
                if self.nan:
                    return x
                raise bad()
            if not math.isfinite(x):
                raise bad()
        if ((self.ge is not None and not x >= self.ge) or (self.gt is not None and not x > self.gt)
                or (self.le is not None and not x <= self.le) or (self.lt is not None and not x < self.lt)):
            raise bad()
        if kind == "int" and not INT64[0] <= x <= INT64[1]:
            raise bad()
        return x

    def check(self, value: Any, who: str = "node"):
        """The validated value (ints made floats where numbers are expected, arrays as lists);
        :class:`~cablelab.errors.CablelabError` naming ``who``, the parameter, the value and
        what is allowed otherwise."""
        if self.convert is not None:
            value = self.convert(value)
        shown = _show(value)
        if not self.is_array:
            if isinstance(value, (list, tuple)):
                raise CablelabError(f"{who}: parameter {self.name}:={shown}: expected {self.allowed()}")
            return self._scalar(value, who, shown)
        if not isinstance(value, (list, tuple)) or not value or \
                (self.length is not None and len(value) not in self.length):
            raise CablelabError(f"{who}: parameter {self.name}:={shown}: expected {self.allowed()}")
        return [self._scalar(x, who, shown) for x in value]

    # ------------------------------------------------------------------ ROS
    def descriptor(self):
        """The ``rcl_interfaces/ParameterDescriptor`` of this parameter (type, description,
        additional constraints, range of a number, read-only)."""
        from rcl_interfaces.msg import FloatingPointRange, IntegerRange, ParameterDescriptor

        text = self.description + (f" [{self.unit}]" if self.unit else "")
        d = ParameterDescriptor(name=self.name, description=text, additional_constraints=self.allowed(),
                                read_only=self.read_only)
        if self.kind == "float" and not self.nan:      # (ROS ranges refuse NaN: the text says it)
            lo = next((b for b in (self.ge, self.gt) if b is not None), -math.inf)
            hi = next((b for b in (self.le, self.lt) if b is not None), math.inf)
            if (lo, hi) != (-math.inf, math.inf):
                d.floating_point_range = [FloatingPointRange(from_value=float(lo), to_value=float(hi), step=0.0)]
        elif self.kind == "int":
            lo = int(self.ge) if self.ge is not None else int(self.gt) + 1 if self.gt is not None else INT64[0]
            hi = int(self.le) if self.le is not None else int(self.lt) - 1 if self.lt is not None else INT64[1]
            if (lo, hi) != INT64:
                d.integer_range = [IntegerRange(from_value=lo, to_value=hi, step=1)]
        return d


def _show(value: Any) -> str:
    """A value as a user would type it after ``:=`` (short)."""
    if isinstance(value, bool):
        text = str(value).lower()
    elif isinstance(value, (list, tuple)):
        text = "[" + ", ".join(_show(x) for x in value) + "]"
    elif isinstance(value, float):
        text = repr(value)
    elif value is None:
        text = "(empty)"
    else:
        text = str(value)
    text = " ".join(text.split())
    return text if len(text) <= 60 else text[:57] + "..."


def check_all(specs, values: dict, who: str = "node") -> dict:
    """Validate ``values`` (name -> override; missing names take the default) against ``specs``:
    name -> validated value, in the order of ``specs``. The ROS-free core of
    :meth:`PlantNode.declare_params`."""
    return {s.name: s.check(values[s.name] if s.name in values else s.default, who) for s in specs}


def merge(*groups) -> tuple:
    """Concatenate parameter tuples; a later Param of the same name replaces an earlier one
    (e.g. a node's own default for a shared parameter)."""
    out: dict[str, Param] = {}
    for g in groups:
        for s in g:
            out[s.name] = s
    return tuple(out.values())


def pick(specs, *names) -> tuple:
    """The specs of ``names`` from ``specs``, in that order (a node that takes over another
    node's parameters); a name ``specs`` does not hold is a KeyError."""
    by = {s.name: s for s in specs}
    return tuple(by[n] for n in names)


def help_text(specs, width: int = 100) -> str:
    """The parameters as the text block of a node's ``--help``."""
    import textwrap

    lines = []
    for s in specs:
        head = f"  {s.name} ({ROS_TYPES[s.kind]}, default {s.default_text()}; {s.allowed()}"
        head += ", read-only)" if s.read_only else ")"
        lines.append(head)
        lines += textwrap.wrap(s.description, width, initial_indent="      ", subsequent_indent="      ")
    return "\n".join(lines)


def markdown_table(specs) -> str:
    """The parameters as a markdown table (docs/nodes.md)."""
    rows = ["| parameter | type | default | allowed | description |", "| --- | --- | --- | --- | --- |"]
    for s in specs:
        rows.append(f"| `{s.name}` | {ROS_TYPES[s.kind]} | `{s.default_text()}` | {s.allowed()} | "
                    f"{s.description.replace('|', '/')} |")
    return "\n".join(rows)


# ----------------------------------------------------------------------------- shared parameters

def executor_params(fast_default: bool = True) -> tuple:
    """Parameters read by :meth:`PlantNode.use_fast_executor`."""
    return (
        Param("fast_executor", fast_default, "spin with cablelab.ros.fastspin.FastExecutor (false: "
              "rclpy's SingleThreadedExecutor)"),
        Param("rt_priority", 0, "SCHED_FIFO priority of the node's threads (0 = normal scheduling; "
              "needs the privilege)", ge=0, le=99),
        Param("cpu_affinity", [-1], "CPU numbers the node's threads run on ([-1] = any)", ge=-1),
        Param("niceness", 0, "lower priority for a node off the critical path (0 = normal)", ge=0, le=19),
        Param("sched_idle", False, "run in the SCHED_IDLE class: only on otherwise idle CPU"),
        Param("sched_slice", 0.0, "EEVDF time slice for a node on the critical path (0 = the "
              "kernel's default)", "s", ge=0.0, le=0.1),
        Param("python_idle", False, "once a compiled per-period path runs: the node's Python thread "
              "in SCHED_IDLE instead of nice 10 (for an otherwise idle machine: other work starves it)"),
    )


START_GATE = (
    Param("wait_for_subscribers", 0, "time starts only once the state topic has this many "
          "subscribers that acknowledged the initial state (at most 60 s)", ge=0, le=1000),
)

DESCRIPTION = Param("description", "", "plant description: a YAML file path or YAML text "
                    "(empty = the node's default)")


def markers_rate(what: str) -> Param:
    """The simulators' ``markers_rate``: how often the 3D view ``what`` (topic and content) is
    published (:func:`cablelab.ros.markers.start_markers`)."""
    return Param("markers_rate", 30.0, f"rate of the 3D view {what} (visualization_msgs/MarkerArray "
                 "in world; 0 = off)", "Hz wall", ge=0.0, le=1000.0)


__all__ = ["Param", "check_all", "merge", "help_text", "markdown_table", "executor_params",
           "START_GATE", "DESCRIPTION", "ROS_TYPES", "markers_rate"]
