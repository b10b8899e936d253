"""The ``mjcf:`` section of the plant description (CONTRACT section 3): any machine described by
a MuJoCo model (MJCF or URDF), carried inline so that a bag holds its own model."""
from __future__ import annotations

import os
from dataclasses import dataclass, field
from typing import Any

from ...errors import CablelabError
from ...fields import check_keys, fail, mapping
from .mjcf import check_names, dof_joints, load_model, names
from .topics import TOPICS

KEYS = ("model", "model_file", "joints", "tendons", "payload_body", "topics")
#: the largest model file read, bytes
MODEL_MAX_BYTES = 16 * 1024 * 1024


@dataclass(frozen=True)
class MjcfDescription:
    """A machine from its MuJoCo model.

    Args:
        model: the MJCF or URDF text (``model_file`` read and inlined).
        joints: the joints whose effort is measured (None: every joint an actuator drives).
        tendons: the tendons whose tension is measured.
        payload_body: the body carrying an unknown payload (effect ``payload_mass``).
        topics: remapped topic names by key (``joint_states``, ``cable_tensions``, ...).
        source: the file the model came from (for messages), else ``mjcf.model``.
        warnings: what loading the model had to leave out (mesh files not found).
    """

    model: str
    joints: tuple[str, ...] | None = None
    tendons: tuple[str, ...] = ()
    payload_body: str | None = None
    topics: dict = field(default_factory=dict)
    source: str = "mjcf.model"
    warnings: tuple[str, ...] = ()
    #: the description's YAML is regenerated with the model text inline (cablelab.description)
    inlines_files: bool = False

    def compiled(self, gravity: float | None = None):
        """A fresh :class:`mujoco.MjModel` of the section's model (see :func:`.mjcf.load_model`)."""
        return load_model(self.model, self.source, gravity)[0]


def _names(obj: dict, key: str, path: str) -> tuple[str, ...] | None:
    if key not in obj or obj[key] is None:
        return None
    v = obj[key]
    if not isinstance(v, list) or not all(isinstance(x, str) and x for x in v):
        raise fail(f"{path}.{key}", f"expected a list of names, got {v!r}")
    return tuple(v)


def _read_model_file(name: str, path: str) -> tuple[str, str]:
    from ...description import DESCRIPTION_DIR

    if not isinstance(name, str) or not name:
        raise fail(f"{path}.model_file", f"expected a file name, got {name!r}")
    full = name if os.path.isabs(name) else os.path.join(DESCRIPTION_DIR.get() or os.getcwd(), name)
    try:
        with open(full, encoding="utf-8") as fh:
            text = fh.read(MODEL_MAX_BYTES + 1)
    except OSError as exc:
        raise fail(f"{path}.model_file", f"cannot read {full} ({exc.strerror})") from None
    except UnicodeDecodeError:
        raise fail(f"{path}.model_file", f"{full} is not UTF-8 text (an MJCF or URDF file)") from None
    if len(text) > MODEL_MAX_BYTES:
        raise fail(f"{path}.model_file", f"{full} is larger than {MODEL_MAX_BYTES} bytes")
    return text, full


def parse_section(obj: Any) -> MjcfDescription:
    """Validate the ``mjcf:`` section: the model compiles, the names are the model's."""
    path = "mjcf"
    obj = mapping(obj, path)
    check_keys(obj, path, (), KEYS)
    if ("model" in obj) == ("model_file" in obj):
        raise fail(path, "give the model either inline ('model') or as a file ('model_file'), "
                         + ("not both" if "model" in obj else "neither is given"))
    inlined = "model_file" in obj
    if inlined:
        text, source = _read_model_file(obj["model_file"], path)
    else:
        text, source = obj["model"], "mjcf.model"
        if not isinstance(text, str) or not text.strip():
            raise fail(f"{path}.model", "expected the MJCF or URDF text")
    model, warnings = load_model(text, source)
    joints = _names(obj, "joints", path)
    check_names(joints or (), dof_joints(model), "joint", f"{path}.joints")
    tendons = _names(obj, "tendons", path) or ()
    check_names(tendons, names(model, "tendon"), "tendon", f"{path}.tendons")
    payload = obj.get("payload_body")
    if payload is not None:
        if not isinstance(payload, str):
            raise fail(f"{path}.payload_body", f"expected a body name, got {payload!r}")
        bodies = names(model, "body")[1:]
        check_names((payload,), bodies, "body", f"{path}.payload_body")
    topics = obj.get("topics") or {}
    topics = mapping(topics, f"{path}.topics")
    check_keys(topics, f"{path}.topics", (), tuple(TOPICS))
    for k, v in topics.items():
        if not isinstance(v, str) or not v.startswith("/"):
            raise fail(f"{path}.topics.{k}", f"expected a topic name starting with '/', got {v!r}")
    return MjcfDescription(model=text, joints=joints, tendons=tendons, payload_body=payload,
                           topics=dict(topics), source=source, warnings=warnings,
                           inlines_files=inlined)


def dump_section(sec: MjcfDescription) -> dict:
    """The section as YAML-ready mapping, the model inline."""
    out: dict = {"model": sec.model}
    if sec.joints is not None:
        out["joints"] = list(sec.joints)
    if sec.tendons:
        out["tendons"] = list(sec.tendons)
    if sec.payload_body:
        out["payload_body"] = sec.payload_body
    if sec.topics:
        out["topics"] = dict(sec.topics)
    return out


def section_of(description) -> MjcfDescription:
    sec = getattr(description, "mjcf", None) if description is not None else None
    if sec is None:
        raise CablelabError("description: plant mjcf needs an 'mjcf:' section")
    return sec
