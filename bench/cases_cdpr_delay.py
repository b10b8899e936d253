"""CDPR designed-experiment cases with a measurement delay invisible in slow moves
(``bench_diagnosis.py --designed cdpr_delay=N``), generated WITHOUT the fitting code.

The robot, its sensors and the recording are bench/cases_cdpr.py's (own structure matrix and
tension distribution; a delay evaluates the whole chain reference -> wrench -> tensions at
``t - tau`` while the reference topic is not delayed); this module only draws the cases. A case
(:func:`draw_delay_case`): an unknown load (total mass 400-900 kg, centre of mass at the
platform's origin), the described sheave radius known, the dynamometers alone
(``--tensions dynamometer``) reading 10-30 ms late ("delay") or on time ("control", every fourth
seed), and a first recording of 60 s of slow sines (0.015-0.035 Hz per axis about the workspace
centre), where the tensions change so little within tau that the delay is not seen. The
benchmark diagnoses that recording, designs an excitation for :data:`PAIR` (tau linearised: the
change of the fitted residual with tau, the wrench re-formed at the delayed pose) and plays it
through the same generator (``truth["reference"]``).

The dynamometers' noise is drawn at 0.1-0.3 % of the mean cable tension (the other CDPR cases:
0.3-3 %): a 10-30 ms delay changes the wrench by the platform's mass times its jerk times tau,
and the jerk of a motion inside the design's speed and acceleration limits (0.3 m/s, 0.4 m/s^2,
harmonics up to 0.25 Hz) keeps that change near 1 % of the cable tension's noise at the other
cases' levels, below what a held-out error gain can show. ``python bench/cases_cdpr_delay.py``
prints each case's delay visibility (cases_cdpr.delay_visibility) on its first recording.

The draw's 10 ms floor is above what the design says its run shows: ``excite`` reports the
smallest delay a designed run tells from none (``excite.detectable_delay``, at the first
recording's noise), 3.7-9.7 ms over the benchmark's 24 cases at these noise levels, and the
first recordings' own 29-54 ms lie above every drawn delay (docs/benchmarks.md prints both per
case).
"""
from __future__ import annotations

import numpy as np

from cases_cdpr import LIMITS, delay_visibility, draw_case, tabulated, write_bag
from cases_common import PlantCase, draw_slow_sines

#: what the designed run must separate: the delay and the accelerated mass (a delay shifts the
#: wrench of the accelerated platform like a phase lag; on slow sines both are small)
PAIR = ("tau", "m_a")


def draw_delay_case(seed: int, kind: str | None = None) -> PlantCase:
    """A case whose first recording hides a measurement delay ("delay") or nothing ("control",
    default every fourth seed); module doc."""
    rng = np.random.default_rng(seed + 32452843)
    if kind is None:
        kind = "control" if seed % 4 == 3 else "delay"
    case = draw_case(seed, kind="control")
    tr = case.truth
    case.options = {"tensions": "dynamometer"}
    tr["noise_rel"] = 10 ** rng.uniform(-3.0, -2.5, 8)
    tau = float(rng.uniform(10e-3, 30e-3))
    if kind == "delay":
        tr["tau"] = tau
        case.hidden = ("time_delay",)
        case.true_params = {"time_delay": {"tau": tau}}
    else:
        tr["tau"] = 0.0
        case.hidden = ()
        case.true_params = {}
    case.family = f"designed {kind}"
    tr.update(first_s=60.0, designed_s=60.0, pair=PAIR, diagnose_first=True,
              reference=draw_slow_sines(rng, LIMITS))
    return case


#: the generator's interface for bench_diagnosis.py: cases_cdpr's simulator and bag writer
__all__ = ["PAIR", "delay_visibility", "draw_delay_case", "tabulated", "write_bag"]


if __name__ == "__main__":      # ./run python bench/cases_cdpr_delay.py: first recordings' visibility
    print("seed  case              tau_ms  visibility (first recording)")
    for s in range(9000, 9012):
        c = draw_delay_case(s)
        if c.hidden:
            c.truth["duration"] = c.truth["first_s"]
            print(f"{s}  {c.family:16s}  {1e3 * c.truth['tau']:6.1f}  {delay_visibility(c):10.3f}")
