"""The MuJoCo model of an ``mjcf`` plant: compiling the user's MJCF or URDF text, with one-line
errors, and the names of its joints, tendons and bodies.

Meshes are not needed for dynamics: when MuJoCo cannot open a mesh (or texture / height field)
file, the mesh geoms and those assets are removed and the model compiles from the inertials as
given, with a warning (a body whose mass came only from its mesh then has none, and MuJoCo says
so).
"""
from __future__ import annotations

import copy
import functools

import numpy as np

from ...errors import CablelabError

#: joint types the workbench handles (one generalised coordinate each)
HINGE, SLIDE = 3, 2


def _one_line(text: str) -> str:
    return " ".join(str(text).split())


def _strip_files(spec) -> int:
    """Remove mesh geoms and file-based assets from an :class:`mujoco.MjSpec`; returns how many
    geoms were removed."""
    import mujoco

    removed = 0
    for g in list(spec.geoms):
        if g.type in (mujoco.mjtGeom.mjGEOM_MESH, mujoco.mjtGeom.mjGEOM_HFIELD, mujoco.mjtGeom.mjGEOM_SDF):
            spec.delete(g)
            removed += 1
    for group in ("meshes", "hfields", "textures", "materials", "skins"):
        for item in list(getattr(spec, group, ())):
            spec.delete(item)
    return removed


@functools.lru_cache(maxsize=32)
def _compile(xml: str, source: str):
    import mujoco

    try:
        return mujoco.MjModel.from_xml_string(xml), ()
    except ValueError as exc:
        first = _one_line(exc)
    if "opening file" not in first.lower() and "resource not found" not in first.lower():
        raise CablelabError(f"{source}: MuJoCo cannot compile the model: {first}")
    try:
        spec = mujoco.MjSpec.from_string(xml)
        n = _strip_files(spec)
        model = spec.compile()
    except ValueError as exc:
        raise CablelabError(f"{source}: MuJoCo cannot compile the model without its mesh files "
                            f"({first}): {_one_line(exc)}") from None
    return model, (f"{source}: {first}; loaded without meshes ({n} mesh geoms removed): the "
                   "dynamics use the inertials as given",)


def load_model(xml: str, source: str = "mjcf.model", gravity: float | None = None):
    """Compile MJCF or URDF text.

    Args:
        xml: the model text; source: what to name in messages (the file, or ``mjcf.model``).
        gravity: g, m/s^2, set along -z of the model's world (None: the model's own).
    Returns:
        ``(model, warnings)``: a fresh :class:`mujoco.MjModel` (the caller may change it) and the
        warnings of loading it (meshes left out).
    Raises:
        CablelabError: the model does not compile: MuJoCo's message on one line, with the source.
    """
    model, warnings = _compile(xml, source)
    model = copy.copy(model)
    if gravity is not None:
        model.opt.gravity[:] = (0.0, 0.0, -float(gravity))
    return model, warnings


def names(model, kind: str) -> list[str]:
    """Names of the model's ``joint``, ``tendon``, ``body`` or ``actuator`` objects, in order."""
    import mujoco

    obj = {"joint": mujoco.mjtObj.mjOBJ_JOINT, "tendon": mujoco.mjtObj.mjOBJ_TENDON,
           "body": mujoco.mjtObj.mjOBJ_BODY, "actuator": mujoco.mjtObj.mjOBJ_ACTUATOR}[kind]
    count = {"joint": model.njnt, "tendon": model.ntendon, "body": model.nbody,
             "actuator": model.nu}[kind]
    return [mujoco.mj_id2name(model, obj, i) or f"{kind}_{i}" for i in range(count)]


def dof_joints(model) -> list[str]:
    """Names of the hinge and slide joints (one generalised coordinate each), in dof order.

    Raises:
        CablelabError: the model has a free or ball joint (its orientation is not a joint angle a
            JointState carries).
    """
    jn = names(model, "joint")
    bad = [jn[i] for i in range(model.njnt) if model.jnt_type[i] not in (HINGE, SLIDE)]
    if bad:
        raise CablelabError(f"mjcf: joint(s) {', '.join(bad)} are free or ball joints; the mjcf "
                            "plant handles hinge and slide joints (one angle or length each)")
    return [jn[i] for i in np.argsort(model.jnt_dofadr)]


def actuated_joints(model) -> list[str]:
    """Joints an actuator drives directly (joint transmission), in dof order."""
    jn = names(model, "joint")
    driven = {int(model.actuator_trnid[a, 0]) for a in range(model.nu) if model.actuator_trntype[a] == 0}
    return [j for j in dof_joints(model) if jn.index(j) in driven]


def check_names(given, known, what: str, path: str) -> None:
    """One-line error naming the first unknown name and the known ones."""
    for name in given:
        if name not in known:
            raise CablelabError(f"{path}: unknown {what} {name!r} (the model's {what}s: "
                                f"{', '.join(known) or 'none'})")
