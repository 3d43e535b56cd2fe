#!/usr/bin/python3
"""Generates the closed-form Lagrange model of the PUMA 560 as C++.

    /usr/bin/python3 scripts/generate_lagrange.py [--out models/dynamics/generated]

Writes lagrange_puma560_3.hpp and lagrange_puma560_6.hpp (the arm with 3 and 6
moving joints, parameters at run time), and lagrange_puma560_folded_3.hpp and
lagrange_puma560_folded_6.hpp, the same with the numbers of
models/robots/puma560.toml folded in before CSE (the 3-joint one with the wrist
held at q4 = q5 = q6 = 0); prints how long generation took and how large the
code is.
Run with Debian's interpreter and SymPy (python3-sympy 1.11): the committed
files are what this script produces there, which CI checks by regenerating
and diffing (scripts/check_generated.sh).

Derivation (Lagrange, symbolic, no numbers but the arm's structure):
  - Joint frames as in models/dynamics/chain.hpp: joint frame j is joint frame j-1 moved
    by Rx(alpha_{j-1}) and p_j = (a_{j-1}, 0, d_{j-1}), then turned by Rz(q_j).
    The twists alpha are the PUMA's (pi/2, 0, -pi/2, pi/2, -pi/2, 0): they are
    the arm's structure and are fixed here; a_j, d_j, every link's ten inertial
    parameters (m, first moment h = m c, inertia about the joint-frame origin),
    the rotor inertias Z^2 Im and gravity are runtime inputs.
  - Link velocities (omega_j, v_j) in frame j, linear in qd; their columns are
    the link Jacobians. Kinetic energy of link j with barycentric parameters:
    T_j = 1/2 m v.v + v.(omega x h) + 1/2 omega.(Io omega), so
    H = sum_j [m Jv^T Jv + Jw^T S(h) Jv - Jv^T S(h) Jw + Jw^T Io Jw] + diag(Z^2 Im).
  - Coriolis and centrifugal terms from Lagrange's equation itself:
    c = d/dt(dT/dqd) - dT/dq with dT/dqd = H qd, i.e.
    c_i = sum_k d(H qd)_i/dq_k qd_k - 1/2 d(qd^T H qd)/dq_i  (exact; equivalent to
    the Christoffel form, with n + 1 instead of n^3 symbolic derivatives).
  - Gravity g = dV/dq, V = -sum_j gvec . (m_j o_j + R_j h_j) in the base frame.
  - cos q_j and sin q_j are symbols c_j, s_j; derivatives use d c_j = -s_j dq_j,
    d s_j = c_j dq_j. Common subexpressions are eliminated per kernel.
Kernels: gravity (g), mass_matrix_upper (H), coriolis (C qd alone) and
dynamics (H and h = C qd + g sharing subexpressions). emit_kernel, header and
the folding are shared with scripts/generate_recursive.py.
"""
import argparse
import os
import re
import sys
import time

import sympy as sp
from sympy.printing.c import C99CodePrinter
from sympy.printing.precedence import PRECEDENCE

TWIST_HALF_PI = [1, 0, -1, 1, -1, 0]  # PUMA 560 standard DH alpha_j in units of pi/2
PARAMS_PER_LINK = ["m", "hx", "hy", "hz", "Ixx", "Iyy", "Izz", "Ixy", "Iyz", "Ixz"]


def rot_x(k):
    """Rx(k pi/2), exactly."""
    c = [1, 0, -1, 0][k % 4]
    s = [0, 1, 0, -1][k % 4]
    return sp.Matrix([[1, 0, 0], [0, c, -s], [0, s, c]])


def rot_z(c, s):
    return sp.Matrix([[c, -s, 0], [s, c, 0], [0, 0, 1]])


def skew(v):
    return sp.Matrix([[0, -v[2], v[1]], [v[2], 0, -v[0]], [-v[1], v[0], 0]])


class Model:
    def __init__(self, n):
        self.n = n
        self.c = sp.symbols(f"c0:{n}")
        self.s = sp.symbols(f"s0:{n}")
        self.qd = sp.symbols(f"qd0:{n}")
        # Runtime parameters, in the order of the parameter vector.
        self.param_names = []
        self.links = []
        for j in range(n):
            syms = {}
            for name in PARAMS_PER_LINK:
                sym = sp.Symbol(f"{name}{j}")
                syms[name] = sym
                self.param_names.append(sym)
            self.links.append(syms)
        self.arm = []
        for j in range(n):
            sym = sp.Symbol(f"arm{j}")
            self.arm.append(sym)
            self.param_names.append(sym)
        self.a, self.d = [], []
        for j in range(n - 1):  # p_{j+1} = (a_j, 0, d_j)
            for lst, name in ((self.a, "a"), (self.d, "d")):
                sym = sp.Symbol(f"{name}{j}")
                lst.append(sym)
                self.param_names.append(sym)
        self.grav = sp.symbols("gx gy gz")
        self.param_names.extend(self.grav)

    def fold(self, values):
        """Replace every runtime parameter by its number (exact zero where it is 0)."""
        num = [sp.Integer(0) if v == 0 else v for v in values]
        it = iter(num)
        for syms in self.links:
            for name in PARAMS_PER_LINK:
                syms[name] = next(it)
        self.arm = [next(it) for _ in self.arm]
        for j in range(len(self.a)):
            self.a[j], self.d[j] = next(it), next(it)
        self.grav = tuple(next(it) for _ in self.grav)

    def p(self, j):
        """Origin of joint frame j in joint frame j-1."""
        if j == 0:
            return sp.Matrix([0, 0, 0])
        return sp.Matrix([self.a[j - 1], 0, self.d[j - 1]])

    def E(self, j):
        return rot_x(0 if j == 0 else TWIST_HALF_PI[j - 1])

    def R(self, j):
        """Rotation joint frame j -> joint frame j-1."""
        return self.E(j) * rot_z(self.c[j], self.s[j])

    def ddq(self, expr, k):
        """d expr / d q_k through c_k and s_k."""
        return sp.diff(expr, self.c[k]) * (-self.s[k]) + sp.diff(expr, self.s[k]) * self.c[k]

    def mass_matrix(self):
        n = self.n
        H = sp.zeros(n, n)
        w = [sp.zeros(3, 1) for _ in range(n)]  # Jacobian columns of omega in current frame
        v = [sp.zeros(3, 1) for _ in range(n)]
        for j in range(n):
            Rt = self.R(j).T
            pj = self.p(j)
            w_new, v_new = [], []
            for i in range(n):
                wi = Rt * w[i]
                vi = Rt * (v[i] + w[i].cross(pj))
                if i == j:
                    wi = wi + sp.Matrix([0, 0, 1])
                w_new.append(wi)
                v_new.append(vi)
            w, v = w_new, v_new
            L = self.links[j]
            h = sp.Matrix([L["hx"], L["hy"], L["hz"]])
            Io = sp.Matrix([[L["Ixx"], L["Ixy"], L["Ixz"]],
                            [L["Ixy"], L["Iyy"], L["Iyz"]],
                            [L["Ixz"], L["Iyz"], L["Izz"]]])
            Sh = skew(h)
            for i in range(j + 1):
                for k in range(i, j + 1):
                    term = (L["m"] * v[i].dot(v[k]) + w[i].dot(Sh * v[k]) - v[i].dot(Sh * w[k])
                            + w[i].dot(Io * w[k]))
                    H[i, k] += term
        for i in range(n):
            H[i, i] += self.arm[i]
            for k in range(i):
                H[i, k] = H[k, i]
        return H

    def gravity(self):
        n = self.n
        R = sp.eye(3)
        o = sp.zeros(3, 1)
        V = 0
        g = sp.Matrix(self.grav)
        for j in range(n):
            o = o + R * self.p(j)
            R = R * self.R(j)
            L = self.links[j]
            h = sp.Matrix([L["hx"], L["hy"], L["hz"]])
            V -= g.dot(L["m"] * o + R * h)
        return [self.ddq(V, i) for i in range(n)]

    def coriolis(self, H):
        n = self.n
        qd = sp.Matrix(self.qd)
        p = H * qd
        T2 = qd.dot(p)  # 2 T
        c = []
        for i in range(n):
            ci = sum((self.ddq(p[i], k) * self.qd[k] for k in range(n)), sp.Integer(0))
            ci -= sp.Rational(1, 2) * self.ddq(T2, i)
            c.append(ci)
        return c


def folded_parameters(robot_file, n):
    """Parameter values (in Model.param_names order) from a standard-DH robot file.

    An independent Python implementation of the conversion that models/dynamics/chain.hpp
    and lock_joints do in C++: DH link frames to joint frames, barycentric
    parameters about each joint-frame origin, and links n..5 lumped into link
    n-1 with their joints held at zero.
    """
    import tomllib
    with open(robot_file, "rb") as f:
        doc = tomllib.load(f)
    if doc["robot"]["convention"] != "standard":
        raise SystemExit(f"{robot_file}: folding needs a standard-DH robot file")
    joints = doc["joint"]
    if len(joints) != len(TWIST_HALF_PI):
        raise SystemExit(f"{robot_file}: expected {len(TWIST_HALF_PI)} joints")
    for j, J in enumerate(joints):
        if abs(J["alpha"] - TWIST_HALF_PI[j] * sp.pi.evalf(30) / 2) > 1e-12 or J.get("offset", 0.0) != 0.0:
            raise SystemExit(f"{robot_file}: joint {j + 1} does not have the PUMA 560's structure")

    def link(J):
        """(m, h, Io) of a link in its joint frame (joint frame = DH frame j-1 * Rz(q_j))."""
        m = sp.Float(J["mass"], 17)
        RF = rot_x(round(J["alpha"] / (float(sp.pi) / 2)))
        t = sp.Matrix([J["a"], 0, J["d"]])
        c = RF * sp.Matrix(J["com"]) + t
        Ixx, Iyy, Izz, Ixy, Iyz, Ixz = J["inertia"]
        Ic = sp.Matrix([[Ixx, Ixy, Ixz], [Ixy, Iyy, Iyz], [Ixz, Iyz, Izz]])
        Ic = RF * Ic * RF.T
        Io = Ic + m * (c.dot(c) * sp.eye(3) - c * c.T)
        return m, m * c, Io

    def move(body, R, t):
        """(m, h, Io) of a body moved by r' = R r + t."""
        m, h, Io = body
        hr = R * h
        Io2 = R * Io * R.T + (2 * t.dot(hr) + m * t.dot(t)) * sp.eye(3) - hr * t.T - t * hr.T - m * t * t.T
        return m, hr + m * t, Io2

    bodies = [link(J) for J in joints]
    if n < len(joints):
        # Lump links n..5 into link n-1: joint frame k in joint frame k-1 is
        # Rx(alpha_{k-1}) with origin (a_{k-1}, 0, d_{k-1}) when q_k = 0.
        m, h, Io = bodies[n - 1]
        R, t = sp.eye(3), sp.zeros(3, 1)
        for k in range(n, len(joints)):
            P = joints[k - 1]
            t = t + R * sp.Matrix([P["a"], 0, P["d"]])
            R = R * rot_x(TWIST_HALF_PI[k - 1])
            mk, hk, Iok = move(bodies[k], R, t)
            m, h, Io = m + mk, h + hk, Io + Iok
        bodies = bodies[:n - 1] + [(m, h, Io)]
    values = []
    for (m, h, Io) in bodies:
        values += [m, h[0], h[1], h[2], Io[0, 0], Io[1, 1], Io[2, 2], Io[0, 1], Io[1, 2], Io[0, 2]]
    values += [J["gear_ratio"] ** 2 * J["rotor_inertia"] for J in joints[:n]]
    for J in joints[:n - 1]:
        values += [J["a"], J["d"]]
    values += list(doc["robot"]["gravity"])
    return [sp.Float(float(v), 17) for v in values]


class Printer(C99CodePrinter):
    """C++ for a generic scalar S: integer powers as products, no libm calls."""

    def _print_Pow(self, expr):
        base, exp = expr.as_base_exp()
        if exp.is_Integer and exp > 0:
            b = self.parenthesize(base, PRECEDENCE["Mul"])
            return "*".join([b] * int(exp))
        if exp.is_Integer and exp < 0:
            return "S(1)/(" + self._print(base ** (-exp)) + ")"
        raise ValueError(f"unexpected power {expr}")

    def _print_Rational(self, expr):
        return f"S({float(expr.p) / float(expr.q)!r})"

    def _print_Integer(self, expr):
        return f"S({int(expr)})"

    def _print_Float(self, expr):
        return f"S({float(expr)!r})"


def without_dead_temporaries(repl, reduced):
    """CSE's temporaries minus those no output needs (CSE can leave one behind
    when its only use was folded into another temporary)."""
    needed = set().union(*(e.free_symbols for e in reduced))
    kept = []
    for sym, e in reversed(repl):
        if sym in needed:
            kept.append((sym, e))
            needed |= e.free_symbols
    return kept[::-1]


def emit_kernel(model, name, outputs, inputs_doc, signature, out_lines, folded=False):
    """CSE over the (name, index, expr) outputs and C++ for one kernel."""
    exprs = [e for (_, _, e) in outputs]
    repl, reduced = sp.cse(exprs, symbols=sp.numbered_symbols("t"), order="none")
    repl = without_dead_temporaries(repl, reduced)
    pr = Printer()
    body = []
    for sym, e in repl:
        body.append(f"  const S {sym} = {pr.doprint(e)};")
    for (arr, idx, _), e in zip(outputs, reduced):
        body.append(f"  {arr}[{idx}] = {pr.doprint(e)};")
    used = set()
    for line in body:
        used.update(re.findall(r"[A-Za-z_][A-Za-z0-9_]*", line))
    out_lines.append(f"  // {inputs_doc}")
    out_lines.append(f"  template <class S>")
    if folded:
        signature = signature.replace("const S* P", "const S* /*P: folded in*/")
    out_lines.append(f"  static void {name}({signature}) {{")
    if any(f"c{j}" in used or f"s{j}" in used for j in range(model.n)):
        out_lines.append("    using std::cos;")
        out_lines.append("    using std::sin;")
    for j in range(model.n):
        if f"c{j}" in used:
            out_lines.append(f"    const S c{j} = cos(q[{j}]);")
        if f"s{j}" in used:
            out_lines.append(f"    const S s{j} = sin(q[{j}]);")
    for j in range(model.n):
        if f"qd{j}" in used:
            out_lines.append(f"    const S qd{j} = qd[{j}];")
    for j in range(model.n):
        if f"qdd{j}" in used:
            out_lines.append(f"    const S qdd{j} = qdd[{j}];")
    for k, sym in enumerate(model.param_names):
        if str(sym) in used:
            out_lines.append(f"    const S& {sym} = P[{k}];")
    out_lines.extend("  " + line for line in body)
    out_lines.append("  }")
    return len(repl)


def header(m, struct, script, title, robot_file=None, values=None):
    """The generated file's opening: what it is, the parameter order, and the
    struct's constants (joint count, twists, parameter names, folded values)."""
    n = m.n
    folded = robot_file is not None
    twist = ", ".join(str(t) for t in TWIST_HALF_PI[:n])
    params = ", ".join(f'"{p}"' for p in m.param_names)
    what = (f"with the parameters of {os.path.relpath(robot_file, os.path.join(os.path.dirname(__file__), '..'))} "
            "folded in" + (" (wrist held at q4 = q5 = q6 = 0)" if n < 6 else "")
            if folded else "with its parameters as runtime inputs P")
    head = [
        f"// GENERATED by scripts/{script} -- do not edit; regenerate instead.",
        f"// {title} of the PUMA 560 with {n} moving joints (SymPy {sp.__version__}),",
        f"// {what}.",
        "// Parameter vector order (kParamNames): per link j the mass, first moment h = m c",
        "// and inertia about the joint-frame origin (models/dynamics/chain.hpp), then the rotor",
        "// inertias Z^2 Im, then a_j and d_j (p_{j+1} = (a_j, 0, d_j)), then gravity.",
        "#pragma once",
        "",
        "#include <cmath>",
        "",
        "namespace pumasim::generated {",
        "",
        f"struct {struct} {{",
        f"  static constexpr int kDof = {n};",
        f"  // Twist alpha_j of each joint frame's fixed rotation Rx(alpha), in units of pi/2.",
        f"  static constexpr int kTwistHalfPi[{n}] = {{{twist}}};",
        f"  static constexpr int kNumParams = {len(m.param_names)};",
        f"  static constexpr const char* kParamNames[{len(m.param_names)}] = {{{params}}};",
    ]
    if folded:
        vals = ", ".join(repr(float(v)) for v in values)
        head.append(f"  // The values folded in; a model must match them to use these kernels.")
        head.append(f"  static constexpr double kFoldedParams[{len(values)}] = {{{vals}}};")
    head.append("")
    return head


def generate(n, robot_file=None):
    t0 = time.time()
    m = Model(n)
    folded = robot_file is not None
    values = None
    if folded:
        values = folded_parameters(robot_file, n)
        m.fold(values)  # numbers enter before the derivation, so zeros prune it early
    H = m.mass_matrix()
    g = m.gravity()
    c = m.coriolis(H)
    t_derive = time.time() - t0
    upper = [("H", i * n + k, H[i, k]) for i in range(n) for k in range(i, n)]
    lines = []
    stats = {}
    stats["gravity"] = emit_kernel(m, "gravity", [("g", i, g[i]) for i in range(n)],
                                   "g(q): gravity torques", "const S* P, const S* q, S* g", lines, folded)
    lines.append("")
    stats["mass_matrix"] = emit_kernel(m, "mass_matrix_upper", upper,
                                       "upper triangle of H(q) (row-major n x n), Z^2 Im included",
                                       "const S* P, const S* q, S* H", lines, folded)
    lines.append("")
    stats["coriolis"] = emit_kernel(m, "coriolis", [("c", i, c[i]) for i in range(n)],
                                    "c(q, qd) = C(q, qd) qd: Coriolis and centrifugal torques (h without g)",
                                    "const S* P, const S* q, const S* qd, S* c", lines, folded)
    lines.append("")
    stats["dynamics"] = emit_kernel(
        m, "dynamics", upper + [("h", i, c[i] + g[i]) for i in range(n)],
        "upper triangle of H(q) and h(q, qd) = C(q, qd) qd + g(q), sharing subexpressions",
        "const S* P, const S* q, const S* qd, S* H, S* h", lines, folded)
    t_total = time.time() - t0
    struct = f"LagrangePuma560Folded_{n}" if folded else f"LagrangePuma560_{n}"
    head = header(m, struct, "generate_lagrange.py", "Closed-form Lagrange model", robot_file, values)
    tail = ["};", "", "}  // namespace pumasim::generated", ""]
    return "\n".join(head + lines + tail), stats, t_derive, t_total


def generator_main(generate, prefix, description):
    """The command line of a generator: writes <prefix>_{,folded_}<n>.hpp for each --dof,
    generate(n, robot_file or None) -> (text, stats, t_derive, t_total) making each."""
    ap = argparse.ArgumentParser(description=description)
    ap.add_argument("--out", default=os.path.join(os.path.dirname(__file__), "..", "models", "dynamics", "generated"))
    ap.add_argument("--dof", type=int, nargs="*", default=[3, 6])
    ap.add_argument("--robot", default=os.path.join(os.path.dirname(__file__), "..", "models", "robots",
                                                    "puma560.toml"),
                    help="robot file whose numbers the folded variant carries")
    args = ap.parse_args()
    os.makedirs(args.out, exist_ok=True)
    for n, fold in [(n, f) for f in (False, True) for n in args.dof]:
        text, stats, t_derive, t_total = generate(n, args.robot if fold else None)
        path = os.path.join(args.out, f"{prefix}_{'folded_' if fold else ''}{n}.hpp")
        with open(path, "w") as f:
            f.write(text)
        print(f"n = {n}{', folded' if fold else ''}: derivation {t_derive:.1f} s, total with CSE and printing {t_total:.1f} s; "
              f"{path}: {len(text):,} bytes, {text.count(chr(10)):,} lines; "
              f"CSE temporaries: " + ", ".join(f"{k} {v}" for k, v in stats.items()), flush=True)


def main():
    generator_main(generate, "lagrange_puma560", __doc__.split("\n")[0])


if __name__ == "__main__":
    sys.exit(main())
