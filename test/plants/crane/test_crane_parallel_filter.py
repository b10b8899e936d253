"""The crane dataset's parallel filter (``--crane-filter parallel``): derivatives at fs / 10, the
efforts and every regressor column low-passed at 3 Hz alike, so the identification equations
stay exact where the payload's swing puts content near the cut-off; the default filters the
positions alone at 3 Hz.

Oracle: the MuJoCo crane (plants/crane/sim.py) without noise, and the model evaluated at the
simulator's own parameters (nothing fitted): its prediction must match the recorded efforts."""
from functools import partial

import numpy as np

from cablelab.model import Model
from cablelab.plant_interface import DatasetOptions
from cablelab.plants.crane import dataset as CD
from cablelab.plants.crane import plant as C
from cablelab.plants.crane.dataset import CRANE_CUTOFF_HZ
from cablelab.plants.crane.model import CraneParams
from cablelab.plants.crane.options import CraneOptions
from cablelab.plants.crane.sim import CraneTruth, reference_trajectory, simulate
from cablelab.description import load_description

DESC = load_description(C.__file__.replace("plant.py", "data/crane.yaml"))
P = CraneParams.from_description(DESC)

TRUE = {"I_tot": P.slew_inertia, "I_b": P.luff_inertia, "m": P.payload_mass, "m_b": P.boom_mass,
        "m_c": P.counterbalance_mass, "l_c": P.counterbalance_distance}


def _relative_model_error(options=None):
    """Per channel: rms(recorded - model at the true parameters) / rms(recorded) on valid samples."""
    r = simulate(CraneTruth(params=P), 40.0, decimate=10, seed=4,
                 reference=partial(reference_trajectory, base_freq=0.2, seed=4))
    ds = CD.dataset_from_arrays(r.t, r.q[:, :3], r.effort, r.t, r.tip, r.payload, DESC, options)
    phi, cols, known = Model("crane", C.baseline(DESC), TRUE).regressor(ds)
    assert not cols                                   # every parameter at its true value
    ok = ds.valid
    res = ds.y[ok] - known[ok]
    return ds, np.sqrt(np.mean(res ** 2, axis=0)) / np.sqrt(np.mean(ds.y[ok] ** 2, axis=0))


def test_parallel_filter_keeps_the_equations_exact():
    ds, err = _relative_model_error(DatasetOptions(plant=CraneOptions(crane_filter="parallel")))
    assert ds.parallel_hz == CRANE_CUTOFF_HZ
    assert np.all(err < 0.01), err
    # the default, the positions alone filtered at the same cut-off: the regressor loses the
    # swing's content near 3 Hz that the efforts keep (moves at 0.2-1 Hz: 4-24 % of the efforts)
    ds_pos, err_pos = _relative_model_error()
    assert not ds_pos.parallel_hz
    assert err_pos.max() > 10 * err.max(), (err_pos, err)


def test_crane_filter_is_a_plant_option():
    opts = DatasetOptions.build(C.PLANT, {"crane_filter": "parallel"})
    assert opts.plant_options(CraneOptions).crane_filter == "parallel"
    assert CraneOptions().crane_filter == "positions"
