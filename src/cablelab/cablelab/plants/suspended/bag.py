"""Write simulated suspended runs as contract bags (CONTRACT sec. 2 ``/suspended/*`` topics,
``/clock``, ``/plant_description``)."""
from __future__ import annotations

import numpy as np

from ...rotations import wxyz_to_xyzw
from . import topics
from .sim import Run
from .swing import swing_from_pose

__all__ = ["write_run", "description_yaml"]


def description_yaml(variant: str = "licas", name: str = "sim", **section) -> str:
    """Description text for ``plant: suspended`` with the given section keys."""
    import yaml

    return yaml.safe_dump({"plant": "suspended", "name": name,
                           "suspended": {"variant": variant, **section}}, sort_keys=False)


def write_run(path, run: Run, S, description: str, *, every: int = 10, pos_noise: float = 0.0,
              seed: int = 0, overwrite: bool = True, suspension=None) -> None:
    """Write one run: platform pose at 1/(every dt) Hz (optional Gaussian noise, m) and the
    ground-truth swing. ``suspension``: (N, 3) measured positions of S at the run's instants,
    written (same rate and noise) as ``/suspended/suspension_pose`` (omitted when None)."""
    from ...bags import BagWriter

    rng = np.random.default_rng(seed)
    t = run.t[::every]
    pos = run.pos[::every] + rng.normal(0, pos_noise, run.pos[::every].shape) if pos_noise else run.pos[::every]
    quat = run.quat[::every]
    S_t = np.asarray(S, float) if suspension is None else np.asarray(suspension, float)[::every]
    sw = swing_from_pose(run.pos[::every], quat, S_t, t=t)
    with BagWriter(path, overwrite=overwrite) as w:
        w.write_description(description)
        w.write_clock(t)
        w.write_poses(topics.PLATFORM_POSE, t, pos, wxyz_to_xyzw(quat))
        if suspension is not None:
            s_meas = S_t + rng.normal(0, pos_noise, S_t.shape) if pos_noise else S_t
            w.write_poses(topics.SUSPENSION_POSE, t, s_meas, np.tile([0.0, 0.0, 0.0, 1.0], (len(t), 1)))
        names = ("swing_x", "swing_y", "yaw", "r_x", "r_y")
        w.write_joint_states(topics.GROUND_TRUTH_SWING, t, names,
                             position=np.stack([sw[k] for k in names], 1))
