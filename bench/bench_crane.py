"""Crane benchmarks: stacked regressor build + solve (002 sec. 5.2: 25 000 equations... here
25 000 samples = 125 000 equations), offline swing-angle estimation, simulation, diagnosis.

Targets: stacked regressor for 25 000 samples built and solved < 0.1 s; swing-angle
estimation >= 1 000 000 samples/s offline.
"""
from __future__ import annotations

import os
import sys
from functools import partial

import numpy as np

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from harness import Bench  # noqa: E402

from cablelab.plants.crane.identify import FIX_002, identify_groups, stacked_regressor  # noqa: E402
from cablelab.plants.crane.kinematics import boom_tip, payload_position  # noqa: E402
from cablelab.plants.crane.model import PARAM_GROUPS, CraneParams  # noqa: E402
from cablelab.plants.crane.swing import estimate_swing  # noqa: E402
from cablelab.plants.crane.sim import CraneTruth, reference_trajectory, simulate, truth_accelerations  # noqa: E402


def main() -> int:
    bench = Bench("crane", __doc__)
    bench.parser.add_argument("--samples", type=int, default=25000)
    bench.parser.add_argument("--swing-samples", type=int, default=1_000_000)
    args = bench.parse()
    p = CraneParams()
    truth = CraneTruth(params=p)

    # ---- simulation (closed loop, 1 kHz MuJoCo, recorded at 100 Hz)
    dur = args.samples / 100.0
    bench.log(f"[crane] simulating {dur:.0f} s ...")
    res = None

    def sim():
        nonlocal res
        res = simulate(truth, dur, decimate=10, reference=partial(reference_trajectory, seed=3))
    t_sim = bench.time(sim, repeat=1)
    bench.row(case="closed-loop simulation", samples=res.t.size, seconds=t_sim,
              rate=dur / t_sim, unit="x real time", target="-")
    qdd = truth_accelerations(truth, res)
    q, qd, tau = res.q, res.qd, res.effort
    n = q.shape[0]

    # ---- stacked regressor (002 sec. 5.2) built and solved
    pi = p.groups()
    fixed = {k: pi[PARAM_GROUPS.index(k)] for k in FIX_002}
    t_build = bench.time(lambda: stacked_regressor(q, qd, qdd, tau), repeat=5)
    bench.row(case="stacked regressor Y_tot (5N x 9)", samples=n, seconds=t_build,
              rate=n / t_build, unit="samples/s", target="-")
    fit = None

    def solve():
        nonlocal fit
        fit = identify_groups(q, qd, qdd, tau, fixed=fixed)
    t_solve = bench.time(solve, repeat=5)
    err = np.max(np.abs(fit.pi - pi) / pi)
    bench.row(case="build + rank + bounded LS (002 fixing)", samples=n, seconds=t_solve,
              rate=n / t_solve, unit="samples/s", target="< 0.1 s",
              note=f"rank {fit.fit.rank}, max rel. error {err:.1e}")

    # ---- offline swing estimation
    m = args.swing_samples
    t = np.arange(m) * 0.01
    a = np.angle(np.exp(1j * (2.0 * np.sin(0.05 * t) + 2.5)))  # wrapping encoder
    b = 0.5 + 0.1 * np.sin(0.2 * t)
    d = 0.8 + 0.1 * np.sin(0.1 * t)
    tip = boom_tip(a, b, 1.0)
    pay = payload_position(a, b, d, 0.2 * np.sin(2 * t), 0.1 * np.cos(2.3 * t), 1.0)
    pay[::500] = np.nan  # dropouts
    t_sw = bench.time(lambda: estimate_swing(t, tip, pay, t, a), repeat=3)
    bench.row(case="swing angles + rates (exact, with dropouts, wraps)", samples=m, seconds=t_sw,
              rate=m / t_sw, unit="samples/s", target=">= 1000000")

    # ---- workbench diagnosis on a 60 s run
    from cablelab.description import load_description
    from cablelab.diagnose import rank_candidates
    from cablelab.model import Model
    from cablelab.plants.crane import dataset as CD
    from cablelab.plants.crane import plant as C

    desc = load_description(os.path.join(os.path.dirname(C.__file__), "data", "crane.yaml"))
    r = simulate(CraneTruth(params=p, base_tilt=(-0.058, 0.0)), 60.0, decimate=10)
    ds = CD.dataset_from_arrays(r.t, r.q[:, :3], r.effort, r.t, r.tip, r.payload, desc)
    t_diag = bench.time(lambda: rank_candidates(Model("crane", C.baseline(desc), {"l_c": 0.3}), ds,
                                                C.candidates(desc)), repeat=1)
    bench.row(case="diagnose (5 candidates x 5 folds)", samples=ds.n, seconds=t_diag,
              rate=ds.n / t_diag, unit="samples/s", target="-")
    bench.done()
    return 0


if __name__ == "__main__":
    sys.exit(main())
