"""Long profile of the fuzz suites: the same properties as test/core/test_fuzz_cli.py and
test/core/test_fuzz_nodes.py with many more (random, not derandomised) examples.

    ./run python bench/fuzz_long.py [--examples N] [--seed S]

Prints the pytest summary (one line per property); exit status is pytest's.
"""
from __future__ import annotations

import argparse
import os
import subprocess
import sys
from pathlib import Path

HERE = Path(__file__).resolve().parent.parent


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--examples", type=int, default=300, help="hypothesis examples per property")
    ap.add_argument("--seed", type=int, default=None, help="hypothesis seed (default random)")
    args = ap.parse_args(argv)
    env = dict(os.environ, CABLELAB_FUZZ_EXAMPLES=str(args.examples), CABLELAB_FUZZ_RANDOM="1")
    cmd = [sys.executable, "-m", "pytest", "-q", "-p", "no:cacheprovider", "-rA", "--durations=0",
           str(HERE / "test" / "core" / "test_fuzz_cli.py"), str(HERE / "test" / "core" / "test_fuzz_nodes.py")]
    if args.seed is not None:
        cmd.append(f"--hypothesis-seed={args.seed}")
    return subprocess.call(cmd, env=env, cwd=HERE)


if __name__ == "__main__":
    sys.exit(main())
