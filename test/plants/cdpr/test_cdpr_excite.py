"""``cablelab excite`` on the CDPR: a recording near one pose confounds the dynamometer offsets
b_i with the payload's mass and centre of mass (W(p) b is nearly constant, like the weight); the
designed platform motion stays in the workspace box with every cable taut when the MuJoCo CAROCA
(plants/cdpr/sim.py) tracks it, the condition number of the named parameters falls, and the fit
on the simulated designed run separates them: mass and offsets come back.

Oracle: the MuJoCo CDPR with a known payload and known dynamometer offsets."""
import json

import numpy as np
import pytest

from cablelab.cli import main
from cablelab.diagnose.identifiability import correlations
from cablelab.excite import get_exciter, read_reference
from cablelab.fit import identify
from cablelab.plants.cdpr.control import PdffConfig
from cablelab.plants.cdpr.sim import (CdprTruth, default_description, default_description_path, simulate,
                                      write_run_bag)
from cablelab.plants.cdpr.topics import REFERENCE
from cablelab.plants.cdpr.trajectory import Trajectory
from cablelab.workbench import build_model, load

BIAS = (40.0, -30.0, 25.0, -20.0, 35.0, -45.0, 15.0, -10.0)
TRUTH = CdprTruth(payload_mass=122.0, payload_com=(0.1, 0.05, -0.6), tension_bias=BIAS,
                  tension_noise=2.0)
PARAMS = [f"b[winch_{i}]" for i in range(1, 9)] + ["m", "mx", "my"]
RATE = 100.0


def _near_one_pose(duration):
    """A slow 5 cm sway in x around the workspace centre (what a short test move records)."""
    t = np.arange(int(duration * RATE) + 1) / RATE
    w = 2 * np.pi / duration
    p = np.zeros((len(t), 3))
    p[:, 2] = 0.9
    p[:, 0] = 0.05 * (1 - np.cos(w * t))
    v, a = np.zeros_like(p), np.zeros_like(p)
    v[:, 0], a[:, 0] = 0.05 * w * np.sin(w * t), 0.05 * w * w * np.cos(w * t)
    return Trajectory(t, p, v, a)


@pytest.fixture(scope="module")
def confounded(tmp_path_factory):
    desc = default_description()
    path = tmp_path_factory.mktemp("cdpr_excite") / "near_one_pose"
    write_run_bag(simulate(desc, TRUTH, reference=_near_one_pose(30.0), rate=RATE), path)
    return str(path)


def test_designed_motion_keeps_cables_taut_and_separates_offsets_from_mass(confounded, tmp_path, capsys):
    plant, desc, ds = load(confounded)
    # the fit's model: the nominal one, the offsets and the platform's inertia (the designed
    # motion accelerates the platform)
    model = build_model(plant, desc, ["tension_sensor_offset", "platform_inertia"])
    ref = tmp_path / "ref"
    assert main(["excite", confounded, "--params", ",".join(PARAMS), "--duration", "60",
                 "-o", str(ref), "--json"]) == 0
    out = json.loads(capsys.readouterr().out)
    assert out["params"] == PARAMS and out["duration"] == pytest.approx(60.0)
    assert out["condition_after"] < out["condition_before"] / 10
    # the platform tracks the designed reference: inside the box, every cable taut
    lim = get_exciter("cdpr").limits(desc)
    play = read_reference(ref, REFERENCE, lim.joints)
    t = np.arange(int(60.0 * RATE) + 1) / RATE
    q, qd, qdd = play(t)
    assert lim.check(q, qd, qdd) == []
    run = simulate(desc, TRUTH, reference=Trajectory(t, q, qd, qdd), rate=RATE)
    assert not run.slack.any()
    assert run.true_tension.min() > PdffConfig().min_tension
    assert np.all(run.true_position >= lim.lower - 0.02) and np.all(run.true_position <= lim.upper + 0.02)
    # identified on the designed run: separated (before: m and the offsets correlate at 0.999 and
    # the mass's standard error is hundreds of kg) and back: the total mass, its centre of mass
    # (first moments within 1.5 kg m, i.e. 3 mm) and every offset (truth spread +-45 N)
    before = identify(model, ds)
    assert before.stderr["m"] > 50.0 and _max_corr(before) > 0.99
    write_run_bag(run, tmp_path / "designed")
    plant, desc, ds2 = load(tmp_path / "designed")
    r = identify(model, ds2)
    assert not r.held, r.held
    assert _max_corr(r) < 0.6 and r.stderr["m"] < 1.0
    truth = TRUTH.resolved(desc)
    assert r.params["m"] == pytest.approx(truth.total_mass, rel=0.005)
    for k, c in (("mx", truth.total_com[0]), ("my", truth.total_com[1])):
        assert r.params[k] == pytest.approx(truth.total_mass * c, abs=1.5)
    for i, b in enumerate(BIAS, start=1):
        assert r.params[f"b[winch_{i}]"] == pytest.approx(b, abs=15.0)


def _max_corr(r) -> float:
    """Largest |correlation| between the mass and a dynamometer offset in a fit."""
    names, corr = correlations(r)
    return max(abs(corr[names.index("m"), names.index(f"b[winch_{i}]")]) for i in range(1, 9))


def test_designed_reference_starts_where_the_simulator_starts():
    """The design begins at rest at point A of the pick-and-place (where ``cable_sim_node --plant
    cdpr`` starts the platform) and reaches the box's centre by the lead-in, as fast as the limits
    allow: positions, speeds and accelerations continuous (each the derivative of the one
    before), within every limit, in the requested duration."""
    from cablelab.excite import FADE_S, design
    from cablelab.plants.cdpr.trajectory import CAROCA_WAYPOINTS

    desc = default_description()
    d = design("cdpr", desc, ["b[winch_1]", "m"], duration=20.0, max_iter=2)
    lim = d.limits
    assert d.t[-1] == pytest.approx(20.0) and 0 < d.lead_in < 20.0 - 8.0
    np.testing.assert_allclose(d.q[0], CAROCA_WAYPOINTS[0], atol=1e-12)
    assert np.abs(d.qd[0]).max() < 1e-12 and np.abs(d.qdd[0]).max() < 1e-12
    k = int(round(d.lead_in * 100))
    np.testing.assert_allclose(d.q[k], 0.5 * (lim.lower + lim.upper), atol=1e-9)   # at rest at the centre
    assert np.abs(d.qd[k]).max() < 1e-9 and np.abs(d.qdd[k]).max() < 1e-9
    assert lim.check(d.q, d.qd, d.qdd) == []
    # the fastest move: one axis reaches its speed or acceleration limit (within a sample)
    peak = np.max(np.maximum(np.abs(d.qd[:k]) / lim.speed, np.abs(d.qdd[:k]) / lim.accel))
    assert 0.98 < peak <= 1.0 + 1e-9
    # smooth through the junction: central differences of q and qd give qd and qdd (away from
    # the Fourier window's corners FADE_S after the lead-in and before the end, where the jerk
    # jumps and the central difference of qd is off by O(dt))
    dt = d.t[1] - d.t[0]
    np.testing.assert_allclose(np.gradient(d.q, dt, axis=0)[1:-1], d.qd[1:-1], atol=2e-4)
    smooth = (np.abs(d.t - d.lead_in - FADE_S) > 0.015) & (np.abs(d.t - d.t[-1] + FADE_S) > 0.015)
    smooth[[0, -1]] = False
    np.testing.assert_allclose(np.gradient(d.qd, dt, axis=0)[smooth], d.qdd[smooth], atol=2e-3)


def test_too_short_for_the_lead_in_is_a_one_line_error(tmp_path, capsys):
    assert main(["excite", "--description", default_description_path(), "--params", "b[winch_1],m",
                 "--duration", "10", "-o", str(tmp_path / "ref")]) != 0
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "--duration 10" in err[0] and "from the machine's start" in err[0], err


@pytest.mark.parametrize("base_hz", [0.05, 0.1])
def test_tune_chooses_the_family_by_the_named_parameters(monkeypatch, base_hz):
    """``Exciter.tune`` sets the Fourier family per design: with one harmonic of ``base_hz`` the
    designed motion after the lead-in is that sine under the fade window, so its speed's spectrum
    peaks at ``base_hz`` (oracle: the FFT of the written reference); the CDPR's own choice keeps
    the 20 s, five-harmonic family for a delay and the 60 s one otherwise."""
    import dataclasses

    from cablelab import excite as E

    ex = get_exciter("cdpr")
    assert ex.tune(("tau", "m_a")) == {"base_hz": 0.05, "harmonics": 5} and ex.tune(("m",)) == {}
    monkeypatch.setitem(E._EXCITERS, "cdpr", dataclasses.replace(
        ex, tune=lambda params: {"base_hz": base_hz, "harmonics": 1}))
    d = E.design("cdpr", default_description(), ["b[winch_1]", "m"], duration=60.0, max_iter=2)
    k = int(round(d.lead_in * 100))
    v = d.qd[k:] - d.qd[k:].mean(axis=0)
    spec = np.abs(np.fft.rfft(v, axis=0)).sum(axis=1)
    f = np.fft.rfftfreq(len(v), 0.01)
    assert f[np.argmax(spec)] == pytest.approx(base_hz, abs=0.02)
