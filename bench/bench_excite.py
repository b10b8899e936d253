"""Speed of experiment design: ``cablelab excite`` for a confounded pair, 60 s of reference.

    ./run python bench/bench_excite.py

Prints wall and CPU seconds of :func:`cablelab.excite.design` (target: < 30 s wall for a 60 s
excitation) and the condition numbers of the pair before (in a recording that confounds it) and
after. One row per entry of :data:`CASES`: (plant, parameters, a function returning the
description and the dataset of the confounding recording). The leg's design time includes
building its steady-hop library (once per process; every leg row here starts without it). The
leg has more rows (:func:`leg_rows`): building the library alone; the design with the library
built, on the levels' triangular factors (what it evaluates) and on the levels' rows themselves
(:func:`cablelab.plants.leg.excite.motion_rows`, what it evaluated before); and
``cablelab excite BAG --params F0,m --duration 60`` as a user runs it (a process: imports, the
bag, the library, the design, the reference written).
"""
from __future__ import annotations

import json
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

from cablelab.excite import design
from cablelab.workbench import load


def _crane_slew_only():
    """The crane slewing alone, luff and hoist held (a hoist offset hidden)."""
    import cablelab.plants.crane as crane_pkg
    from cablelab.plants.crane.reference import slew_only
    from cablelab.plants.crane.sim import CraneTruth, simulate, write_bag

    desc = (Path(crane_pkg.__file__).parent / "data" / "crane.yaml").read_text()
    with tempfile.TemporaryDirectory() as d:
        write_bag(Path(d) / "b", simulate(CraneTruth(torque_offset=(0.0, 0.5, 0.0),
                                                     effort_noise=(0.05, 0.05, 0.1)), 30.0,
                                          reference=slew_only()), desc)
        _, dsc, ds = load(Path(d) / "b")
    return dsc, ds


def _axis_one_way():
    """The EMPS-sized axis creeping one way only (Coulomb friction and an offset hidden)."""
    import cablelab.plants.axis as axis_pkg
    from cablelab.bags import BagWriter
    from cablelab.description import load_description
    from cablelab.plants.axis.sim import AxisTruth
    from cablelab.plants.axis.topics import JOINT_STATES
    from cablelab.plants.axis.truth import simulate_axis

    text = (Path(axis_pkg.__file__).parent / "data" / "emps.yaml").read_text()
    run = simulate_axis(load_description(text), AxisTruth(inertia=95.0, viscous=200.0, coulomb=20.0, offset=-5.0),
                        duration=20.0, noise_effort=1.0,
                        reference_fn=lambda t: -0.2 + 0.02 * t + 0.004 * np.sin(np.pi * t))
    with tempfile.TemporaryDirectory() as d:
        with BagWriter(Path(d) / "b") as w:
            w.write_description(text)
            w.write_joint_states(JOINT_STATES, run.t, ["joint"], position=run.q[:, None],
                                 effort=run.effort[:, None])
        _, dsc, ds = load(Path(d) / "b")
    return dsc, ds


def _leg_low_hops_bag(path: Path) -> Path:
    """The leg hopping 4 mm under the apex controller (a 2.7 N spring preload hidden), 30 s."""
    import cablelab.plants.leg as leg_pkg
    from cablelab.plants.leg.excite import closed_loop
    from cablelab.plants.leg.hybrid import LegParams
    from cablelab.plants.leg.sim import write_bag

    text = (Path(leg_pkg.__file__).parent / "data" / "leg.yaml").read_text()
    nominal = LegParams()
    write_bag(path, closed_loop(nominal.replace(F0=2.7), nominal.z_td + 0.004, 30.0,
                                controller_params=nominal), text)
    return path


def _leg_low_hops():
    """The leg hopping 4 mm under the apex controller (a 2.7 N spring preload hidden)."""
    with tempfile.TemporaryDirectory() as d:
        _, dsc, ds = load(_leg_low_hops_bag(Path(d) / "b"))
    return dsc, ds


def _cdpr_sway():
    """The CDPR swaying 5 cm slowly at one pose (the eight dynamometer offsets confounded with
    the mass and centre of mass): the exact motion's dataset (``plants/cdpr/excite.py``)."""
    from cablelab.excite import get_exciter
    from cablelab.plants.cdpr.sim import default_description

    desc = default_description()
    t = np.arange(0.0, 30.0, 0.05)
    w = 2 * np.pi / 30.0
    q, qd, qdd = np.zeros((len(t), 3)), np.zeros((len(t), 3)), np.zeros((len(t), 3))
    q[:, 2] = 0.9
    q[:, 0], qd[:, 0], qdd[:, 0] = 0.05 * (1 - np.cos(w * t)), 0.05 * w * np.sin(w * t), 0.05 * w * w * np.cos(w * t)
    return desc, get_exciter("cdpr").motion_dataset(t, q, qd, qdd, desc)


def _arm3_base_only():
    """The mjcf arm3 example turning its base alone (payload mass confounded with the shoulder's
    torque offset): the exact motion's dataset (``plants/mjcf/excite.py``)."""
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
    return desc, get_exciter("mjcf").motion_dataset(t, q, qd, qdd, desc)


#: (plant, parameters, recording that confounds them)
CASES = [
    ("crane", ["OF[luff]", "m_c"], _crane_slew_only),
    ("crane", ["OF[hoist]", "m"], _crane_slew_only),
    ("axis", ["Fc", "OF"], _axis_one_way),
    ("leg", ["F0", "m"], _leg_low_hops),
    ("cdpr", [f"b[winch_{i}]" for i in range(1, 9)] + ["m", "mx", "my"], _cdpr_sway),
    ("mjcf", ["m", "OF[shoulder]"], _arm3_base_only),
]


def _row(plant, shown, wall, cpu, before, after):
    print(f"| {plant} | {shown} | 60 s | {wall:.1f} | {cpu:.1f} | {before:.3g} | {after:.3g} |", flush=True)


def _forget_leg_library():
    from cablelab.plants.leg import excite as leg_excite

    leg_excite._LIBRARY.clear()
    leg_excite._FACTORS.clear()


def leg_rows(dsc, ds) -> None:
    """The leg's design on the levels' rows (as it was), and ``cablelab excite`` in a process."""
    import dataclasses
    import resource
    import subprocess

    from cablelab.excite import get_exciter, register_exciter
    from cablelab.plants.leg.excite import motion_rows

    from cablelab.plants.leg.excite import hop_library

    ex = get_exciter("leg")
    _forget_leg_library()
    w0, c0 = time.monotonic(), time.process_time()
    hop_library(dsc)
    print(f"| leg: the steady-hop library alone | | | {time.monotonic() - w0:.1f} | "
          f"{time.process_time() - c0:.1f} | | |", flush=True)
    for label, variant in (("levels' factors", ex), ("levels' rows", dataclasses.replace(ex, motion_dataset=motion_rows))):
        register_exciter("leg", variant)
        try:
            w0, c0 = time.monotonic(), time.process_time()
            r = design("leg", dsc, ["F0", "m"], duration=60.0, before_ds=ds)
            _row(f"leg: design on the {label}, library built", "F0,m", time.monotonic() - w0,
                 time.process_time() - c0, r.condition_before, r.condition_after)
        finally:
            register_exciter("leg", ex)
    with tempfile.TemporaryDirectory() as d:
        bag = _leg_low_hops_bag(Path(d) / "low_hops")
        u0 = resource.getrusage(resource.RUSAGE_CHILDREN)
        w0 = time.monotonic()
        out = subprocess.run([sys.executable, "-m", "cablelab.cli", "excite", str(bag), "--params", "F0,m",
                              "--duration", "60", "-o", str(Path(d) / "ref"), "--json"],
                             check=True, capture_output=True, text=True).stdout
        u1 = resource.getrusage(resource.RUSAGE_CHILDREN)
        j = json.loads(out)
        _row("leg: `cablelab excite BAG` (a process)", "F0,m", time.monotonic() - w0,
             (u1.ru_utime + u1.ru_stime) - (u0.ru_utime + u0.ru_stime), j["condition_before"], j["condition_after"])


def main() -> int:
    print("| plant | params | duration | wall s | CPU s | condition before | after |")
    print("| --- | --- | --- | --- | --- | --- | --- |")
    recordings = {}
    for plant, params, recording in CASES:
        if recording not in recordings:
            recordings[recording] = recording()
        dsc, ds = recordings[recording]
        if plant == "leg":
            _forget_leg_library()
        w0, c0 = time.monotonic(), time.process_time()
        r = design(plant, dsc, params, duration=60.0, before_ds=ds)
        shown = ",".join(params) if len(params) < 4 else f"{params[0]}..{params[-1]} ({len(params)})"
        _row(plant, shown, time.monotonic() - w0, time.process_time() - c0, r.condition_before, r.condition_after)
        if plant == "leg":
            leg_rows(dsc, ds)
    return 0


if __name__ == "__main__":
    sys.exit(main())
