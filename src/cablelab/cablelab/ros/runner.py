"""Run an rclpy node: argument parsing (``--plant``, ``--ros-args``), spin, clean shutdown.

``plant_main(package, argv)`` is the whole ``main`` of every node package: it parses
``--plant``, imports ``<package>.<plant>`` (the plant's adapter module, which exposes
``make_node(args) -> rclpy Node`` and optionally ``add_arguments(parser)``) and runs it with
:func:`run_node`. ``--help`` never needs ROS. Standard ROS arguments (``--ros-args -p name:=value
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
import importlib
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


def run_node(node_factory, args, ros_args: list[str], prog: str) -> int:
    """Init rclpy with ``ros_args``, build the node with ``node_factory(args)``, spin until
    SIGINT/SIGTERM (or ``node.done`` becomes True), shut down cleanly. Returns the exit code."""
    import rclpy
    from rclpy.executors import ExternalShutdownException, SingleThreadedExecutor
    from rclpy.signals import SignalHandlerOptions

    stop = _Stop()
    old = {s: signal.signal(s, stop) for s in (signal.SIGINT, signal.SIGTERM)}
    rclpy.init(args=[prog] + ros_args, signal_handler_options=SignalHandlerOptions.NO)
    node = None
    code = 0
    try:
        try:
            node = node_factory(args)
        except CablelabError as exc:
            print(f"{prog}: error: {exc}", file=sys.stderr)
            return 2
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


def plant_main(package: str, argv: list[str] | None, description: str,
               plants: tuple[str, ...] = ("cdpr", "crane", "axis", "suspended")) -> int:
    """``main`` of a node package: ``--plant P`` selects the module ``<package>.<P>``."""
    argv = list(sys.argv[1:] if argv is None else argv)
    user, ros_args = split_ros_args(argv)
    parser = argparse.ArgumentParser(
        prog=package, description=description,
        epilog="ROS parameters: --ros-args -p name:=value, --params-file FILE.yaml. "
               "Stops cleanly on SIGINT/SIGTERM.")
    parser.add_argument("--plant", choices=plants, required=True, help="which plant")
    pre = argparse.ArgumentParser(add_help=False)
    pre.add_argument("--plant", choices=plants)
    known, _ = pre.parse_known_args(user)
    module = None
    if known.plant:
        try:
            module = importlib.import_module(f"{package}.{known.plant}")
        except ModuleNotFoundError as exc:
            if exc.name != f"{package}.{known.plant}":
                raise
            if "-h" not in user and "--help" not in user:
                print(f"{package}: error: plant {known.plant!r} is not available yet "
                      f"(module {package}.{known.plant} not built)", file=sys.stderr)
                return 2
        if module is not None and hasattr(module, "add_arguments"):
            module.add_arguments(parser)
    args = parser.parse_args(user)
    return run_node(module.make_node, args, ros_args, package)
