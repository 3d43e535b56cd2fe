#!/usr/bin/python3
"""Generates the recursive algorithms (RNEA, CRBA) unrolled for the PUMA 560 as C++.

    /usr/bin/python3 scripts/generate_recursive.py [--out models/dynamics/generated]

Writes recursive_puma560_3.hpp and recursive_puma560_6.hpp (the arm with 3 and 6
moving joints, parameters at run time), and recursive_puma560_folded_3.hpp and
recursive_puma560_folded_6.hpp (the numbers of models/robots/puma560.toml folded
in; the 3-joint one with the wrist held at q4 = q5 = q6 = 0), with the parameter
vector, the structure and the folding of scripts/generate_lagrange.py; prints
how long generation took and how large the code is. Run with Debian's
interpreter and SymPy (python3-sympy 1.11); CI regenerates and diffs
(scripts/check_generated.sh).

These are the customised counterparts of the generic recursive back-ends: the
like-for-like control for the paper's claim (Sokolov & Toth 1999, sec. 5 and
6) that probing the Newton-Euler inverse dynamics is faster than "the normal
use of Lagrange", whose closed form generate_lagrange.py writes for the PUMA.
Nothing is derived anew: the recursions of models/dynamics/rnea.hpp (Luh,
Walker & Paul 1980, in joint frames, moments about the frame origins) and
models/dynamics/crba.hpp (composite rigid bodies, Walker & Orin 1982, method 3)
are run once on SymPy symbols (cos q_j = c_j, sin q_j = s_j, qd_j, qdd_j, and
the parameters, or their numbers), which unrolls them for the PUMA's structure;
a product with an exact 0 vanishes and a factor 1 disappears as SymPy forms the
expressions (the twists are multiples of pi/2, so the fixed rotations are
signed permutations, and p_j = (a_j, 0, d_j)). No trigonometric identity and no
expansion is applied (numbers are not distributed over sums), so the code
keeps the recursion's operations minus those on constant zeros and ones, and
common subexpressions are then eliminated per kernel. Kernels:
  - inverse_dynamics: tau = RNEA(q, qd, qdd), gravity included; the probing
    back-ends call it n + 2 times per forward-dynamics call, as the paper does;
  - mass_matrix_upper: H by the CRBA (Z^2 Im on the diagonal);
  - bias, coriolis, gravity: the RNEA with qdd = 0; with gravity zero; with
    qd = qdd = 0 (the zero inputs substituted before CSE);
  - dynamics: H (CRBA) and h (RNEA, qdd = 0) in one kernel, sharing
    subexpressions, as the generic CRBA back-end shares the joint rotations.
"""
import os
import sys
import time

import sympy as sp
from sympy.core.parameters import distribute

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from generate_lagrange import Model, emit_kernel, folded_parameters, generator_main, header  # noqa: E402


def link_inertia(model, j):
    """(m, h, Io) of link j as SymPy objects (symbols or folded numbers)."""
    L = model.links[j]
    h = sp.Matrix([L["hx"], L["hy"], L["hz"]])
    Io = sp.Matrix([[L["Ixx"], L["Ixy"], L["Ixz"]],
                    [L["Ixy"], L["Iyy"], L["Iyz"]],
                    [L["Ixz"], L["Iyz"], L["Izz"]]])
    return L["m"], h, Io


def rnea(model, qd, qdd, with_gravity):
    """tau = RNEA(q, qd, qdd), unrolled: models/dynamics/rnea.hpp, revolute joints."""
    n = model.n
    zero = sp.zeros(3, 1)
    w_p, wd_p = zero, zero
    a_p = -sp.Matrix(model.grav) if with_gravity else zero
    f, mom = [], []
    for j in range(n):
        R = model.R(j)
        Rt = R.T
        p = model.p(j)
        a = Rt * (a_p + wd_p.cross(p) + w_p.cross(w_p.cross(p)))
        w_in = Rt * w_p
        w = w_in + sp.Matrix([0, 0, qd[j]])
        wd = Rt * wd_p + sp.Matrix([w_in[1] * qd[j], -w_in[0] * qd[j], qdd[j]])
        m, h, Io = link_inertia(model, j)
        f.append(m * a + wd.cross(h) + w.cross(w.cross(h)))
        mom.append(Io * wd + w.cross(Io * w) + h.cross(a))
        w_p, wd_p, a_p = w, wd, a
    tau = [None] * n
    for j in range(n - 1, -1, -1):
        tau[j] = mom[j][2] + model.arm[j] * qdd[j]
        if j > 0:
            R = model.R(j)
            fp = R * f[j]
            f[j - 1] = f[j - 1] + fp
            mom[j - 1] = mom[j - 1] + R * mom[j] + model.p(j).cross(fp)
    return tau


def crba(model):
    """H(q) by composite rigid bodies, unrolled: models/dynamics/crba.hpp, revolute joints."""
    n = model.n
    mc, hc, Ic = [], [], []
    for j in range(n):
        m, h, Io = link_inertia(model, j)
        mc.append(m)
        hc.append(h)
        Ic.append(Io)
    H = sp.zeros(n, n)
    for j in range(n - 1, -1, -1):
        # Force and moment about origin j for a unit acceleration of joint j.
        f = sp.Matrix([-hc[j][1], hc[j][0], 0])
        mom = Ic[j][:, 2]
        H[j, j] = mom[2] + model.arm[j]
        for i in range(j, 0, -1):
            R = model.R(i)
            fp = R * f
            mom = R * mom + model.p(i).cross(fp)
            f = fp
            H[i - 1, j] = mom[2]
        if j > 0:
            # Composite j joins its parent, moved into joint frame j-1.
            R, p = model.R(j), model.p(j)
            hr = R * hc[j]
            mp = mc[j] * p
            mc[j - 1] = mc[j - 1] + mc[j]
            hc[j - 1] = hc[j - 1] + hr + mp
            inertia = R * Ic[j] * R.T - hr * p.T - p * hr.T - mp * p.T
            inertia = inertia + (2 * p.dot(hr) + mp.dot(p)) * sp.eye(3)
            Ic[j - 1] = Ic[j - 1] + inertia
    return H


def emit_all(m, H, tau, bias, cor, grav, folded):
    """The six kernels' C++ lines, and their CSE temporaries."""
    n = m.n
    upper = [("H", i * n + k, H[i, k]) for i in range(n) for k in range(i, n)]
    kernels = [
        ("inverse_dynamics", [("tau", i, tau[i]) for i in range(n)],
         "tau = RNEA(q, qd, qdd), gravity and Z^2 Im qdd included (the probing back-ends' one call)",
         "const S* P, const S* q, const S* qd, const S* qdd, S* tau"),
        ("mass_matrix_upper", upper,
         "upper triangle of H(q) (row-major n x n) by the CRBA, Z^2 Im included",
         "const S* P, const S* q, S* H"),
        ("bias", [("h", i, bias[i]) for i in range(n)],
         "h(q, qd) = C(q, qd) qd + g(q): the RNEA with qdd = 0",
         "const S* P, const S* q, const S* qd, S* h"),
        ("coriolis", [("c", i, cor[i]) for i in range(n)],
         "c(q, qd) = C(q, qd) qd: the RNEA with qdd = 0 and no gravity",
         "const S* P, const S* q, const S* qd, S* c"),
        ("gravity", [("g", i, grav[i]) for i in range(n)],
         "g(q): the RNEA with qd = qdd = 0",
         "const S* P, const S* q, S* g"),
        ("dynamics", upper + [("h", i, bias[i]) for i in range(n)],
         "upper triangle of H(q) (CRBA) and h(q, qd) (RNEA, qdd = 0), sharing subexpressions",
         "const S* P, const S* q, const S* qd, S* H, S* h"),
    ]
    lines, stats = [], {}
    for k, (name, outputs, doc, signature) in enumerate(kernels):
        if k:
            lines.append("")
        stats[name] = emit_kernel(m, name, outputs, doc, signature, lines, folded)
    return lines, stats


def generate(n, robot_file=None):
    t0 = time.time()
    m = Model(n)
    folded = robot_file is not None
    values = None
    if folded:
        values = folded_parameters(robot_file, n)
        m.fold(values)
    qd = list(m.qd)
    qdd = list(sp.symbols(f"qdd0:{n}"))
    zeros = [sp.Integer(0)] * n
    with distribute(False):  # keep m * (x + y) as the recursion writes it
        tau = rnea(m, qd, qdd, True)
        bias = rnea(m, qd, zeros, True)
        cor = rnea(m, qd, zeros, False)
        grav = rnea(m, zeros, zeros, True)
        H = crba(m)
    t_derive = time.time() - t0
    lines, stats = emit_all(m, H, tau, bias, cor, grav, folded)
    t_total = time.time() - t0
    struct = f"RecursivePuma560Folded_{n}" if folded else f"RecursivePuma560_{n}"
    head = header(m, struct, "generate_recursive.py",
                  "RNEA and CRBA unrolled (constant zeros and ones removed)", robot_file, values)
    tail = ["};", "", "}  // namespace pumasim::generated", ""]
    return "\n".join(head + lines + tail), stats, t_derive, t_total


def main():
    generator_main(generate, "recursive_puma560", __doc__.split("\n")[0])


if __name__ == "__main__":
    sys.exit(main())
