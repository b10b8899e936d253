"""Regenerate the crane reference bags (``./run python bags/crane_make.py``).

* ``crane_control``: the crane of ``plants/crane/data/crane.yaml`` exactly as described (nothing missing);
* ``crane_tilt``: the same crane on a base tilted by 3.3 deg (002 sec. 6.5: -0.2 N m on the slew
  joint at rest at beta = 0.5 rad), 1 mm motion-capture noise and 1 % dropouts;
* ``crane_no_counterbalance``: the crane with its counterbalance, described without it (002 sec. 6.4).

Each is 30 s at 50 Hz of the multi-sine excitation under PD + gravity/acceleration feedforward.
"""
from __future__ import annotations

import os
import sys
from functools import partial

import numpy as np

from cablelab.description import load_description
from cablelab.plants.crane.model import CraneParams
from cablelab.plants.crane.sim import CraneTruth, reference_trajectory, simulate, write_bag

HERE = os.path.dirname(os.path.abspath(__file__))
DESC_FILE = os.path.join(os.path.dirname(__import__("cablelab").__file__), "data", "crane.yaml")
DURATION = 30.0
DECIMATE = 20  # 50 Hz recording (MuJoCo at 1 kHz)


def tilt_for_offset(params: CraneParams, offset=-0.2, beta=0.5) -> float:
    """Base rotation about x (rad) that loads the slew joint with ``offset`` N m at rest at alpha = 0."""
    return -float(np.arcsin(-offset / np.cos(beta) / params.first_moment / params.gravity))


def main() -> int:
    text = open(DESC_FILE, encoding="utf-8").read()
    desc = load_description(text)
    p = CraneParams.from_description(desc)
    no_cb = text.replace("  counterbalance: {mass: 2.0, distance: 0.3}\n", "")
    cases = {
        "crane_control": (CraneTruth(params=p), text, 2),
        "crane_tilt": (CraneTruth(params=p, base_tilt=(tilt_for_offset(p), 0.0), mocap_noise=0.001,
                                  mocap_dropout=0.01), text, 0),
        "crane_no_counterbalance": (CraneTruth(params=p), no_cb, 1),
    }
    for name, (truth, yaml_text, seed) in cases.items():
        res = simulate(truth, DURATION, decimate=DECIMATE, seed=seed,
                       reference=partial(reference_trajectory, seed=seed))
        write_bag(os.path.join(HERE, name), res, yaml_text, overwrite=True)
        print(f"wrote bags/{name} ({res.t.size} samples)", file=sys.stderr)
    return 0


if __name__ == "__main__":
    sys.exit(main())
