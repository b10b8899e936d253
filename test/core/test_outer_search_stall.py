"""The outer search's stall rule (:data:`cablelab.fit.identification.OUTER_STALL`) against the
same search without it: a delay of a whole number of samples sits on a kink of the interpolated
cost, where the optimiser's damping ladder returns its start after ~140 evaluations; with the
rule the fit stops early at the same point, with the same linear parameters."""
import numpy as np
import pytest

from cablelab.description import load_description
from cablelab.fit import identification, identify
from cablelab.model import Model

PRISMATIC = load_description("plant: axis\naxis:\n  joint_type: prismatic\n")


def _record(tau: float, seed: int):
    from cablelab.plants.axis.dataset import dataset_from_arrays

    fs = 500.0
    t = np.arange(0, 20, 1 / fs)
    q = 0.3 * np.sin(1.3 * t) + 0.1 * np.sin(4.1 * t + 1)
    qd = 0.3 * 1.3 * np.cos(1.3 * t) + 0.1 * 4.1 * np.cos(4.1 * t + 1)
    qdd = -0.3 * 1.69 * np.sin(1.3 * t) - 0.1 * 4.1**2 * np.sin(4.1 * t + 1)
    force = 12.0 * qdd + 30.0 * qd
    meas = np.interp(t - tau, t, force) + np.random.default_rng(seed).normal(0, 0.05, t.size)
    return dataset_from_arrays(t, q, meas, PRISMATIC, None)


def _fit(ds, stall, monkeypatch):
    calls = []
    real = identification._OuterProblem.residual

    def counted(self, x):
        calls.append(float(np.ravel(x)[0]))
        return real(self, x)

    with monkeypatch.context() as m:
        m.setattr(identification._OuterProblem, "residual", counted)
        m.setattr(identification, "OUTER_STALL", stall)
        r = identify(Model("axis", ("axis_inertia", "joint_viscous_friction", "time_delay")), ds)
    return r, len(calls)


@pytest.mark.parametrize("tau, seed, stalls", [(0.0, 2, True), (0.002, 0, False)])
def test_stall_rule_gives_the_unlimited_search_answer(monkeypatch, tau, seed, stalls):
    ds = _record(tau, seed)
    fast, n_fast = _fit(ds, identification.OUTER_STALL, monkeypatch)
    slow, n_slow = _fit(ds, 10**9, monkeypatch)
    # (this noise draw puts the optimum on the kink at zero delay: the ladder runs without the rule)
    assert (n_fast < n_slow / 2) if stalls else (n_fast == n_slow)
    assert fast.params["tau"] == pytest.approx(slow.params["tau"], abs=1e-7)   # 1e-4 sample
    assert fast.params["tau"] == pytest.approx(tau, abs=1e-3)
    for k in ("M", "Fv"):
        assert fast.params[k] == pytest.approx(slow.params[k], rel=1e-5)
        assert fast.stderr[k] == pytest.approx(slow.stderr[k], rel=1e-3)
