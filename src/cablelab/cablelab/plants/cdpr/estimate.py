"""Offline payload estimation from a bag (``cablelab estimate``): mass and CoM per sample,
vectorised over the whole bag (001 eq. 12-13)."""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ...errors import CablelabError
from ...plant_interface import DatasetOptions
from ...registry import get_plant
from .dataset import CdprArrays, dataset_from_arrays, load_arrays
from .topics import JOINT_STATES as JOINTS, PAYLOAD_ESTIMATE as ESTIMATE
from .estimation import mass_com, mass_com_batch
from .options import CdprOptions
from .geometry import cable_geometry, check_pulley_radius


@dataclass
class Estimate:
    """Per-sample payload estimate of a bag (``cablelab estimate``)."""

    t: np.ndarray
    mass: np.ndarray
    com: np.ndarray
    residual: np.ndarray
    effects: tuple
    params: dict
    truth_mass: float | None = None
    truth_com: np.ndarray | None = None

    def summary(self) -> dict:
        """JSON of CONTRACT section 5 (cdpr) + the model, parameters and, when the bag has the
        ground truth, the mass error in %."""
        ok = np.isfinite(self.mass)
        if not ok.any():
            raise CablelabError("no sample gives a finite mass: the cable geometry of the "
                                "description is degenerate at the recorded poses (e.g. an anchor "
                                "closer to its pulley than the sheave radius)")
        m = self.mass[ok]
        out = {"plant": "cdpr", "samples": int(ok.sum()),
               "mass": {"mean": float(m.mean()), "std": float(m.std()),
                        "max_abs_dev": float(np.abs(m - m.mean()).max())},
               "com": {"x": float(np.mean(self.com[ok, 0])), "y": float(np.mean(self.com[ok, 1]))},
               "effects": list(self.effects), "params": self.params,
               "wrench_residual": float(np.sqrt(np.mean(self.residual[ok] ** 2)))}
        if self.truth_mass:
            err = 100.0 * (m - self.truth_mass) / self.truth_mass
            out["truth"] = {"mass": self.truth_mass, "mass_error_percent": float(err.mean()),
                            "max_error_percent": float(np.abs(err).max())}
            if self.truth_com is not None:
                out["truth"]["com"] = {"x": float(self.truth_com[0]), "y": float(self.truth_com[1])}
        return out


def estimate_arrays(arr: CdprArrays, description, effects=(), params: dict | None = None) -> Estimate:
    """Mass and CoM per sample with the model ``baseline + effects`` (001 eq. 12-13).

    Nuisance parameters the model needs and ``params`` does not give (an unknown sheave radius,
    winch friction, sensor offsets) are identified first on the same data with the workbench
    (separable least squares); then the tensions are corrected and eq. 13 is applied per sample,
    vectorised.
    """
    from ...model import Model

    c = description.cdpr
    baseline = get_plant("cdpr").baseline(description)
    effs = tuple(baseline) + tuple(e for e in effects if e not in baseline)
    Model("cdpr", effs)                                         # validates the ids
    params = dict(params or {})
    need = []
    if "pulley_geometry" in effs and "r_p" not in params:
        if c.pulley_radius > 0:
            params["r_p"] = c.pulley_radius
        else:
            need.append("r_p")
    fr = [e for e in effs if e in ("winch_coulomb_friction", "winch_viscous_friction", "tension_sensor_offset")]
    if need or fr:
        from ...fit import identify

        ds = dataset_from_arrays(arr, description)
        fixed = {"r_p": params["r_p"]} if "r_p" in params and "pulley_geometry" in effs else {}
        # W_I-based friction/offset columns: good to first order in r_p
        ident = identify(Model("cdpr", effs, fixed), ds)
        params.update({k: v for k, v in ident.params.items() if k not in ("m", "mx", "my", "m_a", "mx_a", "my_a", "mz_a")})
    n = arr.tensions.shape[1]
    t = arr.tensions.copy()
    names = [f"winch_{i}" for i in range(1, n + 1)]
    if "winch_coulomb_friction" in effs or "winch_viscous_friction" in effs:
        fc = np.array([params.get(f"Fc[{w}]", 0.0) for w in names])
        fv = np.array([params.get(f"Fv[{w}]", 0.0) for w in names])
        s = np.sign(arr.motor_velocity)
        t = t - arr.scale * (fc * s + fv * arr.motor_velocity) if arr.source == "motor" else t
    if "tension_sensor_offset" in effs:
        t = t - np.array([params.get(f"b[{w}]", 0.0) for w in names])
    r = params.get("r_p", 0.0) if "pulley_geometry" in effs else 0.0
    check_pulley_radius(c.exit_points, c.anchor_points, arr.position, arr.R, r, c.swivel_axes,
                        "r_p (pulley_geometry)" if r != c.pulley_radius else "cdpr.pulley_radius")
    if arr.R is None and "platform_inertia" not in effs:      # level and static: fast kernel
        est = mass_com_batch(c.exit_points, c.anchor_points, arr.position, t, r,
                             description.gravity, c.swivel_axes)
    else:
        geom = cable_geometry(c.exit_points, c.anchor_points, arr.position, arr.R, r, c.swivel_axes)
        est = mass_com(geom, t, description.gravity,
                       arr.acc if "platform_inertia" in effs else None, arr.R)
    return Estimate(arr.t, est.mass, est.com, est.residual, effs,
                    {k: float(v) for k, v in params.items()}, arr.truth_mass, arr.truth_com)


def estimate_bag(bag_path, description=None, options: DatasetOptions | None = None, *, effects=(),
                 out=None) -> Estimate:
    """``cablelab estimate`` for a CDPR bag.

    Args:
        bag_path: bag path or an open :class:`~cablelab.bags.Bag`.
        description: the description (None: the bag's ``/plant_description``).
        options: the tension source and pose (``options.plant``, a :class:`CdprOptions`; None:
            dynamometers, desired pose) and the joint velocities to derive.
        effects: effect ids added to the nominal model (``platform_inertia``, friction, ...).
        out: also write ``/cdpr/payload_estimate`` (InertiaStamped: m, com = (x_G, y_G, NaN),
            frame ``platform``) stamped like the tensions to this bag.
    """
    from ...bags import open_bag

    options = options if options is not None else DatasetOptions(plant=CdprOptions())
    own = options.plant_options(CdprOptions)

    bag = bag_path if hasattr(bag_path, "joint_state") else open_bag(bag_path)   # path or open Bag
    desc = description if description is not None else bag.description
    if desc is None:
        raise CablelabError(f"{bag_path}: no /plant_description in the bag; give --description FILE")
    arr = load_arrays(bag, desc, own.tensions, own.pose, dict(options.derived_velocity).get(JOINTS, ()))
    est = estimate_arrays(arr, desc, effects)
    if out is not None:
        from ...bags import BagWriter
        from ...description import dump_description

        with BagWriter(out, overwrite=True) as w:
            w.write_description(desc.yaml_text or dump_description(desc), float(est.t[0]))
            com = np.column_stack([est.com, np.full(len(est.t), np.nan)])
            w.write_inertia(ESTIMATE, est.t, est.mass, com)
    return est
