"""The mjcf simulator node's ROS-free helpers: the publishing period in whole physics steps and
the hidden payload at the payload body's centre of mass (oracle: the compiled model's body_ipos
and the truth model's total mass)."""
import numpy as np
import pytest

from cablelab.description import load_description
from cablelab.errors import CablelabError
from cablelab.plants.mjcf.sim import default_description, hidden_payload, publish_period, truth_model


@pytest.mark.parametrize("step, rate, want", [(0.002, 250.0, 0.004), (0.002, 150.0, 0.006), (0.002, 500.0, 0.002), (0.002, 1e4, 0.002),
                                               (0.001, 333.0, 0.003), (0.002, float("nan"), 0.002)])
def test_publish_period_is_whole_physics_steps(step, rate, want):
    p = publish_period(step, rate)
    assert p == pytest.approx(want) and round(p / step) == pytest.approx(p / step)


def test_hidden_payload_sits_at_the_bodys_centre_of_mass():
    sec = load_description(default_description()).mjcf
    assert hidden_payload(sec, 0.0) is None
    h = hidden_payload(sec, 1.2)
    model = sec.compiled()
    body = [model.body(i).name for i in range(model.nbody)].index("tool")
    assert h.payload[0] == "tool" and h.payload[1] == 1.2
    np.testing.assert_allclose(h.payload[2], model.body_ipos[body])
    truth = truth_model(sec.model, h)
    assert truth.body_mass.sum() == pytest.approx(model.body_mass.sum() + 1.2)


def test_a_payload_mass_without_a_payload_body_is_a_one_line_error():
    from cablelab.plants.mjcf.examples import ARM3, text
    from cablelab.plants.mjcf.sim import description_yaml

    sec = load_description(description_yaml(text(ARM3))).mjcf
    with pytest.raises(CablelabError, match="payload_mass needs mjcf.payload_body"):
        hidden_payload(sec, 1.0)
