#!/usr/bin/python3
"""PNG plots of one `pumasim run` directory (the paper's Figs. 6-11), each
with the same plot as a PDF beside it (<name>.pdf), in the house style
(experiments/pumasim_exp/style.py: the colour-blind-safe palette, legends
beside the data, the reference in grey dashes under it).

Usage: plot_run.py <run dir> [<out dir>] [--prefix NAME]

Reads only <run dir>/trajectory.csv and stats.json, and writes (each also as .pdf):
  <prefix>path_xy.png        path in the xy plane, reference and simulated (Fig. 6)
  <prefix>speed.png          speed along the path, reference and simulated (Figs. 7, 10, 12)
  <prefix>joints.png         joint trajectories, each with its reference q_ref<j>
                             dashed in its colour where the run has it (Fig. 8)
  <prefix>path_error.png     path error along the path (Figs. 9, 11)
Written into a run folder, they are listed in its marker (`pumasim run
--force` may then replace the folder with them).
"""
import argparse
import math
import os
import sys

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "experiments"))
from pumasim_exp import io as pumasim_io  # noqa: E402
from pumasim_exp import style  # noqa: E402

PLOTS = ("path_xy.png", "speed.png", "joints.png", "path_error.png")


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
    plt = style.pyplot()
    from matplotlib.lines import Line2D
    out = a.out_dir or a.run_dir
    os.makedirs(out, exist_ok=True)
    c, st = load(a.run_dir)
    t = c["t"]
    title = f"{st['scene']}: {st['integrator']}, backend {st['backend']}"
    has_ref = "x_ref" in c

    simulated = style.PALETTE[0]

    fig, ax = plt.subplots(figsize=(6, 5))
    if has_ref:
        ax.plot(c["x_ref"], c["y_ref"], **style.REFERENCE)
    ax.plot(c["x"], c["y"], lw=1, color=simulated, label="simulated")
    ax.set(xlabel="x [m]", ylabel="y [m]", title=title, aspect="equal")
    style.legend_right(ax)
    fig.tight_layout()
    style.save(fig, os.path.join(out, a.prefix + "path_xy.png"))

    fig, ax = plt.subplots(figsize=(7, 3.5))
    if has_ref:
        ax.plot(t, speed(t, c["x_ref"], c["y_ref"]), **style.REFERENCE)
    ax.plot(t, speed(t, c["x"], c["y"]), lw=0.8, color=simulated, label="simulated")
    ax.set(xlabel="t [s]", ylabel="speed in the xy plane [m/s]", title=title)
    style.legend_right(ax)
    fig.tight_layout()
    style.save(fig, os.path.join(out, a.prefix + "speed.png"))

    # Joint j in the palette's j-th colour; its reference q_ref<j> (where the
    # run has one) thin and dashed in the same colour, under the data.
    fig, ax = plt.subplots(figsize=(7, 3.5))
    joints = []
    while f"q{len(joints) + 1}" in c:
        joints.append(len(joints) + 1)
    colors = style.colors(joints)
    any_ref = False
    for j in joints:
        if f"q_ref{j}" in c:
            ax.plot(t, c[f"q_ref{j}"], color=colors[j], lw=0.8, ls="--", zorder=1)
            any_ref = True
        ax.plot(t, c[f"q{j}"], color=colors[j], lw=1, zorder=2, label=f"q{j}")
    ax.set(xlabel="t [s]", ylabel="joint angle [rad]", title=title)
    handles, labels = ax.get_legend_handles_labels()
    if any_ref:
        handles.append(Line2D([], [], color=style.REFERENCE["color"], lw=0.8, ls="--"))
        labels.append("dashed: its reference q_ref")
    if handles:
        style.legend_right(ax, handles, labels)
    fig.tight_layout()
    style.save(fig, os.path.join(out, a.prefix + "joints.png"))

    if has_ref:
        fig, ax = plt.subplots(figsize=(7, 3.5))
        s = arc_length(c["x_ref"], c["y_ref"])
        ax.plot(s, c["path_error"], lw=0.8, color=simulated)
        ax.set(xlabel="arc length along the path [m]", ylabel="path error [mm]",
               title=f"{title}; max {st['max_path_error_mm']:.3f} mm")
        fig.tight_layout()
        style.save(fig, os.path.join(out, a.prefix + "path_error.png"))
    # Plots written into a pumasim run folder are listed in its marker, so that
    # `pumasim run --force` may replace the folder with them (and nothing else):
    # every .png written and the .pdf beside it.
    written = [a.prefix + n[:-len(".png")] + ext for n in PLOTS for ext in (".png", ".pdf")]
    pumasim_io.list_in_marker(out, [n for n in written if os.path.exists(os.path.join(out, n))])


if __name__ == "__main__":
    main()
