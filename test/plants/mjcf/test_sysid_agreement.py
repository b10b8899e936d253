"""The mjcf plant's linear fit (``identify``: MuJoCo inverse dynamics, one least-squares solve)
against an independent oracle, :mod:`mujoco.sysid` (simulation error: Gauss-Newton over RK4
rollouts of the same record, ``plants/mjcf/rollout_fit.py``), on a bag of the example arm made by
the generator of ``bench/bench_mjcf_sysid.py`` (8 s instead of 12): a separate forward
simulation, close to continuous time, holding joint viscous friction, armature and a payload on
the tool.

All ten parameters: the linear fit's 95 % interval holds the truth; the two values agree within
their combined intervals at a family-wise 95 % over the ten (Bonferroni: z = 2.81 instead of
1.96; sysid's intervals clustered by window, a rollout's position error drifting under the
measured efforts' noise); both values near the truth. sysid's values lean high (its noisy
inputs: the noise-driven wander of a rollout shrinks as inertia and damping grow), which is why
the agreement is the pair's, not each interval holding the other's value."""
import numpy as np
import pytest
from scipy.stats import norm

from cablelab import workbench
from cablelab.bags import open_bag
from cablelab.plants.mjcf.examples import ARM3, text
from cablelab.plants.mjcf.rollout_fit import sysid_fit, window_robust_ci
from cablelab.plants.mjcf.sim import Hidden, record, truth_model, write_bag

DAMPING = {"base_yaw": 0.8, "shoulder": 1.5, "elbow": 0.6}
ARMATURE = {"base_yaw": 0.05, "shoulder": 0.08, "elbow": 0.03}
PAYLOAD = ("tool", 1.5, (0.04, 0.0, 0.0))
EFFECTS = ("payload_mass", "joint_viscous_friction", "joint_armature")
SUBSTEPS = 10                    # as the bench: RK4 at 0.2 ms, one sample per 2 ms
Z_FAMILY = float(norm.ppf(1 - 0.05 / (2 * 10)))    # two-sided, ten parameters: 2.81


def test_linear_fit_and_mujoco_sysid_agree_within_their_intervals(tmp_path):
    bag = write_bag(tmp_path / "arm3", text(ARM3),
                    Hidden(payload=PAYLOAD, damping=DAMPING, armature=ARMATURE),
                    duration=8.0, seed=3, payload_body="tool", substeps=SUBSTEPS)
    plant, desc, ds = workbench.load(bag)
    rep = workbench.identify_report(ds, workbench.build_model(plant, desc, list(EFFECTS)), folds=0)
    lin = {k: (v["value"], 1.96 * v["stderr"]) for k, v in rep.params.items()}
    js = open_bag(bag).joint_state("/mjcf/joint_states")
    fit = sysid_fit(desc.mjcf.model, js.t, js.position, js.effort, list(js.names),
                    payload_body="tool", window=0.25)
    truth = {**{f"Fv[{j}]": v for j, v in DAMPING.items()},
             **{f"armature[{j}]": v for j, v in ARMATURE.items()},
             "m": PAYLOAD[1], "com_x": PAYLOAD[2][0], "com_y": PAYLOAD[2][1], "com_z": PAYLOAD[2][2]}
    joint = Z_FAMILY / 1.96                      # 95 % half-widths -> family-wise over ten
    for name, value in truth.items():
        (a, ca), b, cb = lin[name], fit.values[name], fit.ci95_windows[name]
        assert abs(a - b) <= joint * (ca**2 + cb**2) ** 0.5, (name, a, ca, b, cb)
        assert abs(a - value) <= ca, (name, a, ca, value)
        if value:
            assert a == pytest.approx(value, rel=0.03) and b == pytest.approx(value, rel=0.05), (name, a, b)
        else:                     # a centre-of-mass offset of zero, weakly excited sideways
            assert abs(a) < 2e-3 and abs(b) <= cb, (name, a, b, cb)


def test_window_clustered_intervals_match_the_spread_of_window_means():
    """Oracle: the mean of W windows, each an AR(1) series (strongly correlated within a window,
    independent between them), fitted as a one-parameter least squares; its clustered interval
    against the closed-form standard error of the mean of W independent window means, and the
    white-residual interval far narrower."""
    rng = np.random.default_rng(0)
    W, n, rho = 400, 50, 0.95
    e = rng.normal(size=(W, n))
    x = np.empty((W, n))
    x[:, 0] = e[:, 0] / np.sqrt(1 - rho**2)
    for i in range(1, n):                      # AR(1) per window, vectorised over the windows
        x[:, i] = rho * x[:, i - 1] + e[:, i]
    r = x - x.mean()                           # residuals of the fitted mean
    jac = np.ones((W * n, 1))
    ci = window_robust_ci(list(r), jac)[0]
    se_means = x.mean(axis=1).std(ddof=1) / np.sqrt(W)
    assert ci == pytest.approx(1.96 * se_means, rel=0.02)
    white = 1.96 * r.std() / np.sqrt(W * n)
    assert ci > 3 * white


def test_sysid_rollouts_of_a_noise_free_continuous_record_are_exact():
    """Without sensor noise, the oracle's discretisation alone: RK4 rollouts at the record's
    2 ms with each step's mean effort as control, against a truth stepped at 0.2 ms. Holding each
    sample's effort instead would delay the torque by half a step."""
    hidden = Hidden(payload=PAYLOAD, damping=DAMPING, armature=ARMATURE)
    model = truth_model(text(ARM3), hidden, substeps=SUBSTEPS)
    t, q, effort, joints = record(model, hidden, duration=4.0, seed=3, encoder_bits=40,
                                  effort_noise=0.0, effort_quantum=1e-12, substeps=SUBSTEPS)
    fit = sysid_fit(text(ARM3), t, q, effort, joints, payload_body="tool", window=0.5)
    truth = {**{f"Fv[{j}]": v for j, v in DAMPING.items()},
             **{f"armature[{j}]": v for j, v in ARMATURE.items()}, "m": PAYLOAD[1], "com_x": PAYLOAD[2][0]}
    for name, value in truth.items():
        assert fit.values[name] == pytest.approx(value, rel=0.01), (name, fit.values[name])
    assert abs(fit.values["com_y"]) < 5e-4 and abs(fit.values["com_z"]) < 5e-4
