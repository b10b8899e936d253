"""``time_delay``'s lazily shifted signals read exactly what shifting every signal up front gives
(the interpolation of :func:`shift_array` at :func:`shift_weights`), leave the source dataset as
it was, and interpolate only what is read."""
import numpy as np
from hypothesis import given, settings, strategies as st

from cablelab.dataset import Dataset
from cablelab.effects.delay import ShiftedSignals, TIME_DELAY, shift_array, shift_weights


def _dataset(n, rng):
    t = np.arange(n) * 1e-3
    signals = {"q": rng.normal(size=(n, 3)), "J": rng.normal(size=(n, 2, 3)), "g": 9.81,
               "driven": np.ones(3, bool), "mask": rng.normal(size=n) > 0, "edge": np.arange(n)}
    return Dataset(plant="toy", t=t, y=rng.normal(size=(n, 3)), channels=("a", "b", "c"),
                   signals=signals, act_vel=rng.normal(size=(n, 3)))


@settings(max_examples=40, deadline=None)
@given(n=st.integers(20, 300), tau=st.floats(-0.05, 0.05).filter(lambda x: abs(x) > 1e-12),
       seed=st.integers(0, 10))
def test_lazy_shift_equals_the_eager_shift(n, tau, seed):
    ds = _dataset(n, np.random.default_rng(seed))
    before = {k: np.copy(v) for k, v in ds.signals.items()}
    out = TIME_DELAY.transform(ds, {"tau": tau})
    i, w, ok = shift_weights(ds.t, tau)
    assert isinstance(out.signals, ShiftedSignals)
    assert list(out.signals) == list(ds.signals) and len(out.signals) == len(ds.signals)
    for k, v in ds.signals.items():
        got = out.signals[k]
        if isinstance(v, np.ndarray) and v.dtype.kind == "f" and v.shape[0] == n:
            np.testing.assert_array_equal(got, shift_array(v, i, w))
        else:
            assert got is v                   # not time-indexed floats: passed through
    np.testing.assert_array_equal(out.act_vel, shift_array(ds.act_vel, i, w))
    np.testing.assert_array_equal(out.valid, ds.valid & ok)
    np.testing.assert_array_equal(out.y, ds.y)                       # the measurement never moves
    for k, v in before.items():
        np.testing.assert_array_equal(ds.signals[k], v)


def test_only_what_is_read_is_interpolated_and_writes_stay():
    ds = _dataset(100, np.random.default_rng(0))
    out = TIME_DELAY.transform(ds, {"tau": 0.004})
    calls = []
    orig = out.signals._source["J"]
    out.signals._source["J"] = _Counting(orig, calls)
    _ = out.signals["q"]
    assert calls == []                                                 # J untouched
    out.signals["cache"] = np.zeros((100, 2))
    assert "cache" in out.signals and "cache" not in ds.signals
    np.testing.assert_array_equal(out.signals["cache"], np.zeros((100, 2)))
    assert dict(out.signals).keys() == set(ds.signals) | {"cache"}


class _Counting(np.ndarray):
    """An array that records being indexed (interpolated)."""

    def __new__(cls, a, calls):
        obj = np.asarray(a).view(cls)
        obj.calls = calls
        return obj

    def __array_finalize__(self, obj):
        self.calls = getattr(obj, "calls", None)

    def __getitem__(self, idx):
        if self.calls is not None:
            self.calls.append(idx)
        return super().__getitem__(idx)
