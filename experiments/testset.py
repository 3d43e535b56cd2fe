#!/usr/bin/python3
"""Runs the standard ODE test set over the integrator registry and writes results/testset/.

    /usr/bin/python3 experiments/testset.py [--bin build/release/bin/testset] [--out results/testset]
                                            [--reduced] [--problem NAME]... [--integrator NAME]...
                                            [--csv FILE]

Runs the `testset` binary (integrators/testset/testset_main.cpp), which prints
one CSV row per run: every registry integrator on every problem of
integrators/testset/problems.hpp, adaptive methods over an rtol ladder, fixed-step
methods over the problem's dt ladder, the error at the end point against the
published reference value. Writes, into --out:

  testset.csv           the binary's output, as it printed it
  problems.csv          the problems (size, span, tolerance scale, dt ladder, reference source)
  observed_slopes.csv   per problem x integrator: the observed order fitted over the
                        ladder's asymptotic range (experiments/order_fit.py: above the
                        rounding floor, at steps where the method is stable), or why there is
                        none (order_mark), the runs in that range and each other run's mark;
                        and, for the record, the least-squares slope of log10(error) against
                        log10(RHS evaluations) over every run that succeeded (reached the end
                        point with a mixed error below 1), which is not an order
  <problem>.png         work-precision: error against RHS evaluations, one line per
                        integrator (solid, circles: adaptive; dashed, squares: fixed
                        step), the failed runs named in the title; the same as
                        <problem>.pdf beside it (the house style, pumasim_exp/style.py)
  README.md             tables per problem and the methods whose error does not fall
                        with their tolerance; every number read from the CSVs above

--csv FILE: use an earlier run's CSV instead of running the binary.
"""
import argparse
import csv
import io
import math
import os
import subprocess
import sys
import time
from collections import OrderedDict, defaultdict

import order_fit
from pumasim_exp import io as pumasim_io
from pumasim_exp import style
from pumasim_exp.io import ROOT

# An error that rises by more than this factor when the setting tightens is a
# break in monotonicity (smaller changes are noise of the step-size controller).
RISE_FACTOR = 2.0
# A run "succeeded" when it reached the end point with a mixed error below 1
# (at least no wrong leading digit): an unstable fixed step can reach the end
# with a finite error of 1e190, which is no point of a work-precision line.
MAX_ERROR = 1.0
EPS = 2.220446049250313e-16


def rounding_level(r):
    """10 eps x steps: the error that rounding, accumulated over the run's steps, can reach."""
    return 10 * EPS * max(fnum(r["steps"]), 1.0)


def succeeded(r):
    return r["ok"] == "1" and fnum(r["mixed_error"]) < MAX_ERROR


def read_csv_text(text):
    return pumasim_io.parse_table(text).rows


def fnum(x):
    try:
        v = float(x)
    except (TypeError, ValueError):
        return math.nan
    return v


def fmt(x, digits=3):
    v = fnum(x)
    return "–" if math.isnan(v) else f"{v:.{digits}g}"


def fixed4(x):
    """A float with 4 decimals, '' for nan."""
    return f"{x:.4f}" if math.isfinite(x) else ""


def fmt_int(x):
    v = fnum(x)
    return "–" if math.isnan(v) else f"{int(v):,}"


def short(msg, n=110):
    msg = " ".join(msg.split())
    return msg if len(msg) <= n else msg[: n - 1] + "…"


write_atomic = pumasim_io.write_text_atomic


def run_binary(args, extra):
    cmd = [args.bin] + extra
    start = time.monotonic()
    proc = subprocess.run(cmd, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    if proc.returncode != 0:
        sys.stderr.write(proc.stderr)
        raise SystemExit(f"testset.py: {' '.join(cmd)} exited with status {proc.returncode}")
    return proc.stdout, time.monotonic() - start


def slope(points):
    """Least-squares slope of log10(err) against log10(rhs); None with fewer than 2 distinct x."""
    pts = [(math.log10(x), math.log10(y)) for x, y in points if x > 0 and y > 0]
    if len(pts) < 2 or len({p[0] for p in pts}) < 2:
        return None
    mx = sum(p[0] for p in pts) / len(pts)
    my = sum(p[1] for p in pts) / len(pts)
    sxx = sum((p[0] - mx) ** 2 for p in pts)
    sxy = sum((p[0] - mx) * (p[1] - my) for p in pts)
    return sxy / sxx


def loose_to_tight(runs):
    """The runs ordered from the loosest setting to the tightest (rtol or dt both: largest first)."""
    return sorted(runs, key=lambda r: -fnum(r["setting"]))


def ladder_fit(runs):
    """order_fit.asymptotic_fit over one method's ladder (runs: loose to
    tight): the error is the mixed error, n is 1/dt for a fixed step and the
    RHS evaluations for an adaptive method, the floor is the rounding one
    unit of roundoff per step accumulates to, EPS x steps (closed-form and
    published references are taken as exact); a run with a mixed error of
    MAX_ERROR or more is unstable."""
    name, fixed = runs[0]["integrator"], runs[0]["kind"] == "fixed"
    if name not in order_fit.THEORY:
        raise SystemExit(f"testset.py: {name}: no theoretical order in order_fit.THEORY (experiments/order_fit.py)")
    pts = [{"ok": r["ok"] == "1", "e": fnum(r["mixed_error"]), "floor": EPS * max(fnum(r["steps"]), 1.0),
            "n": 1.0 / fnum(r["setting"]) if fixed else fnum(r["rhs_evaluations"])} for r in runs]
    return order_fit.asymptotic_fit(pts, order_fit.THEORY[name], fixed, unstable=MAX_ERROR)


def analyse(groups):
    """Per (problem, integrator): the raw slope, the observed order over the
    asymptotic range (ladder_fit), and the findings on error against tolerance."""
    out = OrderedDict()
    for key, runs in groups.items():
        runs = loose_to_tight(runs)
        ok = [r for r in runs if succeeded(r)]
        s = slope([(fnum(r["rhs_evaluations"]), fnum(r["mixed_error"])) for r in ok])
        rises = []  # (looser run, tighter run, explained by rounding)
        for a, b in zip(ok, ok[1:]):
            if fnum(b["mixed_error"]) > RISE_FACTOR * fnum(a["mixed_error"]):
                rises.append((a, b, fnum(b["mixed_error"]) <= rounding_level(b)))
        falls = None
        if len(ok) >= 2:
            falls = fnum(ok[-1]["mixed_error"]) < fnum(ok[0]["mixed_error"])
        out[key] = {"runs": runs, "ok": ok, "slope": s, "fit": ladder_fit(runs), "rises": rises, "falls": falls,
                    "floor": bool(ok) and fnum(ok[-1]["mixed_error"]) <= rounding_level(ok[-1])}
    return out


# The line and the marker say the kind (solid with circles: adaptive, dashed
# with squares: fixed step); the colour, from the palette, the integrator
# within its kind; past the palette's eight colours the next marker of the
# kind's list keeps the series apart.
KIND_STYLE = {"adaptive": ("-", ["o", "^", "v", "<"]), "fixed": ("--", ["s", "D", "P", "X"])}


def integrator_styles(names, kinds):
    """{name: {color, ls, marker}}: the names in the order given, numbered
    within their kind (KIND_STYLE)."""
    out, count, n = {}, defaultdict(int), len(style.PALETTE)
    for name in names:
        kind = "adaptive" if kinds[name] == "adaptive" else "fixed"
        ls, markers = KIND_STYLE[kind]
        k = count[kind]
        count[kind] += 1
        out[name] = {"color": style.PALETTE[k % n], "ls": ls, "marker": markers[(k // n) % len(markers)]}
    return out


def plot(problem, info, kinds, failed, path, title_extra):
    """path (<problem>.png) and the same as .pdf beside it: error against RHS
    evaluations, one line per integrator (integrator_styles), the legend to
    the right of the data."""
    plt = style.pyplot()

    fig, ax = plt.subplots(figsize=(8.5, 6.2))
    names = sorted(info)
    styles = integrator_styles(names, kinds)
    for name in names:
        ok = info[name]["ok"]
        if not ok:
            continue
        xs = [fnum(r["rhs_evaluations"]) for r in ok]
        ys = [fnum(r["mixed_error"]) for r in ok]
        ax.loglog(xs, ys, ms=4, label=f"{name} ({kinds[name]})", **styles[name])
    ax.set_xlabel("right-hand side evaluations")
    ax.set_ylabel("mixed error at the end point, max |y - y_ref| / (|y_ref| + atol/rtol)")
    ax.grid(True, which="both", alpha=0.3)
    if ax.get_legend_handles_labels()[0]:
        style.legend_right(ax)
    title = f"{problem}: error against work" + title_extra
    if failed:
        title += "\nfailed or error >= 1 (runs of the ladder): " + "; ".join(failed)
    # Long failure lists wrap.
    words, lines, line = title.split(" "), [], ""
    for w in words:
        if "\n" in w:
            head, tail = w.split("\n", 1)
            lines.append((line + " " + head).strip())
            line = tail
        elif len(line) + len(w) + 1 > 120:
            lines.append(line)
            line = w
        else:
            line = (line + " " + w).strip()
    lines.append(line)
    ax.set_title("\n".join(lines), fontsize=7 if len(lines) > 2 else 9)
    fig.tight_layout()
    style.save(fig, path)


def failed_label(name, runs):
    bad = [r for r in runs if not succeeded(r)]
    if not bad:
        return None
    return f"{name} ({len(bad)} of {len(runs)})"


def header(rows, problems, cmd, elapsed, reduced):
    """The README's lines up to and with the problems table: the run counts,
    the error and slope definitions, one row per problem."""
    total_wall = sum(fnum(r["wall_time_s"]) for r in rows if not math.isnan(fnum(r["wall_time_s"])))
    n_ok = sum(r["ok"] == "1" for r in rows)
    n_skip = sum(r["message"].startswith("not run") for r in rows)
    L = ["# The standard ODE test set", "",
         "Generated by `experiments/testset.py` from `testset.csv` (the `testset` binary's output: "
         f"`{cmd}`), `problems.csv` and `observed_slopes.csv`; every number below is read from those files.", "",
         f"{len(rows)} runs ({'reduced set' if reduced else 'full set'}): {n_ok} reached the end point, "
         f"{len(rows) - n_ok - n_skip} failed with a reported reason, {n_skip} not run because the same method "
         f"had already exhausted its budget on that problem at a looser setting. Sum of the runs' wall times "
         f"{total_wall:.1f} s" + ("" if math.isnan(elapsed) else f" (the whole command {elapsed:.1f} s)") + ".", "",
         "Error: the test set's mixed error at the end point, max over components of |y − y_ref| / "
         "(|y_ref| + atol/rtol) with atol/rtol the problem's scale below; scd = −log10(mixed error) is "
         "the number of correct significant digits. Adaptive methods run with rtol = setting and atol = "
         "rtol × scale; fixed-step methods with dt = setting. Observed order: least squares of −log(error) "
         "against log(1/dt) (fixed step) or log(RHS evaluations) (adaptive: a cost exponent, which the "
         "step-size controller shapes; for the variable-order CVODE methods no order) over the ladder's "
         "asymptotic range only (`experiments/order_fit.py`); a run's floor is ε × its steps, the rounding "
         "one unit of roundoff per step adds up to (the references are closed forms or the published "
         f"values, taken as exact), and a run with a mixed error of {MAX_ERROR:g} or more is unstable. "
         + order_fit.RULE_TEXT + " `observed_slopes.csv` has each fit, its runs, its reason and the raw "
         "slope of log10(error) against log10(RHS evaluations) over every run that succeeded.", "",
         "## Problems", "",
         "| problem | equations | stiff | t_end | atol/rtol | fixed steps | reference |",
         "|---|---:|---|---:|---:|---|---|"]
    for p in problems:
        L.append(f"| `{p['problem']}` | {p['equations']} | {'yes' if p['stiff'] == '1' else 'no'} | "
                 f"{fmt(p['t_end'], 7)} | {fmt(p['atol_per_rtol'])} | "
                 f"{', '.join(fmt(d) for d in p['fixed_steps'].split())} | {p['reference_source']} |")
    L.append("")
    return L


def findings(analysis):
    """The findings, one line each: (error not falling with the tolerance,
    breaks in monotonicity, both at the rounding floor, runs that did not
    reach the end point, runs that reached it with an error of MAX_ERROR or more)."""
    not_falling, rising, floor, failing, diverged = [], [], [], [], []
    for (prob, name), a in analysis.items():
        ok, runs = a["ok"], a["runs"]
        if a["falls"] is False:
            lo, hi = ok[0], ok[-1]
            line = (f"`{name}` on `{prob}`: error {fmt(lo['mixed_error'])} at the loosest setting "
                    f"that succeeded ({fmt(lo['setting'])}), {fmt(hi['mixed_error'])} at the tightest "
                    f"({fmt(hi['setting'])}, {fmt_int(hi['steps'])} steps)")
            (floor if a["floor"] else not_falling).append(line)
        for x, y, rounding in a["rises"]:
            line = (f"`{name}` on `{prob}`: error {fmt(x['mixed_error'])} at {fmt(x['setting'])} → "
                    f"{fmt(y['mixed_error'])} at {fmt(y['setting'])} ({fmt_int(y['steps'])} steps)")
            (floor if rounding else rising).append(line)
        big = [r for r in runs if r["ok"] == "1" and not succeeded(r)]
        if big:
            diverged.append(f"`{name}` on `{prob}`: " + ", ".join(
                f"{fmt(r['mixed_error'])} at {fmt(r['setting'])}" for r in big))
        bad = [r for r in runs if r["ok"] != "1" and not r["message"].startswith("not run")]
        if bad:
            skipped = sum(r["message"].startswith("not run") for r in runs)
            settings = ", ".join(fmt(r["setting"]) for r in bad)
            failing.append(f"`{name}` on `{prob}`: {len(bad) + skipped} of {len(runs)} runs "
                           f"({'failed at ' + settings}{f', {skipped} not run after it' if skipped else ''}); "
                           f"first reason: {short(bad[0]['message'], 160)}")
    return not_falling, rising, floor, failing, diverged


def findings_section(analysis):
    """The README's lines on the methods whose error does not fall with their tolerance."""
    not_falling, rising, floor, failing, diverged = findings(analysis)
    L = ["## Methods whose error does not fall with their tolerance", "",
         "Error at the tightest setting that succeeded not below the error at the loosest one:", ""]
    L += [f"- {x}" for x in not_falling] or ["- none"]
    L += ["", f"Error rising by more than a factor {RISE_FACTOR:g} from one setting to the next tighter one "
          "(monotonicity broken):", ""]
    L += [f"- {x}" for x in rising] or ["- none"]
    L += ["", "The same at the rounding floor -- the tighter run's error is below 10 ε × its number of steps, "
          "the size rounding errors accumulated over the steps reach (not a defect of the method):", ""]
    L += [f"- {x}" for x in floor] or ["- none"]
    L += ["", f"Runs that reached the end point with a mixed error of {MAX_ERROR:g} or more (no correct "
          "digit: unstable or far too coarse; left out of the plots and slopes):", ""]
    L += [f"- {x}" for x in diverged] or ["- none"]
    L += ["", "Runs that did not reach the end point (each with its reason in `testset.csv`):", ""]
    L += [f"- {x}" for x in failing] or ["- none"]
    L.append("")
    return L


def method_row(name, a):
    """A problem table's row of one integrator (a: its analysis)."""
    runs, ok = a["runs"], a["ok"]
    kind = runs[0]["kind"]
    ladder = f"{fmt(runs[0]['setting'])} … {fmt(runs[-1]['setting'])} ({len(runs)})"

    def span(col, f):
        if not ok:
            return "–"
        return f(ok[0][col]) if len(ok) == 1 else f"{f(ok[0][col])} → {f(ok[-1][col])}"
    if ok:
        best = max(ok, key=lambda r: fnum(r["scd"]))
        best_s = f"{fmt(best['scd'])} ({fmt_int(best['rhs_evaluations'])})"
    else:
        best_s = "–"
    wall = sum(fnum(r["wall_time_s"]) for r in runs if not math.isnan(fnum(r["wall_time_s"])))
    bad = [r for r in runs if r["ok"] != "1"]
    why = f"{fmt(bad[0]['setting'])}: {short(bad[0]['message'], 90)}" if bad else ""
    if not why and len(ok) < len(runs):
        why = "error ≥ 1 at " + ", ".join(fmt(r["setting"]) for r in runs if not succeeded(r))
    s = order_fit.slope_cell(a["fit"]).replace("|", "/")
    if math.isfinite(a["fit"]["slope"]):
        s += f" ({len(a['fit']['used'])})"
    return (f"| `{name}` | {kind} | {len(ok)} / {len(runs)} | {ladder} | {span('setting', fmt)} | "
            f"{span('scd', fmt)} | {span('rhs_evaluations', fmt_int)} | {best_s} | {s} | {wall:.3g} "
            f"| {why.replace('|', '/')} |")


def problem_sections(problems, analysis):
    """The README's section per problem: its description and a row per integrator."""
    by_problem = defaultdict(list)
    for (prob, name), a in analysis.items():
        by_problem[prob].append((name, a))
    L = []
    for p in problems:
        prob = p["problem"]
        L += [f"## `{prob}`", "", f"{p['description']}. Reference: {p['reference_source']}. "
              f"Plot: `{prob}.png` (and the same as `{prob}.pdf`).", "",
              "| integrator | kind | runs ok | ladder | loosest → tightest setting that succeeded | scd there "
              "| RHS evaluations there | best scd (RHS) | observed order (runs in range) | wall time, s (all runs) "
              "| first failure |",
              "|---|---|---:|---|---|---|---|---|---:|---:|---|"]
        for name, a in by_problem.get(prob, []):
            L.append(method_row(name, a))
        L.append("")
    return L


def readme(rows, problems, analysis, args, cmd, elapsed, reduced):
    """results/testset/README.md's text (without the final newline)."""
    L = header(rows, problems, cmd, elapsed, reduced)
    # The findings: error not falling with the tolerance, breaks in monotonicity, failures.
    L += findings_section(analysis)
    L += problem_sections(problems, analysis)
    return "\n".join(L)


def write_slopes(path, analysis):
    """observed_slopes.csv: per problem x integrator its runs, those that
    succeeded, the raw slope, and the observed order over the asymptotic
    range (or why there is none) with each other run's mark."""
    out = io.StringIO()
    w = csv.writer(out, lineterminator="\n")
    w.writerow(["problem", "integrator", "kind", "theoretical_order", "runs", "runs_ok",
                "slope_log_error_per_log_rhs", "observed_order", "runs_in_range", "order_mark",
                "finest_pair", "finest_pair_mark", "run_marks"])
    for (prob, name), a in analysis.items():
        f = a["fit"]
        marks = "; ".join(f"{fmt(r['setting'])} {m}" for r, m in zip(a["runs"], f["marks"]) if m)
        w.writerow([prob, name, a["runs"][0]["kind"], order_fit.THEORY[name], len(a["runs"]), len(a["ok"]),
                    "" if a["slope"] is None else f"{a['slope']:.4f}", fixed4(f["slope"]), len(f["used"]),
                    f["reason"], fixed4(f["finest_pair"]), f["finest_pair_mark"] or "", marks])
    write_atomic(path, out.getvalue())


def plot_problems(problems, analysis, out_dir, title_extra):
    """<problem>.png and <problem>.pdf in out_dir for every problem."""
    for p in problems:
        prob = p["problem"]
        info = {name: a for (pr, name), a in analysis.items() if pr == prob}
        kinds = {name: a["runs"][0]["kind"] for name, a in info.items()}
        failed = [lab for name in sorted(info) if (lab := failed_label(name, info[name]["runs"]))]
        plot(prob, info, kinds, failed, os.path.join(out_dir, prob + ".png"), title_extra)


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--bin", default=os.path.join(ROOT, "build", "release", "bin", "testset"))
    ap.add_argument("--out", default=os.path.join(ROOT, "results", "testset"))
    ap.add_argument("--reduced", action="store_true", help="few tolerances and steps (CI)")
    ap.add_argument("--problem", action="append", default=[])
    ap.add_argument("--integrator", action="append", default=[])
    ap.add_argument("--csv", help="read this CSV instead of running the binary")
    args = ap.parse_args()

    extra = (["--reduced"] if args.reduced else []) + sum((["--problem", p] for p in args.problem), []) + \
        sum((["--integrator", i] for i in args.integrator), [])
    os.makedirs(args.out, exist_ok=True)
    problems_text, _ = run_binary(args, ["--list-problems"])
    if args.csv:
        with open(args.csv) as f:
            text = f.read()
        elapsed = math.nan
    else:
        text, elapsed = run_binary(args, extra)
    rows = read_csv_text(text)
    if not rows:
        raise SystemExit("testset.py: the binary printed no runs")
    problems = [p for p in read_csv_text(problems_text) if any(r["problem"] == p["problem"] for r in rows)]
    write_atomic(os.path.join(args.out, "testset.csv"), text)
    write_atomic(os.path.join(args.out, "problems.csv"), problems_text)

    groups = OrderedDict()
    for r in rows:
        groups.setdefault((r["problem"], r["integrator"]), []).append(r)
    analysis = analyse(groups)

    write_slopes(os.path.join(args.out, "observed_slopes.csv"), analysis)
    plot_problems(problems, analysis, args.out, " (reduced set)" if args.reduced else "")

    cmd = " ".join([os.path.relpath(args.bin, ROOT)] + extra)
    if args.csv:
        cmd += f" (read from {os.path.relpath(args.csv, ROOT)})"
    text_md = readme(rows, problems, analysis, args, cmd, elapsed, args.reduced)
    write_atomic(os.path.join(args.out, "README.md"), text_md + "\n")
    print(f"testset.py: {len(rows)} runs, wrote {os.path.relpath(args.out, ROOT)}/")


if __name__ == "__main__":
    main()
