"""``cablelab replay BAG [--rate R]``: republish a bag on its original topics (a real ROS 2 node,
see :mod:`cablelab.ros.replayer`), with /clock and the transient-local /plant_description."""
from __future__ import annotations

HELP = "republish a bag on its original topics with /clock and /plant_description"


def add_arguments(p) -> None:
    p.add_argument("bag", help="rosbag2 directory or its .mcap file")
    p.add_argument("--rate", type=float, default=1.0, help="replay speed factor (default 1)")
    p.add_argument("--topics", help="comma-separated subset of topics to replay")
    p.add_argument("--start-delay", type=float, default=1.0,
                   help="start once every topic has a subscriber, or after this many s")
    p.add_argument("--quiet", action="store_true", help="no progress lines on stderr")


def run(args) -> int:
    from ..bags import open_bag
    from ..errors import CablelabError
    from ..ros.runner import run_node

    if args.rate <= 0:
        raise CablelabError(f"--rate must be > 0, got {args.rate}")
    open_bag(args.bag)  # bad bag: one-line error before ROS starts
    topics = [t.strip() for t in args.topics.split(",")] if args.topics else None

    def factory(_args):
        from ..ros.replayer import ReplayNode

        return ReplayNode(args.bag, args.rate, start_delay=args.start_delay, topics=topics,
                          quiet=args.quiet)

    return run_node(factory, args, [], "cablelab replay")
