"""The hardware seam of a control loop: what the loop reads from a robot and writes to it.

A control loop (:mod:`cablelab.control_loop`, the ``control_loop`` executable) does, every period,
``state = hardware.read()`` -> ``command = law.update(state)`` -> ``hardware.write(command)``,
as ros2_control's controller manager does with its hardware interfaces. The loop only knows the
small :class:`HardwareInterface` protocol below, so a simulator and a real robot's driver are
interchangeable: a plant ships its MuJoCo simulator as one implementation (e.g.
:class:`cablelab.plants.cdpr.hardware.SimulatedCdpr`), and a user's driver is another class with
the same five members, named by the loop's ``hardware`` parameter (``package.module:Class``).
:class:`DriverStub` is the starting point for one: every method raises an error saying what it
must do.

No ROS here: the protocol is plain Python over numpy arrays, testable without a robot or DDS.
"""
from __future__ import annotations

from dataclasses import dataclass, field
from typing import Mapping, Protocol, Sequence, runtime_checkable

import numpy as np

from .errors import CablelabError

__all__ = ["HardwareState", "HardwareInterface", "DriverStub", "load_hardware_class"]


@dataclass
class HardwareState:
    """One reading of the hardware.

    Args:
        t: stamp of the reading, s (the simulator's time, or the driver's clock).
        position: (n,) joint (motor) positions q, rad or m, in ``joint_names`` order.
        velocity: (n,) joint rates q', rad/s or m/s.
        effort: (n,) measured joint efforts (motor torques from current), N m or N.
        extra: further measurements by name, each an array (e.g. the CDPR's ``tension`` and
            ``cable_length`` per cable, the platform ``position`` and ``quat``).
    """

    t: float
    position: np.ndarray
    velocity: np.ndarray
    effort: np.ndarray
    extra: Mapping[str, np.ndarray] = field(default_factory=dict)


@runtime_checkable
class HardwareInterface(Protocol):
    """What a control loop needs of a robot (or of its simulator).

    ``start()`` is called once before the first period (power the drives, open the bus; a
    simulator settles its initial state), ``read()`` once at the start of every period, and
    ``write(command)`` once per period right after the law computed the command; ``stop()`` once
    at the end (brakes on, bus closed), also after an error. ``write(None)`` means the law had no
    valid command this period (bad state or missing reference): the hardware must go to its safe
    behaviour (e.g. engage the brakes), not hold a stale command for ever.

    A simulator advances its physics by one period in ``write`` (the command is held over the
    period, as a drive holds it until the next one); a driver returns from ``write`` as soon as
    the command is on its way. Both must return well within a period: ``read`` and ``write`` are
    on the loop's deadline path.
    """

    #: names of the n joints (motors) of ``position``/``velocity``/``effort`` and of the command
    joint_names: Sequence[str]

    def start(self) -> None: ...

    def read(self) -> HardwareState: ...

    def write(self, command: np.ndarray | None) -> None: ...

    def stop(self) -> None: ...


class DriverStub:
    """A real robot's driver, not written yet: subclass it (or copy its five members) and
    implement each method; the loop needs nothing else.

    Every method raises :class:`~cablelab.errors.CablelabError` naming what it must do, so a
    loop started with ``hardware:=stub`` stops at once with that message instead of moving
    anything. Args: ``joint_names`` (the n joints the loop will command, in order) and
    ``description`` (the plant description, for the driver's own checks).
    """

    def __init__(self, joint_names: Sequence[str] = (), description=None):
        self.joint_names = tuple(joint_names)
        self.description = description

    def _missing(self, what: str):
        return CablelabError(f"{type(self).__name__}.{what} is not implemented: this is the stub of a "
                             "real-hardware driver (cablelab.hardware.DriverStub); write a class with "
                             "start(), read() -> HardwareState, write(command), stop() and joint_names "
                             "for your robot and name it with the control loop's parameter "
                             "hardware:=package.module:Class (docs/nodes.md, 'Plugging in a driver')")

    def start(self) -> None:
        """Open the connection to the drives and enable them (or raise if they are not ready)."""
        raise self._missing("start() (open the bus, enable the drives)")

    def read(self) -> HardwareState:
        """Return the newest measurement: a :class:`HardwareState` with the stamp, the n joint
        positions, rates and efforts in ``joint_names`` order and any extra sensors by name."""
        raise self._missing("read() (return the newest HardwareState)")

    def write(self, command: np.ndarray | None) -> None:
        """Send the (n,) joint efforts to the drives; ``None``: apply the safe state (brakes)."""
        raise self._missing("write(command) (send the efforts; None = brakes)")

    def stop(self) -> None:
        """Engage the brakes and close the connection (called once, also after an error)."""


def load_hardware_class(spec: str):
    """The class named by ``package.module:Class`` (a control loop's ``hardware`` parameter);
    one-line CablelabError if it cannot be imported or does not have the protocol's members."""
    import importlib

    module, sep, name = str(spec).partition(":")
    if not sep or not module or not name:
        raise CablelabError(f"hardware {spec!r}: expected 'package.module:Class'")
    try:
        cls = getattr(importlib.import_module(module), name)
    except (ImportError, AttributeError) as exc:
        raise CablelabError(f"hardware {spec!r}: cannot import it ({exc})") from None
    missing = [m for m in ("start", "read", "write", "stop") if not callable(getattr(cls, m, None))]
    if missing:
        raise CablelabError(f"hardware {spec!r}: missing method(s) {', '.join(missing)} of "
                            "cablelab.hardware.HardwareInterface")
    return cls
