"""Speed of experiment design: ``cablelab excite`` for a confounded pair, 60 s of reference.

    ./run python bench/bench_excite.py

Prints wall and CPU seconds of :func:`cablelab.excite.design` (target: < 30 s wall for a 60 s
excitation) and the condition numbers before (crane: a recording that holds the luff still; CDPR:
a slow sway at one pose; mjcf arm3: the base turning alone) and after.
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
    cases = [("crane", dsc, params, ds) for params in (["OF[luff]", "m_c"], ["OF[hoist]", "m"])]
    cases += [_cdpr_case(), _mjcf_case()]
    print("| plant | params | duration | wall s | CPU s | condition before | after |")
    print("| --- | --- | --- | --- | --- | --- | --- |")
    for plant, dsc, params, before in cases:
        w0, c0 = time.monotonic(), time.process_time()
        r = design(plant, dsc, params, duration=60.0, before_ds=before)
        shown = ",".join(params) if len(params) < 4 else f"{params[0]}..{params[-1]} ({len(params)})"
        print(f"| {plant} | {shown} | 60 s | {time.monotonic() - w0:.1f} | "
              f"{time.process_time() - c0:.1f} | {r.condition_before:.3g} | {r.condition_after:.3g} |")
    return 0


def _cdpr_case():
    """CDPR: dynamometer offsets vs mass and centre of mass, before = a slow 5 cm sway at one
    pose (the exact motion's dataset, :func:`cablelab.plants.cdpr.excite.motion_dataset`)."""
    from cablelab.excite import get_exciter
    from cablelab.plants.cdpr.sim import default_description

    desc = default_description()
    t = np.arange(0.0, 30.0, 0.05)
    w = 2 * np.pi / 30.0
    q, qd, qdd = np.zeros((len(t), 3)), np.zeros((len(t), 3)), np.zeros((len(t), 3))
    q[:, 2] = 0.9
    q[:, 0], qd[:, 0], qdd[:, 0] = 0.05 * (1 - np.cos(w * t)), 0.05 * w * np.sin(w * t), 0.05 * w * w * np.cos(w * t)
    before = get_exciter("cdpr").motion_dataset(t, q, qd, qdd, desc)
    return "cdpr", desc, [f"b[winch_{i}]" for i in range(1, 9)] + ["m", "mx", "my"], before


def _mjcf_case():
    """mjcf arm3 example: payload mass vs shoulder torque offset, before = the base turning alone."""
    import cablelab.plants.mjcf as mjcf_pkg
    from cablelab.description import load_description
    from cablelab.excite import get_exciter
    from cablelab.plants.mjcf.sim import description_yaml

    xml = (Path(mjcf_pkg.__file__).parent / "examples" / "arm3.xml").read_text()
    desc = load_description(description_yaml(xml, payload_body="tool"))
    t = np.arange(0.0, 30.0, 0.05)
    q, qd, qdd = np.zeros((len(t), 3)), np.zeros((len(t), 3)), np.zeros((len(t), 3))
    q[:, 0], q[:, 1], q[:, 2] = np.sin(0.5 * t), 0.3, -0.5
    qd[:, 0], qdd[:, 0] = 0.5 * np.cos(0.5 * t), -0.25 * np.sin(0.5 * t)
    return "mjcf", desc, ["m", "OF[shoulder]"], get_exciter("mjcf").motion_dataset(t, q, qd, qdd, desc)


if __name__ == "__main__":
    sys.exit(main())
