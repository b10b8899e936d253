"""Print the measured numbers of the suspended acceptance tests A2-A5 and A10 (spec
000_suspended.md sec. 8) that src/cablelab/cablelab/plants/suspended/README.md quotes.

    nice -n 10 ./run python bench/suspended_acceptance.py
"""
from __future__ import annotations

import sys
from pathlib import Path

import mujoco
import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "test" / "plants" / "suspended"))

from cablelab.plants.suspended.mjcf import build_truth, build_virtual  # noqa: E402
from cablelab.plants.suspended.params import parameter_set  # noqa: E402
from cablelab.plants.suspended.reference import planar_reference  # noqa: E402
from cablelab.plants.suspended.sim import (initial_state, simulate, simulate_paper_levelling,  # noqa: E402
                                           truth_start)
from cablelab.plants.suspended.swing import yaw_from_quat  # noqa: E402
from test_suspended_model import _licas_y_swing, period  # noqa: E402
from test_suspended_swing_control import _decay  # noqa: E402


def main() -> None:
    for lv in ("tendon", "paper"):
        r, tilt = _licas_y_swing(lv)
        print(f"A2 {lv}: period {period(r.t, r.pos[:, 1]):.4f} s, max |y| 18-20 s "
              f"{np.abs(r.pos[r.t > 18, 1]).max():.4f} m, max tilt {tilt.max():.3g} rad")
    p = parameter_set("cranebot")
    m = build_virtual(p)
    r = simulate(m, initial_state(m, {"J9": 0.05}), 20.0)[0]
    print(f"A3 CRANEbot x period {period(r.t, r.pos[:, 0]):.4f} s")
    r = simulate(m, initial_state(m, {"J7": 0.2}), 20.0)[0]
    print(f"A3 CRANEbot yaw period {period(r.t, np.unwrap(yaw_from_quat(r.quat))):.4f} s")
    m5 = build_virtual(p.replace(kp10=0.041))
    r = simulate(m5, initial_state(m5, {"J7": 0.2}), 40.0)[0]
    y = np.abs(np.unwrap(yaw_from_quat(r.quat))[r.t > 36])
    print(f"A3 k_p10 = 0.041: |yaw| over 36-40 s {y.min():.3f}-{y.max():.3f} rad")
    pl = parameter_set("licas")
    mt = build_truth(pl)
    r = simulate(mt, truth_start(mt, pl, swing_x=0.1987), 20.0)[0]
    d = mujoco.MjData(mt)
    lens = []
    for q in r.qpos[100::50]:
        d.qpos[:] = q
        mujoco.mj_kinematics(mt, d)
        mujoco.mj_tendon(mt, d)
        lens.append(d.ten_length.copy())
    print(f"A4 truth y period {period(r.t, r.pos[:, 1]):.4f} s (theory "
          f"{2 * np.pi * np.sqrt(pl.L / 9.81) * (1 + 0.1987 ** 2 / 16):.4f} s), tilt "
          f"{2 * np.abs(r.quat[:, 1:3]).max():.3g} rad, cables {np.min(lens):.5f}-{np.max(lens):.5f} m")
    r = simulate(mt, truth_start(mt, pl, yaw=0.3), 10.0)[0]
    print(f"A4 truth yaw period {period(r.t, np.unwrap(yaw_from_quat(r.quat))):.4f} s")
    for lv in ("tendon", "paper"):
        m = build_virtual(pl, levelling=lv, lock=("J7", "J9", "J10", "J12"), freeze_arms=True, integrator="RK4")
        x0 = initial_state(m, {"J8": 0.1987, "J11": -0.1987})
        r = simulate(m, x0, 10.0)[0] if lv == "tendon" else simulate_paper_levelling(m, pl, x0, 10.0)
        ref = planar_reference(pl, 0.1987, -0.1987, r.t, levelling=lv)
        print(f"A5 {lv}: max |q8 MuJoCo RK4 - solve_ivp| over 10 s {np.abs(r.qpos[:, 0] - ref[:, 0]).max():.3g} rad")
    t0, _ = _decay(0.0)
    t1, tau = _decay(0.3)
    print(f"A10 1/e time: k_s = 0 {t0} s (30 s record), k_s = 0.3 {t1:.2f} s, max |tau| {tau:.2f} N m")


if __name__ == "__main__":
    main()
