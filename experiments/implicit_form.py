#!/usr/bin/python3
"""The implicit form beside the ODE: IDA on F(t, x, x') = 0 against CVODE's BDF on x' = f.

    /usr/bin/python3 experiments/implicit_form.py [--out DIR] [--work DIR] [--reduced]

The plant's implicit form puts inverse dynamics on the speeds' rows,
H(q) qdd + h(q, qd) - tau = 0 (one back-end call, no factorisation of H), and
x' - f on the others: a third position in the probing debate, a formulation
that never inverts H per evaluation (H enters only IDA's Newton matrix).

Two measurements:
  per evaluation  bench_plant's rhs/<scene> and residual/<scene> rows (Google
                  Benchmark, 5 repetitions, medians; the residual at the
                  initial state with x' = f, each call at a new time): the
                  residual's time over one right-hand side's, in one run;
  per run         each scene run by cvode-bdf (the ODE), ida (the implicit
                  form, its Newton matrix from the exact Jacobian) and ida
                  --jacobian differences (IDA's own difference quotients) at
                  rtol 1e-6 and 1e-8 (atol 1e-3 rtol per state scale): steps,
                  rejected steps, residual or RHS evaluations, Jacobians,
                  the integration's wall time, and the end state's distance
                  from a reference run (cvode-bdf at rtol 1e-11, atol 1e-14),
                  max over the states per unit of their scale (stats.json's
                  atol per state / atol).

Writes DIR (default results/implicit_form/): runs.csv, per_evaluation.json
(bench_plant's output) and README.md (the tables, read back from them). Run
folders go to --work (default build/implicit_form/), with private copies of
the binaries. --reduced (CI): 1 s, rtol 1e-6, one repetition, into
build/implicit_form-reduced/.
"""
import argparse
import json
import os
import shutil
import subprocess
import sys

from pumasim_exp import io as pumasim_io
from pumasim_exp.io import ROOT, PUMASIM

SCENES = ["paper_slow_viscous", "smooth_line_quintic", "paper_slow_6dof_hybrid", "panda_tracking"]
METHODS = [("cvode-bdf", []), ("ida", []), ("ida", ["--jacobian", "differences"])]
RTOLS = [1e-6, 1e-8]
REFERENCE = ("cvode-bdf", ["--rtol", "1e-11", "--atol", "1e-14"])


def run(work, scene, integ, options, t_end):
    tag = f"{scene}.{integ}{''.join(o.strip('-') for o in options)}"
    out = os.path.join(work, tag)
    cmd = [PUMASIM, "run", os.path.join(ROOT, "experiments", "scenes", scene + ".toml"), "--integrator", integ,
           "--out", out, "--force"] + options + (["--t-end", repr(t_end)] if t_end else [])
    return pumasim_io.run_or_exit(cmd, out, "implicit_form")


def end_distance(r, ref):
    """max over the states of |x - x_ref| / scale at the last row (scale: atol per state / atol)."""
    atol = r.stats["atol"]
    scale = {name: a / atol for name, a in r.stats["atol_per_component"].items()}
    last, last_ref = r.trajectory.data[-1], ref.trajectory.data[-1]
    d = 0.0
    for k, name in enumerate(r.trajectory.names):
        if name in scale:
            d = max(d, abs(last[k] - last_ref[k]) / scale[name])
    return d


def runs_table(work, t_end, rtols):
    rows = []
    for scene in SCENES:
        ref = run(work, scene, REFERENCE[0], REFERENCE[1], t_end)
        for integ, extra in METHODS:
            for rtol in rtols:
                opts = ["--rtol", repr(rtol), "--atol", repr(1e-3 * rtol)] + extra
                r = run(work, scene, integ, opts, t_end)
                s = r.stats
                rows.append({"scene": scene, "integrator": integ,
                             "jacobian": "differences" if extra else "exact", "rtol": rtol, "ok": s["ok"],
                             "steps": s["steps"], "rejected_steps": s["rejected_steps"],
                             "evaluations": s["rhs_evaluations"], "jacobians": s["jacobian_evaluations"],
                             "root_events": s["root_events"], "wall_s": s["integration_wall_time_s"],
                             "end_distance": end_distance(r, ref)})
                print(f"{scene} {integ} {' '.join(extra)} rtol {rtol:g}: {s['steps']} steps", flush=True)
    return rows


def per_evaluation(bench, out_json, repetitions):
    cmd = [bench, "--benchmark_filter=^(rhs|residual)/", f"--benchmark_repetitions={repetitions}",
           "--benchmark_report_aggregates_only=true", f"--benchmark_out={out_json}", "--benchmark_out_format=json"]
    p = subprocess.run(cmd, capture_output=True, text=True)
    if p.returncode != 0:
        sys.exit(f"implicit_form: {' '.join(cmd)} failed ({p.returncode}): {p.stderr.strip()}")
    with open(out_json) as f:
        doc = json.load(f)
    med = {}
    for b in doc["benchmarks"]:
        if b.get("aggregate_name", "median" if repetitions == 1 else None) != "median":
            continue
        kind, scene = b["run_name"].split("/", 1)
        med.setdefault(scene, {})[kind] = b
    return doc["context"], med


def write_readme(out, rows, context, med, reduced):
    cmd = "experiments/implicit_form.py" + (" --reduced" if reduced else "")
    lines = ["# The implicit form beside the ODE", "",
             f"Generated by `{cmd}`; every number below is read from `runs.csv` and `per_evaluation.json` in this "
             "folder; do not edit.", "",
             "## Per evaluation", "",
             f"bench_plant on {context.get('num_cpus')} CPUs at {context.get('mhz_per_cpu')} MHz, load average "
             f"{', '.join(f'{x:.2f}' for x in context.get('load_avg', []))} at the start; medians of the "
             "repetitions. The residual: inverse dynamics on the speeds' rows, no factorisation of H; the "
             "right-hand side: forward dynamics (H, its Cholesky factor, h).", "",
             "| scene | joints | rhs [ns] | residual [ns] | residual ÷ rhs |", "|---|---:|---:|---:|---:|"]
    for scene, b in med.items():
        if "residual" not in b:
            continue
        lines.append(f"| {scene} | {int(b['residual']['n'])} | {b['rhs']['real_time']:.0f} | "
                     f"{b['residual']['real_time']:.0f} | {b['residual']['ratio_to_rhs']:.2f} |")
    lines += ["", "## Per run", "",
              "End distance: the end state's largest difference from the reference run (cvode-bdf at rtol "
              "1e-11), per unit of each state's scale. Evaluations: IDA's residuals (with its difference "
              "quotients' under `differences`), CVODE's right-hand sides.", "",
              "| scene | integrator | Jacobian | rtol | steps | rejected | evaluations | Jacobians | events | "
              "wall [ms] | end distance |", "|---|---|---|---:|---:|---:|---:|---:|---:|---:|---:|"]
    for r in rows:
        ok = "" if str(r["ok"]) == "True" else " (failed)"
        lines.append(f"| {r['scene']} | {r['integrator']} | {r['jacobian']} | {float(r['rtol']):g} | "
                     f"{int(r['steps']):,}{ok} | {int(r['rejected_steps']):,} | {int(r['evaluations']):,} | "
                     f"{int(r['jacobians']):,} | {int(r['root_events'])} | {1e3 * float(r['wall_s']):.1f} | "
                     f"{float(r['end_distance']):.2g} |")
    pumasim_io.write_text_atomic(os.path.join(out, "README.md"), "\n".join(lines) + "\n")


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--out", default=None)
    ap.add_argument("--work", default=None)
    ap.add_argument("--reduced", action="store_true")
    args = ap.parse_args()
    out, work = pumasim_io.script_folders(args, "implicit_form", "implicit_form")
    global PUMASIM
    bench_src = os.path.join(os.path.dirname(PUMASIM), "bench_plant")
    bench = os.path.join(work, "bench_plant")
    shutil.copy2(bench_src, bench)
    PUMASIM = pumasim_io.private_copy(PUMASIM, work)
    context, med = per_evaluation(bench, os.path.join(out, "per_evaluation.json"), 1 if args.reduced else 5)
    rows = runs_table(work, 1.0 if args.reduced else None, RTOLS[:1] if args.reduced else RTOLS)
    pumasim_io.write_table(os.path.join(out, "runs.csv"), rows, columns=list(rows[0].keys()),
                           comments=[f"{' '.join(['experiments/implicit_form.py'] + (['--reduced'] if args.reduced else []))}"
                                     ": pumasim run SCENE --integrator I --rtol R --atol 1e-3R [--jacobian differences]"])
    write_readme(out, rows, context, med, args.reduced)
    print(f"implicit form: {os.path.relpath(out, ROOT)}/")


if __name__ == "__main__":
    main()
