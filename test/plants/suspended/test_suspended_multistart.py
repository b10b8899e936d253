"""Discrete ambiguity of the virtual-joint identification: the compound pendulum's conjugate
branch (identify.conjugate_depth) and the multi-start that finds and reports it.

Oracles: the MuJoCo swing period of the chain at the two depths (a lone compound pendulum: the
same period, its closed form d + d' = L_eq); the generating depth of a simulated record (the
repo LiCAS l9z = 0.824 m)."""
import dataclasses

import numpy as np
import pytest

from cablelab.plants.suspended.identify import (basin_text, conjugate_depth, identify,
                                                licas_experiments)
from cablelab.plants.suspended.params import parameter_set


def _lone_link():
    """LiCAS with the platform and arms made light (10 g each) and J8, J9 undamped: the swing
    about x is a compound pendulum whose conjugate depth has the same period (a damped one
    would not: the decay rate f_v / 2J changes with J)."""
    p = parameter_set("licas")
    arm = tuple(dataclasses.replace(a, mass=0.01, inertia=(1e-5, 1e-5, 1e-5, 0, 0, 0)) for a in p.arm)
    return p.replace(m_plat=0.01, I_plat=(1e-5,) * 3, arm=arm, fv=(p.fv[0], 0.0, 0.0))


def _y_only(p, noise=1e-3):
    """The swing about x (J8, started at 0.15 rad), seen in r_y, 6 s."""
    ident, _ = licas_experiments(p, plant="virtual", duration=6.0, seed=1, pos_noise=noise)
    return [dataclasses.replace(ident[1], use=np.array([False, True, False]))]


def test_conjugate_depth_swings_with_the_same_period():
    p = _lone_link()
    d2 = conjugate_depth(p, "l9z", 0)
    assert 0.0 < d2 < p.l9z
    ys = [_y_only(p.replace(l9z=d), noise=0.0)[0].y[:, 1] for d in (p.l9z, d2, 0.5 * (p.l9z + d2))]
    amp = np.abs(ys[0]).max()
    assert np.abs(ys[1] - ys[0]).max() < 1e-3 * amp             # the same swing, 6 s (3 periods)
    assert np.abs(ys[2] - ys[0]).max() > 0.3 * amp              # a depth between them is not
    assert conjugate_depth(p.replace(l9z=d2), "l9z", 0) == pytest.approx(p.l9z, rel=1e-9)   # involution


def test_multi_start_finds_the_generating_depth_from_the_wrong_basin():
    p = parameter_set("licas")                          # generated with l9z = 0.824 m
    exps = _y_only(p)
    wrong = {"l9z": conjugate_depth(p, "l9z", 0)}
    one = identify(exps, p, ["l9z"], start=wrong, max_iter=15)
    assert one.values["l9z"] < 0.3                      # a local fit stays on the conjugate branch
    multi = identify(exps, p, ["l9z"], start=wrong, max_iter=15, starts=1)
    assert multi.values["l9z"] == pytest.approx(0.824, rel=0.01)
    assert len(multi.basins) >= 2 and multi.basins[0]["error"] < 0.5 * multi.basins[-1]["error"]
    assert multi.ambiguous_with == [] and basin_text(multi) == ""   # the other basin fits worse


def test_two_basins_that_fit_alike_are_reported():
    p = _lone_link()
    multi = identify(_y_only(p), p, ["l9z"], max_iter=15, starts=1)
    assert multi.ambiguous_with, multi.basins
    depths = sorted([multi.values["l9z"]] + [o["values"]["l9z"] for o in multi.ambiguous_with])
    assert depths[0] == pytest.approx(conjugate_depth(p, "l9z", 0), rel=0.05)
    assert depths[-1] == pytest.approx(p.l9z, rel=0.05)
    assert "ambiguous with" in basin_text(multi) and "l9z" in basin_text(multi)
