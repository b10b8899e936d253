"""``excite.design`` naming the delay ``tau`` (time_delay, a nonlinear parameter) through its
linearised column, the sensitivity of the fitted residual to tau (:class:`cablelab.excite.Linearised`;
the CDPR, whose outputs the delay re-forms, in test/plants/cdpr/test_cdpr_excite_delay.py).

Oracles: on the crane, whose outputs the delay leaves alone, the column against the closed form
``d y / d tau = -d y0 / dt`` (the delay evaluates the model at ``t - tau``: minus the time
derivative of the undelayed model output, taken of the output, no delayed dataset built), and the condition number of {tau, I_tot} on a slow reference (the delay is
invisible: its column is small and nearly a combination of the others) against the designed one."""
from pathlib import Path

import numpy as np
import pytest

import cablelab.plants.crane as crane_pkg
from cablelab import excite as E
from cablelab.description import load_description
from cablelab.errors import CablelabError
from cablelab.model import Model

DESC = load_description(str(Path(crane_pkg.__file__).parent / "data" / "crane.yaml"))
KNOWN = {"m_b": DESC.crane.boom_mass, "m_c": DESC.crane.counterbalance.mass,
         "l_c": DESC.crane.counterbalance.distance}
EFFECTS = ("crane_rigid_body", "counterbalance", "joint_viscous_friction", "time_delay")
THETA = {"I_tot": 0.05, "I_b": 0.02, "m": 0.5, "Fv[slew]": 0.2, "Fv[luff]": 0.1, "Fv[hoist]": 1.0}


def _motion(fs: float, duration: float, hz: float, amp: float):
    """A sine on every joint about its range's centre, ``(t, q, qd, qdd)``."""
    lim = E.get_exciter("crane").limits(DESC)
    t = np.arange(0.0, duration, 1.0 / fs)
    w = 2 * np.pi * hz
    centre = 0.5 * (lim.lower + lim.upper)
    a = amp * 0.5 * (lim.upper - lim.lower)
    phase = np.array([0.0, 1.0, 2.0])
    q = centre + a * np.sin(w * t[:, None] + phase)
    return t, q, a * w * np.cos(w * t[:, None] + phase), -a * w * w * np.sin(w * t[:, None] + phase)


@pytest.mark.parametrize("tau0", [0.0, 0.03])
def test_tau_column_is_minus_the_time_derivative_of_the_model_output(tau0):
    ex = E.get_exciter("crane")
    ds = ex.motion_dataset(*_motion(1000.0, 12.0, 0.3, 0.8), DESC)
    model = Model("crane", EFFECTS, KNOWN)
    col = E.Linearised(model, THETA, tau0).tau_column(ds)
    y0, ok0 = model.predict(ds, {**THETA, "tau": tau0})
    oracle = -np.gradient(y0, ds.t, axis=0)
    ok = ok0 & np.isfinite(col).all(axis=1)
    assert ok.sum() > 0.9 * ds.n
    for c in range(3):
        scale = np.sqrt(np.mean(oracle[ok, c] ** 2))
        assert scale > 0
        assert np.sqrt(np.mean((col[ok, c] - oracle[ok, c]) ** 2)) < 0.02 * scale


def test_design_raises_the_delay_information_over_a_slow_reference():
    ex = E.get_exciter("crane")
    slow = ex.motion_dataset(*_motion(100.0, 60.0, 0.05, 0.3), DESC)
    params = ("tau", "I_tot")
    d = E.design("crane", DESC, params, duration=30.0, seed=1, max_iter=15, before_ds=slow,
                 effects=("joint_viscous_friction",), fixed=KNOWN, values=THETA)
    print(f"condition number of {{tau, I_tot}}: slow reference {d.condition_before:.4g} -> "
          f"designed {d.condition_after:.4g}")
    assert "time_delay" in d.model.effects
    assert d.condition_after < d.condition_before / 3
    # the designed motion's column is the delay's information: it holds on a recomputation with
    # the model at the same linearisation point
    lin = E.Linearised(Model("crane", d.model.effects, KNOWN), THETA, 0.0)
    again = E.condition(lin, ex.motion_dataset(d.t, d.q, d.qd, d.qdd, DESC), params)
    assert again == pytest.approx(d.condition_after, rel=1e-6)
    assert not E.get_exciter("crane").limits(DESC).check(d.q, d.qd, d.qdd)


def test_other_nonlinear_parameters_are_refused():
    with pytest.raises(CablelabError, match="l_c"):
        E.design("crane", DESC, ("l_c",), duration=20.0, max_iter=1)
