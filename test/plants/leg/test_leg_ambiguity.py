"""Preload vs stance mass on the hopping leg (issue case): with the leg's mass free, a 2.7 N
spring preload and a stance inertia (``phase_effective_mass``) are one stance force on a
recording whose stances all look alike: the diagnosis must say the two are ambiguous instead of
naming the better-scoring one as the answer. With the weighed mass known (the description's
1.55 kg) the stance weight pins the mass and the preload is found on its own.

Data: the MuJoCo hybrid plant (plants/leg/sim.py), which shares no code with the inverse model."""
from __future__ import annotations

import math
from pathlib import Path

import pytest

import cablelab.plants.leg as leg_pkg
from cablelab.plants.leg.description import leg_of
from cablelab.plants.leg.hybrid import LegParams
from cablelab.plants.leg.sim import simulate, write_bag
from cablelab.workbench import build_model, diagnose, load

DESC = Path(leg_pkg.__file__).parent / "data" / "leg.yaml"
TRUE = LegParams(F0=2.7)
SCHEDULE = [(1.5, 0.30), (2.5, 0.35), (3.0, 0.30), (2.0, 0.35), (2.5, 0.30)]  # (T N m, P s), 4 s each


def _law(t, sim):
    T, P = SCHEDULE[min(int(t // 4.0), len(SCHEDULE) - 1)]
    return T * math.sin(2 * math.pi * (t - sim.t_d) / P)


@pytest.fixture(scope="module")
def loaded(tmp_path_factory):
    path = tmp_path_factory.mktemp("leg_amb") / "preload"
    write_bag(path, simulate(TRUE, TRUE.z_td + 0.03, 0.0, 20.0, _law), DESC.read_text())
    return load(path)


def test_preload_and_stance_mass_are_ambiguous_with_the_mass_free(loaded):
    plant, desc, ds = loaded
    out = diagnose(ds, build_model(plant, desc, ["impact_restitution"]), plant.candidates(desc))
    by = {c.effect: c.to_json() for c in out.ranking}
    assert by["spring_preload"]["significant"] and by["phase_effective_mass"]["significant"]
    assert by["spring_preload"]["ambiguous_with"] == ["phase_effective_mass"]
    assert by["phase_effective_mass"]["ambiguous_with"] == ["spring_preload"]
    text = "\n".join(out.lines())
    assert "ambiguous: " in text and "names no winner" in text
    for other in ("contact_delay", "guide_coulomb_friction", "spring_nonlinearity"):
        assert "ambiguous_with" not in by[other]


def test_with_the_weighed_mass_the_preload_stands_alone(loaded):
    plant, desc, ds = loaded
    model = build_model(plant, desc, ["impact_restitution"], fixed={"m": leg_of(desc).mass})
    out = diagnose(ds, model, plant.candidates(desc))
    first = out.ranking[0].to_json()
    assert first["effect"] == "spring_preload" and first["significant"]
    assert "ambiguous_with" not in first
    assert first["params"]["F0"] == pytest.approx(2.7, rel=0.10)


def test_impacts_are_reported_as_the_papers_velocity_ratios(loaded):
    """003 eq. 24 / Table 2 name beta_td, beta_lo: the ranking row and identify report those
    (truth 0.57, 1.13), the momentum coefficients c_td, c_lo only under "internal"."""
    plant, desc, ds = loaded
    out = diagnose(ds, build_model(plant, desc, fixed={"m": leg_of(desc).mass}),
                   ["impact_restitution"]).to_json()
    row = out["ranking"][0]
    assert set(row["params"]) == {"beta_td", "beta_lo"} and row["units"]["beta_td"] == "1"
    assert row["params"]["beta_td"] == pytest.approx(TRUE.beta_td, rel=0.05)
    assert row["params"]["beta_lo"] == pytest.approx(TRUE.beta_lo, rel=0.05)
    assert set(row["internal"]) == {"c_td", "c_lo"}
    assert "beta_td = " in row["explanation"] and "c_td" not in row["explanation"]
    # with m fixed the ratio's error is the coefficient's over m (delta method, m exact)
    from cablelab.fit import identify as fit

    r = fit(build_model(plant, desc, ["impact_restitution"], fixed={"m": leg_of(desc).mass}), ds)
    phys = r.physical("impact_restitution", ds)
    assert phys["beta_td"]["stderr"] == pytest.approx(r.stderr["c_td"] / leg_of(desc).mass, rel=1e-4)
