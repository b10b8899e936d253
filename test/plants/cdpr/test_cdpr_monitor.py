"""The live model monitor (``model_monitor --plant cdpr``) and its ROS-free core.

Proof: a simulated CDPR run (simulator + monitor + recorder as real processes over DDS; the
platform held at the reference pose A by its winch brakes, so the physics does not depend on how
loaded the machine is) where 100 kg is put on the platform at t = 30 s raises WARN (or ERROR) on
/diagnostics naming the force channel within 2 s of the change (stamps: sim time); the same run
without the change raises none. Core: the band check against hand-made residuals (hold and clear times exact), and
the monitor on the recorded reference run: no alarm, and the residual it publishes equals the
batch workbench's (the same dataset and prediction code on the same window)."""
import json
import sys
import time

import numpy as np
import pytest

from cablelab.monitor import ERROR, WARN, BandCheck


def test_band_check_holds_then_clears():
    t = np.arange(0, 10, 0.01)
    r = np.zeros((len(t), 2))
    r[(t >= 3.0) & (t < 6.0), 0] = 5.0          # channel a out from 3 to 6 s (band 1)
    r[(t >= 7.0) & (t < 7.3), 1] = 5.0          # channel b out for 0.3 s only: no alarm
    bc = BandCheck(("a", "b"), [1.0, 1.0], hold=0.5, error_factor=3.0)
    raised = []
    for k in range(0, len(t), 7):                 # in uneven batches, as the evaluations come
        raised += bc.push(t[k:k + 7], r[k:k + 7])
        if abs(t[min(k + 6, len(t) - 1)] - 5.0) < 0.04:
            assert bc.level() == ERROR             # 5 > 3 bands
    assert [(a.channel, a.level) for a in raised] == [("a", ERROR)]
    assert raised[0].since == pytest.approx(3.0) and raised[0].raised == pytest.approx(3.5)
    assert bc.level() == 0 and not bc.alarms       # back inside for 0.5 s after 6 s
    bc2 = BandCheck(("a",), [1.0], hold=0.5)
    assert [a.level for a in bc2.push(t, np.where((t > 1) & (t < 2), 2.0, 0.0)[:, None])] == [WARN]


def _feed(bag, mon, period_ns=250_000_000, until=None):
    msgs = []
    for tp in mon.topics:
        tn, raws = bag.raw(tp)
        msgs += [(int(a), tp, r) for a, r in zip(tn, raws)]
    msgs.sort(key=lambda m: m[0])
    nxt, out = msgs[0][0] + period_ns, []
    for ns, tp, r in msgs:
        mon.add(tp, r)
        if ns >= nxt:
            nxt += period_ns
            s = mon.step()
            if s is not None:
                out.append(s)
    return out


def test_monitor_on_the_reference_run_fits_and_matches_the_batch_prediction():
    from pathlib import Path

    from cablelab.bags import open_bag
    from cablelab.conditioning import Conditioning
    from cablelab.model import Model
    from cablelab.plant_interface import DatasetOptions
    from cablelab.plants.cdpr.options import CdprOptions
    from cablelab.monitor import MonitorModel, ResidualMonitor
    from cablelab.registry import get_plant

    root = Path(__file__).resolve().parents[3]
    bag = open_bag(root / "bags" / "cdpr_m1_reference")
    mon = ResidualMonitor("cdpr", bag.description, MonitorModel(()), calibrate=10.0)
    out = _feed(bag, mon)
    assert mon.calibrated and not mon.check.history, [a.line() for a in mon.check.history]
    t = np.concatenate([s.t for s in out])
    assert np.all(np.diff(t) > 0) and t[-1] - t[0] > 25.0        # every sample once, in order
    # the calibrated mass: the true moving mass (366 + 122 kg) within 2 %
    assert mon.params["m"] == pytest.approx(488.0, rel=0.02)
    # batch oracle: the workbench's dataset of the whole recording with the same parameters
    plant = get_plant("cdpr")
    ds = plant.dataset(bag, bag.description, DatasetOptions(Conditioning(), plant=CdprOptions("dynamometer")))
    y_hat, valid = Model("cdpr", tuple(plant.baseline(bag.description))).predict(ds, mon.params)
    pred = np.concatenate([s.prediction for s in out])
    j = np.searchsorted(ds.t, t)
    assert np.abs(ds.t[j] - t).max() < 1e-9
    # the live window's filter edges differ from the whole record's: compare the prediction,
    # which depends on the (unfiltered) reference pose and the parameters only
    np.testing.assert_allclose(pred, y_hat[j], rtol=1e-9, atol=1e-6)


def _run(launcher, tmp_path, change: bool) -> list:
    """sim + monitor + recorder of /diagnostics; returns the monitor's statuses
    [(level, message, values)]."""
    from cablelab.bags import open_bag

    bag_dir = tmp_path / ("change" if change else "steady")
    launcher.start("recorder", [sys.executable, "-m", "cablelab.cli", "record", "-o", bag_dir, "--quiet",
                                "--topics", "/diagnostics,/cdpr/model/residual"])
    launcher.start("monitor", [sys.executable, "-m", "payload_estimator.monitor", "--plant", "cdpr",
                               "--ros-args", "-p", "calibrate:=10.0", "-p", "hold:=0.5"])
    launcher.wait_for_topics({"/diagnostics": 2}, timeout=90)
    params = {"real_time": True, "rate": 100.0, "duration": 36.0, "payload_mass": 0.0, "settle": 1000.0,
              "wait_for_subscribers": 2, "markers_rate": 0.0}
    if change:
        params.update({"mass_change": 100.0, "mass_change_time": 30.0})
    launcher.node("sim", "cable_sim_node", "cdpr", params)
    deadline = time.monotonic() + 240
    while launcher.procs["sim"].alive() and time.monotonic() < deadline:
        time.sleep(0.5)
    assert not launcher.procs["sim"].alive(), "the simulator did not finish 36 s"
    time.sleep(5.0)                                 # the monitor works through its last window
    launcher.stop_all()
    bag = open_bag(bag_dir)
    ts = __import__("cablelab.cdr", fromlist=["typestore"]).typestore()
    out = []
    for raw in bag.raw("/diagnostics")[1]:
        msg = ts.deserialize_cdr(raw, "diagnostic_msgs/msg/DiagnosticArray")
        for st in msg.status:
            if st.name == "model_monitor":
                out.append((int(st.level), st.message, {kv.key: kv.value for kv in st.values}))
    assert bag.counts.get("/cdpr/model/residual", 0) > 1000     # the residual was published
    return out


def test_monitor_warns_within_2_s_of_a_100_kg_payload_change(launcher, tmp_path):
    statuses = _run(launcher, tmp_path, change=True)
    assert any(v.get("band Fz") for _, _, v in statuses), "the monitor never calibrated"
    alarms = [(lvl, msg, v) for lvl, msg, v in statuses if lvl >= 1 and "alarm Fz raised at s" in v]
    assert alarms, [s for s in statuses[-2:]]
    lvl, msg, v = alarms[0]
    raised = float(v["alarm Fz raised at s"])
    assert 30.0 <= float(v["alarm Fz since s"]) and raised <= 32.0, v
    assert "Fz" in msg and "outside its band" in msg
    since = [float(val) for _, _, v in statuses for k, val in v.items() if k.endswith(" since s")]
    assert min(since) >= 30.0, "an alarm before the change"


def test_monitor_stays_quiet_without_a_change(launcher, tmp_path):
    statuses = _run(launcher, tmp_path, change=False)
    assert any(v.get("band Fz") for _, _, v in statuses), "the monitor never calibrated"
    alarms = [s for s in statuses if any(k.startswith("alarm ") for k in s[2])]
    assert not alarms, alarms[:2]
    assert statuses[-1][2]["alarms raised"] == "0"
