"""The recorder's two ways of stepping the truth, against a closed form.

MuJoCo's explicit Euler (implicit damping off), one step per sample, makes the positions' second
difference the acceleration it computed, but its velocity is the backward difference of the
positions, half a step behind their own: the damping force ``F_v v`` of that discrete machine is
``F_v (v - dt/2 qdd)``, which a continuous-time inverse-dynamics fit reads as an inertia
``F_v dt/2`` lower. Recorded close to continuous time (RK4 at a tenth of the step, the drive
updated every physics step), the same fit finds the armature itself. Both records share their
excitation and noise, so their difference isolates the integrator."""
import numpy as np
import pytest

from cablelab import workbench
from cablelab.plants.mjcf.examples import ARM3, text
from cablelab.plants.mjcf.sim import Hidden, write_bag

DAMPING = {"base_yaw": 0.8, "shoulder": 1.5, "elbow": 0.6}
ARMATURE = {"base_yaw": 0.05, "shoulder": 0.08, "elbow": 0.03}
DT = 0.002                                          # arm3.xml's timestep: one sample per step


def armatures(path, substeps):
    bag = write_bag(path, text(ARM3), Hidden(damping=DAMPING, armature=ARMATURE), duration=4.0,
                    seed=7, substeps=substeps)
    plant, desc, ds = workbench.load(bag)
    rep = workbench.identify_report(
        ds, workbench.build_model(plant, desc, ["joint_viscous_friction", "joint_armature"]), folds=0)
    return {j: (rep.params[f"armature[{j}]"]["value"], 1.96 * rep.params[f"armature[{j}]"]["stderr"])
            for j in ARMATURE}


def test_euler_record_reads_armature_low_by_damping_half_step_and_continuous_record_does_not(tmp_path):
    euler = armatures(tmp_path / "euler", 1)
    smooth = armatures(tmp_path / "rk4", 10)
    for j, truth in ARMATURE.items():
        shift = DAMPING[j] * DT / 2
        a, (b, cb) = euler[j][0], smooth[j]
        assert b == pytest.approx(truth, abs=max(cb, 0.01 * truth)), (j, b, cb)
        assert a - b == pytest.approx(-shift, rel=0.3), (j, a, b, shift)
        assert not np.isclose(a, truth, atol=0.5 * shift), (j, a, truth)
