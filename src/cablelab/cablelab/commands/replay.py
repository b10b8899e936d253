"""``cablelab replay BAG [--rate R]``: republish a bag on its original topics (a real ROS 2 node,
see :mod:`cablelab.ros.replayer`), with /clock and the transient-local /plant_description."""
from __future__ import annotations

from .numeric import number
from ._workbench_args import add_recover

HELP = "republish a bag on its original topics with /clock and /plant_description"


def add_arguments(p) -> None:
    p.add_argument("bag", help="rosbag2 directory or its .mcap file")
    p.add_argument("--rate", type=number(gt=0), default=1.0, help="replay speed factor (default 1)")
    p.add_argument("--topics", help="comma-separated subset of topics to replay")
    p.add_argument("--start-delay", type=number(ge=0, le=3600, unit="s"), default=1.0,
                   help="start once every topic has a subscriber, or after this many s")
    p.add_argument("--quiet", action="store_true", help="no progress lines on stderr")
    add_recover(p)


def run(args) -> int:
    from ..bags import open_bag
    from ..errors import CablelabError
    from ..ros.runner import run_node

    import math

    if not (math.isfinite(args.rate) and args.rate > 0):
        raise CablelabError(f"--rate {args.rate!r}: expected a speed factor > 0 (e.g. 1 or 0.5)")
    if not (math.isfinite(args.start_delay) and args.start_delay >= 0):
        raise CablelabError(f"--start-delay {args.start_delay!r}: expected seconds >= 0")
    bag = open_bag(args.bag, recover=args.recover)  # bad bag: one-line error before ROS starts
    topics = [t.strip() for t in args.topics.split(",") if t.strip()] if args.topics else None
    if args.topics is not None:
        unknown = [t for t in topics or [""] if t not in bag.topics]
        if unknown:
            raise CablelabError(f"--topics {','.join(unknown) or repr(args.topics)}: not in {args.bag} "
                                f"(topics: {', '.join(sorted(bag.topics)) or 'none'})")

    import shutil
    import tempfile

    source, tmp_dir = args.bag, None
    if bag.recovered:   # --recover on an unfinished bag: replay its repaired copy
        from ..bags.repair import repair_bag

        tmp_dir = tempfile.mkdtemp(prefix="cablelab-replay-")
        source = repair_bag(args.bag, f"{tmp_dir}/bag")["bag"]

    def factory():
        from ..ros.replayer import ReplayNode

        return ReplayNode(source, args.rate, start_delay=args.start_delay, topics=topics,
                          quiet=args.quiet)

    try:
        return run_node(factory, [], "cablelab replay")
    finally:
        if tmp_dir is not None:
            shutil.rmtree(tmp_dir, ignore_errors=True)
