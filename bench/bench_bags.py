"""Bag write and read throughput for 1 kHz sensor_msgs/JointState streams.

Writes --seconds s of a 1 kHz JointState topic with --joints joints (position, velocity, effort)
into a rosbag2 MCAP bag with cablelab's BagWriter, reads it back into numpy with open_bag(...)
.joint_state(...), and for reference reads it with rosbags' generic per-message deserialiser.
Targets: read >= 200 000 msg/s, write >= 100 000 msg/s.
"""
from __future__ import annotations

import shutil
import sys
import tempfile
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))
from harness import Bench  # noqa: E402

from cablelab.bags import BagWriter, open_bag  # noqa: E402
from cablelab.cdr import typestore  # noqa: E402


def main(argv=None) -> int:
    bench = Bench("bags", __doc__)
    bench.parser.add_argument("--seconds", type=float, default=60.0, help="s of 1 kHz data (60)")
    bench.parser.add_argument("--joints", type=int, default=8, help="joints per message (8)")
    bench.parser.add_argument("--repeat", type=int, default=3)
    args = bench.parse(argv)
    n = int(args.seconds * 1000)
    names = [f"winch_{i + 1}" for i in range(args.joints)]
    rng = np.random.default_rng(0)
    t = np.arange(n) * 1e-3
    q, qd, eff = (rng.normal(size=(n, args.joints)) for _ in range(3))
    tmp = Path(tempfile.mkdtemp(prefix="bench-bags-"))
    try:
        path = tmp / "bag"

        def write():
            with BagWriter(path, overwrite=True) as w:
                w.write_joint_states("/cdpr/joint_states", t, names, q, qd, eff)

        bench.log(f"writing {n} messages ({args.joints} joints), best of {args.repeat}")
        tw = bench.time(write, args.repeat)
        size = (path / "bag.mcap").stat().st_size
        bench.row(case="write JointState (BagWriter)", messages=n, seconds=tw, rate=n / tw,
                  unit="msg/s", target=">= 100 000", MB=size / 1e6)

        result = {}

        def read():
            result["js"] = open_bag(path).joint_state("/cdpr/joint_states")

        tr = bench.time(read, args.repeat)
        assert np.array_equal(result["js"].position, q), "read back differs"
        bench.row(case="read JointState -> numpy (open_bag)", messages=n, seconds=tr, rate=n / tr,
                  unit="msg/s", target=">= 200 000", MB=size / 1e6)

        bag = open_bag(path)

        def decode_only():
            bag.clear_cache()
            bag.joint_state("/cdpr/joint_states")

        td = bench.time(decode_only, args.repeat)
        bench.row(case="  of which CDR decode (cablelab.cdr)", messages=n, seconds=td, rate=n / td,
                  unit="msg/s", target="", MB=size / 1e6)

        ts = typestore()
        raws = bag.raw("/cdpr/joint_states")[1]
        m = min(n, 20000)

        def reference():
            pos = np.array([ts.deserialize_cdr(r, "sensor_msgs/msg/JointState").position for r in raws[:m]])
            return pos

        tref = bench.time(reference, 1)
        bench.row(case="reference: rosbags deserialize_cdr per msg", messages=m, seconds=tref,
                  rate=m / tref, unit="msg/s", target="", MB=float("nan"))
    finally:
        shutil.rmtree(tmp, ignore_errors=True)
    bench.done()
    return 0


if __name__ == "__main__":
    sys.exit(main())
