#!/usr/bin/env python3
"""Turns the dynamics benchmark's JSON into results/dynamics_backends.md and
the cost-against-n plot beside it (dynamics_cost_vs_n.png and the same as
dynamics_cost_vs_n.pdf, matplotlib, in the house style: pumasim_exp/style.py).

Usage: dynamics_table.py <bench_dynamics JSON> <output .md>

Every number in the output is read from the JSON (Google Benchmark medians of
5 repetitions, and the operation counts the benchmark attaches as counters),
but the published reference points (the paper's 425/369, Armstrong, Khatib &
Burdick 1986) and issue 17's figures for RBDL and Pinocchio, which are
constants below with their sources; ratios are taken between benchmarks of the
same run, except the ratios to issue 17's figures, which are labelled so.
"""
import json
import os
import subprocess
import sys
from collections import defaultdict

from pumasim_exp import style

PAPER_MUL, PAPER_ADD = 425, 369  # Sokolov & Toth 1999, sec. 5: Lagrange, n = 6, per step
# Armstrong, Khatib & Burdick 1986, "The explicit dynamic model and inertial
# parameters of the PUMA 560 arm", Proc. IEEE ICRA 1986, vol. 3, pp. 510-518.
# Read here only in text (OCR) copies: the abstract and opening at
# https://zbook.org/read/b3be7e_the-explicit-dynamic-and-inertial-parameters-of-puma-566-pdf.html,
# the derivation's paragraph in a copy embedded in http://gildia-stark.phorum.pl/viewtopic.php?p=726.
# Their Table 1 (cost of the RNE, of the full explicit model and of the
# abbreviated one) was not found in a readable form; its figures are not quoted.
AKB86_READ = ("read in OCR text copies (zbook.org/read/b3be7e…, and a copy embedded in "
              "gildia-stark.phorum.pl/viewtopic.php?p=726); OCR errors are possible")
AKB86 = [
    ("Armstrong, Khatib & Burdick 1986, ICRA, pp. 510–518, abstract",
     "the explicit PUMA 560 model \"abbreviated from the full explicit model with a 1% significance "
     "criterion\" (terms below 1 % dropped: not exact), n = 6: \"can be evaluated with 305 calculations, "
     "one fifth the number required by the recursive Newton-Euler method\"; multiplies and additions "
     "together; " + AKB86_READ, "305 (total)", "(in the total)"),
    ("Armstrong, Khatib & Burdick 1986, sec. on the derivation",
     "the raw output of their symbolic program EMDEG, \"including Coriolis and centrifugal terms\", "
     "before their simplification (a size of generated code, not their model's cost); " + AKB86_READ,
     "15,000", "3,500"),
    ("Armstrong, Khatib & Burdick 1986, Table 1",
     "the cost of the RNE algorithm, of the full explicit model and of the abbreviated one, which the "
     "text says Table 1 gives: the table was not found in a readable source here, so its figures (and "
     "any split into kinetic-energy matrix, Coriolis/centrifugal and gravity terms) are not quoted",
     "not found", "not found"),
]
# Issue 17 of this project ("The whole run at the limit"), its targets: "random48: CRBA and
# forward dynamics <= 1.0x the best anchor's figure as measured on this kind of machine (CRBA
# about 5.5 us, forward dynamics about 8.5 us)", the best of RBDL and Pinocchio, measured by the
# issue's author; the issue names neither library's version nor build, and gives no figure for
# other n. Neither library is part of this project or installed here (not in Debian 12).
ANCHOR_SOURCE = ("issue 17's figures: the best of RBDL and Pinocchio at n = 48, measured by the "
                 "issue's author on this kind of machine (versions and build not given in the "
                 "issue); not part of the project, not measured in this run")
ANCHORS = {("H", 48): 5500.0, ("fd", 48): 8500.0}  # ns
PLOT_NAME = "dynamics_cost_vs_n.png"
REFERENCE = "rnea-probing"
OPS = ("mul", "add", "div", "sqrt", "trig")
SPLIT = ("H", "c", "g", "solve", "id")  # counter prefixes of the forward-dynamics rows
# Like for like: (kind, probing, Lagrange, CRBA) back-ends of the same kind.
KINDS = [
    ("generic", "rnea-probing", "lagrange-euler", "crba"),
    ("generated, parameters at run time", "rnea-probing-symbolic", "lagrange-symbolic", "crba-symbolic"),
    ("generated, numbers folded in", "rnea-probing-symbolic-puma560", "lagrange-symbolic-puma560",
     "crba-symbolic-puma560"),
]


def load(path):
    with open(path) as f:
        doc = json.load(f)
    rows = defaultdict(dict)  # (quantity, robot) -> backend -> record
    plant = defaultdict(dict)  # scene -> "plant_rhs" / "plant_jacobian" -> record
    for b in doc["benchmarks"]:
        if b.get("aggregate_name") != "median":
            continue
        parts = b["run_name"].split("/")
        scale = {"ns": 1.0, "us": 1e3, "ms": 1e6, "s": 1e9}[b["time_unit"]]
        if len(parts) == 2:  # plant_rhs/<scene>, plant_jacobian/<scene>
            plant[parts[1]][parts[0]] = {"ns": b["real_time"] * scale, "m": int(round(b["m"])),
                                         "n": int(round(b["n"]))}
            continue
        quantity, robot, backend = parts
        rows[(quantity, robot)][backend] = {
            "ns": b["real_time"] * scale,
            # operation counts: not on the `jacobian` rows
            **{k: int(round(b.get(k, 0))) for k in ("n", "mul", "add", "div", "sqrt", "trig")},
            # forward dynamics only: the split (H_, c_, g_, solve_, id_ counters)
            **{k: int(round(v)) for k, v in b.items()
               if k.split("_")[0] in SPLIT and k.split("_")[-1] in OPS},
        }
    ctx = dict(doc["context"])
    ctx["source"] = os.path.relpath(os.path.abspath(path), os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
    ctx["repetitions"] = max((b.get("repetitions", 1) for b in doc["benchmarks"]), default="?")
    return ctx, rows, plant


def fmt_ns(x):
    return f"{x:,.0f}" if x >= 100 else f"{x:.1f}"


def git_revision():
    try:
        return subprocess.check_output(["git", "rev-parse", "--short", "HEAD"], text=True).strip()
    except (OSError, subprocess.CalledProcessError):
        return "unknown"


def header(ctx):
    """The document's title and the description of the run (the benchmark's context ctx) and columns."""
    out = []
    w = out.append
    w("# Dynamics back-ends: time per call and operation counts\n")
    w("Generated by `experiments/bench_dynamics.sh` (Google Benchmark, `experiments/bench_dynamics.cpp`) "
      f"and `experiments/dynamics_table.py` from `{ctx['source']}`. Do not edit by hand.\n")
    # bench_dynamics records the build that ran (its build information) in the
    # context; a JSON written before it did is described as the release preset.
    revision = ctx.get("pumasim_git_revision") or git_revision()
    build = (f"{ctx['pumasim_build_type']} (`{ctx['pumasim_flags']}`, {ctx.get('pumasim_compiler', '?')})"
             if "pumasim_flags" in ctx and "pumasim_build_type" in ctx else "Release (`-O3 -march=native`)")
    w(f"- run: {ctx.get('date', '?')}, git `{revision}`, host `{ctx.get('host_name', '?')}`, "
      f"{ctx.get('num_cpus', '?')} CPUs at {ctx.get('mhz_per_cpu', '?')} MHz, "
      f"pumasim built {build}; the Google Benchmark library itself reports "
      f"build type '{ctx.get('library_build_type', '?')}' (Debian's package), which does not affect "
      f"the timed code")
    w(f"- time: median of {ctx['repetitions']} repetitions of the wall time per call, through the `DynamicsBackend` "
      "interface (one virtual call per call), deterministic random state")
    w(f"- ratio: time / time of `{REFERENCE}` for the same robot and quantity, in the same run")
    w("- operations: one call run on the `Counted` scalar (multiplies, additions and subtractions, "
      "divisions, square roots, sin/cos); they do not depend on the machine\n")
    w("`fd` = forward dynamics qdd = H⁻¹(tau − h) with the rotor inertia Z²Im in H; "
      "`H` = mass matrix; `id` = inverse dynamics (the RNEA for every back-end but "
      "`lagrange-euler`, whose inverse dynamics is its own D qdd + h + c).\n")
    return out


def robot_section(robot, rows, backends):
    """One robot's section: per back-end (fastest forward dynamics first) the
    times, ratios and operation counts; nothing without forward-dynamics rows."""
    out = []
    w = out.append
    fd, H, idr = rows.get(("fd", robot), {}), rows.get(("H", robot), {}), rows.get(("id", robot), {})
    if not fd:
        return out
    n = next(iter(fd.values()))["n"]
    w(f"## {robot} (n = {n})\n")
    w("| back-end | fd [ns] | fd ratio | H [ns] | H ratio | id [ns] | fd mul | fd add | fd div | fd sqrt | fd trig | H mul | H add |")
    w("|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|")
    for b in sorted(backends, key=lambda b: fd.get(b, {}).get("ns", float("inf"))):
        if b not in fd:
            continue
        f, h, i = fd[b], H.get(b), idr.get(b)
        ratio_f = f["ns"] / fd[REFERENCE]["ns"] if REFERENCE in fd else float("nan")
        ratio_h = h["ns"] / H[REFERENCE]["ns"] if h and REFERENCE in H else float("nan")
        w(f"| `{b}` | {fmt_ns(f['ns'])} | {ratio_f:.2f} | {fmt_ns(h['ns']) if h else '–'} | "
          f"{ratio_h:.2f} | {fmt_ns(i['ns']) if i else '–'} | {f['mul']:,} | {f['add']:,} | "
          f"{f['div']} | {f['sqrt']} | {f['trig']} | {h['mul'] if h else 0:,} | {h['add'] if h else 0:,} |")
    if REFERENCE in fd and REFERENCE in idr:
        calls = n + 2
        honest = fd[REFERENCE]["ns"] / (calls * idr[REFERENCE]["ns"])
        w(f"\n`{REFERENCE}` forward dynamics = {honest:.2f} × the time of {calls} (n + 2) RNEA calls "
          f"({fmt_ns(fd[REFERENCE]['ns'])} ns against {calls} × {fmt_ns(idr[REFERENCE]['ns'])} ns); "
          f"the rest is the Cholesky solve and the subtractions.")
    w("")
    return out


def like_for_like(rows, robots):
    """The paper's claim, like for like: per PUMA robot and kind, the forward
    dynamics of probing, of Lagrange and of the CRBA, and probing's ratios."""
    out = []
    w = out.append
    pumas = [r for r in robots if r.startswith("puma560")]
    if not pumas:
        return out
    w("## The paper's claim, like for like\n")
    w("Forward dynamics of the PUMA 560: all six joints (n = 6), and the first three with the wrist "
      "held at zero (n = 3: the joints the paper's experiment moves; its dynamics module, the paper "
      "says, takes all six into account). Each row compares back-ends of one kind. *generic*: they serve any arm "
      "and multiply by the PUMA's zero parameters like by any other (`lagrange-euler` is the textbook "
      "Lagrange-Euler formulation, the paper's reference [10]). *generated*: made for the PUMA by "
      "the same SymPy pipeline (`scripts/generate_lagrange.py` for Lagrange, "
      "`scripts/generate_recursive.py` for the RNEA and the CRBA: the recursion unrolled, operations "
      "on constant zeros and ones removed, common subexpressions shared), with the parameters at run "
      "time (any arm of the PUMA's structure) or with `puma560.toml`'s numbers folded in. Probing "
      "is n + 2 inverse-dynamics calls of the RNEA of its kind. Ratios are between times of the "
      "same run; the machine is shared (2 cores, other jobs running): a ratio near 1 is not "
      "decided by one run.\n")
    w("| robot | kind | probing [ns] | Lagrange [ns] | CRBA [ns] | probing / Lagrange | "
      "probing / CRBA | probing mul / add | Lagrange mul / add | CRBA mul / add |")
    w("|---|---|---:|---:|---:|---:|---:|---:|---:|---:|")
    for robot in pumas:
        fd = rows.get(("fd", robot), {})
        n = next(iter(fd.values()))["n"] if fd else "?"
        for kind, probing, lagrange, crba in KINDS:
            if not all(b in fd for b in (probing, lagrange, crba)):
                continue
            p, l, c = fd[probing], fd[lagrange], fd[crba]
            w(f"| {robot} (n = {n}) | {kind} (`{probing}`, `{lagrange}`, `{crba}`) | {fmt_ns(p['ns'])} | "
              f"{fmt_ns(l['ns'])} | {fmt_ns(c['ns'])} | {p['ns'] / l['ns']:.2f} | {p['ns'] / c['ns']:.2f} | "
              f"{p['mul']:,} / {p['add']:,} | {l['mul']:,} / {l['add']:,} | {c['mul']:,} / {c['add']:,} |")
    w("")
    return out


def split_counts(rows, robots):
    """Operation counts of H, c = C qd, g and the solve per back-end, on the PUMA robots."""
    out = []
    w = out.append
    pumas = [r for r in robots if r.startswith("puma560")]
    if not pumas:
        return out
    w("## Operation counts split: H, c, g and the solve\n")
    w("One standalone call of each part through the back-end's own code (`Counted` scalar): `H` the "
      "mass matrix (with Z²Im); `c` = C(q, q̇) q̇, the Coriolis and centrifugal torques (h without "
      "gravity); `g` the gravity torques; `solve` the Cholesky factorisation of H and the two "
      "substitutions (the same for every back-end that forms H; the ABA forms no H); `id` one "
      "inverse-dynamics call; `fd` one forward-dynamics call as the back-end runs it. A back-end "
      "that shares work between its parts (the joint rotations; subexpressions of H and h in one "
      "generated kernel) spends less on `fd` than on its parts called one by one; probing spends "
      "n + 2 `id` calls on `fd` (its `H` is n + 1 of them: g, then one per column). Each cell is "
      "multiplies / additions; divisions, square roots and sin/cos are listed for `fd`.\n")
    w("| robot | back-end | H | c | g | solve (mul / add / div / sqrt) | id | fd | fd div / sqrt / trig |")
    w("|---|---|---:|---:|---:|---:|---:|---:|---:|")
    for robot in pumas:
        fd = rows.get(("fd", robot), {})
        for b in [x for kind in KINDS for x in kind[1:]] + sorted(set(fd) - {x for k in KINDS for x in k[1:]}):
            if b not in fd or "H_mul" not in fd[b]:
                continue
            r = fd[b]
            part = lambda k: f"{r[k + '_mul']:,} / {r[k + '_add']:,}"  # noqa: E731
            solve = (f"{r['solve_mul']} / {r['solve_add']} / {r['solve_div']} / {r['solve_sqrt']}"
                     if r["solve_mul"] else "none")
            w(f"| {robot} (n = {r['n']}) | `{b}` | {part('H')} | {part('c')} | {part('g')} | {solve} | "
              f"{part('id')} | {r['mul']:,} / {r['add']:,} | {r['div']} / {r['sqrt']} / {r['trig']} |")
    w("")
    return out


def reference_points():
    """Published operation counts for the PUMA 560, with what each counts."""
    out = []
    w = out.append
    w("## Published reference points\n")
    w("| source | what it counts, as the source says | multiplies | additions |")
    w("|---|---|---:|---:|")
    w(f"| Sokolov & Toth 1999, sec. 5 (the paper) | \"when the Lagrange formulation is used and "
      f"(n = 6 joints) there are {PAPER_MUL} multiplies and {PAPER_ADD} additions are required to take in "
      f"one simulation step\"; nothing more: not which terms (H, h, C), whether the numbers are folded "
      f"in, whether sin/cos, the solve or the probing are included, nor where the figure comes from | "
      f"{PAPER_MUL} | {PAPER_ADD} |")
    for source, what, mul, add in AKB86:
        w(f"| {source} | {what} | {mul} | {add} |")
    w("")
    return out


def cost_against_n(rows, robots, backends):
    """The forward dynamics' time, multiplies and ratio to REFERENCE against n
    on the random chains (nothing without random chains)."""
    out = []
    w = out.append
    rand = sorted((r for r in robots if r.startswith("random")), key=lambda r: int(r[6:]))
    if not rand:
        return out
    w("## Cost against n (random chains), forward dynamics\n")
    w("| back-end | " + " | ".join(f"n = {r[6:]} [ns]" for r in rand) + " | " +
      " | ".join(f"mul n = {r[6:]}" for r in rand) + " |")
    w("|---|" + "---:|" * (2 * len(rand)))
    # Back-ends made for one arm (generated for the PUMA) have no row here.
    backends = [b for b in backends if any(b in rows.get(("fd", r), {}) for r in rand)]
    for b in backends:
        cells = [fmt_ns(rows[("fd", r)][b]["ns"]) if b in rows[("fd", r)] else "–" for r in rand]
        muls = [f"{rows[('fd', r)][b]['mul']:,}" if b in rows[("fd", r)] else "–" for r in rand]
        w(f"| `{b}` | " + " | ".join(cells) + " | " + " | ".join(muls) + " |")
    w("")
    w("Mass matrix H (with Z²Im), time per call:\n")
    w("| back-end | " + " | ".join(f"n = {r[6:]} [ns]" for r in rand) + " | " +
      " | ".join(f"mul n = {r[6:]}" for r in rand) + " |")
    w("|---|" + "---:|" * (2 * len(rand)))
    for b in backends:
        if not any(b in rows.get(("H", r), {}) for r in rand):
            continue
        cells = [fmt_ns(rows[("H", r)][b]["ns"]) if b in rows.get(("H", r), {}) else "–" for r in rand]
        muls = [f"{rows[('H', r)][b]['mul']:,}" if b in rows.get(("H", r), {}) else "–" for r in rand]
        w(f"| `{b}` | " + " | ".join(cells) + " | " + " | ".join(muls) + " |")
    w("")
    w(f"Ratio to `{REFERENCE}`, forward dynamics:\n")
    w("| back-end | " + " | ".join(f"n = {r[6:]}" for r in rand) + " |")
    w("|---|" + "---:|" * len(rand))
    for b in backends:
        cells = []
        for r in rand:
            row = rows[("fd", r)]
            cells.append(f"{row[b]['ns'] / row[REFERENCE]['ns']:.2f}" if b in row and REFERENCE in row else "–")
        w(f"| `{b}` | " + " | ".join(cells) + " |")
    w("")
    return out


def jacobian_section(rows, robots, backends):
    """The forward dynamics' exact derivatives against the forward dynamics, per robot and back-end."""
    out = []
    w = out.append
    if not any(q == "jacobian" for q, _ in rows):
        return out
    w("## Exact derivatives of the forward dynamics\n")
    w("`jacobian` = dqdd/d(q, qd, tau) exactly (`DynamicsDerivatives`: the back-end's h and H in double, "
      "the Cholesky factor of H and H⁻¹ formed from it once (dFD/dtau, then two matrix products), and dID/dq, dID/dqd from analytical world-frame recursions in double "
      "(`models/dynamics/rnea_derivatives.hpp`, after Carpentier & Mansard 2018, RSS): dFD/dq = -H⁻¹ dID/dq, dFD/dqd = -H⁻¹ dID/dqd, "
      "dFD/dtau = H⁻¹), beside the same back-end's `fd`, same state, same run. A forward difference "
      "of the forward dynamics costs 3n + 1 `fd` calls.\n")
    w("| robot | back-end | fd [ns] | jacobian [ns] | jacobian / fd | 3n + 1 |")
    w("|---|---|---:|---:|---:|---:|")
    for robot in robots:
        fd, jac = rows.get(("fd", robot), {}), rows.get(("jacobian", robot), {})
        for b in sorted(backends, key=lambda b: jac.get(b, {}).get("ns", float("inf"))):
            if b not in fd or b not in jac:
                continue
            n = fd[b]["n"]
            w(f"| {robot} | `{b}` | {fmt_ns(fd[b]['ns'])} | {fmt_ns(jac[b]['ns'])} | "
              f"{jac[b]['ns'] / fd[b]['ns']:.2f} | {3 * n + 1} |")
    w("")
    return out


def against_anchors(rows, backends):
    """Our times at the n of issue 17's figures for RBDL and Pinocchio, beside them."""
    out = []
    w = out.append
    present = [(q, n) for (q, n) in sorted(ANCHORS) if rows.get((q, f"random{n}"))]
    if not present:
        return out
    w("## Large arms beside issue 17's figures for RBDL and Pinocchio\n")
    w(f"Anchor: {ANCHOR_SOURCE}. Our times are this run's (random chain, seed as in "
      f"`experiments/bench_dynamics.cpp`); a ratio to an anchor compares two runs on two "
      f"occasions, not one run, so only a clear margin means more than the machine's noise. "
      f"Plot: `{PLOT_NAME}` (and the same as `{os.path.splitext(PLOT_NAME)[0]}.pdf`).\n")
    w("| quantity | n | anchor [ns] (issue 17) | back-end | ours [ns] | ours / anchor |")
    w("|---|---:|---:|---|---:|---:|")
    for q, n in present:
        row = rows[(q, f"random{n}")]
        for b in sorted((b for b in backends if b in row), key=lambda b: row[b]["ns"]):
            if row[b]["ns"] > 10 * ANCHORS[(q, n)]:
                continue  # O(n^2) and worse back-ends: in the tables above
            w(f"| {'forward dynamics' if q == 'fd' else 'mass matrix H'} | {n} | "
              f"{fmt_ns(ANCHORS[(q, n)])} | `{b}` | {fmt_ns(row[b]['ns'])} | "
              f"{row[b]['ns'] / ANCHORS[(q, n)]:.2f} |")
    w("")
    return out


def plant_section(plant):
    """One right-hand side of a scene's plant against its exact Jacobian."""
    out = []
    w = out.append
    if not plant:
        return out
    w("## The plant: one right-hand side and its exact Jacobian\n")
    w("`plant_rhs` = one f(t, x) of the scene's plant (its back-end; the reference cached at t); "
      "`plant_jacobian` = df/dx exactly (`Plant::jacobian_exact`: one pass of f on a 24-tangent dual "
      "number per 24 states, the dynamics' tangents from `TangentBackend`), the implicit methods' "
      "default; forward differences (`--jacobian differences`) cost m + 1 right-hand sides (m states).\n")
    w("| scene | joints | states m | rhs [ns] | jacobian [ns] | jacobian / rhs | m + 1 |")
    w("|---|---:|---:|---:|---:|---:|---:|")
    for scene, r in plant.items():
        if "plant_rhs" not in r or "plant_jacobian" not in r:
            continue
        f, j = r["plant_rhs"], r["plant_jacobian"]
        w(f"| `{scene}` | {f['n']} | {f['m']} | {fmt_ns(f['ns'])} | {fmt_ns(j['ns'])} | "
          f"{j['ns'] / f['ns']:.2f} | {f['m'] + 1} |")
    w("")
    return out


def plot_cost(rows, robots, backends, path):
    """Time per call against n on the random chains, forward dynamics and H, log-log,
    with issue 17's figures for RBDL and Pinocchio as separate markers (grey
    stars); written to path (.png) and the same as .pdf beside it (style.save).
    A back-end plotted keeps its style (style.series: colour, then dash and
    marker beyond eight) across both panels."""
    plt = style.pyplot()

    rand = sorted((r for r in robots if r.startswith("random")), key=lambda r: int(r[6:]))
    if not rand:
        return
    panels = [("fd", "forward dynamics"), ("H", "mass matrix H")]
    points = {(q, b): [(int(r[6:]), rows[(q, r)][b]["ns"] / 1e3) for r in rand if b in rows.get((q, r), {})]
              for q, _ in panels for b in backends}
    plotted = [b for b in backends if any(len(points[(q, b)]) >= 2 for q, _ in panels)]
    styles = style.series_styles(plotted)
    fig, axes = plt.subplots(1, 2, figsize=(12, 5), sharey=True)
    for ax, (q, title) in zip(axes, panels):
        for b in plotted:
            pts = points[(q, b)]
            if len(pts) >= 2:
                ax.plot(*zip(*pts), label=b, **styles[b])
        anchors = [(n, t / 1e3) for (aq, n), t in sorted(ANCHORS.items()) if aq == q]
        if anchors:
            ax.plot(*zip(*anchors), linestyle="none", marker="*", markersize=14, color="0.35", zorder=3,
                    label="issue 17: best of RBDL, Pinocchio (not this run)")
        ax.set_xscale("log")
        ax.set_yscale("log")
        ax.set_xticks([int(r[6:]) for r in rand])
        ax.set_xticklabels([r[6:] for r in rand])
        ax.set_xlabel("joints n (random chains)")
        ax.set_title(title)
        ax.grid(True, which="both", alpha=0.3)
    axes[0].set_ylabel("time per call [µs]")
    # Both panels' entries (a back-end may have points in one panel only), one legend beside the right one.
    entries = {}
    for ax in axes:
        for h, lab in zip(*ax.get_legend_handles_labels()):
            entries.setdefault(lab, h)
    order = [b for b in plotted if b in entries] + [lab for lab in entries if lab not in plotted]
    style.legend_right(axes[1], [entries[lab] for lab in order], order)
    fig.suptitle("Dynamics back-ends: cost against n (medians of one run of bench_dynamics)")
    fig.tight_layout()
    style.save(fig, path)


def main(src, dst):
    ctx, rows, plant = load(src)
    backends = sorted({b for r in rows.values() for b in r})
    robots = []  # in the order of the JSON
    for (_, robot) in rows:
        if robot not in robots:
            robots.append(robot)
    out = header(ctx)
    out += like_for_like(rows, robots)
    out += split_counts(rows, robots)
    out += reference_points()
    out += jacobian_section(rows, robots, backends)
    out += plant_section(plant)
    for robot in robots:
        out += robot_section(robot, rows, backends)
    # Cost against n on the random chains.
    out += cost_against_n(rows, robots, backends)
    out += against_anchors(rows, backends)
    plot_cost(rows, robots, backends, os.path.join(os.path.dirname(dst) or ".", PLOT_NAME))
    with open(dst, "w") as f:
        f.write("\n".join(out))


if __name__ == "__main__":
    if len(sys.argv) != 3:
        sys.exit("usage: dynamics_table.py <bench.json> <out.md>")
    main(sys.argv[1], sys.argv[2])
