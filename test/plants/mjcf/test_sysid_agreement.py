"""The mjcf plant's linear fit (``identify``: MuJoCo inverse dynamics, one least-squares solve)
against an independent oracle, :mod:`mujoco.sysid` (simulation error: Gauss-Newton over rollouts
of the same record, ``plants/mjcf/rollout_fit.py``), on a short bag of the example arm recorded
from a separate forward simulation holding joint viscous friction and a payload on the tool.
Both must give the truth within 3 % and the same values within their 95 % intervals (sysid's
widened for its rollout residual's autocorrelation, as cablelab widens its own: the intervals
mujoco.sysid computes assume a white residual, which a rollout's drifting position error is not)."""
import pytest

from cablelab import workbench
from cablelab.bags import open_bag
from cablelab.plants.mjcf.examples import ARM3, text
from cablelab.plants.mjcf.rollout_fit import sysid_fit
from cablelab.plants.mjcf.sim import Hidden, write_bag

DAMPING = {"base_yaw": 0.8, "shoulder": 1.5, "elbow": 0.6}
PAYLOAD = ("tool", 1.5, (0.04, 0.0, 0.0))
EFFECTS = ("payload_mass", "joint_viscous_friction")


def test_linear_fit_and_mujoco_sysid_agree_within_their_intervals(tmp_path):
    bag = write_bag(tmp_path / "arm3", text(ARM3), Hidden(payload=PAYLOAD, damping=DAMPING),
                    duration=3.0, seed=3, payload_body="tool")
    plant, desc, ds = workbench.load(bag)
    rep = workbench.identify_report(ds, workbench.build_model(plant, desc, list(EFFECTS)), folds=0)
    lin = {k: (v["value"], 1.96 * v["stderr"]) for k, v in rep.params.items()}
    js = open_bag(bag).joint_state("/mjcf/joint_states")
    fit = sysid_fit(desc.mjcf.model, js.t, js.position, js.effort, list(js.names),
                    payload_body="tool", window=0.5,
                    effects=("joint_viscous_friction", "payload_mass"))
    truth = {**{f"Fv[{j}]": v for j, v in DAMPING.items()}, "m": PAYLOAD[1], "com_x": PAYLOAD[2][0]}
    for name, value in truth.items():
        (a, ca), b, cb = lin[name], fit.values[name], fit.ci95_inflated[name]
        assert abs(a - b) <= (ca**2 + cb**2) ** 0.5, (name, a, ca, b, cb)
        assert a == pytest.approx(value, rel=0.03) and b == pytest.approx(value, rel=0.03), (name, a, b)
