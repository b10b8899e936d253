"""``cablelab repair BAG``: rewrite an unfinished recording (recorder killed: MCAP without footer,
summary or index, maybe no metadata.yaml) as a complete rosbag2 bag.

The complete records up to the last flushed chunk, every intact chunk of a damaged file and
every file of a split bag that is there are read with the bags reader's recover path
(:func:`~cablelab.bags.reader.open_bag` ``recover=True``, :mod:`cablelab.bags.salvage`) and
written again, byte for byte, with
:meth:`~cablelab.bags.writer.BagWriter.write_raw` in log-time order: the result has a
``metadata.yaml``, an MCAP summary and chunk index, and opens in rosbags, the indexed ``mcap``
reader and every cablelab verb. The output appears whole or not at all (:mod:`cablelab.atomic`).
"""
from __future__ import annotations

from pathlib import Path

import numpy as np

from ..errors import CablelabError
from .reader import open_bag
from .series import DESCRIPTION_TOPIC
from .writer import BagWriter


def default_output(path) -> Path:
    """``run`` -> ``run_repaired``; a bag's ``run/run_0.mcap`` -> ``run_repaired`` too (never
    inside the input bag); a lone ``x.mcap`` -> ``x_repaired`` beside it."""
    from ..atomic import input_paths

    p = Path(path)
    if p.suffix == ".mcap" and len(input_paths(p)) > 1:   # the .mcap of a bag directory
        p = p.resolve().parent
    stem = p.stem if p.suffix == ".mcap" else p.name
    return p.with_name(f"{stem}_repaired")


def repair_bag(path, out=None, *, overwrite: bool = False) -> dict:
    """Rewrite the readable part of ``path`` into the complete bag ``out``.

    Args:
        path: bag directory or .mcap file (finished or not).
        out: bag directory to create (default :func:`default_output`); never the input.
        overwrite: replace an existing ``out``.
    Returns:
        ``{"bag", "source", "recovered", "messages", "topics": {topic: count}, "duration",
        "warnings"}``; ``warnings`` says what could not be saved (damaged chunks skipped, files of
        a split bag missing, with counts): the output then holds only the intact part.
    Raises:
        CablelabError: unreadable input, nothing to recover, unwritable output (one line).
    """
    from ..atomic import atomic_output, check_target

    out = Path(out) if out is not None else default_output(path)
    check_target(out, overwrite=overwrite, inputs=[path], option="-o")
    bag = open_bag(path, recover=True)
    total = int(sum(bag.counts.values()))
    if total == 0:
        raise CablelabError(f"{path}: no complete message to recover (killed before its first flush?)")
    topics = [t for t in bag.topics if bag.counts.get(t, 0)]
    times, order_topic, payloads = [], [], []
    for k, topic in enumerate(topics):
        t_ns, raws = bag.raw(topic)
        times.append(np.asarray(t_ns, dtype=np.int64))
        order_topic.append(np.full(len(raws), k, dtype=np.int64))
        payloads.extend(raws)
    t_all = np.concatenate(times)
    k_all = np.concatenate(order_topic)
    order = np.argsort(t_all, kind="stable")          # one log-time order over all topics
    with atomic_output(out, overwrite=overwrite, inputs=[path], option="-o", verb="repair") as tmp:
        with BagWriter(tmp) as w:
            for topic in topics:
                w.add_topic(topic, bag.topics[topic], transient_local=topic == DESCRIPTION_TOPIC)
            for i in order.tolist():                  # one write per message: the writer's API
                w.write_raw(topics[k_all[i]], int(t_all[i]), payloads[i])
    return {"bag": str(out), "source": str(path), "recovered": bool(bag.recovered), "messages": total,
            "topics": {t: bag.counts[t] for t in topics}, "duration": bag.end - bag.start,
            "warnings": list(bag.warnings)}
