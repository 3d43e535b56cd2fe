#!/usr/bin/python3
"""Observed order of every integrator on scenes of the plant.

    /usr/bin/python3 experiments/observed_order.py [--out DIR] [--work DIR]
        [--jobs N] [--paper-t-end T] [--reduced]
    /usr/bin/python3 experiments/observed_order.py --replot [--out DIR]   # the plots alone, from DIR's tables

Scenes: smooth_line_quintic (a C-infinity reference: one straight line,
quintic timing, viscous friction; 8 s), the same with La = 20 mH
(smooth_line_quintic_La20mH: the armature pole ten times slower, which
separates a method's order from the order reduction a stiff, explicitly
time-dependent current causes) and paper_slow_viscous (the paper's
path of lines and arcs with its piecewise speed table, viscous friction; its
breakpoints are time events at which the driver stops; 24 s, --paper-t-end
to shorten). The driver stops only where the right-hand side changes and
reads the outputs (every 10 ms) from each method's dense output, so the
error at the outputs is the method's global error there.

Per scene: a reference run (cvode-bdf, rtol 1e-12, atol 1e-15), cross-checked
by odeint-dopri5 at the same tolerances (their difference is reported). The
error of a run is

    e = max over all output rows and the states q, qd, i_motor, z_piv of
        |x - x_ref| / max(1, |x_ref|)

(the slopes are fitted on e); the max joint-angle error [rad] is recorded too.
Fixed-step methods (euler, rk4, ab2, ab3, ab4) run a dt ladder 2e-3 ...
1.25e-4 (halving); the slope is d log e / d log dt. Adaptive methods run an
rtol ladder 1e-3 ... 1e-9 (atol = 1e-3 rtol); the slope is
-d log e / d log(RHS evaluations). Both are least-squares fits over the
ladder's asymptotic range only, as experiments/order_fit.py finds it: above
the floor (100 x the reference-vs-check difference), below 1e-2 (higher:
"too coarse"), and at steps where the method is stable -- not failed, e < 1
and finite, and not at the ladder's coarse end while the error grows with
the step faster than the order allows (order_fit's docstring has the whole
rule, its RULE_TEXT goes into the README). A method with fewer than two runs
in that range gets no slope: the table prints the reason ("too few points",
how many runs were unstable, below floor, ...) and, in parentheses, the
slope over every finished run, which is not an order; a finest-pair slope
that is not positive or steeper than order + 1 is printed with its reason
too. Every run not fitted has its reason in ladder.csv (fit_mark).

Writes DIR (default results/observed_order/): observed_order.csv (one row per
scene and method: theoretical and observed order or why there is none, runs
used, error range), ladder.csv (every run, its floor and why it is not in the
fit), references.csv (reference vs check), <scene>.png and the same as
<scene>.pdf (error against dt and against RHS evaluations, in the house style
of pumasim_exp/style.py) and README.md (the table, read
back from the CSVs). Run folders go to --work (default build/observed_order/),
with a private copy of the pumasim binary ($PUMASIM if set), so that a
rebuild meanwhile does not change the program under measurement.
--reduced (CI, under 30 s): the scenes cut to 1 s and 2.5 s (past
paper_slow_viscous's first breakpoint), rk4 and ab2 at three dt (5e-4 ...),
cvode-bdf and odeint-dopri5 at three rtol, run folders in
build/observed_order-reduced/.
"""
import argparse
import concurrent.futures
import json
import math
import os
import re
import shutil
import subprocess
import sys
import time

import numpy as np

import order_fit
from pumasim_exp import io as pumasim_io
from pumasim_exp import style
from order_fit import THEORY
from pumasim_exp.io import ROOT, PUMASIM

REFERENCE = ("cvode-bdf", ["--rtol", "1e-12", "--atol", "1e-15"])
CHECK = ("odeint-dopri5", ["--rtol", "1e-12", "--atol", "1e-15"])
ASYMPTOTIC_FACTOR = 100  # the floor: this times reference vs check (order_fit: "below floor" at or under it)
ASYMPTOTIC_MAX = 1e-2    # the range's upper end (order_fit: "too coarse" at or above it)
UNSTABLE = order_fit.UNSTABLE  # e at or above this (or not finite): unstable
ORDER_TOLERANCE = 0.3    # a fixed-step method reaches its order p if |slope - p| <= this
STATE = re.compile(r"(q|qd|i_motor|z_piv|z_fric)\d+")


def private_copy(work):
    """Copies the pumasim binary to work/ (pumasim_io.private_copy), so that
    every run of this experiment uses one program."""
    global PUMASIM
    PUMASIM = pumasim_io.private_copy(PUMASIM, work)


def integrators():
    """The registry's entries by name (`pumasim integrators --json`)."""
    p = subprocess.run([PUMASIM, "integrators", "--json"], capture_output=True, text=True, check=True)
    return {entry["name"]: entry for entry in json.loads(p.stdout)}


def trajectory(run_dir):
    """Columns of trajectory.csv by name without the unit, as float arrays."""
    try:
        return pumasim_io.read_trajectory(run_dir).arrays()
    except pumasim_io.RunFolderError as e:
        sys.exit(f"observed_order: {e}")


def errors(ref, run):
    """(e over every state relative to max(1, |x_ref|), max joint-angle error
    [rad]); nan unless the run has every output row of the reference."""
    n = len(ref["t"])
    if len(run["t"]) != n or np.max(np.abs(run["t"] - ref["t"])) > 1e-9:
        return math.nan, math.nan
    states = [h for h in ref if STATE.fullmatch(h)]
    e = max(float(np.max(np.abs(run[h] - ref[h]) / np.maximum(1.0, np.abs(ref[h])))) for h in states)
    dq = max(float(np.max(np.abs(run[h] - ref[h]))) for h in ref if re.fullmatch(r"q\d+", h))
    return e, dq


def execute(work, label, t_end, name, opts):
    """One pumasim run into a fresh folder; returns (folder, stats)."""
    scene, sets = VARIANTS[label]
    tag = name + "_" + "_".join(o.lstrip("-") for o in opts)
    out = os.path.join(work, label, tag)
    shutil.rmtree(out, ignore_errors=True)
    cmd = [PUMASIM, "run", os.path.join(ROOT, "experiments", "scenes", scene + ".toml"),
           "--integrator", name, "--t-end", repr(t_end), "--out", out] + opts
    for x in sets:
        cmd += ["--set", x]
    if "--dt" in opts:  # the step count is t_end / dt: no budget
        cmd += ["--max-steps", "0"]
    p = subprocess.run(cmd, capture_output=True, text=True, cwd=ROOT)
    if p.returncode == 2 or not pumasim_io.has_stats(out):
        sys.exit(f"{' '.join(cmd)}: exit status {p.returncode}: {p.stderr.strip()}")
    try:
        return out, pumasim_io.read_stats(out)
    except pumasim_io.RunFolderError as e:
        sys.exit(f"{' '.join(cmd)}: exit status {p.returncode}: {e}")


# The scenes (rows of the table): a label, the scene file and its overrides.
# smooth_line_quintic_La20mH: the C-infinity scene with the armature pole ten
# times slower (-105 instead of -1050 1/s), to separate a method's order from
# what the stiff current does to it (order reduction of one-step methods with
# low stage order on stiff, explicitly time-dependent problems).
VARIANTS = {
    "smooth_line_quintic": ("smooth_line_quintic", []),
    "smooth_line_quintic_La20mH": ("smooth_line_quintic", ["motor.inductance=0.02"]),
    "paper_slow_viscous": ("paper_slow_viscous", []),
}


def fmt(x, spec=".3g"):
    return "" if x is None or (isinstance(x, float) and math.isnan(x)) else format(x, spec)


def read_csv(path):
    return pumasim_io.read_table(path).rows


def parse_args():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--out", default=None)
    ap.add_argument("--work", default=None)
    ap.add_argument("--jobs", type=int, default=2)
    ap.add_argument("--paper-t-end", type=float, default=24.0)
    ap.add_argument("--reduced", action="store_true")
    ap.add_argument("--replot", action="store_true",
                    help="only redraw the plots from ladder.csv and references.csv in --out (no run)")
    return ap.parse_args()


def ladders(a, summaries):
    """(scenes {label: t_end}, fixed-step methods, their dt ladder, adaptive
    methods, their rtol ladder) of a full or --reduced run; summaries: `pumasim
    integrators` ({name: summary})."""
    if a.reduced:
        scenes = {"smooth_line_quintic": 1.0, "paper_slow_viscous": 2.5}  # 2.5 s: past the first breakpoint
        fixed, dts = ["rk4", "ab2"], [5e-4, 2.5e-4, 1.25e-4]
        adaptive, rtols = ["cvode-bdf", "odeint-dopri5"], [1e-4, 1e-6, 1e-8]
    else:
        scenes = {"smooth_line_quintic": 8.0, "smooth_line_quintic_La20mH": 8.0, "paper_slow_viscous": a.paper_t_end}
        # Every fixed-step method the registry lists, so that a new one
        # cannot be left out.
        fixed = [m for m in sorted(summaries) if summaries[m]["kind"] == "fixed-step"]
        dts = [2e-3 / 2 ** k for k in range(5)]
        adaptive = [m for m in sorted(summaries) if m not in fixed]
        rtols = [10.0 ** -k for k in range(3, 10)]
    return scenes, fixed, dts, adaptive, rtols


def check_theory(methods, summaries):
    """Exits unless every method is registered and has its theoretical order
    in THEORY, agreeing with the registry's order (a variable-order method's
    highest)."""
    for m in methods:
        if m not in summaries:
            sys.exit(f"{m}: not in `pumasim integrators`")
        if m not in THEORY:
            sys.exit(f"{m}: no theoretical order in THEORY (experiments/observed_order.py)")
        registered = str(summaries[m]["order"])
        if registered != THEORY[m].split("-")[-1]:
            sys.exit(f"{m}: the registry says order {registered}, THEORY says {THEORY[m]}")


def job_list(scenes, fixed, dts, adaptive, rtols):
    """Every run: (scene, role, integrator, kind, setting value, options); per
    scene the reference, the check, then each method's ladder, coarse to fine."""
    jobs = []
    for scene in scenes:
        jobs.append((scene, "reference", REFERENCE[0], "reference", math.nan, REFERENCE[1]))
        jobs.append((scene, "check", CHECK[0], "check", math.nan, CHECK[1]))
        for m in fixed:
            jobs += [(scene, "run", m, "fixed", dt, ["--dt", repr(dt)]) for dt in dts]
        for m in adaptive:
            jobs += [(scene, "run", m, "adaptive", r, ["--rtol", repr(r), "--atol", repr(r * 1e-3)])
                     for r in rtols]
    return jobs


def ladder_row(scene, j, st, e, dq, diff, diff_q):
    """ladder.csv's row of run j (stats st; errors e, dq against the reference,
    nan if it failed) with its floors (ASYMPTOTIC_FACTOR times the
    reference-vs-check differences); order_row fills in whether it enters
    the fits, and why not."""
    if not st["ok"]:
        status = "failed"
    elif not (e < UNSTABLE):
        status = "unstable"
    else:
        status = "ok"
    return {"scene": scene, "integrator": j[2], "kind": j[3],
            "setting": ("dt=" if j[3] == "fixed" else "rtol=") + f"{j[4]:g}",
            "value": j[4], "ok": st["ok"], "status": status, "error": e,
            "max_joint_error_rad": dq, "steps": st["steps"],
            "rhs_evaluations": st["rhs_evaluations"], "floor": ASYMPTOTIC_FACTOR * diff,
            "floor_joint": ASYMPTOTIC_FACTOR * diff_q, "failure": st["failure"]}


def scene_errors(scene, t_end, mine):
    """(references.csv's row, ladder.csv's rows) of one scene from its runs
    mine = [(job, (folder, stats))]; exits if its reference or check failed."""
    (ref_dir, ref_st), = [d for j, d in mine if j[1] == "reference"]
    (chk_dir, chk_st), = [d for j, d in mine if j[1] == "check"]
    if not (ref_st["ok"] and chk_st["ok"]):
        sys.exit(f"{scene}: reference or check failed: {ref_st['failure']} {chk_st['failure']}")
    ref = trajectory(ref_dir)
    diff, diff_q = errors(ref, trajectory(chk_dir))
    ref_row = {"scene": scene, "t_end_s": t_end,
               "reference": f"{REFERENCE[0]} {' '.join(REFERENCE[1])}",
               "check": f"{CHECK[0]} {' '.join(CHECK[1])}",
               "difference": diff, "difference_joint_rad": diff_q,
               "reference_rhs_evaluations": ref_st["rhs_evaluations"],
               "time_events": ref_st.get("time_events", "")}
    ladder = []
    for j, (d, st) in mine:
        if j[1] != "run":
            continue
        e, dq = errors(ref, trajectory(d)) if st["ok"] else (math.nan, math.nan)
        ladder.append(ladder_row(scene, j, st, e, dq, diff, diff_q))
    return ref_row, ladder


def ladder_fit(runs, col, floor_col):
    """order_fit.asymptotic_fit over one method's ladder (runs: ladder.csv's
    rows, coarse to fine) in the error column col with its floors; n is 1/dt
    for a fixed step, the RHS evaluations for an adaptive method."""
    fixed = runs[0]["kind"] == "fixed"
    pts = [{"ok": r["ok"], "e": r[col], "floor": r[floor_col],
            "n": 1.0 / r["value"] if fixed else float(r["rhs_evaluations"])} for r in runs]
    return order_fit.asymptotic_fit(pts, THEORY[runs[0]["integrator"]], fixed, ceiling=ASYMPTOTIC_MAX)


def order_row(scene, m, ladder):
    """observed_order.csv's row of method m on a scene: the slopes fitted over
    its ladder's asymptotic range (order_fit), or why there is none; marks the
    ladder's rows (used_in_fit, fit_mark and the same for the joint angles)."""
    runs = [r for r in ladder if r["scene"] == scene and r["integrator"] == m]
    f = ladder_fit(runs, "error", "floor")
    fq = ladder_fit(runs, "max_joint_error_rad", "floor_joint")
    for r, mark, mark_q in zip(runs, f["marks"], fq["marks"]):
        r.update(used_in_fit=mark is None, fit_mark=mark or "", used_in_joint_fit=mark_q is None,
                 joint_fit_mark=mark_q or "")
    use = [runs[i] for i in f["used"]]
    return {"scene": scene, "integrator": m, "kind": runs[0]["kind"], "theoretical_order": THEORY[m],
            "observed_slope": f["slope"], "slope_mark": f["reason"], "raw_slope": f["raw_slope"],
            "runs_used": len(use), "runs": len(runs),
            "error_min": min((r["error"] for r in use), default=math.nan),
            "error_max": max((r["error"] for r in use), default=math.nan),
            "slope_finest_pair": f["finest_pair"], "finest_pair_mark": f["finest_pair_mark"] or "",
            "observed_slope_joint": fq["slope"], "joint_slope_mark": fq["reason"],
            "joint_runs_used": len(fq["used"]),
            "dropped": "; ".join(f"{r['setting']} {r['fit_mark']}" for r in runs if r["fit_mark"])}


def write_tables(out, rows, ladder, refs):
    """observed_order.csv, ladder.csv and references.csv in out (floats as repr)."""
    def write(name, table, cols):
        pumasim_io.write_table(os.path.join(out, name), table, columns=cols,
                               fmt=lambda v: repr(v) if isinstance(v, float) else v)

    write("observed_order.csv", rows, ["scene", "integrator", "kind", "theoretical_order", "observed_slope",
                                       "slope_mark", "raw_slope", "runs_used", "runs", "error_min", "error_max",
                                       "slope_finest_pair", "finest_pair_mark", "observed_slope_joint",
                                       "joint_slope_mark", "joint_runs_used", "dropped"])
    write("ladder.csv", ladder, ["scene", "integrator", "kind", "setting", "ok", "status", "error",
                                 "max_joint_error_rad", "steps", "rhs_evaluations", "floor", "used_in_fit",
                                 "fit_mark", "floor_joint", "used_in_joint_fit", "joint_fit_mark", "failure"])
    write("references.csv", refs, list(refs[0]))


def main():
    a = parse_args()
    out = a.out or os.path.join(ROOT, "results", "observed_order")
    if a.replot:  # the plots alone, from the tables in out: no run
        plots(out, [r["scene"] for r in read_csv(os.path.join(out, "references.csv"))])
        print(f"observed order: plots redrawn from {out}/ladder.csv and references.csv")
        return
    work = a.work or os.path.join(ROOT, "build", "observed_order-reduced" if a.reduced else "observed_order")
    private_copy(work)
    summaries = integrators()
    scenes, fixed, dts, adaptive, rtols = ladders(a, summaries)
    check_theory(fixed + adaptive, summaries)

    start = time.time()
    jobs = job_list(scenes, fixed, dts, adaptive, rtols)
    with concurrent.futures.ThreadPoolExecutor(max_workers=a.jobs) as pool:
        done = list(pool.map(lambda j: execute(work, j[0], scenes[j[0]], j[2], j[5]), jobs))
    run_time = time.time() - start

    os.makedirs(out, exist_ok=True)
    ladder, refs = [], []
    for scene in scenes:
        mine = [(j, d) for j, d in zip(jobs, done) if j[0] == scene]
        ref_row, scene_ladder = scene_errors(scene, scenes[scene], mine)
        refs.append(ref_row)
        ladder += scene_ladder
    rows = [order_row(scene, m, ladder) for scene in scenes for m in fixed + adaptive]
    write_tables(out, rows, ladder, refs)
    plots(out, scenes)
    readme(out, run_time, a)
    print(f"observed order: {len(jobs)} runs in {run_time:.1f} s; {out}/observed_order.csv")


def plots(out, scenes):
    """<scene>.png and <scene>.pdf in out, from ladder.csv and references.csv:
    the fixed-step methods' error against dt (left), the adaptive ones'
    against RHS evaluations (right). Every method has its own style across
    both panels (style.series: colour, then dash and marker shape beyond
    eight); a filled marker enters the fit, a hollow one does not. One legend,
    right of the right-hand panel."""
    from matplotlib.lines import Line2D
    plt = style.pyplot()
    ladder = read_csv(os.path.join(out, "ladder.csv"))
    refs = {r["scene"]: r for r in read_csv(os.path.join(out, "references.csv"))}
    for scene in scenes:
        fig, axes = plt.subplots(1, 2, figsize=(11, 4.2))
        floor = ASYMPTOTIC_FACTOR * float(refs[scene]["difference"])
        panels = {kind: [r for r in ladder if r["scene"] == scene and r["kind"] == kind and r["status"] == "ok"]
                  for kind in ("fixed", "adaptive")}
        methods = list(dict.fromkeys(r["integrator"] for kind in ("fixed", "adaptive") for r in panels[kind]))
        styles = style.series_styles(methods)
        for ax, kind in zip(axes, ["fixed", "adaptive"]):
            runs = panels[kind]
            for m in dict.fromkeys(r["integrator"] for r in runs):
                st = styles[m]
                rs = [r for r in runs if r["integrator"] == m]
                x = [float(r["setting"].split("=")[1]) if kind == "fixed" else float(r["rhs_evaluations"])
                     for r in rs]
                y = [float(r["error"]) for r in rs]
                ax.loglog(x, y, ls=st["ls"], color=st["color"], lw=1)
                for xi, yi, r in zip(x, y, rs):
                    ax.loglog(xi, yi, st["marker"], color=st["color"],
                              mfc=st["color"] if r["used_in_fit"] == "True" else "none")
            ax.axhline(floor, color="grey", ls=":", lw=1)
            ax.axhline(ASYMPTOTIC_MAX, color="grey", ls=":", lw=1)
            ax.set_xlabel("dt [s]" if kind == "fixed" else "RHS evaluations")
            ax.set_ylabel("max |x - x_ref| / max(1, |x_ref|)")
            ax.set_title(f"{kind}-step" if kind == "fixed" else "adaptive (rtol ladder)")
            ax.grid(True, which="both", alpha=0.3)
        if methods:
            handles = [Line2D([], [], lw=1, **styles[m]) for m in methods]
            labels = [f"{m} (order {THEORY[m]})" for m in methods]
            handles.append(Line2D([], [], ls="none", marker="o", color="0.35", mfc="none"))
            labels.append("hollow: outside the fit")
            style.legend_right(axes[1], handles, labels)
        fig.suptitle(f"{scene}, {float(refs[scene]['t_end_s']):g} s: filled markers enter the fit (the asymptotic "
                     f"range; dotted: {ASYMPTOTIC_FACTOR} x reference vs check, and {ASYMPTOTIC_MAX:g})", fontsize=9)
        fig.tight_layout()
        style.save(fig, os.path.join(out, f"{scene}.png"))


def reaches(slope, theory):
    return abs(slope - float(theory)) <= ORDER_TOLERANCE


def _verdict_lists(fx):
    """(reach their order, do not, cannot be measured) among the fixed-step
    rows fx of observed_order.csv (strings, as read back)."""
    num = lambda r, k: float(r[k])
    fitted = [r for r in fx if not math.isnan(num(r, "observed_slope"))]
    good = [r for r in fitted if reaches(num(r, "observed_slope"), r["theoretical_order"])]
    return good, [r for r in fitted if r not in good], [r for r in fx if r not in fitted]


def verdict(scene, rows):
    """The README's verdict line on the fixed-step methods of one scene (rows:
    observed_order.csv's): who reaches its order, who does not, who cannot be
    measured and why, slopes short in the joint angles, runs dropped."""
    num = lambda r, k: float(r[k])
    fx = [r for r in rows if r["scene"] == scene and r["kind"] == "fixed"]
    good, bad, unfit = _verdict_lists(fx)
    parts = []
    if good:
        parts.append(", ".join(f"{r['integrator']} ({num(r, 'observed_slope'):.2f})" for r in good)
                     + (" reaches its order" if len(good) == 1 else " reach their orders"))
    if bad:
        parts.append(", ".join(f"{r['integrator']} ({num(r, 'observed_slope'):.2f} for order {r['theoretical_order']}"
                               + (f"; {num(r, 'slope_finest_pair'):.2f} over its finest pair"
                                  if r["runs_used"] != "2" and not r["finest_pair_mark"] else "") + ")" for r in bad)
                     + (" does not" if len(bad) == 1 else " do not"))
    if unfit:
        parts.append(", ".join(f"{r['integrator']} ({r['slope_mark']})" for r in unfit)
                     + (" cannot be measured: fewer than two of " + ("its" if len(unfit) == 1 else "their")
                        + " runs lie in the asymptotic range"))
    short = [r for r in fx if not math.isnan(num(r, "observed_slope_joint"))
             and num(r, "observed_slope_joint") < float(r["theoretical_order"]) - ORDER_TOLERANCE]
    if short:
        parts.append("in the joint angles alone " + ", ".join(
            f"{r['integrator']} {num(r, 'observed_slope_joint'):.2f}" for r in short)
            + " (below " + ("its order" if len(short) == 1 else "their orders") + ")")
    dropped = []
    for r in fx:
        ds = [d.split(" ", 1) for d in r["dropped"].split("; ") if d]
        for status in dict.fromkeys(st for _, st in ds):
            dropped.append(f"{r['integrator']} at " + ", ".join(v for v, st in ds if st == status) + f" ({status})")
    if dropped:
        parts.append("runs outside the asymptotic range: " + ", ".join(dropped))
    return f"- {scene}: " + "; ".join(parts) + "."


def _slope_cell(r, col, mark_col, runs_col=None, raw_col=None):
    """A README table's cell: a fitted slope (with its run count), or '–' and
    why there is none (with the slope over every finished run, if raw_col)."""
    v = float(r[col])
    if math.isnan(v):
        raw = float(r[raw_col]) if raw_col else math.nan
        why = r[mark_col] + (f"; all finished runs: {raw:.2f}, not an order" if not math.isnan(raw) else "")
        return f"– ({why})" if why else "–"
    return f"{v:.2f}" + (f" ({r[runs_col]})" if runs_col else "")


def _finest_cell(r):
    """The finest pair's cell: its slope, or the slope marked with why it is no order."""
    v = float(r["slope_finest_pair"])
    if math.isnan(v):
        return "–"
    return f"{v:.2f}" if not r["finest_pair_mark"] else f"({v:.2f}: {r['finest_pair_mark']})"


def readme(out, run_time, a):
    rows = read_csv(os.path.join(out, "observed_order.csv"))
    refs = read_csv(os.path.join(out, "references.csv"))
    num = lambda r, k: float(r[k])
    L = ["# Observed order of the integrators", "",
         "Generated by `experiments/observed_order.py" + (" --reduced" if a.reduced else "") +
         f"` ({run_time:.0f} s with {a.jobs} jobs); every number below is read from",
         "`observed_order.csv`, `ladder.csv` and `references.csv` in this folder.", "",
         "Error of a run (the slopes are fitted on it): the max over all output rows (every 10 ms)",
         "and the states q, qd, i_motor, z_piv of |x − x_ref| / max(1, |x_ref|); the reference is",
         "CVODE BDF at rtol 1e-12, atol 1e-15, cross-checked by Dormand–Prince at the same tolerances.",
         "Fixed-step: slope of log(error) against log(dt), dt = 2e-3 … 1.25e-4 halving; adaptive: slope",
         "of −log(error) against log(RHS evaluations), rtol = 1e-3 … 1e-9, atol = 1e-3 rtol. Fitted by",
         "least squares over the ladder's asymptotic range only (`experiments/order_fit.py`): the floor is",
         f"{ASYMPTOTIC_FACTOR} × the reference-vs-check difference, and a run with an error of {ASYMPTOTIC_MAX:g} or "
         "more is too coarse.", order_fit.RULE_TEXT,
         "A slope outside the range is printed only in parentheses with the reason (a method's",
         "ladder.csv rows say why each run was left out: `fit_mark`). Beside it: the slope over the",
         "two finest runs of the range (in parentheses, with the reason, where it is no order), and",
         "the slope of the max joint-angle error [rad] (its own range: the floor from the joint-angle",
         "reference-vs-check difference). For the variable-order CVODE methods the adaptive slope is a",
         "cost exponent, not an order.",
         "`smooth_line_quintic_La20mH` is `smooth_line_quintic` with `--set motor.inductance=0.02`: the",
         "armature pole ten times slower (−105 instead of −1050 1/s), the same motion; a one-step method",
         "whose slope is short of its order on the shipped scene and reaches it here shows order",
         "reduction from the stiff current (low stage order), not a wrong coefficient.",
         "Plots: `<scene>.png` (and the same as `<scene>.pdf`).", "",
         "| scene | t_end [s] | reference vs check | (joint angles [rad]) | reference RHS | time events |",
         "|---|---|---|---|---|---|"]
    for r in refs:
        L.append(f"| {r['scene']} | {num(r, 't_end_s'):g} | {fmt(num(r, 'difference'))} | "
                 f"{fmt(num(r, 'difference_joint_rad'))} | {r['reference_rhs_evaluations']} | {r['time_events']} |")
    L += ["", "| scene | integrator | kind | order | observed slope | finest pair | runs used | error range "
              "| joint-angle slope (runs) | runs outside the range |", "|---|---|---|---|---|---|---|---|---|---|"]
    for r in rows:
        rng = f"{fmt(num(r, 'error_min'), '.2g')} … {fmt(num(r, 'error_max'), '.2g')}" if r["runs_used"] != "0" else ""
        L.append(f"| {r['scene']} | {r['integrator']} | {r['kind']} | {r['theoretical_order'].replace('-', '–')} | "
                 f"{_slope_cell(r, 'observed_slope', 'slope_mark', raw_col='raw_slope')} | {_finest_cell(r)} | "
                 f"{r['runs_used']}/{r['runs']} | {rng} | "
                 f"{_slope_cell(r, 'observed_slope_joint', 'joint_slope_mark', 'joint_runs_used')} | {r['dropped']} |")
    L += ["", f"Verdicts: a fixed-step method reaches its order p when its observed slope is within "
              f"{ORDER_TOLERANCE} of p.", ""]
    for scene in dict.fromkeys(r["scene"] for r in rows):
        L.append(verdict(scene, rows))
    pumasim_io.write_text_atomic(os.path.join(out, "README.md"), "\n".join(L) + "\n")


if __name__ == "__main__":
    main()
