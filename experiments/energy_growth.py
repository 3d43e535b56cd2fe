#!/usr/bin/python3
"""Does the energy error drift or stay bounded? The lossless arm over 10^4 s.

    /usr/bin/python3 experiments/energy_growth.py [--out DIR] [--work DIR] [--reduced]

The scene energy_long_time (the passive PUMA 560, six joints, no drive, no
friction: its mechanical energy is constant) run for 10^4 s by the
symplectic midpoint rule (symplectic-midpoint) and by methods that are not
symplectic: RK4 at the same steps, and the two adaptive methods that drift
least in the energy sweep (experiments/sweeps/energy_long_time.toml),
ARKODE's ERK and CVODE's Adams at rtol 1e-8. The energy error is the
ledger's residual, E(t) - E(0) here (every loss is zero), read at every
output (every 0.25 s: the outputs come from the dense output and change no
step).

Per run: the largest |E(t) - E(0)| in each decade of time, (0, 10], (10, 100],
(100, 1000] and (1000, 10^4] s; its growth exponent, the least-squares slope
of log(that maximum) against log(the decade's end) over the decades after
the first (0 for a bounded error, 1 for a linear drift); and the residual's
range over the last decade. A plot shows max |E - E(0)| per 10 s bin against
time.

Writes DIR (default results/energy_long_time/): energy_growth.csv,
energy_growth.md and energy_growth.png. Run folders go to --work (default
build/energy_growth/), with a private copy of the pumasim binary. --reduced:
100 s (two decades, the exponent over both), into build/energy_growth-reduced/.
"""
import argparse
import math
import os
import subprocess
import sys

import numpy as np

from pumasim_exp import io as pumasim_io
from pumasim_exp import plots
from pumasim_exp.io import ROOT, PUMASIM

SCENE = "energy_long_time"
OUTPUT_INTERVAL = 0.25
BIN = 10.0
RUNS = [  # (integrator, option, value)
    ("symplectic-midpoint", "--dt", 2e-3),
    ("symplectic-midpoint", "--dt", 1e-3),
    ("rk4", "--dt", 2e-3),
    ("rk4", "--dt", 1e-3),
    ("arkode-erk", "--rtol", 1e-8),
    ("cvode-adams", "--rtol", 1e-8),
]


def run(work, integ, option, value, t_end):
    out = os.path.join(work, f"{integ}_{option[2:]}{value:g}")
    cmd = [PUMASIM, "run", os.path.join(ROOT, "experiments", "scenes", SCENE + ".toml"), "--integrator", integ,
           option, repr(value), "--t-end", repr(t_end), "--set", f"scene.output_interval={OUTPUT_INTERVAL!r}",
           "--out", out, "--force"]
    if option == "--rtol":
        cmd += ["--atol", repr(1e-3 * value)]  # the energy sweep's atol_factor
    p = subprocess.run(cmd, capture_output=True, text=True, cwd=ROOT)
    if p.returncode != 0:
        sys.exit(f"energy_growth: {' '.join(cmd)} failed ({p.returncode}): {p.stderr.strip()}")
    try:
        r = pumasim_io.load_run(out)
    except pumasim_io.RunFolderError as e:
        sys.exit(f"energy_growth: {' '.join(cmd)}: {e}")
    return r.stats, r.meta, r.trajectory["t"], r.trajectory["ledger_residual"]


def decades(t_end):
    ends = [10.0 ** k for k in range(1, int(round(math.log10(t_end))) + 1)]
    return list(zip([0.0] + ends[:-1], ends))


def growth_exponent(maxima, ends):
    x, y = np.log(ends), np.log(maxima)
    return float(np.polyfit(x, y, 1)[0])


def summarise(integ, option, value, stats, t, r, t_end):
    row = {"integrator": integ, "setting": f"{option[2:]} {value:g}", "steps": stats["steps"],
           "rhs_evaluations": stats["rhs_evaluations"],
           "integration_wall_time_s": stats["integration_wall_time_s"]}
    maxima, ends = [], []
    for a, b in decades(t_end):
        sel = (t > a) & (t <= b)
        m = float(np.max(np.abs(r[sel])))
        row[f"max_abs_residual_J_to_{b:g}s"] = m
        maxima.append(m), ends.append(b)
    fit = slice(1, None) if len(maxima) >= 3 else slice(None)  # the first decade left out when three remain
    row["growth_exponent"] = growth_exponent(maxima[fit], ends[fit])
    last = (t > decades(t_end)[-1][0])
    row["last_decade_min_J"] = float(np.min(r[last]))
    row["last_decade_max_J"] = float(np.max(r[last]))
    return row


def envelope(t, r):
    bins = np.floor(np.maximum(t - 1e-9, 0) / BIN).astype(int)
    centres, peaks = [], []
    for k in np.unique(bins):
        sel = bins == k
        centres.append((k + 1) * BIN)
        peaks.append(float(np.max(np.abs(r[sel]))))
    return np.array(centres), np.array(peaks)


def plot(path, curves):
    plt = plots.pyplot()
    fig, ax = plt.subplots(figsize=(7.0, 4.2))
    for k, (label, (x, y)) in enumerate(curves.items()):
        keep = y > 0
        ax.loglog(x[keep], y[keep], label=label, lw=1.2)
    ax.set_xlabel("time [s]")
    ax.set_ylabel(f"max |E(t) − E(0)| per {BIN:g} s [J]")
    ax.set_title("Lossless PUMA 560: energy error over time")
    ax.legend(fontsize=7, ncol=2)
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)


def write_md(path, rows, t_end, reduced, meta):
    ends = [b for _, b in decades(t_end)]
    cmd = "experiments/energy_growth.py" + (" --reduced" if reduced else "")
    lines = [f"# Energy error over {t_end:g} s: drift or bounded?", "",
             f"Generated by `{cmd}`; every number below is read from `energy_growth.csv` in this folder; do not edit.",
             "",
             f"Scene `{SCENE}` (the passive arm, no losses), {t_end:g} s, outputs every {OUTPUT_INTERVAL:g} s. "
             "max |ΔE| per decade: the largest |E(t) − E(0)| (the ledger residual) in it. Growth exponent: the "
             "least-squares slope of log(max |ΔE|) against log(the decade's end) over the decades after the "
             "first (0: bounded; 1: a linear drift). Last decade: the residual's range there. " +
             (pumasim_io.revision_line(meta) if meta else ""), "",
             "| integrator | setting | " + " | ".join(f"max \\|ΔE\\| to {b:g} s [J]" for b in ends) +
             " | growth exponent | last decade [J] | RHS | steps |",
             "|---|---|" + "---:|" * (len(ends) + 4)]
    for r in rows:
        cells = [f"{r[f'max_abs_residual_J_to_{b:g}s']:.3g}" for b in ends]
        lines.append(f"| {r['integrator']} | {r['setting']} | " + " | ".join(cells) +
                     f" | {r['growth_exponent']:.2f} | [{r['last_decade_min_J']:.3g}, {r['last_decade_max_J']:.3g}]"
                     f" | {int(r['rhs_evaluations']):,} | {int(r['steps']):,} |")
    lines += ["", "The symplectic midpoint counts one RHS per fixed-point iteration (one mass matrix, its Cholesky "
              "factor, one mass matrix on dual numbers and one bias vector)."]
    pumasim_io.write_text_atomic(path, "\n".join(lines) + "\n")


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--out", default=None)
    ap.add_argument("--work", default=None)
    ap.add_argument("--reduced", action="store_true")
    args = ap.parse_args()
    name = "energy_growth-reduced" if args.reduced else "energy_growth"
    out = args.out or (os.path.join(ROOT, "build", name) if args.reduced
                       else os.path.join(ROOT, "results", "energy_long_time"))
    work = args.work or os.path.join(ROOT, "build", name, "runs")
    os.makedirs(out, exist_ok=True)
    os.makedirs(work, exist_ok=True)
    global PUMASIM
    PUMASIM = pumasim_io.private_copy(PUMASIM, work)
    t_end = 100.0 if args.reduced else 1e4
    rows, curves = [], {}
    for integ, option, value in RUNS:
        stats, meta, t, r = run(work, integ, option, value, t_end)
        rows.append(summarise(integ, option, value, stats, t, r, t_end))
        curves[f"{integ} {option[2:]} {value:g}"] = envelope(t, r)
        print(f"{integ} {option} {value:g}: growth exponent {rows[-1]['growth_exponent']:.2f}", flush=True)
    pumasim_io.write_table(os.path.join(out, "energy_growth.csv"), rows, columns=list(rows[0].keys()),
                           comments=[f"experiments/energy_growth.py{' --reduced' if args.reduced else ''}: "
                                     f"pumasim run experiments/scenes/{SCENE}.toml --integrator I --dt H | "
                                     f"--rtol R --atol 1e-3R --t-end {t_end:g} "
                                     f"--set scene.output_interval={OUTPUT_INTERVAL:g}"])
    write_md(os.path.join(out, "energy_growth.md"), rows, t_end, args.reduced, meta)
    plot(os.path.join(out, "energy_growth.png"), curves)
    print(f"energy growth: {os.path.relpath(out, ROOT)}/")


if __name__ == "__main__":
    main()
