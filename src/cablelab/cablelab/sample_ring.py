"""A control loop's samples handed to another process through shared memory, in order, none lost.

A control loop must not spend its period publishing: serialising and sending half a dozen
messages per period costs several times the read -> law -> write body, and in the loop's
process it also holds the GIL at the next deadline. :class:`SampleRing` is a single-producer,
single-consumer ring buffer of fixed-width float64 records in one
:class:`multiprocessing.shared_memory.SharedMemory` block: the loop writes one record per period
(:meth:`SampleRing.put`: a few numpy copies, no lock, no system call), a publisher process
(:mod:`cablelab.ros.loop_publisher`) takes the records in batches (:meth:`SampleRing.take`) and
publishes them. A full ring refuses the record (never overwrites one not yet taken) and counts
it in ``lost``; nothing else is ever dropped, and records are taken in the order they were put.

:class:`StateLayout` packs a :class:`~cablelab.hardware.HardwareState` and its command into one
record and back: stamp, joint positions, rates and efforts, each extra measurement, the command
(NaN-filled with a flag 0 when the law had none); an extra the state lacks is NaN-filled and
left out again when unpacked. Its :meth:`StateLayout.to_dict` crosses the
process boundary as JSON.

The counters are two int64 in the block's header (``written`` by the producer, ``taken`` by the
consumer, each written by one side only), so the two sides never wait on each other. The
producer stores a record, then the counter that makes it visible; the consumer loads the counter,
then the records (x86-64 keeps stores, and loads, in program order as other CPUs see them; on a
weakly ordered CPU this relies on the time between the two Python statements).
"""
from __future__ import annotations

from dataclasses import dataclass
from multiprocessing import shared_memory

import numpy as np

from .hardware import HardwareState

__all__ = ["StateLayout", "SampleRing"]

# header slots (int64)
_WRITTEN, _TAKEN, _CLOSED, _LOST, _WIDTH, _CAPACITY, _COST_NS, _COST_RECORDS = range(8)
_HEADER = 8          # int64 slots (64 bytes: the records start cache-line aligned)


@dataclass(frozen=True)
class StateLayout:
    """Where each part of a (state, command) pair sits in a record.

    Args:
        n: joints (length of ``position``, ``velocity``, ``effort``).
        extras: ``(name, size)`` of each extra measurement, in record order.
        ncommand: length of the command.
    """

    n: int
    extras: tuple[tuple[str, int], ...]
    ncommand: int

    @classmethod
    def of(cls, state: HardwareState, ncommand: int | None = None) -> "StateLayout":
        """The layout of records like ``state`` (its extras' names and sizes) with commands of
        ``ncommand`` values (default: one per joint)."""
        n = len(state.position)
        extras = tuple((str(k), int(np.size(v))) for k, v in state.extra.items())
        return cls(n, extras, n if ncommand is None else int(ncommand))

    @property
    def width(self) -> int:
        """float64 values per record: stamp, 3 n joint values, extras, command, command flag."""
        return 1 + 3 * self.n + sum(s for _, s in self.extras) + self.ncommand + 1

    def slices(self) -> dict[str, slice]:
        out, i = {}, 1
        for name, size in (("position", self.n), ("velocity", self.n), ("effort", self.n),
                           *((f"extra:{k}", s) for k, s in self.extras), ("command", self.ncommand)):
            out[name] = slice(i, i + size)
            i += size
        return out

    def pack(self, row: np.ndarray, state: HardwareState, command) -> None:
        """Write ``state`` and ``command`` (or None) into ``row`` (width,)."""
        p, v, e, c, extras = self._plan
        row[0] = state.t
        row[p] = state.position
        row[v] = state.velocity
        row[e] = state.effort
        extra = state.extra
        for name, sl in extras:
            value = extra.get(name)
            row[sl] = np.nan if value is None else value
        if command is None:
            row[c] = np.nan
            row[-1] = 0.0
        else:
            row[c] = command
            row[-1] = 1.0

    def unpack(self, row: np.ndarray) -> tuple[HardwareState, np.ndarray | None]:
        """The (state, command) of a record (arrays are copies: the ring's slot is reused). An
        extra the state did not have (all NaN in the record) is left out."""
        p, v, e, c, extras = self._plan
        row = np.array(row, dtype=float)
        nan = np.isnan(row)
        extra = {}
        for name, sl in extras:
            if not nan[sl.start] or not nan[sl].all():      # (the first value decides most often)
                extra[name] = row[sl]
        command = row[c] if row[-1] != 0.0 else None
        return HardwareState(float(row[0]), row[p], row[v], row[e], extra), command

    @property
    def _extra_keys(self) -> tuple[tuple[str, str], ...]:
        return tuple((name, f"extra:{name}") for name, _ in self.extras)

    @property
    def _plan(self) -> tuple:
        """(position, velocity, effort, command slices, ((extra name, slice), ...)) for :meth:`pack`."""
        plan = self.__dict__.get("_plan_cache")
        if plan is None:
            s = self.slices()
            plan = (s["position"], s["velocity"], s["effort"], s["command"],
                    tuple((name, s[key]) for name, key in self._extra_keys))
            object.__setattr__(self, "_plan_cache", plan)
        return plan

    def to_dict(self) -> dict:
        return {"n": self.n, "extras": [list(e) for e in self.extras], "ncommand": self.ncommand}

    @classmethod
    def from_dict(cls, d: dict) -> "StateLayout":
        return cls(int(d["n"]), tuple((str(k), int(s)) for k, s in d["extras"]), int(d["ncommand"]))


class SampleRing:
    """Single-producer single-consumer ring of ``capacity`` records of ``width`` float64 in shared
    memory (module docstring). Build with :meth:`create` (the producer's side, which owns and
    finally :meth:`unlink`\\ s the block) or :meth:`attach` (the consumer's, by ``name``)."""

    def __init__(self, shm: shared_memory.SharedMemory, owner: bool):
        self.shm, self.owner = shm, owner
        self.header = np.ndarray((_HEADER,), np.int64, shm.buf)
        self.width, self.capacity = int(self.header[_WIDTH]), int(self.header[_CAPACITY])
        self.data = np.ndarray((self.capacity, self.width), np.float64, shm.buf, offset=8 * _HEADER)
        self._written = int(self.header[_WRITTEN])      # the producer's own count (it alone writes it)

    @classmethod
    def create(cls, width: int, capacity: int) -> "SampleRing":
        width, capacity = int(width), int(capacity)
        if width < 1 or capacity < 2:
            raise ValueError(f"sample ring: width {width} and capacity {capacity} must be >= 1 and >= 2")
        shm = shared_memory.SharedMemory(create=True, size=8 * (_HEADER + width * capacity))
        header = np.ndarray((_HEADER,), np.int64, shm.buf)
        header[:] = 0
        header[_WIDTH], header[_CAPACITY] = width, capacity
        return cls(shm, owner=True)

    @classmethod
    def attach(cls, name: str) -> "SampleRing":
        shm = shared_memory.SharedMemory(name=name)
        try:        # the producer owns the block: this process's resource tracker must not unlink it
            from multiprocessing import resource_tracker
            resource_tracker.unregister(shm._name, "shared_memory")  # noqa: SLF001 - Python < 3.13 has no track=False
        except Exception:  # noqa: BLE001 - no tracker: nothing to undo
            pass
        return cls(shm, owner=False)

    @property
    def name(self) -> str:
        return self.shm.name

    # ------------------------------------------------------------------ producer
    def slot(self) -> np.ndarray | None:
        """The row to fill next, or None when the ring is full (then :meth:`commit` is not called
        and the record is counted as lost)."""
        w = self._written
        if w - int(self.header[_TAKEN]) >= self.capacity:
            self.header[_LOST] += 1
            return None
        return self.data[w % self.capacity]

    def commit(self) -> None:
        """Make the row :meth:`slot` returned visible to the consumer."""
        self._written += 1
        self.header[_WRITTEN] = self._written

    def put(self, values) -> bool:
        """Append one record (width,); False (and counted in ``lost``) when the ring is full."""
        row = self.slot()
        if row is None:
            return False
        row[:] = values
        self.commit()
        return True

    def close(self) -> None:
        """No more records will come (the consumer takes the rest, then stops)."""
        self.header[_CLOSED] = 1

    # ------------------------------------------------------------------ consumer
    def take(self, most: int | None = None) -> np.ndarray:
        """The records put and not yet taken (at most ``most``), oldest first, as a copy (k, width);
        they are then free for the producer."""
        r, w = int(self.header[_TAKEN]), int(self.header[_WRITTEN])
        k = w - r if most is None else min(w - r, int(most))
        if k <= 0:
            return self.data[:0].copy()
        i = r % self.capacity
        if i + k <= self.capacity:
            out = self.data[i:i + k].copy()
        else:
            out = np.concatenate([self.data[i:], self.data[:i + k - self.capacity]])
        self.header[_TAKEN] = r + k
        return out

    def report_cost(self, cpu_s: float, records: int) -> None:
        """The consumer's CPU time spent on ``records`` records (for the producer's figures)."""
        self.header[_COST_NS], self.header[_COST_RECORDS] = int(cpu_s * 1e9), int(records)

    # ------------------------------------------------------------------ both
    @property
    def consumer_cpu_per_record(self) -> float | None:
        """s of the consumer's CPU per record, as it last reported (:meth:`report_cost`)."""
        n = int(self.header[_COST_RECORDS])
        return int(self.header[_COST_NS]) * 1e-9 / n if n > 0 else None

    @property
    def closed(self) -> bool:
        return bool(self.header[_CLOSED])

    @property
    def written(self) -> int:
        return int(self.header[_WRITTEN])

    @property
    def taken(self) -> int:
        return int(self.header[_TAKEN])

    @property
    def backlog(self) -> int:
        """Records put and not yet taken."""
        return self.written - self.taken

    @property
    def lost(self) -> int:
        """Records refused because the ring was full."""
        return int(self.header[_LOST])

    def release(self) -> None:
        """Unmap the block (and remove it, on the owner's side)."""
        self.header = self.data = None
        try:
            self.shm.close()
        except BufferError:             # a view of a row still alive: the mapping goes with the process
            pass
        if self.owner:
            try:
                self.shm.unlink()
            except FileNotFoundError:
                pass
