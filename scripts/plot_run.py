#!/usr/bin/python3
"""PNG plots of one `pumasim run` directory (the paper's Figs. 6-11).

Usage: plot_run.py <run dir> [<out dir>] [--prefix NAME]

Reads only <run dir>/trajectory.csv and stats.json, and writes:
  <prefix>path_xy.png        path in the xy plane, reference and simulated (Fig. 6)
  <prefix>speed.png          speed along the path, reference and simulated (Figs. 7, 10, 12)
  <prefix>joints.png         joint trajectories (Fig. 8)
  <prefix>path_error.png     path error along the path (Figs. 9, 11)
"""
import argparse
import math
import os
import sys

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "experiments"))
from pumasim_exp import io as pumasim_io  # noqa: E402


def load(run_dir):
    """({column name without its unit: list of floats}, stats dict) of a run folder."""
    try:
        run = pumasim_io.load_run(run_dir)
    except pumasim_io.RunFolderError as e:
        sys.exit(f"plot_run: {e}")
    return run.trajectory.lists(), run.stats


def speed(t, x, y):
    v = [0.0]
    for k in range(1, len(t)):
        v.append(math.hypot(x[k] - x[k - 1], y[k] - y[k - 1]) / (t[k] - t[k - 1]))
    return v


def arc_length(x, y):
    s = [0.0]
    for k in range(1, len(x)):
        s.append(s[-1] + math.hypot(x[k] - x[k - 1], y[k] - y[k - 1]))
    return s


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("run_dir")
    ap.add_argument("out_dir", nargs="?")
    ap.add_argument("--prefix", default="")
    a = ap.parse_args()
    out = a.out_dir or a.run_dir
    os.makedirs(out, exist_ok=True)
    c, st = load(a.run_dir)
    t = c["t"]
    title = f"{st['scene']}: {st['integrator']}, backend {st['backend']}"
    has_ref = "x_ref" in c

    fig, ax = plt.subplots(figsize=(6, 5))
    if has_ref:
        ax.plot(c["x_ref"], c["y_ref"], "k--", lw=1, label="reference")
    ax.plot(c["x"], c["y"], lw=1, label="simulated")
    ax.set(xlabel="x [m]", ylabel="y [m]", title=title, aspect="equal")
    ax.legend()
    fig.tight_layout()
    fig.savefig(os.path.join(out, a.prefix + "path_xy.png"), dpi=110)
    plt.close(fig)

    fig, ax = plt.subplots(figsize=(7, 3.5))
    if has_ref:
        ax.plot(t, speed(t, c["x_ref"], c["y_ref"]), "k--", lw=1, label="reference")
    ax.plot(t, speed(t, c["x"], c["y"]), lw=0.8, label="simulated")
    ax.set(xlabel="t [s]", ylabel="speed in the xy plane [m/s]", title=title)
    ax.legend()
    fig.tight_layout()
    fig.savefig(os.path.join(out, a.prefix + "speed.png"), dpi=110)
    plt.close(fig)

    fig, ax = plt.subplots(figsize=(7, 3.5))
    j = 1
    while f"q{j}" in c:
        ax.plot(t, c[f"q{j}"], lw=1, label=f"q{j}")
        j += 1
    ax.set(xlabel="t [s]", ylabel="joint angle [rad]", title=title)
    ax.legend(ncol=3)
    fig.tight_layout()
    fig.savefig(os.path.join(out, a.prefix + "joints.png"), dpi=110)
    plt.close(fig)

    if has_ref:
        fig, ax = plt.subplots(figsize=(7, 3.5))
        s = arc_length(c["x_ref"], c["y_ref"])
        ax.plot(s, c["path_error"], lw=0.8)
        ax.set(xlabel="arc length along the path [m]", ylabel="path error [mm]",
               title=f"{title}; max {st['max_path_error_mm']:.3f} mm")
        fig.tight_layout()
        fig.savefig(os.path.join(out, a.prefix + "path_error.png"), dpi=110)
        plt.close(fig)
    # Plots written into a pumasim run folder are listed in its marker, so that
    # `pumasim run --force` may replace the folder with them (and nothing else).
    pumasim_io.list_in_marker(out, [a.prefix + n for n in ("path_xy.png", "speed.png", "joints.png", "path_error.png")
                                    if os.path.exists(os.path.join(out, a.prefix + n))])


if __name__ == "__main__":
    main()
