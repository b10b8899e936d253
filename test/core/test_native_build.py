"""cablelab.native builds C against the installed ros-jazzy and MuJoCo wheels with the pinned
compiler, and the library binds to the same MuJoCo and rcl the Python process uses."""
from __future__ import annotations

import ctypes

import mujoco
import pytest

from cablelab import native

PROBE = r"""
#include <mujoco/mujoco.h>
#include <rcl/rcl.h>
int probe_mj_version(void) { return mj_version(); }
/* a model compiled by the Python binding, stepped from C through its address */
double probe_step(const mjModel *m, mjData *d, int n) {
  for (int i = 0; i < n; i++) mj_step(m, d);
  return d->time;
}
int probe_rcl_context_ok(void) {
  rcl_init_options_t io = rcl_get_zero_initialized_init_options();
  if (rcl_init_options_init(&io, rcl_get_default_allocator()) != RCL_RET_OK) return 0;
  rcl_context_t c = rcl_get_zero_initialized_context();
  if (rcl_init(0, NULL, &io, &c) != RCL_RET_OK) return 0;
  int ok = rcl_context_is_valid(&c);
  rcl_shutdown(&c);
  rcl_context_fini(&c);
  rcl_init_options_fini(&io);
  return ok;
}
"""

PENDULUM = """<mujoco><option timestep="0.001"/><worldbody><body><joint name="j" type="hinge" axis="0 1 0"/>
<geom type="capsule" fromto="0 0 0 0 0 -1" size="0.05"/></body></worldbody></mujoco>"""


def test_probe_builds_and_binds_to_the_process_mujoco_and_rcl(tmp_path):
    src = tmp_path / "probe.c"
    src.write_text(PROBE)
    path = native.build("probe", [src])
    assert native.build("probe", [src]) == path  # cached by content
    lib = ctypes.CDLL(str(path))
    assert lib.probe_mj_version() == mujoco.mj_version()
    assert lib.probe_rcl_context_ok() == 1
    # the same trajectory as the Python binding's own mj_step (one library, one model)
    m = mujoco.MjModel.from_xml_string(PENDULUM)
    d1, d2 = mujoco.MjData(m), mujoco.MjData(m)
    d1.qpos[0] = d2.qpos[0] = 0.7
    lib.probe_step.restype = ctypes.c_double
    lib.probe_step.argtypes = [ctypes.c_void_p, ctypes.c_void_p, ctypes.c_int]
    t = lib.probe_step(m._address, d1._address, 500)
    for _ in range(500):
        mujoco.mj_step(m, d2)
    assert t == pytest.approx(0.5)
    assert d1.qpos[0] == d2.qpos[0] and d1.qvel[0] == d2.qvel[0]
    assert abs(d1.qpos[0] - 0.7) > 0.1  # it swung


def test_a_broken_source_names_itself_in_one_line(tmp_path):
    src = tmp_path / "broken.c"
    src.write_text("int f(void) { return undefined_name; }\n")
    with pytest.raises(native.NativeUnavailable, match=r"compiling broken\.c failed:.*undefined_name") as e:
        native.build("broken", [src])
    assert "\n" not in str(e.value)


def test_switched_off_keeps_the_python_path(monkeypatch):
    monkeypatch.setenv("CABLELAB_NATIVE", "0")
    monkeypatch.setattr(native, "_loaded", {})
    assert native.load("anything") is None
    assert native.unavailable_reason("anything") == "CABLELAB_NATIVE=0"
