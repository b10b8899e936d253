"""The CDPR's MuJoCo simulator behind the hardware seam (:mod:`cablelab.hardware`).

:class:`SimulatedCdpr` is a :class:`~cablelab.hardware.HardwareInterface` over
:class:`~cablelab.plants.cdpr.sim.CdprSim`: ``read()`` is one sample of the winch sensors
(motor angle, rate, torque from current; dynamometer tensions, paid-out lengths and the measured
pose as extras, and the simulation's true pose as ``true_position``, ``true_quat``),
``write(torques)`` holds the torques for one control period of physics, and
``write(None)`` engages the winch brakes (:class:`WinchBrakes`), the robot's own safety
behaviour when no valid command comes. The ``cable_sim_node`` uses the same brakes.
"""
from __future__ import annotations

import numpy as np

from ...hardware import HardwareState
from .sim import CdprSim, CdprTruth

__all__ = ["WinchBrakes", "SimulatedCdpr"]


class WinchBrakes:
    """Locked winch brakes: each motor angle is locked where it was when the commands stopped,
    holding the last torque that carried the load (a stiff PD about the locked angle).

    Args:
        sim: the simulation whose winches brake.
        gains: (N m/rad, N m s/rad) of the brake's PD.
    """

    def __init__(self, sim: CdprSim, gains: tuple[float, float] = (5.0, 0.05)):
        self.sim, self.gains = sim, gains
        self.q = None       # locked motor angles (None: released)
        self.u = None       # torque held by the brakes

    def release(self) -> None:
        """A command drives the winches again: the next braking locks anew."""
        self.q = None

    def torque(self, last_command: np.ndarray | None) -> np.ndarray:
        """Brake torques (n,) N m now; locks on the first call after :meth:`release`, holding
        ``last_command`` (or, without one, the torques of the cables' present tensions)."""
        ms = self.sim.measure()
        if self.q is None:
            self.q = ms["motor_angle"].copy()
            c = self.sim.desc.cdpr
            self.u = (np.array(last_command, float) if last_command is not None
                      else (c.drum_radius / c.gear_ratio) * self.sim.truth_state()["tension"])
        kp, kd = self.gains
        return self.u + kp * (self.q - ms["motor_angle"]) - kd * ms["motor_velocity"]


class SimulatedCdpr:
    """The CDPR simulator as hardware of a control loop at ``rate`` Hz.

    Args:
        desc: plant description with a cdpr section.
        truth: the simulated robot (:class:`~cablelab.plants.cdpr.sim.CdprTruth`); its
            ``timestep`` must divide the period.
        rate: control rate, Hz: each ``write`` runs ``1 / (rate * timestep)`` physics steps.
        position: start position of the platform (3,), m.
        settle: s the robot hangs on its locked brakes in :meth:`start` before time 0 (so the
            first reading already carries the load, as the simulator node starts).
    """

    def __init__(self, desc, truth: CdprTruth, rate: float, position, settle: float = 0.5):
        self.sim = CdprSim(desc, truth, np.asarray(position, float))
        self.n = self.sim.n
        self.joint_names = tuple(f"winch_{i}" for i in range(1, self.n + 1))
        self.nstep = max(1, int(round(1.0 / (rate * self.sim.truth.timestep))))
        self.brakes = WinchBrakes(self.sim)
        self.settle = float(settle)
        self.command = None         # last valid command, N m
        self.braked = 0             # periods run on the brakes (write(None))

    def start(self) -> None:
        for _ in range(int(round(self.settle / self.sim.truth.timestep))):
            self.sim.step(self.brakes.torque(None), 1)
        self.sim.data.time = 0.0
        self.brakes.release()

    def read(self) -> HardwareState:
        ms = self.sim.measure()
        tp, tq = self.sim.truth_pose()
        return HardwareState(self.sim.time, ms["motor_angle"], ms["motor_velocity"], ms["motor_torque"],
                             {"tension": ms["tension"], "cable_length": ms["cable_length"],
                              "position": ms["position"], "quat": ms["quat"],
                              "true_position": tp, "true_quat": tq})

    def write(self, command: np.ndarray | None) -> None:
        if command is None:
            for _ in range(self.nstep):          # brakes act continuously: every physics step
                self.sim.step(self.brakes.torque(self.command), 1)
            self.braked += 1
            return
        self.brakes.release()
        self.command = command
        self.sim.step(command, self.nstep)

    def stop(self) -> None:
        """Nothing to release (a driver would engage the brakes here)."""
