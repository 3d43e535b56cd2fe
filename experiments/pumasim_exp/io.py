"""Reading `pumasim run` folders and reading and writing sweep tables: the
one place the Python scripts (experiments/*.py, scripts/*.py) do it (the
experiments package's io module; it was experiments/pumasim_io.py).

    from pumasim_exp import io as pumasim_io    # from experiments/ (the script's own folder)
    sys.path.insert(0, os.path.join(ROOT, "experiments"))   # first, from scripts/ or tests/

Run folders (simulation/run_folder.cpp writes them): a folder
holding trajectory.csv, stats.json, meta.json, scene.resolved.toml and the
marker file .pumasim-run, which starts with a '#' comment line saying it is a
pumasim run folder and then lists the files pumasim (or scripts/plot_run.py)
wrote there, one name a line. pumasim fills the folder under a temporary name
and renames it into place, so a folder whose marker lists every file it needs,
each present, is complete. trajectory.csv: one header row of names with units
("t [s]", "q1 [rad]", ...), then one row of numbers per output time.

Sweep tables (experiments/sweep.py, planning.py, observed_order.py,
output_grid.py write them under results/): CSV with optional leading comment
lines ("# ..."), one header row, then the rows; written atomically (a
temporary file beside the target, then a rename), so a reader never sees half
a table.

Atomic writes, JSON, locks and output sets are the files module's
(experiments/pumasim_exp/files.py), re-exported here.
"""
import csv
import io
import math
import os
import subprocess
import sys

import numpy as np

# The file primitives (files.py), part of this module's interface: a script
# imports io alone.
from .files import (FileLock, OutputsMismatch, check_outputs, private_copy, read_json,  # noqa: F401
                    remove_dead_temporaries, sha256_file, write_json_atomic, write_output_set, write_text_atomic)

# The project's root: this file is experiments/pumasim_exp/io.py.
ROOT = os.path.normpath(os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", ".."))
# The pumasim binary: $PUMASIM, else the release build's.
PUMASIM = os.environ.get("PUMASIM", os.path.join(ROOT, "build", "release", "bin", "pumasim"))

RUN_MARKER = ".pumasim-run"
MARKER_TITLE = "# a pumasim run folder"  # the marker's first line starts with this
TRAJECTORY, STATS, META, RESOLVED_SCENE = "trajectory.csv", "stats.json", "meta.json", "scene.resolved.toml"
RUN_FILES = (TRAJECTORY, STATS, META, RESOLVED_SCENE)  # what every `pumasim run` writes


class RunFolderError(Exception):
    """A folder that is not a complete pumasim run folder, or a file in it that is damaged."""


# ---------------------------------------------------------------- run folders

def marker_entries(run_dir):
    """The files the marker of run_dir lists (in its order); RunFolderError
    if there is no marker or it is not pumasim's."""
    marker = os.path.join(run_dir, RUN_MARKER)
    if not os.path.isfile(marker):
        raise RunFolderError(f"{run_dir}: not a pumasim run folder (no {RUN_MARKER} marker)")
    with open(marker) as f:
        lines = f.read().splitlines()
    if not lines or not lines[0].startswith(MARKER_TITLE):
        raise RunFolderError(f"{run_dir}: {RUN_MARKER} does not start with '{MARKER_TITLE}'")
    return [line for line in lines if line and not line.startswith("#")]


def check_run_folder(run_dir, needs=(TRAJECTORY, STATS)):
    """Raises RunFolderError unless run_dir is a complete pumasim run folder:
    its marker is pumasim's, lists every file of `needs`, and every file it
    lists is there. Returns the listed files."""
    listed = marker_entries(run_dir)
    missing = [n for n in needs if n not in listed]
    if missing:
        raise RunFolderError(f"{run_dir}: the {RUN_MARKER} marker does not list {', '.join(missing)}")
    absent = [n for n in listed if not os.path.exists(os.path.join(run_dir, n))]
    if absent:
        raise RunFolderError(f"{run_dir}: incomplete: {', '.join(absent)} listed by {RUN_MARKER} but absent")
    return listed


def remove_run_folder(run_dir):
    """Removes the pumasim run folder run_dir (absent: nothing to do): the
    files its marker lists, then the marker, then the folder, so that a
    removal killed half-way leaves a folder this function still recognises
    (an empty one is removed too). RunFolderError, nothing removed, if it is
    no pumasim run folder or holds a file the marker does not list."""
    if not os.path.lexists(run_dir):
        return
    if not os.path.isdir(run_dir) or os.path.islink(run_dir):
        raise RunFolderError(f"{run_dir}: not a folder; not removed")
    present = set(os.listdir(run_dir))
    if present:
        listed = set(marker_entries(run_dir))
        foreign = sorted(present - listed - {RUN_MARKER})
        if foreign:
            raise RunFolderError(f"{run_dir}: holds {', '.join(foreign)}, which pumasim did not write; not removed")
        for name in sorted(listed & present):
            os.remove(os.path.join(run_dir, name))
        os.remove(os.path.join(run_dir, RUN_MARKER))
    os.rmdir(run_dir)


def has_stats(run_dir):
    """True if run_dir holds a stats.json (pumasim wrote a run there, failed or not)."""
    return os.path.exists(os.path.join(run_dir, STATS))


def _read_run_json(run_dir, name, check):
    """A JSON document of a run folder as a dict (check: the folder first, as check_run_folder)."""
    if check:
        check_run_folder(run_dir, needs=(name,))
    path = os.path.join(run_dir, name)
    try:
        return read_json(path)
    except ValueError as e:
        raise RunFolderError(f"{path}: not JSON: {e}") from None


def read_stats(run_dir, check=True):
    """stats.json of a run folder as a dict."""
    return _read_run_json(run_dir, STATS, check)


def read_meta(run_dir, check=True):
    """meta.json of a run folder as a dict."""
    return _read_run_json(run_dir, META, check)


def column_name(header_cell):
    """'q1 [rad]' -> 'q1' (a trajectory column's name without its unit)."""
    return header_cell.split(" [")[0]


class Trajectory:
    """trajectory.csv of a run: header (the cells as written, with units),
    names (without units), units, text (the rows as written, lists of
    strings) and data (a float array, one row per output time)."""

    def __init__(self, header, text, path="trajectory.csv"):
        self.path = path
        self.header = list(header)
        self.names = [column_name(h) for h in self.header]
        self.units = [h[len(n) + 2:-1] if h.endswith("]") and len(h) > len(n) else "" for h, n in
                      zip(self.header, self.names)]
        self.text = text
        self.data = np.array([[float(v) for v in r] for r in text], dtype=float).reshape(-1, len(self.header))

    def __len__(self):
        return self.data.shape[0]

    def __contains__(self, name):
        return name in self.names

    def __getitem__(self, name):
        """The column `name` (without its unit) as a float array."""
        return self.data[:, self.index(name)]

    def index(self, name):
        try:
            return self.names.index(name)
        except ValueError:
            raise KeyError(f"{self.path}: no column '{name}'; it has {', '.join(self.names)}") from None

    def arrays(self):
        """{name: float array} in the file's column order."""
        return {h: self.data[:, i] for i, h in enumerate(self.names)}

    def lists(self):
        """{name: list of floats} in the file's column order."""
        return {h: self.data[:, i].tolist() for i, h in enumerate(self.names)}


def parse_trajectory(text, path="trajectory.csv"):
    """A Trajectory from the text of a trajectory.csv; RunFolderError if it is
    truncated (no final newline, a short or long row, a cell that is no
    number) or has no header."""
    if not text:
        raise RunFolderError(f"{path}: empty")
    if not text.endswith("\n"):
        raise RunFolderError(f"{path}: truncated (the last line has no end)")
    rows = list(csv.reader(io.StringIO(text)))
    header, body = rows[0], rows[1:]
    if not header or not header[0].startswith("t"):
        raise RunFolderError(f"{path}: expected a header starting with the time column t, got {header[:3]}")
    for k, r in enumerate(body):
        if len(r) != len(header):
            raise RunFolderError(f"{path}: truncated: row {k + 1} has {len(r)} cells, the header {len(header)}")
    try:
        return Trajectory(header, body, path)
    except ValueError as e:
        raise RunFolderError(f"{path}: a cell is not a number: {e}") from None


def read_trajectory(run_dir, check=True):
    """trajectory.csv of a run folder as a Trajectory."""
    if check:
        check_run_folder(run_dir, needs=(TRAJECTORY,))
    path = os.path.join(run_dir, TRAJECTORY)
    with open(path, newline="") as f:
        return parse_trajectory(f.read(), path)


class Run:
    """A loaded run folder: path, stats (dict), meta (dict, None if absent), trajectory."""

    def __init__(self, path, stats, meta, trajectory):
        self.path, self.stats, self.meta, self.trajectory = path, stats, meta, trajectory


def load_run(run_dir):
    """The run folder run_dir, checked (check_run_folder) and loaded."""
    listed = check_run_folder(run_dir, needs=(TRAJECTORY, STATS))
    return Run(run_dir, read_stats(run_dir, check=False),
               read_meta(run_dir, check=False) if META in listed else None,
               read_trajectory(run_dir, check=False))


def revision_line(meta):
    """A sentence naming the program that made a run (its meta.json as a dict):
    revision, uncommitted changes, compiler, build type, start time."""
    dirty = " with uncommitted changes" if meta.get("git_dirty") else ""
    return (f"Runs made by pumasim at git revision `{meta.get('git_revision')}`{dirty} "
            f"({meta.get('compiler')}, {meta.get('build_type')}), started {meta.get('started_utc')}.")


def list_in_marker(run_dir, names):
    """Adds names (files the caller wrote into run_dir) to its marker, so that
    `pumasim run --force` may replace the folder with them; does nothing when
    run_dir is no run folder."""
    marker = os.path.join(run_dir, RUN_MARKER)
    if not os.path.exists(marker):
        return
    with open(marker) as f:
        listed = set(f.read().split())
    with open(marker, "a") as f:
        f.writelines(n + "\n" for n in names if n not in listed)


# ---------------------------------------------------------------- sweep tables

class Table:
    """A sweep table: comments (the leading '# ' lines, without '# ' and the
    line end), columns (the header's names) and rows (dicts of strings)."""

    def __init__(self, comments, columns, rows):
        self.comments, self.columns, self.rows = comments, columns, rows

    def __iter__(self):
        return iter(self.rows)

    def __len__(self):
        return len(self.rows)


def parse_table(text):
    """A Table from CSV text: leading '#' lines, a header, rows."""
    lines = list(io.StringIO(text))  # split at '\n' only, as iterating over a file does
    k = 0
    while k < len(lines) and lines[k].startswith("#"):
        k += 1
    comments = [line.rstrip("\r\n")[1:].removeprefix(" ") for line in lines[:k]]
    reader = csv.DictReader(lines[k:])
    rows = list(reader)
    return Table(comments, list(reader.fieldnames or []), rows)  # no header (empty text): no columns, no rows


def read_table(path):
    """The sweep table at path (a Table; values are the strings written)."""
    with open(path) as f:
        return parse_table(f.read())


def table_text(rows, columns=None, comments=(), fmt=None, lineterminator="\r\n"):
    """The CSV text of a table: each comment as '# comment\\n', the header
    (columns; default every key of the rows in order of appearance), then the
    rows (a missing key: empty; keys not in columns: left out), each value
    passed through fmt (default str; floats with full precision) and csv's
    quoting, rows ending in lineterminator (csv's default '\\r\\n')."""
    if columns is None:
        columns = []
        for r in rows:
            columns += [k for k in r if k not in columns]
    out = io.StringIO(newline="")
    for c in comments:
        out.write(f"# {c}\n")
    w = csv.DictWriter(out, fieldnames=list(columns), extrasaction="ignore", lineterminator=lineterminator)
    w.writeheader()
    for r in rows:
        w.writerow({k: fmt(x) if fmt else x for k, x in r.items()})
    return out.getvalue()


def write_table(path, rows, columns=None, comments=(), fmt=None, lineterminator="\r\n"):
    """Writes table_text(...) to path atomically (path + '.tmp', then a rename)."""
    tmp = path + ".tmp"
    with open(tmp, "w", newline="") as f:
        f.write(table_text(rows, columns, comments, fmt, lineterminator))
    os.replace(tmp, path)


def fmt_6g(x):
    """Floats with 6 significant digits ('%.6g'), everything else as it is: the sweep tables' format."""
    return f"{x:.6g}" if isinstance(x, float) else x


def fnum(x):
    """A table cell as a float (nan if it is empty or no number)."""
    try:
        return float(x)
    except (TypeError, ValueError):
        return math.nan


def script_folders(args, name, results_dir):
    """(out, work) of an experiment script with --out, --work and --reduced:
    out defaults to results/<results_dir> (--reduced: build/<name>-reduced),
    work to build/<name>[-reduced]/runs; both are made."""
    tag = name + "-reduced" if args.reduced else name
    out = args.out or (os.path.join(ROOT, "build", tag) if args.reduced else os.path.join(ROOT, "results", results_dir))
    work = args.work or os.path.join(ROOT, "build", tag, "runs")
    os.makedirs(out, exist_ok=True)
    os.makedirs(work, exist_ok=True)
    return out, work


def run_or_exit(cmd, out, who):
    """Runs `pumasim run` as cmd (its folder out) and loads the run; exits
    naming the command when it fails or leaves no readable folder."""
    p = subprocess.run(cmd, capture_output=True, text=True, cwd=ROOT)
    if p.returncode != 0:
        sys.exit(f"{who}: {' '.join(cmd)} failed ({p.returncode}): {p.stderr.strip()}")
    try:
        return load_run(out)
    except RunFolderError as e:
        sys.exit(f"{who}: {' '.join(cmd)}: {e}")
