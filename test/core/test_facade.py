"""The public facade (``import cablelab``): a diagnosis scripted with its names only finds the
effect hidden in a simulated recording, with the simulated value."""
import importlib
import os
import subprocess
import sys

import pytest

import cablelab
from cablelab.bags import BagWriter
from cablelab.plants.axis.sim import AxisTruth
from cablelab.plants.axis.truth import simulate_axis

DESC = "plant: axis\nname: facade slide\naxis:\n  joint_type: prismatic\n  inertia: 2.0\n"
#: the simulated truth: the nominal model (inertia + viscous) lacks the Coulomb friction FC
M, FV, FC = 2.0, 5.0, 1.0


@pytest.fixture(scope="module")
def bag(tmp_path_factory):
    run = simulate_axis(cablelab.load_description(DESC), AxisTruth(inertia=M, viscous=FV, coulomb=FC),
                        duration=12.0, fs=250.0, amplitude=0.3, noise_effort=0.05, seed=4)
    path = str(tmp_path_factory.mktemp("facade") / "axis")
    with BagWriter(path) as w:
        w.write_description(DESC)
        w.write_joint_states("/axis/joint_states", run.t, ["joint"], run.q[:, None], None,
                             run.effort[:, None])
    return path


def test_hidden_coulomb_friction_ranks_first_through_the_facade(bag, tmp_path, monkeypatch):
    assert "axis" in cablelab.available_plants()
    plant, desc, ds = cablelab.load(bag)
    assert isinstance(desc, cablelab.Description) and isinstance(ds, cablelab.Dataset)
    model = cablelab.build_model(plant, desc)
    assert "joint_coulomb_friction" not in model.effects
    d = cablelab.find_missing_effects(ds, model, plant.candidates(desc), folds=4, greedy_mode=True)
    assert isinstance(d, cablelab.Diagnosis)
    top = d.ranking[0]
    assert isinstance(top, cablelab.Candidate)
    assert top.effect == "joint_coulomb_friction" and top.significant
    assert top.params["Fc"] == pytest.approx(FC, rel=0.05)          # the simulated value
    assert top.error_after < 0.5 * top.error_before
    assert [s.added for s in d.greedy[1:]] == ["joint_coulomb_friction"]
    assert isinstance(d.final, cablelab.Step) and d.final.params["M"] == pytest.approx(M, rel=0.02)
    # the JSON the command prints is the same object's
    assert d.to_json()["ranking"][0]["effect"] == "joint_coulomb_friction"

    full = model.with_effect("joint_coulomb_friction")
    before, after = cablelab.compare(ds, model), cablelab.compare(ds, full)
    assert isinstance(after, cablelab.Comparison)
    assert after.channels["joint"]["nrmse"] < 0.5 * before.channels["joint"]["nrmse"]
    ident = cablelab.identify_report(ds, full, folds=0)
    assert isinstance(ident, cablelab.IdentifyReport) and ident.quality.cv_nrmse is None
    fc = ident.params["Fc"]
    assert fc["value"] == pytest.approx(FC, rel=0.05) and 0 < fc["stderr"] < 0.05 * FC

    # the report draws the diagnosis it is given: no fit of its own
    from cablelab.fit import identification as fitting

    def no_fit(*args, **kwargs):
        raise AssertionError("the report refitted a model")

    monkeypatch.setattr(fitting, "_identify_once", no_fit)
    page = cablelab.build_report(ds, d, str(tmp_path / "report"))
    assert isinstance(page, cablelab.ReportPage) and os.path.isfile(page.index)
    assert "joint_coulomb_friction" in open(page.index, encoding="utf-8").read()


def test_every_public_name_resolves_and_none_shadows_a_package():
    for name in cablelab.__all__:
        assert getattr(cablelab, name) is not None, name
    importlib.import_module("cablelab.diagnose")
    importlib.import_module("cablelab.report")
    assert cablelab.diagnose.__name__ == "cablelab.diagnose"     # the package, not a function
    assert cablelab.report.__name__ == "cablelab.report"
    with pytest.raises(AttributeError, match="no attribute 'nonexistent'"):
        cablelab.nonexistent


def test_import_cablelab_stays_light():
    """The nodes and the command line import cablelab: the workbench loads on first use only."""
    code = ("import sys, cablelab; heavy = [m for m in ('cablelab.workbench', 'cablelab.diagnose', "
            "'scipy') if m in sys.modules]; print(heavy)")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    assert out.stdout.strip() == "[]", out.stdout
