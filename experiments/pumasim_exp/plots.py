"""A sweep's plots: <sweep>.png (the ranking error against wall time and
against right-hand-side evaluations, a line per integrator, a panel row per
variant) and <sweep>_cost.png (the cheapest run within every target against
the variant value), from the merged rows only; each also as .pdf, in the
house style (style.py)."""
import math

from . import style
from .measures import BELOW_REFERENCE_FACTOR, ranking


def pyplot():
    """matplotlib.pyplot on the Agg back-end, in the house style (style.py)."""
    return style.pyplot()


def usable(x):
    """True for a number that a log axis can show (finite, positive)."""
    return isinstance(x, (int, float)) and math.isfinite(x) and x > 0


def integrator_colors(integrators):
    """{integrator: {color, ls}}, the integrators sorted by name: the
    colour-blind-safe palette, then the same colours dashed (style.series;
    the marker is the plot's: hollow means below the reference's accuracy)."""
    return {n: {k: v for k, v in style.series(i).items() if k != "marker"} for i, n in enumerate(integrators)}


def _plot_lines(ax, pts, line, label):
    """One integrator's line through pts = [(x, y, hollow)] in its style
    `line` ({color, ls}), its markers hollow where hollow is True."""
    ax.plot([p[0] for p in pts], [p[1] for p in pts], lw=1, label=label, **line)
    for hollow in (False, True):
        sel = [p for p in pts if p[2] == hollow]
        if sel:
            ax.plot([p[0] for p in sel], [p[1] for p in sel], "o", ms=4, color=line["color"],
                    mfc="none" if hollow else line["color"])


def plot_work_precision(plt, s, rows, agreement, colors, path, fmt="png"):
    """<sweep>.png: the ranking error against wall time and against RHS
    evaluations, one line per integrator (colors: integrator_colors), a panel
    row per variant; written to path in format fmt."""
    from matplotlib.lines import Line2D
    rcol, runit, rlabel, rtarget = ranking(s)
    nv = len(s["variants"])
    fig, axes = plt.subplots(nv, 2, figsize=(11, 3.6 * nv), squeeze=False)
    for i, v in enumerate(s["variants"]):
        a = agreement[v["label"]]
        for j, (key, label) in enumerate((("wall_time_median_s", "wall time [s] (median of the repeats)"),
                                          ("rhs_evaluations", "right-hand-side evaluations"))):
            ax = axes[i][j]
            for n in colors:
                pts = sorted((r[key], r[rcol], r["below_reference_accuracy"] is True) for r in rows
                             if r["variant"] == v["label"] and r["integrator"] == n and r["ok"] and
                             usable(r[rcol]) and usable(r[key]))
                if pts:
                    _plot_lines(ax, pts, colors[n], n)
            if math.isfinite(a[rcol]):
                ax.axhline(max(a[rcol], 1e-300), color="0.35", lw=0.8, ls=":", zorder=1, label="reference vs check")
            ax.axhline(rtarget, color="0.5", lw=0.8, ls="--", zorder=1, label=f"target {rtarget:g} {runit}")
            nfail = sum(1 for r in rows if r["variant"] == v["label"] and not r["ok"])
            ax.set(xscale="log", yscale="log", xlabel=label, ylabel=f"{rlabel} [{runit}]",
                   title=f"{v['label']}" + (f" ({nfail} failed runs, see CSV)" if nfail else "")
                   + (" — reference too weak" if s["rank_by"] in a["reference_too_weak"] else ""))
            ax.grid(True, which="major", lw=0.3)
    handles, labels = axes[0][1].get_legend_handles_labels()
    handles.append(Line2D([], [], ls="none", marker="o", ms=4, color="k", mfc="none"))
    labels.append(f"hollow: within {BELOW_REFERENCE_FACTOR}× of reference vs check (below its accuracy)")
    style.legend_right(axes[0][1], handles, labels)
    fig.suptitle(f"{s['title']} — ranked by {rlabel}", fontsize=10)
    fig.tight_layout()
    style.write(fig, path, fmt)  # path: a temporary (.tmp)
    plt.close(fig)


def plot_cost(plt, s, plottable, colors, path, fmt="png"):
    """<sweep>_cost.png: the RHS evaluations of each integrator's cheapest run
    within every target, against the variant value."""
    _, runit, rlabel, rtarget = ranking(s)
    fig, ax = plt.subplots(figsize=(7, 4.5))
    for n, pts in sorted(plottable.items()):
        if pts:
            _plot_lines(ax, [(p["value"], p["rhs"], p["below_reference_accuracy"] is True) for p in pts],
                        colors[n], n)
    ax.plot([], [], ls="none", marker="o", ms=4, color="k", mfc="none",
            label=f"hollow: error within {BELOW_REFERENCE_FACTOR}× of reference vs check")
    ax.set(xscale="log", yscale="log", xlabel=s["x"], ylabel="RHS evaluations (cheapest run within target)")
    ax.set_title(f"{s['title']}\ncost to reach {rlabel} ≤ {rtarget:g} {runit} (ranking measure)"
                 + (" and every other target" if len(s["targets"]) > 1 else ""), fontsize=8)
    ax.grid(True, which="major", lw=0.3)
    style.legend_right(ax)
    fig.tight_layout()
    style.write(fig, path, fmt)  # path: a temporary (.tmp)
    plt.close(fig)
