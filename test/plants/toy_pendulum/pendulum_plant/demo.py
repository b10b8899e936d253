"""The plant's part of ``./run demo``: set :data:`DEMO` to a :class:`cablelab.demo.DemoPart`
(record: the DDS runs; analyse: the table rows and pages) to join the demo; None: no part."""
from __future__ import annotations

DEMO = None
