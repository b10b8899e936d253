"""The leg section of ``./run demo``: data from the MuJoCo plant with the impact map and
a 2.7 N spring preload hidden; ``diagnose --greedy`` on 003's model without impact adds
``impact_restitution`` then ``spring_preload`` (error waterfall); the 003 Fig. 11 comparison of
apex height and time errors with and without the impact map; plots of the apex-to-apex return
map and of the residual around touch-down / lift-off. Then the experiment-design loop with the
mass free: low hops under the apex controller confound the preload F0 with the mass m,
``cablelab excite`` designs an apex-height schedule, the controller plays it on the hybrid leg
(offline, :func:`.excite.closed_loop`) and the fit on that run finds both (condition numbers
before and after in the table).
"""
from __future__ import annotations

import json
import math
from pathlib import Path

import numpy as np

from ...demo import DemoPart, PartResult

SCHEDULE = [(1.5, 0.30), (2.5, 0.35), (3.0, 0.30), (2.0, 0.35), (2.5, 0.30)]  # (T N m, P s)


def _law(block_s: float):
    def law(t, sim):
        T, P = SCHEDULE[min(int(t // block_s), len(SCHEDULE) - 1)]
        return T * math.sin(2 * math.pi * (t - sim.t_d) / P)
    return law


def run(out_dir: Path, quick: bool = False) -> dict:
    """Run the demo, write ``leg_demo.json`` and plots into ``out_dir``; returns the table rows."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    from ...workbench import build_model, diagnose, load
    from .description import leg_of
    from .hybrid import LegParams
    from .identify import apex_errors, record_from_trajectory, simulate_strides, stride_segments
    from .sim import simulate, write_bag
    from .strides import apexes

    out_dir = Path(out_dir)
    out_dir.mkdir(parents=True, exist_ok=True)
    desc_path = Path(__file__).parent / "data" / "leg.yaml"
    truth = LegParams(F0=2.7)
    block = 2.0 if quick else 4.0
    traj = simulate(truth, truth.z_td + 0.03, 0.0, block * len(SCHEDULE), _law(block))
    bag = out_dir / "leg_hidden_impact_preload"
    write_bag(bag, traj, desc_path.read_text(), overwrite=True)
    plant, desc, ds = load(bag)
    # the leg is weighed (003: 1.62 kg on a scale): its mass is known. With m free, a spring
    # preload F_0 and a stance inertia m - F_0 / g (phase_effective_mass) are the same stance force
    res = diagnose(ds, build_model(plant, desc, fixed={"m": leg_of(desc).mass}), plant.candidates(desc),
                   greedy_mode=True).to_json()
    rows = []
    for s in res["greedy"]:
        rows.append({"step": s["added"] or "003 model without impact (baseline)", "cv_error": s["error"]})
    final = res["greedy"][-1]["params"]
    m = final["m"]
    ident = {"m": m, "d_s": final["d_s"], "d_f": final["d_f"]}
    if "c_td" in final:
        ident.update(beta_td=1 - final["c_td"] / m, beta_lo=1 - final["c_lo"] / m)
    if "F0" in final:
        ident["F0"] = final["F0"]

    # 003 Fig. 11: single strides of the demo data simulated with and without the impact map
    model = LegParams(**{k: v for k, v in ident.items() if k in ("m", "d_s", "d_f", "beta_td", "beta_lo", "F0")})
    segs = stride_segments([record_from_trajectory(traj)])
    sims = simulate_strides(segs, [model, model.no_impact()])
    full, none = apex_errors(segs, sims[0]), apex_errors(segs, sims[1])
    fig11 = {"strides": len(segs),
             "apex_height_mae_mm": {"with_impact": 1e3 * float(np.mean(full["height"])),
                                    "without_impact": 1e3 * float(np.mean(none["height"]))},
             "apex_time_mae_ms": {"with_impact": 1e3 * float(np.mean(full["time"])),
                                  "without_impact": 1e3 * float(np.mean(none["time"]))},
             "paper": "003 Fig. 11: box plots only (no numbers, spec E10); with impact < without"}

    # plots: error waterfall, apex return map, residual around the transitions
    fig, ax = plt.subplots(1, 3, figsize=(15, 4))
    ax[0].bar(range(len(rows)), [r["cv_error"] for r in rows])
    ax[0].set_xticks(range(len(rows)), [r["step"].split(" (")[0] for r in rows], rotation=20, fontsize=7)
    ax[0].set_ylabel("CV error (NRMSE)")
    ax[0].set_title("greedy diagnose waterfall")
    ap = apexes(traj.t, traj.z_meas, traj.contact)
    h = 1e3 * (ap[:, 1] - truth.z_td)
    ax[1].plot(h[:-1], h[1:], "o", ms=3)
    lim = [min(h.min(), 0), h.max() * 1.05]
    ax[1].plot(lim, lim, "k:", lw=0.8)
    ax[1].set_xlabel("apex n above z_td (mm)")
    ax[1].set_ylabel("apex n+1 (mm)")
    ax[1].set_title("apex-to-apex return map")
    win = np.arange(-40, 41)
    for j, (lab, sim) in enumerate((("with impact", sims[0]), ("without impact", sims[1]))):
        err = []
        for k, sg in enumerate(segs):
            e = sim[k, : sg.n, 1] - sg.zd
            idx = np.flatnonzero(np.diff(sg.contact) != 0) + 1
            for i in idx:
                if 40 <= i < sg.n - 41:
                    err.append(e[i + win])
        if err:
            ax[2].plot(win, 1e3 * np.mean(np.abs(err), axis=0), label=lab)
    ax[2].set_xlabel("samples from a contact edge (ms)")
    ax[2].set_ylabel("mean |zdot residual| (mm/s)")
    ax[2].set_title("residual around transitions")
    ax[2].legend()
    fig.tight_layout()
    fig.savefig(out_dir / "leg_demo.png", dpi=110)
    plt.close(fig)
    out = {"waterfall": rows, "identified": ident, "truth": {"beta_td": truth.beta_td, "beta_lo": truth.beta_lo,
                                                            "F0": truth.F0, "m": truth.m},
           "fig11": fig11, "plot": str(out_dir / "leg_demo.png")}
    out["excite"] = _excite_loop(desc, plant, truth, quick)
    (out_dir / "leg_demo.json").write_text(json.dumps(out, indent=2))
    out["bag"] = str(bag)
    return out


def _excite_loop(desc, plant, truth, quick: bool) -> dict:
    """Low hops (4 mm) confound F0 with m (m free); the designed apex-height schedule, played by
    the apex controller on the hybrid leg, separates them: condition numbers and both fits."""
    from ...excite import design
    from ...fit import identify
    from ...workbench import build_model
    from .dataset import dataset_from_arrays
    from .excite import closed_loop
    from .hybrid import LegParams

    nominal = LegParams()
    dur = 30.0 if quick else 60.0

    def ds_of(tr):
        return dataset_from_arrays(tr.t, tr.z_meas, tr.contact, tr.tau, desc)

    low = ds_of(closed_loop(truth, nominal.z_td + 0.004, dur, controller_params=nominal))
    d = design("leg", desc, ["F0", "m"], duration=dur, before_ds=low, max_iter=10 if quick else 30)
    run = ds_of(closed_loop(truth, lambda t: np.interp(t, d.t, d.q[:, 0]), dur, controller_params=nominal))
    model = build_model(plant, desc, ["impact_restitution", "spring_preload"])
    fits = {k: identify(model, ds).params for k, ds in (("low_hops", low), ("designed", run))}
    return {"condition_before": d.condition_before, "condition_after": d.condition_after,
            "design_s": d.seconds, "duration_s": dur,
            **{f"{k}_{p}": float(v[p]) for k, v in fits.items() for p in ("F0", "m")}}


def _page(out_dir: Path, rows: list) -> str:
    """``leg.html``: the table and the plots."""
    import html

    table = "".join("<tr>" + "".join(f"<td>{html.escape(str(c))}</td>" for c in r) + "</tr>" for r in rows)
    path = out_dir / "leg.html"
    path.write_text("<!DOCTYPE html><html><head><meta charset='utf-8'><title>hopping leg demo</title>"
                    "</head><body style='font-family:sans-serif;max-width:1100px;margin:auto'>"
                    "<h1>Parallel-elastic hopping leg (003): impact map and preload hidden</h1>"
                    "<table border=1 cellpadding=4><tr><th>quantity</th><th>cablelab</th><th>003</th>"
                    f"</tr>{table}</table><img src='leg_demo.png' style='max-width:100%'></body></html>")
    return str(path)


def _analyse(out_dir: Path, args, res: dict) -> PartResult:
    """The demo table: waterfall, identified impact parameters, 003 Fig. 11 apex errors."""
    w, ident, truth, f11 = res["waterfall"], res["identified"], res["truth"], res["fig11"]
    rows = [["diagnose --greedy waterfall (held-out error)",
             " -> ".join(f"{r['step'].split(' (')[0]} {100 * r['cv_error']:.1f} %" for r in w),
             "impact_restitution, spring_preload (hidden)"],
            ["beta_td / beta_lo (truth)",
             f"{ident.get('beta_td', float('nan')):.3f} / {ident.get('beta_lo', float('nan')):.3f} "
             f"({truth['beta_td']:.3f} / {truth['beta_lo']:.3f})", "Table 2"],
            ["spring preload F0 (N, truth 2.7)", f"{ident.get('F0', float('nan')):.2f}", "hidden"],
            ["apex height MAE with / without impact (mm)",
             f"{f11['apex_height_mae_mm']['with_impact']:.2f} / {f11['apex_height_mae_mm']['without_impact']:.2f}",
             "Fig. 11: with < without"],
            ["apex time MAE with / without impact (ms)",
             f"{f11['apex_time_mae_ms']['with_impact']:.1f} / {f11['apex_time_mae_ms']['without_impact']:.1f}",
             "Fig. 11: with < without"]]
    ex = res.get("excite")
    if ex:
        rows += [["excite F0,m (m free): condition number low hops -> designed apex schedule",
                  f"{ex['condition_before']:.3g} -> {ex['condition_after']:.3g} "
                  f"(designed in {ex['design_s']:.1f} s)", "-"],
                 ["F0 (N) / m (kg) from low hops -> designed schedule (truth 2.7 / 1.55)",
                  f"{ex['low_hops_F0']:.2f} / {ex['low_hops_m']:.3f} -> "
                  f"{ex['designed_F0']:.2f} / {ex['designed_m']:.3f}", "hidden"]]
    return PartResult(rows=rows, bags=[res["bag"]], page=_page(Path(out_dir), rows),
                      first=w[1]["step"] if len(w) > 1 else "")


DEMO = DemoPart(plant="leg", title="Hopping leg (003), impact map and preload hidden", order=40,
                add_arguments=lambda group: None,
                record=lambda out, args: run(out, quick=args.quick), analyse=_analyse,
                subdir="leg", how="MuJoCo hybrid-plant data (offline), then the workbench")
