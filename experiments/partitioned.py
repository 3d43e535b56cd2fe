#!/usr/bin/python3
"""The paper's integration scheme, partitioned: Adams-Bashforth of orders 1-4
on the whole state (monolithic) beside the exponential Adams-Bashforth
methods (etd-ab2..4: the armature current equation, linear in the current,
advanced exactly over the step; the mechanics and the PIV integrals by AB-k),
each under two controller schemes:

  continuous  the PIV law evaluated in every right-hand side; the multistep
              history restarts at the reference's breakpoints;
  loop        the paper's LabVIEW loop as we read it: the controller sampled
              once per step (servo period = dt, output held) and the
              Adams-Bashforth history carried across the samples
              (pumasim run --keep-history).

    /usr/bin/python3 experiments/partitioned.py [--quick]

Writes results/paper/partitioned.md and partitioned.csv: per scheme, method
and step, whether the run stayed stable, the maximum path error (the tracking
error, against the reference path) and the integration error (the maximum
wrist-centre distance from a reference solution of the same scheme's ODE:
rk4 at dt = 1e-5; for the loop, that of the sampled controller restarted at
every sample, which the loop approximates), and the difference between that
reference and a cross-check (rk4 at 2e-5). Runs go to build/partitioned/.
--quick: 2 s of the scene instead of 24 s (a smoke run, nothing written to
results/).
"""
import argparse
import math
import os
import subprocess
import sys

import numpy as np

from pumasim_exp import io as pumasim_io
from pumasim_exp.io import ROOT, PUMASIM

SCENE = os.path.join(ROOT, "experiments", "scenes", "paper_slow.toml")
WORK = os.path.join(ROOT, "build", "partitioned")
OUT = os.path.join(ROOT, "results", "paper")
METHODS = ["euler", "ab2", "ab3", "ab4", "etd-ab2", "etd-ab3", "etd-ab4"]
STEPS = [1e-3, 5e-4]
REFERENCE_DT, CHECK_DT = 1e-5, 2e-5
SCHEMES = {
    "continuous": [],
    "loop": ["--keep-history"],
}


def scheme_sets(scheme, dt):
    if scheme == "loop":
        return ["--set", 'controller.mode="sampled"', "--set", f"controller.servo_period={dt!r}"]
    return []


def run(name, scheme, integrator, dt, sample_dt, t_end, extra):
    out = os.path.join(WORK, scheme, name)
    cmd = [PUMASIM, "run", SCENE, "--integrator", integrator, "--dt", repr(dt), "--out", out, "--force",
           "--quiet", *scheme_sets(scheme, sample_dt), *extra]
    if t_end:
        cmd += ["--t-end", repr(t_end)]
    p = subprocess.run(cmd, capture_output=True, text=True, cwd=ROOT)
    if p.returncode not in (0, 1):  # 1: the run failed as a reported result (divergence)
        sys.exit(f"partitioned.py: {' '.join(cmd)} exited {p.returncode}: {p.stderr.strip()}")
    return pumasim_io.load_run(out)


def wrist_distance_mm(a, b):
    """Max distance of the wrist centre (x, y, z) between two runs at their common output times [mm]."""
    ta, tb = a.trajectory["t"], b.trajectory["t"]
    n = min(len(ta), len(tb))
    if n == 0 or not np.allclose(ta[:n], tb[:n], rtol=0, atol=1e-9):
        raise SystemExit(f"partitioned.py: {a.path} and {b.path} have different output times")
    d = [a.trajectory[c][:n] - b.trajectory[c][:n] for c in ("x", "y", "z")]
    return 1e3 * float(np.max(np.sqrt(d[0] ** 2 + d[1] ** 2 + d[2] ** 2)))


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--quick", action="store_true", help="2 s of the scene; nothing written to results/")
    args = ap.parse_args()
    t_end = 2.0 if args.quick else None
    rows, refs = [], {}
    for scheme, extra in SCHEMES.items():
        for dt in STEPS:
            # The reference solves the same ODE: for the loop, the controller sampled every dt.
            ref = run(f"reference-{dt!r}", scheme, "rk4", REFERENCE_DT, dt, t_end, [])
            check = run(f"check-{dt!r}", scheme, "rk4", CHECK_DT, dt, t_end, [])
            refs[(scheme, dt)] = (ref, wrist_distance_mm(ref, check))
            for m in METHODS:
                r = run(f"{m}-{dt!r}", scheme, m, dt, dt, t_end, extra)
                ok = bool(r.stats["ok"])
                rows.append({
                    "scheme": scheme, "integrator": m, "dt_s": dt, "stable": ok,
                    "failure": "" if ok else r.stats["failure"],
                    "max_path_error_mm": r.stats["max_path_error_mm"] if ok else math.nan,
                    "max_path_deviation_mm": r.stats["max_path_deviation_mm"] if ok else math.nan,
                    "integration_error_mm": wrist_distance_mm(r, ref) if ok else math.nan,
                    "reference_path_error_mm": ref.stats["max_path_error_mm"],
                    "reference_vs_check_mm": refs[(scheme, dt)][1],
                    "rhs_evaluations": r.stats["rhs_evaluations"],
                })
    for r in rows:
        print(f"{r['scheme']:10s} {r['integrator']:8s} dt={r['dt_s']:g}: "
              + (f"path error {r['max_path_error_mm']:.4f} mm, integration error {r['integration_error_mm']:.4f} mm"
                 if r["stable"] else "UNSTABLE: " + r["failure"][:70]))
    if args.quick:
        return
    write(rows)


def fmt(x, digits=4):
    return "–" if isinstance(x, float) and math.isnan(x) else f"{x:.{digits}f}"


def write(rows):
    columns = list(rows[0].keys())
    pumasim_io.write_table(os.path.join(OUT, "partitioned.csv"), rows, columns,
                           comments=[f"generated by /usr/bin/python3 experiments/partitioned.py; scene "
                                     f"experiments/scenes/paper_slow.toml (3 joints, 24 s, the paper's friction "
                                     f"rule); reference rk4 dt={REFERENCE_DT:g}, check rk4 dt={CHECK_DT:g}"])
    lines = [
        "# The paper's integration scheme: monolithic and partitioned Adams-Bashforth",
        "",
        "Generated by `/usr/bin/python3 experiments/partitioned.py` (table: `partitioned.csv`); do not edit by hand.",
        "Scene `paper_slow` (3 joints, 24 s, the paper's stick-slip rule, PIV gains for 15 Hz).",
        pumasim_io.revision_line(pumasim_io.read_meta(os.path.join(WORK, "continuous", f"ab2-{STEPS[-1]!r}"))),
        "",
        "- **Methods.** `euler`, `ab2`..`ab4`: Adams-Bashforth on the whole state (monolithic). `etd-ab2`..`etd-ab4`:"
        " exponential Adams-Bashforth, the armature current advanced exactly for the voltage and back-EMF that the"
        " formula extrapolates from the history, the mechanics and PIV integrals by AB-k (partitioned; `integrators/exponential.cpp`).",
        "- **Schemes.** *continuous*: the PIV law in every right-hand side. *loop*: the paper's LabVIEW loop as we"
        " read it (the paper does not describe it): the controller sampled once per step and held"
        " (`controller.mode = \"sampled\"`, servo period = dt) and the multistep history carried across the samples"
        " (`pumasim run --keep-history`).",
        "- **Errors.** *path error*: the run's maximum distance from the reference path at the same time (the"
        " tracking error, the paper's measure); *integration error*: the maximum wrist-centre distance from a"
        " reference solution of the same scheme's ODE (rk4, dt = 1e-5; for the loop, the sampled controller"
        " restarted at every sample), at the 10 ms outputs. *Finished*: no: the run diverged (a non-finite state,"
        " reported with its time); yes: it reached the end, which alone does not mean it stayed accurate.",
        "",
    ]
    for scheme in SCHEMES:
        for dt in STEPS:
            sub = [r for r in rows if r["scheme"] == scheme and r["dt_s"] == dt]
            ref = sub[0]
            lines += [f"## {scheme}, dt = {dt * 1e3:g} ms", "",
                      f"Reference path error {ref['reference_path_error_mm']:.4f} mm; reference against its"
                      f" check (rk4 at {CHECK_DT:g} s): {ref['reference_vs_check_mm']:.2g} mm.", "",
                      "| method | finished | path error [mm] | integration error [mm] | RHS evaluations |",
                      "|---|---|---:|---:|---:|"]
            for r in sub:
                lines.append(f"| `{r['integrator']}` | {'yes' if r['stable'] else 'no'} | {fmt(r['max_path_error_mm'])}"
                             f" | {fmt(r['integration_error_mm'])} | {r['rhs_evaluations']:,} |")
            lines.append("")
    pumasim_io.write_text_atomic(os.path.join(OUT, "partitioned.md"), "\n".join(lines))
    print(f"wrote {os.path.relpath(os.path.join(OUT, 'partitioned.md'), ROOT)}")


if __name__ == "__main__":
    main()
