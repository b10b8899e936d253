"""The crane's own options: how its identification equations are low-passed. Also a command-line
option of the verbs that read a crane bag (``--crane-filter``)."""
from __future__ import annotations

from dataclasses import dataclass

from ...plant_interface import option

#: ``positions``: the positions low-passed at the crane's cut-off, derivatives from them, the
#: efforts as recorded; ``parallel``: derivatives at fs / 10, the efforts and every regressor
#: column low-passed at the cut-off alike (:mod:`cablelab.parallel_filter`)
CRANE_FILTERS = ("positions", "parallel")


@dataclass(frozen=True)
class CraneOptions:
    """Attributes:
        crane_filter: one of :data:`CRANE_FILTERS` (used when ``--cutoff`` is not given).
    """

    crane_filter: str = option(
        "positions", choices=CRANE_FILTERS,
        verbs=("compare", "diagnose", "identify", "report", "excite"),
        help="low-pass of the crane's equations at 3 Hz: 'positions' (default; the positions, "
             "derivatives from them) or 'parallel' (derivatives at fs/10, efforts and regressor "
             "columns at 3 Hz alike: exact where the swing has content near 3 Hz)")
