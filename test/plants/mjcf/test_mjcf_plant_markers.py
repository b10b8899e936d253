"""The ``mjcf`` plant's 3D view comes from the model's own geoms and tendons.

Oracle: the four-cable camera robot's geometry in closed form. Its carriage (a box on three slide
joints along world x, y, z, at (0, 0, 3) m when the joints are 0) is drawn at (x, y, 3 + z) of the
recorded joints; each cable is drawn from its winch site (fixed in the XML) to the carriage's hook
(the carriage's origin), over its pulley. (The simulator's live 3D view over DDS:
test/core/test_sim_markers_live.py.)"""
from __future__ import annotations

import numpy as np
import pytest

from cablelab.bags import open_bag
from cablelab.markers import CUBE, LINE_LIST
from cablelab.plants.mjcf.examples import CABLECAM
from cablelab.plants.mjcf.sim import Hidden, write_bag
from cablelab.registry import get_plant

CABLES = ["cable_1", "cable_2", "cable_3", "cable_4"]
WINCH = np.array([[-6, -4, 0.2], [6, -4, 0.2], [6, 4, 0.2], [-6, 4, 0.2]], float)
START = np.array([0.0, 0.0, 3.0])


def _carriage_and_cables(markers):
    """The carriage box's position and the four cables' point lists of one frame."""
    boxes = [m for m in markers if m.ns == "geoms" and m.type == CUBE]
    assert len(boxes) == 1, [m.ns for m in markers]
    cables = sorted((m for m in markers if m.ns == "tendons" and m.type == LINE_LIST), key=lambda m: m.id)
    assert len(cables) == 4
    return np.array(boxes[0].position), [np.asarray(m.points, float) for m in cables]


@pytest.fixture(scope="module")
def cam_bag(tmp_path_factory):
    return write_bag(tmp_path_factory.mktemp("cam") / "cam", CABLECAM.read_text(),
                     Hidden(payload=("carriage", 1.5, (0, 0, -0.1))), duration=3.0, seed=2,
                     payload_body="carriage", tendons=CABLES)


def test_recorded_run_drawn_at_the_recorded_joints(cam_bag):
    bag = open_bag(cam_bag)
    t, frames = get_plant("mjcf").markers(bag, bag.description)
    js = bag.joint_state("/mjcf/joint_states", ["x", "y", "z"])
    assert 25 <= len(frames) / (js.t[-1] - js.t[0]) <= 35            # about 30 Hz
    layout = [(m.ns, m.id, m.type, 0 if m.points is None else len(m.points)) for m in frames[0]]
    assert all([(m.ns, m.id, m.type, 0 if m.points is None else len(m.points)) for m in f] == layout for f in frames)
    moved = 0.0
    for tk, frame in zip(t, frames):
        k = int(np.argmin(np.abs(js.t - tk)))
        assert js.t[k] == pytest.approx(tk, abs=1e-9)
        carriage, cables = _carriage_and_cables(frame)
        want = START + js.position[k]
        np.testing.assert_allclose(carriage, want, atol=1e-9)
        for i, pts in enumerate(cables):
            np.testing.assert_allclose(pts[0], WINCH[i], atol=1e-9)       # from its winch
            np.testing.assert_allclose(pts[-1], want, atol=1e-9)          # to the hook
            assert pts[:, 2].max() > 5.5                                   # over the mast-top pulley
        moved = max(moved, float(np.linalg.norm(js.position[k])))
    assert moved > 0.01


def test_cables_coloured_by_the_recorded_tensions(cam_bag):
    """The colour scale runs from green (slack) to red (the largest tension drawn, doubled): a
    cable carrying more has more red and less green."""
    bag = open_bag(cam_bag)
    t, frames = get_plant("mjcf").markers(bag, bag.description)
    ten = bag.joint_state("/mjcf/cable_tensions", CABLES)
    cables = sorted((m for m in frames[-1] if m.ns == "tendons"), key=lambda m: m.id)
    tension = ten.effort[np.searchsorted(ten.t, t[-1], side="right") - 1]
    assert np.ptp(tension) > 1.0, tension                  # the four cables carry different loads
    red = np.array([m.colour[0] for m in cables])
    order = np.argsort(tension)
    assert np.all(np.diff(red[order]) >= -1e-12), (tension, red)
