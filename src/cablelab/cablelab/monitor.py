"""Live model monitor, ROS-free: the plant's workbench model run on a stream of raw messages,
its residual checked against a band (``model_monitor`` is the ROS adapter).

:class:`StreamWindow` keeps the last seconds of each input topic as serialised CDR messages (the
bytes a ROS subscription or a bag delivers) and turns them into an in-memory
:class:`~cablelab.bags.Bag`; :class:`ResidualMonitor` builds the plant's dataset from it with the
workbench's own conditioning (:attr:`cablelab.registry.Plant.dataset`), predicts the output
channels with the identified model (:meth:`cablelab.model.Model.predict`) and passes the new
samples' residuals to :class:`BandCheck`, which raises an alarm when a channel's residual stays
outside its band for longer than ``hold`` s (WARN; ERROR beyond ``error_factor`` bands) and
clears it after ``hold`` s back inside.

The model and its band come from a ``cablelab identify --json`` document (parameters, and the
band = ``band_sigma`` x the channel's residual RMS), or are identified on the first
``calibrate`` s of the stream (the nominal model of the description; band from that fit's
residual, outliers trimmed: :func:`trimmed_rms`). Times are the messages' header stamps (sim
time in simulation), so detection delays are measured on the machine's clock, however loaded
the computer.
"""
from __future__ import annotations

import json
from collections import deque
from dataclasses import dataclass, field

import numpy as np

from .errors import CablelabError

WARN, ERROR = 1, 2


def stamp_ns(data: bytes) -> int | None:
    """Header stamp (ns) of a serialised stamped message (CDR: a 4-byte encapsulation header,
    then ``header.stamp.sec`` int32 and ``nanosec`` uint32); None if too short."""
    if len(data) < 12:
        return None
    sec = int.from_bytes(data[4:8], "little", signed=True)
    nsec = int.from_bytes(data[8:12], "little", signed=False)
    return sec * 1_000_000_000 + nsec


def trimmed_rms(r) -> np.ndarray:
    """RMS per column of ``r`` (N, C) without its outliers (beyond 5 robust sigmas, 1.4826 x
    the median absolute deviation, from the median): a start-up transient in the calibration
    window does not widen the band, the spread of normal running does."""
    r = np.asarray(r, dtype=float)
    med = np.nanmedian(r, axis=0)
    sigma = 1.4826 * np.nanmedian(np.abs(r - med), axis=0)
    keep = np.abs(r - med) <= 5.0 * np.maximum(sigma, 1e-300)
    return np.sqrt(np.nanmean(np.where(keep, r, np.nan) ** 2, axis=0))


class StreamWindow:
    """The last ``seconds`` of each topic as serialised messages, ordered by header stamp."""

    def __init__(self, topics: dict, seconds: float, required=()):
        self.topics = dict(topics)
        self.required = tuple(required)
        self.seconds = float(seconds)
        self.buf = {t: deque() for t in self.topics}
        self.newest = None

    def add(self, topic: str, data: bytes) -> bool:
        """Keep one message (False: unknown topic or unstamped, not kept)."""
        ns = stamp_ns(data)
        if topic not in self.buf or ns is None:
            return False
        q = self.buf[topic]
        q.append((ns, bytes(data)))
        self.newest = ns if self.newest is None else max(self.newest, ns)
        lo = self.newest - int(self.seconds * 1e9)
        while q and q[0][0] < lo:
            q.popleft()
        return True

    def span(self) -> float:
        """Seconds covered by every topic that has messages at once (0 while a required one has
        none)."""
        if any(not self.buf[t] for t in self.required):
            return 0.0
        qs = [q for q in self.buf.values() if q]
        if not qs:
            return 0.0
        return (min(q[-1][0] for q in qs) - max(q[0][0] for q in qs)) * 1e-9

    def bag(self):
        from .bags.reader import _make_bag

        return _make_bag("<live>", self.topics, {t: [m[0] for m in q] for t, q in self.buf.items()},
                         {t: [m[1] for m in q] for t, q in self.buf.items()})


@dataclass
class Alarm:
    """A channel whose residual left its band: level (1 WARN, 2 ERROR), the stamp it left
    (``since``), the stamp the alarm was raised (``raised``), its size (mean |residual| of the
    out-of-band samples so far) and the band."""

    channel: str
    level: int
    since: float
    raised: float
    size: float
    band: float

    def line(self, unit: str = "") -> str:
        u = f" {unit}" if unit else ""
        return (f"{self.channel}: residual {self.size:.4g}{u} outside its band +-{self.band:.4g}{u} since "
                f"t = {self.since:.3f} s (raised at {self.raised:.3f} s)")


class BandCheck:
    """Per channel: outside the band for longer than ``hold`` s -> alarm; back inside for
    ``hold`` s -> cleared."""

    def __init__(self, channels, band, hold: float, error_factor: float = 3.0):
        self.channels = tuple(channels)
        self.band = np.asarray(band, dtype=float).reshape(-1)
        if self.band.shape != (len(self.channels),) or not np.all(self.band > 0):
            raise CablelabError(f"model monitor: band {self.band.tolist()}: expected {len(self.channels)} "
                                "positive numbers")
        self.hold = float(hold)
        self.error_factor = float(error_factor)
        n = len(self.channels)
        self.out_since = [None] * n          # stamp the current out-of-band run began
        self.in_since = [None] * n           # stamp the current in-band run began
        self.sum_abs = np.zeros(n)
        self.count = np.zeros(n, dtype=int)
        self.alarms: dict[str, Alarm] = {}
        self.history: list[Alarm] = []       # every alarm raised, in order

    def push(self, t, r) -> list[Alarm]:
        """Residuals ``r`` (n, C) at stamps ``t`` (n,) in order; returns the alarms raised now."""
        t = np.asarray(t, dtype=float).reshape(-1)
        r = np.asarray(r, dtype=float).reshape(len(t), -1)
        raised = []
        for c, ch in enumerate(self.channels):
            a = np.abs(r[:, c])
            ok = np.isfinite(a)
            for ti, ai in zip(t[ok].tolist(), a[ok].tolist()):   # a few samples per call
                if ai > self.band[c]:
                    self.in_since[c] = None
                    if self.out_since[c] is None:
                        self.out_since[c], self.sum_abs[c], self.count[c] = ti, 0.0, 0
                    self.sum_abs[c] += ai
                    self.count[c] += 1
                    size = self.sum_abs[c] / self.count[c]
                    level = ERROR if size > self.error_factor * self.band[c] else WARN
                    if ti - self.out_since[c] >= self.hold:
                        old = self.alarms.get(ch)
                        if old is None or level > old.level:
                            al = Alarm(ch, level, self.out_since[c], ti, size, float(self.band[c]))
                            self.alarms[ch] = al
                            self.history.append(al)
                            raised.append(al)
                        else:
                            old.size = size
                else:
                    self.out_since[c] = None
                    if self.in_since[c] is None:
                        self.in_since[c] = ti
                    if ch in self.alarms and ti - self.in_since[c] >= self.hold:
                        del self.alarms[ch]
        return raised

    def level(self) -> int:
        return max((a.level for a in self.alarms.values()), default=0)


@dataclass
class MonitorModel:
    """What the monitor runs: effects, parameter values by name, band per channel (None:
    calibrate on the stream)."""

    effects: tuple
    params: dict | None = None
    band: dict | None = None

    @classmethod
    def from_identify_json(cls, text: str, band_sigma: float, source: str = "identify JSON") -> "MonitorModel":
        try:
            doc = json.loads(text)
            effects = tuple(doc["effects"])
            params = {k: float(v["value"]) for k, v in doc["params"].items()}
            band = {ch: band_sigma * float(m["rms"]) for ch, m in doc["fit"]["channels"].items()}
        except (ValueError, KeyError, TypeError) as exc:
            raise CablelabError(f"{source}: not the JSON of cablelab identify --json ({type(exc).__name__}: "
                                f"{exc})") from None
        return cls(effects, params, band)


@dataclass
class Samples:
    """New monitored samples: stamps (n,), measured, prediction, residual (n, C)."""

    t: np.ndarray
    measured: np.ndarray
    prediction: np.ndarray
    channels: tuple = ()
    raised: list = field(default_factory=list)

    @property
    def residual(self) -> np.ndarray:
        return self.measured - self.prediction


class ResidualMonitor:
    """The plant's model on a live stream.

    Args:
        plant_name: plant id; desc: its :class:`~cablelab.description.Description`.
        model: :class:`MonitorModel` (effects; params and band, or None to calibrate).
        window: seconds of the stream each evaluation conditions (the newest samples are the
            conditioning border away from its end: the detection delay's floor).
        hold: seconds outside the band before an alarm. band_sigma: band = band_sigma x the
            residual RMS (calibration). calibrate: seconds of stream the calibration fits on.
        options: plant options by name (``tensions`` ...), as the command line's; those the plant
            does not have are left out.
    """

    def __init__(self, plant_name: str, desc, model: MonitorModel, *, window: float = 3.0,
                 hold: float = 0.5, band_sigma: float = 4.0, calibrate: float = 10.0,
                 error_factor: float = 3.0, options: dict | None = None):
        import dataclasses

        from .model import Model
        from .plant_interface import DatasetOptions
        from .registry import get_plant

        self.plant = get_plant(plant_name)
        self.desc = desc
        self.model = Model(plant_name, tuple(model.effects) or tuple(self.plant.baseline(desc)))
        self.params = model.params
        self.band_by_channel = model.band
        self.window, self.hold, self.band_sigma = float(window), float(hold), float(band_sigma)
        self.calibrate_s, self.error_factor = float(calibrate), float(error_factor)
        own = {f.name for f in dataclasses.fields(self.plant.options_type)} if self.plant.options_type else set()
        self.options = DatasetOptions.build(self.plant, {k: v for k, v in dict(options or {}).items()
                                                         if k in own})
        self.topics = self.input_topics(self.plant)
        self.stream = StreamWindow(self.topics, max(self.window, self.calibrate_s if self.params is None else 0.0),
                                   required=[t for t, _ in self.plant.topics])
        self.check: BandCheck | None = None
        self.channels: tuple = ()
        self.last_t = -np.inf
        self.evaluations = 0
        self.samples = 0
        self.problem = ""

    @staticmethod
    def input_topics(plant) -> dict:
        """Topic -> type of what the plant's workbench dataset reads: its required topics and
        the checked optional ones (never ground truth, estimates or commands)."""
        topics = dict(plant.topics)
        topics.update({t: plant.contract_topics[t] for t in plant.checked_topics if t in plant.contract_topics})
        return topics

    @property
    def calibrated(self) -> bool:
        return self.check is not None

    def add(self, topic: str, data: bytes) -> bool:
        return self.stream.add(topic, data)

    def _dataset(self):
        return self.plant.dataset(self.stream.bag(), self.desc, self.options)

    def _calibrate(self) -> None:
        from .fit import identify

        ds = self._dataset()
        if self.params is None:
            ident = identify(self.model, ds)
            self.params = {k: float(v) for k, v in ident.params.items()}
            band = self.band_sigma * trimmed_rms(ident.residual)
        else:
            band = np.array([self.band_by_channel.get(ch, np.nan) for ch in ds.channels])
            if not np.all(np.isfinite(band)):
                raise CablelabError(f"model monitor: the identify JSON has no residual RMS for channels "
                                    f"{', '.join(ds.channels)}")
        self.channels = tuple(ds.channels)
        self.units = tuple(ds.units)
        floor = 1e-9 * np.maximum(1.0, np.nanmax(np.abs(ds.y), axis=0))
        self.check = BandCheck(self.channels, np.maximum(band, floor), self.hold, self.error_factor)
        self.stream.seconds = self.window

    def step(self) -> Samples | None:
        """Evaluate the window: the samples newer than the last evaluation's (None while
        calibrating or when the window is too short to condition)."""
        need = self.calibrate_s if self.params is None else self.window
        if self.stream.span() < min(need, self.window if self.check else need) * 0.9:
            return None
        try:
            if self.check is None:
                self._calibrate()
            ds = self._dataset()
            y_hat, valid = self.model.predict(ds, self.params)
        except CablelabError as exc:
            self.problem = str(exc)
            return None
        self.problem = ""
        self.evaluations += 1
        keep = np.asarray(valid, dtype=bool) & (ds.t > self.last_t) & np.isfinite(y_hat).all(axis=1)
        if not keep.any():
            return None
        t = ds.t[keep]
        self.last_t = float(t[-1])
        out = Samples(t, ds.y[keep], y_hat[keep], self.channels)
        out.raised = self.check.push(t, out.residual)
        self.samples += len(t)
        return out

    def status(self) -> tuple[int, str, dict]:
        """``(level, message, values)`` for /diagnostics."""
        if self.check is None:
            return 0, self.problem or f"calibrating on the first {self.calibrate_s:g} s of the stream", {}
        units = dict(zip(self.channels, self.units))
        values = {f"band {ch}": f"{b:.4g}" for ch, b in zip(self.channels, self.check.band)}
        values["samples"] = str(self.samples)
        values["alarms raised"] = str(len(self.check.history))
        if not self.check.alarms:
            return (1 if self.problem else 0), self.problem or "model fits", values
        for a in self.check.alarms.values():
            values[f"alarm {a.channel}"] = a.line(units.get(a.channel, ""))
            values[f"alarm {a.channel} raised at s"] = f"{a.raised:.3f}"
            values[f"alarm {a.channel} since s"] = f"{a.since:.3f}"
        msg = "; ".join(a.line(units.get(a.channel, "")) for a in self.check.alarms.values())
        return self.check.level(), msg, values


__all__ = ["Alarm", "BandCheck", "MonitorModel", "ResidualMonitor", "Samples", "StreamWindow", "stamp_ns", "trimmed_rms"]
