"""Generator of the boom-crane dynamics from 002's energies (002 eq. 3.1-3.4, A.1-A.6, 4.1-4.2).

Run ``python -m cablelab.plants.crane.symbolic`` to (re)write
:mod:`cablelab.plants.crane.dynamics_generated`; the test suite regenerates the source in memory
and checks it is identical to the committed file. sympy is needed only here, never at import
of the library.

What is derived (nothing of A.7-A.11 is typed by hand):

* positions of the boom centre, the payload and the counterbalance from the generalised
  coordinates q = [alpha, beta, d, theta1, theta2] (CONTRACT sec. 2, 002 Fig. 3.1, Table 3.3);
* T (002 eq. A.1: 1/2 m_b |v_tip/2|^2 + 1/2 m |v_M|^2 + 1/2 m_c |v_c|^2 + 1/2 I_tot alpha_dot^2
  + 1/2 I_b beta_dot^2) and V (002 eq. A.2);
* tau = d/dt dL/dqd - dL/dq (002 eq. A.6, i.e. A.7-A.11 = M qdd + C qd + G of eq. 3.5);
* the regressor Y(q, qd, qdd) with tau = Y pi, pi the 9 parameter groups of 002 eq. 4.2.
"""
from __future__ import annotations

import os
import sys

PARAM_GROUPS = ("I_tot", "lb2_mb", "lb2_m", "lb_m", "m", "lb_mb", "I_b", "lc2_mc", "lc_mc")


def derive():
    """Symbolic derivation. Returns ``(q, qd, qdd, g, Y)`` with Y a 5x9 sympy Matrix."""
    import sympy as sp

    t = sp.symbols("t")
    g = sp.symbols("g", positive=True)
    I_tot, I_b, lb, lc, m, mb, mc = sp.symbols("I_tot I_b l_b l_c m m_b m_c", positive=True)
    names = ("alpha", "beta", "d", "theta1", "theta2")
    funcs = [sp.Function(n)(t) for n in names]
    alpha, beta, d, th1, th2 = funcs
    Rz = sp.Matrix([[sp.cos(alpha), -sp.sin(alpha), 0], [sp.sin(alpha), sp.cos(alpha), 0], [0, 0, 1]])
    boom_dir = sp.Matrix([sp.cos(beta) * sp.cos(alpha), sp.cos(beta) * sp.sin(alpha), sp.sin(beta)])
    tip = lb * boom_dir                                    # x_b, y_b, z_b (002 Table 3.3)
    rope = sp.Matrix([sp.sin(th2), sp.sin(th1) * sp.cos(th2), -sp.cos(th1) * sp.cos(th2)])
    payload = tip + Rz * (d * rope)                        # x_M, y_M, z_M
    cbal = -lc * boom_dir                                  # x_c, y_c, z_c (behind the luff pivot)

    def sq(v):
        # |v|^2 evaluated in the slewing frame (Rz^T v has the same norm, free of alpha)
        vd = (Rz.T * v.diff(t)).applyfunc(lambda e: sp.trigsimp(sp.expand(e)))
        return sp.expand((vd.T * vd)[0])

    T = (sp.Rational(1, 8) * mb * sq(tip) + sp.Rational(1, 2) * m * sq(payload)
         + sp.Rational(1, 2) * mc * sq(cbal)
         + sp.Rational(1, 2) * I_tot * alpha.diff(t) ** 2 + sp.Rational(1, 2) * I_b * beta.diff(t) ** 2)  # A.1
    V = mb * g * tip[2] / 2 + m * g * payload[2] + mc * g * cbal[2]                                    # A.2
    L = T - V                                                                                           # A.5
    q = sp.symbols(" ".join(names))
    qd = sp.symbols(" ".join(n + "_d" for n in names))
    qdd = sp.symbols(" ".join(n + "_dd" for n in names))
    subs = {}
    for f, a, b, c in zip(funcs, q, qd, qdd):
        subs[f.diff(t, 2)] = c
        subs[f.diff(t)] = b
    tau = []
    for f in funcs:
        e = sp.diff(L.diff(f.diff(t)), t) - L.diff(f)                                                   # A.6
        e = e.subs(subs)
        e = e.subs({f: s for f, s in zip(funcs, q)})
        tau.append(sp.expand(e))
    # regressor: tau_i is a polynomial in the physical parameters; each monomial is one group of 4.2
    group_of = {
        (1, 0, 0, 0, 0, 0, 0): 0,  # I_tot
        (0, 0, 2, 0, 0, 1, 0): 1,  # l_b^2 m_b
        (0, 0, 2, 0, 1, 0, 0): 2,  # l_b^2 m
        (0, 0, 1, 0, 1, 0, 0): 3,  # l_b m
        (0, 0, 0, 0, 1, 0, 0): 4,  # m
        (0, 0, 1, 0, 0, 1, 0): 5,  # l_b m_b
        (0, 1, 0, 0, 0, 0, 0): 6,  # I_b
        (0, 0, 0, 2, 0, 0, 1): 7,  # l_c^2 m_c
        (0, 0, 0, 1, 0, 0, 1): 8,  # l_c m_c
    }
    gens = (I_tot, I_b, lb, lc, m, mb, mc)
    Y = sp.zeros(5, 9)
    for i, e in enumerate(tau):
        poly = sp.Poly(e, *gens)
        for monom, coeff in poly.terms():
            if monom not in group_of:
                raise RuntimeError(f"equation {i}: monomial {monom} is not a group of 002 eq. 4.2")
            Y[i, group_of[monom]] += coeff
    energies = {"T": T, "V": V, "funcs": funcs, "t": t, "params": gens}
    return q, qd, qdd, g, Y, energies


def generate_source() -> str:
    """Python source of the vectorised numpy regressor (deterministic)."""
    import sympy as sp
    from sympy.printing.numpy import NumPyPrinter

    q, qd, qdd, g, Y, _ = derive()
    entries = [(i, j, Y[i, j]) for i in range(5) for j in range(9) if Y[i, j] != 0]
    # trig of the coordinates as plain symbols -> far fewer operations after cse
    trig = {}
    for s in q:
        if str(s) == "d":
            continue
        c, sn = sp.symbols(f"c_{s} s_{s}")
        trig[sp.cos(s)] = c
        trig[sp.sin(s)] = sn
    exprs = [sp.expand(e.subs(trig)) for _, _, e in entries]
    for e in exprs:
        if e.has(sp.sin, sp.cos):
            raise RuntimeError(f"trigonometric term left after substitution: {e}")
    repl, reduced = sp.cse(exprs, symbols=sp.numbered_symbols("x"), order="canonical")
    pr = NumPyPrinter()
    lines = [
        '"""Boom-crane regressor Y(q, qd, qdd) of 002 eq. 4.1-4.2 - GENERATED, do not edit.',
        "",
        "Written by ``python -m cablelab.plants.crane.symbolic`` from the energies of 002 eq. A.3-A.4",
        "(Euler-Lagrange, eq. A.6). tau = Y @ pi with pi = " + ", ".join(PARAM_GROUPS) + ".",
        '"""',
        "import numpy as np",
        "",
        f"PARAM_GROUPS = {PARAM_GROUPS!r}",
        "",
        "",
        "def regressor(q, qd, qdd, g=9.81):",
        '    """(N, 5, 9) regressor; q, qd, qdd are (N, 5) [alpha, beta, d, theta1, theta2] (rad, m)."""',
        "    q = np.asarray(q, dtype=float)",
        "    qd = np.asarray(qd, dtype=float)",
        "    qdd = np.asarray(qdd, dtype=float)",
        "    n = q.shape[0]",
    ]
    used = set()
    for _, e in repl:
        used |= {str(x) for x in e.free_symbols}
    for e in reduced:
        used |= {str(x) for x in e.free_symbols}
    for k, sym in enumerate(q):
        for arr, name in (("q", sym), ("qd", qd[k]), ("qdd", qdd[k])):
            if str(name) in used:
                lines.append(f"    {name} = {arr}[:, {k}]")
    for sym in q:
        if str(sym) == "d":
            continue
        for f, fn in (("c", "cos"), ("s", "sin")):
            if f"{f}_{sym}" in used:
                lines.append(f"    {f}_{sym} = np.{fn}(q[:, {list(q).index(sym)}])")
    for sym, e in repl:
        lines.append(f"    {sym} = {pr.doprint(e)}")
    lines.append("    Y = np.zeros((n, 5, 9))")
    for (i, j, _), e in zip(entries, reduced):
        lines.append(f"    Y[:, {i}, {j}] = {pr.doprint(e)}")
    lines.append("    return Y")
    lines.append("")
    return "\n".join(lines)


TARGET = os.path.join(os.path.dirname(os.path.abspath(__file__)), "dynamics_generated.py")


def main(argv=None) -> int:
    src = generate_source()
    with open(TARGET, "w", encoding="utf-8") as fh:
        fh.write(src)
    print(f"wrote {TARGET} ({len(src.splitlines())} lines)", file=sys.stderr)
    return 0


if __name__ == "__main__":
    sys.exit(main())
