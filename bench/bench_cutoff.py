"""Does the automatic cut-off for slow recordings (``conditioning.motion_cutoff``) leave the
diagnosis benchmark's axis cases alone? Prints, per sample rate, how many of the cases keep the
default fs / 10 and the cut-offs of those that do not.

    nice -n 10 ./run python bench/bench_cutoff.py --cases 60
"""
from __future__ import annotations

import argparse
import os
import sys
from collections import defaultdict

import numpy as np

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from diagnosis_cases import draw_case, simulate  # noqa: E402


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--cases", type=int, default=60)
    ap.add_argument("--seed", type=int, default=1000)
    a = ap.parse_args()
    from cablelab.conditioning import motion_cutoff

    kept, moved = defaultdict(int), defaultdict(list)
    for seed in range(a.seed, a.seed + a.cases):
        rec = simulate(draw_case(seed))
        fs = round(1.0 / float(np.median(np.diff(rec["t"]))), 3)
        cut, warn = motion_cutoff(np.asarray(rec["q"], float), fs, fs / 10.0)
        if cut == fs / 10.0 and not warn:
            kept[fs] += 1
        else:
            moved[fs].append((seed, cut))
    print("| fs (Hz) | cases | default fs/10 kept | changed (seed: cut-off Hz) |")
    print("|---|---|---|---|")
    for fs in sorted(set(kept) | set(moved)):
        ch = ", ".join(f"{s}: {c:.3g}" for s, c in moved[fs]) or "none"
        print(f"| {fs:g} | {kept[fs] + len(moved[fs])} | {kept[fs]} | {ch} |")
    return 0


if __name__ == "__main__":
    sys.exit(main())
