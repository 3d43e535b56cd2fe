#!/usr/bin/python3
"""Trajectory planning methods compared on the paper's path.

    /usr/bin/python3 experiments/planning.py [--out DIR] [--reduced]

Scene experiments/scenes/planning.toml (the paper's arm, drives, friction and
PIV controller, RK4 at 0.5 ms): the time-optimal timing under the drives'
limits is planned first, which gives the shortest traversal time T_opt; then
every method runs at the paper's T = 24 s, at 12, 6 and 3 s, and at T_opt:
the paper's piecewise speed table, trapezoid, jerk-limited S-curve, quintic
(Cartesian timing along the path), and joint-space cubic and quintic splines
through 16 via-points timed by the trapezoid. The time-optimal timing runs at
T_opt, planned with 80 % of the voltage range (the scene's default, the rest
left to feedback) and with 100 %. Each run is `pumasim run --set ...`.

Writes DIR (default results/planning/): planning.csv (every run: tracking and
path errors, peak voltage and current per joint, the share of the outputs at
which a drive saturates), planning.png (errors against traversal time, one
line per method), planning_along_path.png (distance to the path along it, per
method, at two traversal times), each plot also as .pdf beside it (the house
style, pumasim_exp/style.py), and summary.json for experiments/report.py.
--reduced (CI): T = 24 s cut to 1 s and T_opt only, into build/planning-reduced/.
"""
import argparse
import math
import os
import subprocess
import sys
import tomllib

from pumasim_exp import io as pumasim_io
from pumasim_exp import style
from pumasim_exp.io import ROOT, PUMASIM
SCENE = os.path.join(ROOT, "experiments", "scenes", "planning.toml")
PAPER_PROFILE = "[[0.0, 0.0], [0.08, 1.0], [0.3, 1.0], [0.4, 0.5], [0.55, 0.8], [0.75, 0.8], [0.9, 0.3], [1.0, 0.0]]"
VIA = 16
# Written after reading results/planning/planning.csv (regenerated with the rest), each sentence with the
# assertions report.py checks against the table (experiments/planning_findings.toml).
with open(os.path.join(ROOT, "experiments", "planning_findings.toml"), "rb") as _f:
    FINDINGS = " ".join(f["text"] for f in tomllib.load(_f)["findings"])


# The methods run at every traversal time: their --set values.
METHODS = {
    "table (paper)": ['reference.timing="table"', f"reference.profile={PAPER_PROFILE}"],
    "trapezoid": ['reference.timing="trapezoid"', "reference.blend=0.2"],
    "S-curve": ['reference.timing="scurve"', "reference.blend=0.25", "reference.jerk_fraction=0.25"],
    "quintic": ['reference.timing="quintic"'],
    "joint cubic": ['reference.timing="trapezoid"', "reference.blend=0.2", 'reference.interpolation="joint-cubic"',
                    f"reference.via_segments={VIA}"],
    "joint quintic": ['reference.timing="trapezoid"', "reference.blend=0.2",
                      'reference.interpolation="joint-quintic"', f"reference.via_segments={VIA}"],
}


def run(runs_dir, label, sets, t_end=None):
    path = os.path.join(runs_dir, label)
    cmd = [PUMASIM, "run", SCENE, "--out", path, "--force", "--set", "scene.output_interval=0.002"]
    for s in sets:
        cmd += ["--set", s]
    if t_end is not None:
        cmd += ["--t-end", repr(t_end)]
    p = subprocess.run(cmd, capture_output=True, text=True)
    if p.returncode not in (0, 1):
        sys.exit(f"planning: {' '.join(cmd)} failed ({p.returncode}): {p.stderr.strip()}")
    try:
        return pumasim_io.read_stats(path), path
    except pumasim_io.RunFolderError as e:
        sys.exit(f"planning: {' '.join(cmd)}: {e}")


def along_path(run_dir):
    tr = pumasim_io.read_trajectory(run_dir)
    return tr["t"].tolist(), tr["path_deviation"].tolist()


def table_row(method, T, stats, note=""):
    """planning.csv's row of one run (its stats.json: stats)."""
    n = len(stats["peak_voltage_V"])
    return {
        "method": method, "traversal_time_s": T, "ok": stats["ok"], "failure": stats["failure"],
        "max_tracking_error_mm": stats["max_path_error_mm"], "rms_tracking_error_mm": stats["rms_path_error_mm"],
        "max_path_deviation_mm": stats["max_path_deviation_mm"],
        "rms_path_deviation_mm": stats["rms_path_deviation_mm"],
        **{f"peak_voltage_V_j{j + 1}": stats["peak_voltage_V"][j] for j in range(n)},
        **{f"peak_current_A_j{j + 1}": stats["peak_current_A"][j] for j in range(n)},
        **{f"saturated_share_j{j + 1}": stats["saturated_fraction"][j] for j in range(n)},
        "saturates": any(s > 0 for s in stats["saturated_fraction"]),
        "wall_time_s": stats["wall_time_s"], "note": note,
    }


def run_all(runs, reduced):
    """Runs the time-optimal timing, then every method at every traversal
    time; returns (rows, {(method, T): run folder}, T_opt, the times)."""
    rows, traces = [], {}

    def record(method, T, stats, path, note=""):
        rows.append(table_row(method, T, stats, note))
        traces[(method, T)] = path

    stats, path = run(runs, "time-optimal_80pct", [], 1.0 if reduced else None)
    t_opt = stats["reference_duration_s"]
    record("time-optimal", t_opt, stats, path, "80 % of the voltage range planned")
    if not reduced:
        stats, path = run(runs, "time-optimal_100pct", ["planning.voltage_fraction=1.0"])
        record("time-optimal (100 %)", stats["reference_duration_s"], stats, path, "the whole voltage range planned")
    times = [t_opt] if reduced else [24.0, 12.0, 6.0, 3.0, t_opt]
    for m, sets in METHODS.items():
        for T in times:
            label = f"{m.split(' (')[0].replace(' ', '-')}_T{T:.4g}"
            stats, path = run(runs, label, sets + [f"reference.traversal_time={T!r}"], 1.0 if reduced else None)
            record(m, T, stats, path)
        print(f"planning: {m} done", flush=True)
    return rows, traces, t_opt, times


def plot_errors(plt, rows, colors, t_opt, path):
    """planning.png (and planning.pdf beside it): max tracking error and max
    distance to the path against the traversal time, one line per method
    (colors: {method: color}; a method run at one T only is a star)."""
    fig, axes = plt.subplots(1, 2, figsize=(11, 4.2))
    for ax, key, lab in ((axes[0], "max_tracking_error_mm", "max tracking error [mm]"),
                         (axes[1], "max_path_deviation_mm", "max distance to the path [mm]")):
        for m in colors:
            pts = sorted((r["traversal_time_s"], r[key]) for r in rows if r["method"] == m and r["ok"])
            if pts:
                ax.plot(*zip(*pts), "o-" if len(pts) > 1 else "*", ms=5 if len(pts) > 1 else 12, lw=1,
                        color=colors[m], label=m)
        ax.set(xscale="log", yscale="log", xlabel="traversal time T [s]", ylabel=lab)
        ax.axvline(t_opt, color="0.35", lw=0.6, ls=":")
        ax.grid(True, which="major", lw=0.3)
    style.legend_right(axes[1])
    fig.suptitle("Planning methods on the paper's path (3 joints, RK4 0.5 ms); dotted: the time-optimal T", fontsize=10)
    fig.tight_layout()
    style.save(fig, path)


def plot_along_path(plt, traces, colors, shown, path):
    """planning_along_path.png (and planning_along_path.pdf beside it): the
    distance to the path along it, one panel per traversal time in shown, one
    line per method (colors: {method: color}), one legend below the panels."""
    fig, axes = plt.subplots(len(shown), 1, figsize=(10, 3.4 * len(shown)), squeeze=False)
    for ax, T in zip(axes[:, 0], shown):
        for m in colors:
            if (m, T) in traces:
                t, d = along_path(traces[(m, T)])
                ax.plot([x / T for x in t], [max(y, 1e-6) for y in d], lw=0.8, color=colors[m], label=m)
        ax.set(yscale="log", xlabel="t / T", ylabel="distance to the path [mm]", title=f"T = {T:.3g} s")
        ax.grid(True, which="major", lw=0.3)
    entries = {}
    for ax in axes[:, 0]:
        for h, lab in zip(*ax.get_legend_handles_labels()):
            entries.setdefault(lab, h)
    fig.tight_layout()
    style.legend_below(fig, list(entries.values()), list(entries), ncol=4)
    style.save(fig, path)


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--out", default=None)
    ap.add_argument("--reduced", action="store_true")
    a = ap.parse_args()
    out = a.out or os.path.join(ROOT, *(("build", "planning-reduced") if a.reduced else ("results", "planning")))
    os.makedirs(out, exist_ok=True)
    runs = os.path.join(ROOT, "build", "planning-reduced-runs" if a.reduced else "planning-runs")  # not committed
    plt = style.pyplot()

    rows, traces, t_opt, times = run_all(runs, a.reduced)
    pumasim_io.write_table(os.path.join(out, "planning.csv"), rows, columns=list(rows[0].keys()),
                           comments=[f"experiments/planning.py on experiments/scenes/planning.toml; "
                                     f"time-optimal T_opt = {t_opt:.6g} s"], fmt=pumasim_io.fmt_6g)
    # The methods plotted (the 100 % time-optimal run is in the table only), each with its color.
    colors = style.colors(list(METHODS) + ["time-optimal"])
    plot_errors(plt, rows, colors, t_opt, os.path.join(out, "planning.png"))
    shown = [T for T in ([6.0, t_opt] if not a.reduced else [t_opt])]
    plot_along_path(plt, traces, colors, shown, os.path.join(out, "planning_along_path.png"))
    pumasim_io.write_json_atomic(os.path.join(out, "summary.json"),
                                 {"t_opt_s": t_opt, "findings": FINDINGS, "via_segments": VIA, "times_s": times},
                                 indent=1)
    print(f"planning: {len(rows)} runs -> {out} (T_opt = {t_opt:.4g} s)")


if __name__ == "__main__":
    main()
