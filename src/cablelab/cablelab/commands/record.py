"""``cablelab record -o BAG (--plant P | --topics a,b)``: record contract topics into a bag.

A real ROS 2 node (see :mod:`cablelab.ros.recorder`); stops on SIGINT/SIGTERM or after
``--duration`` and closes the bag. Samples a publisher dropped before the recorder had them are
counted per topic: WARN on /diagnostics, a warning line at the end, ``cablelab.lost.<topic>`` in
the bag's metadata.yaml ``custom_data`` (shown by ``cablelab info``).
"""
from __future__ import annotations

from .numeric import number

HELP = "record a plant's contract topics (or --topics) into a rosbag2 MCAP bag"
DESCRIPTION = (HELP + ". Samples a publisher dropped before the recorder had them are counted per "
               "topic: WARN on /diagnostics, a warning at the end, and cablelab.lost.<topic> in the "
               "bag metadata's custom_data (cablelab info shows them).")


def add_arguments(p) -> None:
    p.add_argument("-o", "--output", required=True, help="bag directory to create")
    from ..registry import available_plants

    p.add_argument("--plant", choices=available_plants(),
                   help="record this plant's contract topics (+ /clock, /plant_description)")
    p.add_argument("--topics", help="comma-separated topics to record (types discovered)")
    p.add_argument("--duration", type=number(ge=0, unit="s"), default=0.0, help="stop after this many s (0: on signal)")
    p.add_argument("--overwrite", action="store_true", help="replace an existing bag")
    p.add_argument("--flush-period", type=number(gt=0, le=3600, unit="s"), default=1.0,
                   help="s between flushes to disk (bounds what a SIGKILL loses)")
    p.add_argument("--quiet", action="store_true", help="no progress lines on stderr")


def topic_set(args) -> dict:
    from ..errors import CablelabError
    from ..topics import plant_topics

    topics: dict = {}
    if args.plant:
        topics.update(plant_topics(args.plant))
    if args.topics:
        for name in args.topics.split(","):
            name = name.strip()
            if not name.startswith("/"):
                raise CablelabError(f"--topics: topic names start with '/', got {name!r}")
            topics.setdefault(name, None)
    if not topics:
        raise CablelabError("record: give --plant or --topics")
    return topics


def run(args) -> int:
    from ..bags import BagWriter
    from ..ros.runner import run_node

    import math

    from ..atomic import check_target
    from ..errors import CablelabError

    if not (math.isfinite(args.duration) and args.duration >= 0):
        raise CablelabError(f"--duration {args.duration!r}: expected seconds >= 0 (0: until Ctrl-C)")
    if not (math.isfinite(args.flush_period) and args.flush_period > 0):
        raise CablelabError(f"--flush-period {args.flush_period!r}: expected seconds > 0")
    topics = topic_set(args)
    check_target(args.output, overwrite=args.overwrite, option="-o")   # read-only / missing parent
    writer = BagWriter(args.output, overwrite=args.overwrite)  # refuses an existing path first

    def factory():
        from ..ros.recorder import RecorderNode

        return RecorderNode(writer, topics, duration=args.duration,
                            flush_period=args.flush_period, quiet=args.quiet)

    return run_node(factory, [], "cablelab record")
