"""The ROS-free simulator: :class:`PendulumSim` steps the MuJoCo model (:mod:`.mjcf`) under a
held torque; :func:`simulate` runs it under a torque law and :func:`write_bag` records a run as a
contract bag (what the simulator node publishes), for tests and offline data."""
from __future__ import annotations

import mujoco
import numpy as np

from . import topics
from .mjcf import JOINT, build_mjcf


class PendulumSim:
    """The plant of description section ``section`` with hinge ``damping`` (N m s/rad)."""

    def __init__(self, section, damping: float = 0.0, timestep: float = 0.001):
        self.model = mujoco.MjModel.from_xml_string(build_mjcf(section, damping, timestep))
        self.data = mujoco.MjData(self.model)

    @property
    def t(self) -> float:
        return float(self.data.time)

    def state(self) -> tuple[float, float, float]:
        """(t s, q rad, qd rad/s)."""
        return self.t, float(self.data.qpos[0]), float(self.data.qvel[0])

    def advance(self, tau: float, dt: float) -> None:
        """Hold torque ``tau`` (N m) for ``dt`` s."""
        self.data.ctrl[0] = tau
        for _ in range(max(1, int(round(dt / self.model.opt.timestep)))):
            mujoco.mj_step(self.model, self.data)


def simulate(section, duration: float, rate: float, torque, damping: float = 0.0) -> dict:
    """Arrays ``t, q, qd, tau`` sampled at ``rate`` Hz for ``duration`` s under ``torque(t)``,
    held over each period; the torque reported with a sample is the one held over the period
    ending there (as the simulator node publishes it; 0 with the first sample)."""
    sim = PendulumSim(section, damping)
    n = int(round(duration * rate)) + 1
    out = np.empty((n, 4))
    out[0] = (*sim.state(), 0.0)
    for i in range(1, n):
        tau = float(torque(sim.t))
        sim.advance(tau, 1.0 / rate)
        out[i] = (*sim.state(), tau)
    return dict(zip(("t", "q", "qd", "tau"), out.T))


def write_bag(path, run: dict, description_yaml: str, *, torque_noise: float = 0.0, seed: int = 0,
              overwrite: bool = False) -> None:
    """Write a :func:`simulate` run as a bag: the joint states (measured torque with white noise
    of ``torque_noise`` N m), /clock and /plant_description."""
    from cablelab.bags import BagWriter

    noise = np.random.default_rng(seed).normal(0.0, torque_noise, run["t"].size) if torque_noise else 0.0
    with BagWriter(path, overwrite=overwrite) as w:
        w.write_description(description_yaml)
        w.write_clock(run["t"])
        w.write_joint_states(topics.JOINT_STATES, run["t"], [JOINT], position=run["q"][:, None],
                             velocity=run["qd"][:, None], effort=(run["tau"] + noise)[:, None])
