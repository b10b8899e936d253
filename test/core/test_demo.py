"""The demo's crane helpers against MuJoCo, and the combined index page."""
from __future__ import annotations

import mujoco
import numpy as np
import pytest
from scipy.optimize import root

from cablelab.description import load_description
from cablelab.plants.crane.model import CraneParams
from cablelab.plants.crane.sim import CraneTruth, build_model, gravity_in_base, set_state
from cablelab import demo
from cablelab.plants.crane import demo as demo_crane


@pytest.fixture(scope="module")
def params():
    import cablelab

    desc = load_description(str(__import__("pathlib").Path(cablelab.__file__).parent / "plants" / "crane" / "data" / "crane.yaml"))
    return CraneParams.from_description(desc)


def slew_torque_at_rest(truth: CraneTruth, alpha: float, beta: float, d: float = 0.6) -> float:
    """Slew torque (N m) that holds the MuJoCo crane at rest with the payload hanging in its
    equilibrium (zero generalised force on both swing joints, found numerically)."""
    model = build_model(truth)
    data = mujoco.MjData(model)

    def state(sw):
        set_state(model, data, [alpha, beta, d, sw[0], sw[1]])
        return data.qfrc_bias.copy()

    sw = root(lambda s: state(s)[2:4], [0.0, 0.0], tol=1e-14).x
    bias = state(sw)
    assert np.abs(bias[2:4]).max() < 1e-10          # really the equilibrium
    return float(bias[0])


def test_tilt_for_rest_torque_gives_002_offset_in_mujoco(params):
    """002 sec. 6.5: the hidden tilt the demo gives the simulator loads the slew joint with -0.2 N m
    at rest at beta = 0.5 rad (MuJoCo's bias force as the independent oracle)."""
    tilt = demo_crane.tilt_for_rest_torque(params.first_moment, params.gravity)
    assert 0.02 < abs(tilt) < 0.1                    # a few degrees, like a non-rigid base
    truth = CraneTruth(params=params, base_tilt=(tilt, 0.0))
    assert slew_torque_at_rest(truth, 0.0, demo_crane.REST_LUFF) == pytest.approx(-0.2, abs=1e-9)
    # an untilted base needs no slew torque at rest
    assert abs(slew_torque_at_rest(CraneTruth(params=params), 0.4, 0.5)) < 1e-12


@pytest.mark.parametrize("alpha,beta", [(0.0, 0.5), (0.7, 0.3), (-2.0, -0.2)])
def test_rest_torque_of_fitted_tilt_matches_mujoco(params, alpha, beta):
    """The rest torque the demo reads off the fitted base_tilt angles (tilt_x = -g_y / g,
    tilt_y = g_x / g) equals the torque MuJoCo needs to hold the tilted crane, for a tilt about
    both axes and any pose."""
    truth = CraneTruth(params=params, base_tilt=(-0.04, 0.03))
    g = gravity_in_base(truth)
    fitted = {"tilt_x": -g[1] / params.gravity, "tilt_y": g[0] / params.gravity}
    assert demo_crane.rest_torque(fitted, params.first_moment, params.gravity, alpha, beta) == pytest.approx(
        slew_torque_at_rest(truth, alpha, beta), abs=1e-9)


def test_index_page_links_both_plants(tmp_path):
    parts = {}
    for name in ("cdpr", "crane"):
        (tmp_path / name).mkdir()
        parts[f"{name} <plant>"] = demo.PartResult(rows=[["q & a", "1.0", "2.0"]],
                                                   bags=[tmp_path / name / "run"],
                                                   report=tmp_path / name / "index.html",
                                                   page=tmp_path / name / "page.html")
    text = open(demo.index_page(tmp_path, parts)).read()
    for name in ("cdpr", "crane"):
        assert f"href='{name}/page.html'" in text and f"href='{name}/index.html'" in text
    assert "&lt;plant&gt;" in text and "q &amp; a" in text      # escaped, relative links


def test_demo_parts_come_from_the_plant_registry():
    """Every plant with a ``demo`` module brings its part and its options; none is named here."""
    names = [p.plant for p in demo.demo_parts()]
    assert names[:2] == ["cdpr", "crane"]
    from cablelab.registry import available_plants

    assert set(names) <= set(available_plants())
    with pytest.raises(SystemExit):
        demo.main(["--skip-nonexistent"])
