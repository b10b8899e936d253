"""Run an rclpy node: argument parsing (``--plant``, ``--ros-args``), spin, clean shutdown.

``plant_main(package, role, argv)`` is the whole ``main`` of every node package: it parses
``--plant`` (any plant of :mod:`cablelab.registry`), imports the plant's node module for the
role (``<plant package>.nodes.<role>``, which exposes ``PARAMETERS`` and
``make_node() -> rclpy Node``) and runs it with :func:`run_node`. ``--help`` never needs ROS. Standard ROS arguments (``--ros-args -p name:=value
--params-file f.yaml -r from:=to``) pass through to rclpy.

A node may define ``executor_factory()`` returning the executor to spin it with (e.g.
:class:`.fastspin.FastExecutor`); default rclpy's SingleThreadedExecutor.

Shutdown: SIGINT and SIGTERM stop the spin loop; the node's ``drain(executor)`` method (if any)
processes what is already queued, its ``shutdown()`` method (if any) runs
(e.g. the recorder closes its bag), then the node is destroyed and rclpy shut down; exit code 0.
A :class:`~cablelab.errors.CablelabError` while building the node prints one line, exit 2.
"""
from __future__ import annotations

import argparse
import gc
import signal
import sys
import threading

from ..errors import CablelabError


def split_ros_args(argv: list[str]) -> tuple[list[str], list[str]]:
    """Split argv into (user arguments, ROS arguments incl. the ``--ros-args`` markers)."""
    user, ros, inside = [], [], False
    for arg in argv:
        if arg == "--ros-args":
            inside = True
            ros.append(arg)
        elif arg == "--" and inside:
            inside = False
            ros.append(arg)
        elif inside:
            ros.append(arg)
        else:
            user.append(arg)
    return user, ros


class _Stop:
    def __init__(self):
        self.event = threading.Event()
        self.signal = None

    def __call__(self, signum, _frame):
        self.signal = signum
        self.event.set()


def _tight_timers() -> None:
    """Wake timed waits on time: Linux delays a normal thread's timed wake-up by up to its timer
    slack (50 us by default) to batch wake-ups, a twentieth of a 1 kHz period. Set to 1 ns for
    this thread and the threads it starts (DDS threads start in rclpy.init); no privilege
    needed. Elsewhere (no prctl) nothing happens."""
    try:
        import ctypes

        ctypes.CDLL(None, use_errno=True).prctl(29, 1, 0, 0, 0)   # PR_SET_TIMERSLACK
    except (OSError, AttributeError):
        pass


def run_node(node_factory, ros_args: list[str], prog: str) -> int:
    """Init rclpy with ``ros_args``, build the node with ``node_factory()``, spin until
    SIGINT/SIGTERM (or ``node.done`` becomes True), shut down cleanly. Returns the exit code."""
    import rclpy
    from rclpy.executors import ExternalShutdownException, SingleThreadedExecutor
    from rclpy.signals import SignalHandlerOptions

    stop = _Stop()
    old = {s: signal.signal(s, stop) for s in (signal.SIGINT, signal.SIGTERM)}
    _tight_timers()
    problem = mixed_lists(ros_args)
    if problem:            # (rcl would refuse it too, after logging an error line of its own)
        for s, h in old.items():
            signal.signal(s, h)
        print(f"{prog}: error: {problem}", file=sys.stderr)
        return 2
    try:
        rclpy.init(args=[prog] + ros_args, signal_handler_options=SignalHandlerOptions.NO)
    except Exception as exc:  # noqa: BLE001 - rcl's argument parser: one line, not a traceback
        for s, h in old.items():
            signal.signal(s, h)
        print(f"{prog}: error: {ros_args_problem(exc)}", file=sys.stderr)
        return 2
    node = None
    code = 0
    try:
        try:
            node = node_factory()
        except CablelabError as exc:
            print(f"{prog}: error: {exc}", file=sys.stderr)
            return 2
        unknown = getattr(node, "unknown_parameters", None)
        if callable(unknown) and unknown():
            node.get_logger().warning(f"parameters this node does not have (ignored): {', '.join(unknown())}; "
                                      f"{prog} --help lists its parameters")
        # what start-up built lives to the end: keep it out of the collector's scans, so that a
        # full collection in a 1 kHz callback costs microseconds, not milliseconds
        gc.collect()
        gc.freeze()
        factory = getattr(node, "executor_factory", None)   # a node may bring a leaner executor
        executor = factory() if callable(factory) else SingleThreadedExecutor()
        executor.add_node(node)
        while not stop.event.is_set() and rclpy.ok() and not getattr(node, "done", False):
            executor.spin_once(timeout_sec=0.1)
        drain = getattr(node, "drain", None)
        if callable(drain) and rclpy.ok():
            drain(executor)  # e.g. the recorder takes what DDS already delivered
        code = int(getattr(node, "exit_code", 0) or 0)
    except (KeyboardInterrupt, ExternalShutdownException):
        pass
    except CablelabError as exc:
        print(f"{prog}: error: {exc}", file=sys.stderr)
        code = 2
    finally:
        if node is not None:
            shutdown = getattr(node, "shutdown", None)
            if callable(shutdown):
                try:
                    shutdown()
                except Exception as exc:  # noqa: BLE001 - report, still tear down
                    print(f"{prog}: error during shutdown: {exc}", file=sys.stderr)
                    code = code or 1
            node.destroy_node()
        rclpy.try_shutdown()
        for s, h in old.items():
            signal.signal(s, h)
    return code


def ros_args_problem(exc: Exception) -> str:
    """rcl's complaint about ``--ros-args`` as one line (e.g. a list mixing integers and numbers,
    which rcl refuses: ``-p com:=[0, 0.5]`` must be written ``[0.0, 0.5]``)."""
    text = " ".join(str(exc).split())
    for cut in (", at /", " at /"):
        text = text.split(cut)[0]
    text = text.replace("failed to initialize rcl: ", "")
    hint = (" (write every element of a number list with a decimal point, e.g. [0.0, 0.5])"
            if "same type" in text else "")
    return f"bad --ros-args: {text}{hint}"


def mixed_lists(ros_args: list[str]) -> str:
    """The problem with a ``-p name:=[...]`` list mixing integers and numbers (rcl refuses such a
    list: every element of a number list must be written with a decimal point), else ''."""
    import yaml

    for i, arg in enumerate(ros_args[:-1]):
        if arg not in ("-p", "--param") or ":=" not in ros_args[i + 1]:
            continue
        name, _, text = ros_args[i + 1].partition(":=")
        if not text.strip().startswith("["):
            continue
        try:
            value = yaml.safe_load(text)
        except yaml.YAMLError:
            continue
        kinds = {type(x) for x in value} if isinstance(value, list) else set()
        if {int, float} <= kinds:
            return (f"bad --ros-args: parameter {name}:={text}: a list mixing integers and numbers; "
                    f"write every element with a decimal point, e.g. "
                    f"[{', '.join(repr(float(x)) if isinstance(x, (int, float)) else str(x) for x in value)}]")
    return ""


def parameters_of(module) -> tuple:
    """The parameter specs (:class:`~cablelab.ros.params.Param`) of a plant's node module: its
    ``PARAMETERS``."""
    return tuple(getattr(module, "PARAMETERS", ()))


#: node role of each node package (its executable is ``main(role)`` over the plant registry)
ROLES = {"cable_sim_node": "sim", "payload_estimator": "estimator", "pd_feedforward": "controller"}


def node_module(plant: str, role: str):
    """The module of a plant's node for ``role`` (``sim``, ``estimator``, ``controller``,
    ``control_loop``): ``<plant package>.nodes.<role>``, with ``PARAMETERS`` and
    ``make_node() -> rclpy Node``. None when the plant has no node for that role."""
    from ..registry import plant_module

    try:
        return plant_module(plant, f"nodes.{role}")
    except ModuleNotFoundError as exc:
        if exc.name and exc.name.endswith((".nodes", f".nodes.{role}")):
            return None
        raise


def role_main(package: str, role: str, description: str):
    """The ``main(argv=None)`` of a node package: :func:`plant_main` for its role."""
    def main(argv: list[str] | None = None) -> int:
        return plant_main(package, role, argv, description)

    main.__doc__ = f"``{package} --plant PLANT``: {description}"
    return main


def plant_main(package: str, role: str, argv: list[str] | None, description: str) -> int:
    """``main`` of a node package: ``--plant P`` selects plant P's node for ``role``."""
    from ..registry import available_plants

    from .params import help_text

    plants = available_plants()
    argv = list(sys.argv[1:] if argv is None else argv)
    user, ros_args = split_ros_args(argv)
    if any(a in ("-h", "--help") for a in ros_args):     # --ros-args --help: the same help
        user.append("--help")
        ros_args = [a for a in ros_args if a not in ("-h", "--help")]
    parser = argparse.ArgumentParser(
        prog=package, description=description, formatter_class=argparse.RawDescriptionHelpFormatter,
        epilog="ROS parameters: --ros-args -p name:=value, --params-file FILE.yaml "
               "(with --plant P, --help lists P's). Stops cleanly on SIGINT/SIGTERM.")
    parser.add_argument("--plant", choices=plants, required=True, help="which plant")
    pre = argparse.ArgumentParser(add_help=False)
    pre.add_argument("--plant", choices=plants)
    known, _ = pre.parse_known_args(user)
    module = None
    if known.plant:
        try:
            module = node_module(known.plant, role)
        except CablelabError as exc:
            print(f"{package}: error: {exc}", file=sys.stderr)
            return 2
        if module is None and "-h" not in user and "--help" not in user:
            print(f"{package}: error: plant {known.plant!r} has no {role} node", file=sys.stderr)
            return 2
        specs = parameters_of(module) if module is not None else ()
        if specs:
            parser.epilog = (f"ROS parameters of {package} --plant {known.plant} (--ros-args -p "
                             f"name:=value, or --params-file FILE.yaml):\n{help_text(specs)}\n\n"
                             "Stops cleanly on SIGINT/SIGTERM.")
    args = parser.parse_args(user)
    return run_node(module.make_node, ros_args, f"{package} --plant {args.plant}")
