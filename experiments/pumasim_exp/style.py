"""The one plot style of every committed figure (results/) and of scripts/plot_run.py.

- A colour-blind-safe palette: Okabe and Ito's eight colours ("Color Universal
  Design", 2008; the palette Wong recommends in Nature Methods 8, 441, 2011),
  yellow last (weak on white). A ninth series takes the first colour again
  with the next dash pattern and marker, so that up to 32 series stay apart
  without relying on colour alone.
- Legends off the data: to the right of the axes (or below them), never over
  the lines; `save` keeps them inside the file (bbox_inches="tight").
- The reference a plot is measured against (the commanded joint angles, the
  path) is drawn under the data, in grey dashes, labelled "reference".
- Vector output beside the raster: `save(fig, "x.png")` writes x.png and x.pdf,
  each through a temporary file (nothing half-written), without time stamps
  (the same data give the same bytes of PDF).

Standard library and Debian's python3-matplotlib only.
"""
import os

# Okabe & Ito (2008): black, orange, sky blue, bluish green, blue, vermillion,
# reddish purple, yellow (moved last).
PALETTE = ["#000000", "#E69F00", "#56B4E9", "#009E73", "#0072B2", "#D55E00", "#CC79A7", "#F0E442"]
DASHES = ["-", "--", "-.", ":"]
MARKERS = ["o", "s", "^", "D"]
REFERENCE = {"color": "0.55", "lw": 1.0, "ls": "--", "zorder": 1, "label": "reference"}
PNG_DPI = 90  # the PNG is for browsing; the PDF beside it is the figure to print


def pyplot():
    """matplotlib.pyplot on the Agg back-end (files only), with the house style."""
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    from cycler import cycler
    plt.rcParams.update({
        "axes.prop_cycle": cycler(color=PALETTE),
        "font.size": 9,
        "axes.titlesize": 9,
        "axes.labelsize": 9,
        "legend.fontsize": 7,
        "legend.frameon": False,
        "axes.grid": True,
        "grid.linewidth": 0.3,
        "grid.color": "0.85",
        "lines.linewidth": 1.0,
        "lines.markersize": 4,
        "pdf.fonttype": 42,  # TrueType: text stays text in the PDF
        "savefig.dpi": PNG_DPI,
    })
    return plt


def series(k):
    """The k-th series' style: {color, ls, marker}."""
    n = len(PALETTE)
    return {"color": PALETTE[k % n], "ls": DASHES[(k // n) % len(DASHES)], "marker": MARKERS[(k // n) % len(MARKERS)]}


def series_styles(names):
    """{name: style} for the names in the order given."""
    return {name: series(k) for k, name in enumerate(names)}


def colors(names):
    """{name: colour} for the names in the order given (the palette, cycling)."""
    return {name: PALETTE[k % len(PALETTE)] for k, name in enumerate(names)}


def legend_right(ax, handles=None, labels=None, ncol=1, **kw):
    """The legend to the right of ax, outside the data."""
    args = [] if handles is None else [handles, labels]
    return ax.legend(*args, loc="upper left", bbox_to_anchor=(1.01, 1.0), borderaxespad=0.0, ncol=ncol, **kw)


def legend_below(fig, handles, labels, ncol=4, **kw):
    """One legend for the whole figure, below its axes."""
    return fig.legend(handles, labels, loc="upper center", bbox_to_anchor=(0.5, 0.0), ncol=ncol, **kw)


# No time stamps or versions in the files: the same figure, the same bytes.
METADATA = {"png": {"Software": None}, "pdf": {"CreationDate": None, "ModDate": None, "Producer": None, "Creator": None}}


def write(fig, path, fmt, dpi=PNG_DPI):
    """Writes the figure to exactly path in format fmt ("png" or "pdf"), the
    legends outside the axes included (for a caller that writes temporaries
    itself, as a sweep's output set does)."""
    fig.savefig(path, format=fmt, dpi=dpi, bbox_inches="tight", metadata=METADATA[fmt])


def save(fig, path, dpi=PNG_DPI):
    """Writes path (a .png) and the same figure as a .pdf beside it, each
    through a temporary file, then closes the figure; returns both paths."""
    import matplotlib.pyplot as plt
    root, ext = os.path.splitext(path)
    if ext != ".png":
        raise ValueError(f"style.save: {path}: expected a .png path (the .pdf goes beside it)")
    for target, fmt in ((path, "png"), (root + ".pdf", "pdf")):
        tmp = target + ".tmp"
        write(fig, tmp, fmt, dpi)
        os.replace(tmp, target)
    plt.close(fig)
    return [path, root + ".pdf"]
