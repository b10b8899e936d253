"""Speed of experiment design: ``cablelab excite`` for a confounded pair, 60 s of reference.

    ./run python bench/bench_excite.py

Prints wall and CPU seconds of :func:`cablelab.excite.design` (target: < 30 s wall for a 60 s
excitation) and the condition numbers before (a recording that holds the luff still) and after.
"""
from __future__ import annotations

import sys
import tempfile
import time
from pathlib import Path

import numpy as np

import cablelab.plants.crane as crane_pkg
from cablelab.excite import design
from cablelab.plants.crane.sim import CraneTruth, simulate, write_bag
from cablelab.workbench import load


def _slew_only(t):
    q = np.zeros((len(t), 3))
    qd, qdd = np.zeros_like(q), np.zeros_like(q)
    w = 2 * np.pi * 0.1
    q[:, 0], qd[:, 0], qdd[:, 0] = 0.3 * np.sin(w * t), 0.3 * w * np.cos(w * t), -0.3 * w * w * np.sin(w * t)
    q[:, 1], q[:, 2] = 0.5, 0.6
    return q, qd, qdd


def main() -> int:
    desc = (Path(crane_pkg.__file__).parent / "data" / "crane.yaml").read_text()
    with tempfile.TemporaryDirectory() as d:
        write_bag(Path(d) / "b", simulate(CraneTruth(torque_offset=(0.0, 0.5, 0.0),
                                                     effort_noise=(0.05, 0.05, 0.1)), 30.0,
                                          reference=_slew_only), desc)
        _, dsc, ds = load(Path(d) / "b")
    print("| plant | params | duration | wall s | CPU s | condition before | after |")
    print("| --- | --- | --- | --- | --- | --- | --- |")
    for params in (["OF[luff]", "m_c"], ["OF[hoist]", "m"]):
        w0, c0 = time.monotonic(), time.process_time()
        r = design("crane", dsc, params, duration=60.0, before_ds=ds)
        print(f"| crane | {','.join(params)} | 60 s | {time.monotonic() - w0:.1f} | "
              f"{time.process_time() - c0:.1f} | {r.condition_before:.3g} | {r.condition_after:.3g} |")
    return 0


if __name__ == "__main__":
    sys.exit(main())
