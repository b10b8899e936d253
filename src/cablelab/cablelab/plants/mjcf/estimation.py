"""Payload mass and centre of mass from a window of joint efforts (and tensions): the least
squares of ``payload_mass``'s MuJoCo columns against what the model's own inverse dynamics
leaves unexplained (ROS-free; the live estimator node runs it on a sliding window)."""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ...conditioning import Conditioning
from ...errors import CablelabError
from ...model import KNOWN_OUTPUT
from ...plant_interface import DatasetOptions
from .dataset import dataset_from_arrays


@dataclass(frozen=True)
class PayloadEstimate:
    """m (kg) added to ``payload_body``, its centre of mass (m, body frame), samples used."""

    m: float
    com: np.ndarray
    samples: int


def payload_estimate(t, q, effort, description, *, tension=None, driven=None,
                     border: int = 20) -> PayloadEstimate:
    """Fit the payload on ``description.mjcf.payload_body`` to a record (arrays in dof order,
    as :func:`.dataset.dataset_from_arrays`). A first moment the motion does not excite stays at
    the body's own centre of mass (minimum-norm solution).

    Raises:
        CablelabError: no ``payload_body`` in the description, the tensions of its measured
            ``tendons`` missing or of the wrong shape, or too few usable samples.
    """
    sec = description.mjcf
    if sec is None or not sec.payload_body:
        raise CablelabError("payload estimate: the description names no mjcf.payload_body")
    if sec.tendons and (tension is None or np.shape(tension) != (len(t), len(sec.tendons))):
        raise CablelabError(f"payload estimate: the description measures tendons "
                            f"{', '.join(sec.tendons)}: need their tensions, shape ({len(t)}, "
                            f"{len(sec.tendons)}), got {None if tension is None else np.shape(tension)}")
    ds = dataset_from_arrays(t, q, effort, description, DatasetOptions(Conditioning(border=border)),
                             tension=tension, driven=driven)
    ok = ds.valid
    if ok.sum() < 10:
        raise CablelabError(f"payload estimate: {int(ok.sum())} usable samples, need 10")
    cols = ds.signals["payload_columns"][ok]
    r = (ds.y - ds.signals[KNOWN_OUTPUT])[ok]
    a = cols.reshape(-1, cols.shape[2])
    sc = np.linalg.norm(a, axis=0)
    sc = np.where(sc > 1e-9 * max(float(sc.max()), 1e-300), sc, np.inf)
    theta = np.linalg.lstsq(a / sc, r.reshape(-1), rcond=1e-9)[0] / sc
    m = float(theta[0])
    c0 = ds.signals["payload_com0"]
    com = c0 + (theta[1:] / m if m else np.zeros(3))
    return PayloadEstimate(m=m, com=com, samples=int(ok.sum()))
