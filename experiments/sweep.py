#!/usr/bin/python3
"""Sweeps: variants of a scene x integrators x settings, as independent runs.

    /usr/bin/python3 experiments/sweep.py experiments/sweeps/<name>.toml
        [--jobs N] [--shard K/N] [--merge] [--reduced] [--out DIR] [--work DIR]

A sweep file (experiments/sweeps/README.md has the format) names a base scene,
its variants (scene overrides, as `pumasim run --set`), a reference and a
cross-check method, and the integrators with their settings. Every (variant,
method, setting) is one run of `pumasim run`, written by pumasim atomically
into build/sweeps/<sweep>/<variant>/<run>/ and repeated for the wall-time
median; then a summary <run>.json is written atomically (temporary file and
rename). A run with a summary is complete and is skipped on a re-run if its
key still matches: a SHA-256 over everything that determines the run -- the
scene as pumasim resolves it with the sweep's and the variant's --set values
(`pumasim check`: every default filled in, the robot file's hash), the
integrator and its options, t_end, the step budget, the repeats, and the
program (`pumasim --version`: revision, compiler, flags; for a build with
uncommitted changes also the binary's own SHA-256). A changed scene, robot
file, setting, horizon or program re-runs the run instead of reusing it, and
--merge refuses a summary whose key no longer matches. An interrupted run
leaves no summary and is redone. A run is run under its lock
(build/sweeps/<sweep>/<run>.lock, fcntl.flock, held by the sweep and the
pumasim it starts until the summary is written; a killed process leaves only
the empty file): two sweep.py processes on one sweep share its runs, each
run run once, and one that finds a run locked does the others first, then
waits and finds it complete. Each attempt first removes the run's folder an
earlier attempt left, so a pumasim that crashes is reported as a crash, never
read from an older folder. A folder that cannot be written (read-only, disk
full) is an error naming it.

Without --shard the runs go to N local processes (--jobs, default: the
number of cores) and the results are merged at the end. --shard K/N takes only
the runs whose index in the sorted run list is K-1 modulo N, so one sweep
splits over machines: as a Slurm job array

    #SBATCH --array=1-8
    python3 experiments/sweep.py S --shard $SLURM_ARRAY_TASK_ID/8 --jobs 1

or under GNU parallel: `parallel python3 experiments/sweep.py S --shard {}/8
--jobs 1 ::: 1 2 3 4 5 6 7 8`; then one `sweep.py S --merge` over the shared
build/sweeps/ writes the table. --merge compares each run with its variant's
reference at the output times in every error measure (tool position [mm],
tool orientation [rad], joint angles [rad], motor currents [A], RMS position,
final state), the reference with its cross-check in the same measures, and
writes results/<sweep>/: <sweep>.csv (every run, failures with their reason,
runs below the reference's accuracy flagged, whether each is within every
target the sweep sets and which it misses, each adaptive run's global error
over its rtol, the wall-time spread), <sweep>.png (the ranking error,
sweep.rank_by, against wall time and against right-hand-side evaluations, one
line per integrator and a panel row per variant, hollow markers below the
reference's accuracy), <sweep>_precision.md (experiments/precision_table.py:
per adaptive method its error over rtol and the slope of log error against
log rtol; per integrator and variant the cheapest run within every target,
and the measure that disqualifies a run cheaper on the ranking measure
alone), <sweep>_cost.png when the sweep has several variants (the RHS
evaluations each integrator needs to be within every target, against the
variant value) and
<sweep>_summary.json for the report (with each variant's reference verdict:
too weak where it differs from its check by more than target/100). These are
written to temporaries first and then renamed into place, the summary last,
carrying each file's SHA-256: a merge killed at any instant leaves the
earlier set or a summary that does not match the table beside it, which the
report refuses (re-run --merge); two merges of one sweep take turns.
Each worker pins its pumasim runs to a CPU of its own where the platform allows.

--reduced (CI): the first and last variants, two settings per method, one
repeat, short horizon, into build/sweeps-reduced/ and --out (default
build/sweeps-reduced/results/<folder>): checks the pipeline end to end,
writes nothing under results/.
"""
import argparse
import concurrent.futures
import functools
import hashlib
import json
import math
import os
import re
import shutil
import signal
import statistics
import subprocess
import sys
import threading
import tomllib

import numpy as np

import mode_sequence
import mode_table
import precision_table
import pumasim_io
from pumasim_io import ROOT, PUMASIM


class SweepError(Exception):
    pass


# The error measures of a run against its variant's reference (and of the
# reference against its cross-check): name (for `rank_by`), CSV column, unit,
# the sweep key of its accuracy target, and a label for tables and plots.
MEASURES = {
    "tool_position": ("max_tool_position_error_mm", "mm", "target_mm", "max tool position error"),
    "tool_orientation": ("max_tool_orientation_error_rad", "rad", "target_orientation_rad",
                         "max tool orientation error"),
    "joint": ("max_joint_error_rad", "rad", "target_joint_rad", "max joint-angle error"),
    "current": ("max_current_error_A", "A", "target_current_A", "max motor-current error"),
}
DEFAULT_RANK = "tool_position"
BELOW_REFERENCE_FACTOR = 10  # a run's ranking error within this factor of reference vs check: flagged
WEAK_REFERENCE_FACTOR = 100  # reference vs check must be this far below the target, or the reference is too weak

# The keys a [sweep] table may have.
SWEEP_KEYS = {"name", "title", "scene", "folder", "t_end", "reduced_t_end", "repeats", "x", "target_mm",
              "findings", "set", "max_steps", "limit_variant", "stuck_variant", "rank_by",
              *(m[2] for m in MEASURES.values())}


def _need(path, table, key, kind, where):
    """table[key], which must exist and be a `kind`; else a SweepError naming path and where."""
    if key not in table:
        raise SweepError(f"{path}: {where}: missing required key '{key}'")
    if not isinstance(table[key], kind):
        raise SweepError(f"{path}: {where}.{key}: expected {kind.__name__}, got {type(table[key]).__name__}")
    return table[key]


def _read_toml(path):
    """The sweep file's TOML document."""
    with open(path, "rb") as f:
        try:
            return tomllib.load(f)
        except tomllib.TOMLDecodeError as e:
            raise SweepError(f"{path}: TOML syntax error: {e}")


def _sweep_table(path, doc):
    """The [sweep] table's settings (unknown keys refused, defaults filled in),
    with the accuracy targets per measure; and the table itself."""
    known = {"sweep", "reference", "check", "variant", "method"}
    for k in doc:
        if k not in known:
            raise SweepError(f"{path}: unknown table '{k}'; expected one of: {', '.join(sorted(known))}")
    sw = _need(path, doc, "sweep", dict, "(top level)")
    for k in sw:
        if k not in SWEEP_KEYS:
            raise SweepError(f"{path}: unknown key 'sweep.{k}'")
    s = {
        "name": _need(path, sw, "name", str, "sweep"),
        "title": sw.get("title", sw["name"]),
        "scene": _need(path, sw, "scene", str, "sweep"),
        "t_end": float(sw["t_end"]) if "t_end" in sw else None,
        "repeats": int(sw.get("repeats", 3)),
        "x": sw.get("x", "variant"),
        "target_mm": float(sw.get("target_mm", 1e-3)),
        "findings": sw.get("findings", ""),
        "set": list(sw.get("set", [])),
        "folder": sw.get("folder", sw["name"]),
        "max_steps": int(sw.get("max_steps", 0)),
        "limit_variant": sw.get("limit_variant"),
        "stuck_variant": sw.get("stuck_variant"),
        "file": os.path.relpath(path, ROOT),
        "rank_by": sw.get("rank_by", DEFAULT_RANK),
    }
    if s["rank_by"] not in MEASURES:
        raise SweepError(f"{path}: sweep.rank_by: expected one of: {', '.join(MEASURES)}")
    # Accuracy targets per measure (the position one has always a value).
    s["targets"] = {col: (s["target_mm"] if key == "target_mm" else float(sw[key]))
                    for col, _, key, _ in MEASURES.values() if key == "target_mm" or key in sw}
    if MEASURES[s["rank_by"]][0] not in s["targets"]:
        raise SweepError(f"{path}: sweep.rank_by = \"{s['rank_by']}\" needs its target "
                         f"sweep.{MEASURES[s['rank_by']][2]}")
    return s, sw


def _method_of(path, t, where):
    """(integrator, options) of a [reference] or [check] table."""
    for k in t:
        if k not in ("integrator", "options"):
            raise SweepError(f"{path}: unknown key '{where}.{k}'; expected integrator, options")
    return (_need(path, t, "integrator", str, where), [str(o) for o in t.get("options", [])])


def _variants(path, doc, s):
    """The [[variant]] tables (default: one variant, 'base'), each with its
    reference and cross-check (default: the sweep's)."""
    variants = []
    for k, v in enumerate(doc.get("variant", [{"label": "base", "set": []}])):
        for key in v:
            if key not in ("label", "value", "set", "reference", "check", "methods", "if_integrator"):
                raise SweepError(f"{path}: unknown key 'variant[{k}].{key}'")
        lab = _need(path, v, "label", str, f"variant[{k}]")
        variants.append({"label": lab, "value": v.get("value", k), "set": list(v.get("set", [])),
                         "reference": _method_of(path, v["reference"], f"variant[{k}].reference")
                         if "reference" in v else s["reference"],
                         "check": _method_of(path, v["check"], f"variant[{k}].check") if "check" in v else s["check"],
                         # its own [[method]] list (default: the sweep's), and an integrator it needs
                         "methods": _methods(path, {"method": v["methods"]}, f"variant[{k}].methods")
                         if "methods" in v else None,
                         "if_integrator": v.get("if_integrator")})
    return variants


def _listed_integrators():
    """The integrators `pumasim integrators` lists."""
    p = subprocess.run([PUMASIM, "integrators", "--json"], capture_output=True, text=True)
    if p.returncode != 0:
        raise SweepError(f"{PUMASIM} integrators --json: exit status {p.returncode}: {p.stderr.strip()}")
    return {entry["name"] for entry in json.loads(p.stdout)}


def _guarded(s):
    """Leaves out, in place, the variants whose if_integrator pumasim does not
    list (an integrator not built yet: the variant runs once it is), naming
    them in s["skipped_variants"]."""
    needed = [v for v in s["variants"] if v["if_integrator"]]
    listed = _listed_integrators() if needed else set()
    s["skipped_variants"] = [f"{v['label']} (needs the integrator {v['if_integrator']}, which this pumasim "
                             "does not list)" for v in needed if v["if_integrator"] not in listed]
    s["variants"] = [v for v in s["variants"] if not v["if_integrator"] or v["if_integrator"] in listed]


def _methods(path, doc, where="method"):
    """(integrator, settings, extra options) per integrator of the [[method]]
    tables; a setting is (kind, value, pumasim options), kind 'dt' or 'rtol'."""
    methods = []
    for k, m in enumerate(_need(path, doc, "method", list, "(top level)")):
        names = _need(path, m, "integrator", list, f"{where}[{k}]")
        if "dt" in m:
            settings = [("dt", float(d), ["--dt", repr(float(d))]) for d in m["dt"]]
        elif "rtol" in m:
            fac = float(m.get("atol_factor", 1e-3))
            settings = [("rtol", float(r), ["--rtol", repr(float(r)), "--atol", repr(float(r) * fac)])
                        for r in m["rtol"]]
        else:
            raise SweepError(f"{path}: {where}[{k}]: expected 'dt' or 'rtol'")
        extra = [str(o) for o in m.get("options", [])]
        for name in names:
            methods.append((name, settings, extra))
    return methods


def _reduce(s, sw):
    """--reduced, in place: the first and last variants, two settings per
    method, one repeat, the reduced horizon if the sweep names one."""
    s["variants"] = [s["variants"][0]] + ([s["variants"][-1]] if len(s["variants"]) > 1 else [])
    s["methods"] = [(n, st[:2], ex) for n, st, ex in s["methods"]]
    for v in s["variants"]:
        if v["methods"]:
            v["methods"] = [(n, st[:2], ex) for n, st, ex in v["methods"]]
    s["repeats"] = 1
    labels = [v["label"] for v in s["variants"]]
    for key in ("limit_variant", "stuck_variant"):
        if s[key] not in labels:
            s[key] = None
    if "reduced_t_end" in sw:
        s["t_end"] = float(sw["reduced_t_end"])


def load_sweep(path, reduced):
    """The sweep file at path as a dict (experiments/sweeps/README.md has the
    format); SweepError naming the key if it is malformed."""
    doc = _read_toml(path)
    s, sw = _sweep_table(path, doc)
    for key in ("reference", "check"):
        s[key] = _method_of(path, _need(path, doc, key, dict, "(top level)"), key)
    s["variants"] = _variants(path, doc, s)
    for key in ("limit_variant", "stuck_variant"):
        if s[key] and s[key] not in [v["label"] for v in s["variants"]]:
            raise SweepError(f"{path}: sweep.{key}: expected one of the variants' labels")
    s["methods"] = _methods(path, doc)
    _guarded(s)
    if reduced:
        _reduce(s, sw)
    return s


def slug(text):
    return "".join(c if c.isalnum() or c in "-._" else "_" for c in text)


def run_list(s):
    """Every run of the sweep, sorted by id: (id, variant, tag, integrator, options, repeats)."""
    runs = []
    for v in s["variants"]:
        vdir = slug(v["label"])
        runs.append((f"{vdir}/reference", v, "reference", *v["reference"], 1))
        runs.append((f"{vdir}/check", v, "check", *v["check"], 1))
        for name, settings, extra in v["methods"] or s["methods"]:
            for kind, value, opts in settings:
                tag = f"{name}_{kind}{value:g}" + ("_" + slug(" ".join(o.lstrip("-") for o in extra)) if extra else "")
                runs.append((f"{vdir}/{tag}", v, tag, name, opts + extra, s["repeats"]))
    return sorted(runs, key=lambda r: r[0])


def scene_file(s):
    return os.path.join(ROOT, "experiments", "scenes", s["scene"] + ".toml")


class CpuPinning:
    """One CPU per worker thread, for the pumasim processes it starts: the
    first worker takes the first CPU this process may run on
    (os.sched_getaffinity, which respects a Slurm or cgroup CPU set), the next
    the next one, cycling when there are more workers than CPUs. A run is
    pinned with `taskset -c CPU` if taskset is installed, else by
    os.sched_setaffinity in the child before exec (subprocess preexec_fn); on
    a platform with neither nothing is pinned and the runs record that."""

    def __init__(self):
        self.cpus = sorted(os.sched_getaffinity(0)) if hasattr(os, "sched_getaffinity") else []
        self.taskset = shutil.which("taskset")
        self.method = ("taskset" if self.taskset else "sched_setaffinity") if self.cpus else None
        self.local = threading.local()
        self.lock = threading.Lock()
        self.workers = 0

    def cpu(self):
        """This worker's CPU (None: no pinning on this platform)."""
        if not self.cpus:
            return None
        if not hasattr(self.local, "cpu"):
            with self.lock:
                self.local.cpu = self.cpus[self.workers % len(self.cpus)]
                self.workers += 1
        return self.local.cpu

    def wrap(self, cmd):
        """(command, preexec_fn, cpu) that runs cmd on this worker's CPU."""
        cpu = self.cpu()
        if cpu is None:
            return cmd, None, None
        if self.taskset:
            return [self.taskset, "-c", str(cpu)] + cmd, None, cpu
        return cmd, (lambda: os.sched_setaffinity(0, {cpu})), cpu


def run_options(s, run):
    """pumasim run's options for a run, besides the scene file and the folder."""
    rid, variant, tag, name, opts, repeats = run
    args = ["--integrator", name] + opts
    for o in s["set"] + variant["set"]:
        args += ["--set", o]
    if s["t_end"]:
        args += ["--t-end", repr(s["t_end"])]
    # The sweep's budget is for adaptive methods and not for the references;
    # a fixed-step run's count is t_end / dt, known in advance: no budget.
    if s["max_steps"] and tag not in ("reference", "check") and "--rtol" in opts:
        args += ["--max-steps", str(s["max_steps"])]
    if "--dt" in opts:  # no budget: the step count is t_end / dt
        args += ["--max-steps", "0"]
    return args


@functools.lru_cache(maxsize=None)
def program_identity(pumasim):
    """`pumasim --version` (revision, compiler, flags, build type); for a build
    from a tree with uncommitted changes ("-dirty") also the binary's SHA-256,
    as the revision alone does not say what it runs."""
    p = subprocess.run([pumasim, "--version"], capture_output=True, text=True)
    if p.returncode != 0:
        raise SweepError(f"{pumasim} --version: exit status {p.returncode}: {p.stderr.strip()}")
    ident = p.stdout.strip()
    if "-dirty" in ident.split(" (")[0]:
        with open(pumasim, "rb") as f:
            ident += " sha256 " + hashlib.sha256(f.read()).hexdigest()
    return ident


@functools.lru_cache(maxsize=None)
def resolved_scene(pumasim, scene, sets):
    """The scene as pumasim resolves it with the --set values `sets` (a
    tuple): `pumasim check`'s text (every default, the state layout, and the
    hash of every file the scene read: the footer's `# input file:` lines)
    without the paths, so that the key says what a run computes, not where
    its files lie (the scene file's path; each input file's path, its hash
    kept)."""
    cmd = [pumasim, "check", scene]
    for o in sets:
        cmd += ["--set", o]
    p = subprocess.run(cmd, capture_output=True, text=True, cwd=ROOT)
    if p.returncode != 0:
        raise SweepError(f"{' '.join(cmd)}: {p.stderr.strip()}")
    lines = []
    for line in p.stdout.splitlines():
        if line.startswith("# Resolved scene"):
            continue
        for head in ("# robot file: ", "# input file: "):
            if line.startswith(head):
                line = head + line[line.rfind(" ("):]
        lines.append(line)
    return "\n".join(lines) + "\n"


def run_key(s, run):
    """SHA-256 (hex) of everything that determines a run: the resolved scene
    (with the sweep's and the variant's --set values), pumasim run's options
    (integrator, its settings, t_end, budget), the repeats and the program."""
    variant, repeats = run[1], run[5]
    doc = {"program": program_identity(PUMASIM),
           "scene": resolved_scene(PUMASIM, scene_file(s), tuple(s["set"] + variant["set"])),
           "options": run_options(s, run), "repeats": repeats}
    return hashlib.sha256(json.dumps(doc, sort_keys=True).encode()).hexdigest()


def complete(work, run, key):
    """The run's summary if it exists and was made with this key, else None."""
    path = os.path.join(work, run[0] + ".json")
    if not os.path.exists(path):
        return None
    sm = pumasim_io.read_json(path)
    return sm if sm.get("key") == key else None


def _lock_run(work, rid, wait):
    """The run's lock (work/<rid>.lock, beside its summary) once taken; None
    if another process holds it and wait is False. SweepError naming the
    path if the lock file cannot be made (a read-only or full folder)."""
    lock = pumasim_io.FileLock(os.path.join(work, rid + ".lock"))
    try:
        os.makedirs(os.path.dirname(lock.path), exist_ok=True)
        return lock if lock.acquire(wait) else None
    except OSError as e:
        raise SweepError(f"cannot write {e.filename or lock.path} (the run's lock): {e.strerror}")


def _run_once(full, cmd, out, preexec, lock):
    """One repeat of a run: the stats of the run folder that this pumasim
    process wrote at out (the folder of an earlier attempt was removed
    before it); SweepError if it wrote none (a crash) or bad input."""
    try:
        pumasim_io.remove_run_folder(out)
    except (OSError, pumasim_io.RunFolderError) as e:
        raise SweepError(f"cannot replace the earlier attempt's run folder: {e}")
    p = subprocess.run(full, capture_output=True, text=True, cwd=ROOT, preexec_fn=preexec, pass_fds=(lock.fd,))
    if p.returncode == 2:  # bad input: the sweep file is wrong, not the method (or --out not writable)
        raise SweepError(f"{' '.join(cmd)}: {p.stderr.strip()}")
    if not os.path.exists(out):  # pumasim itself failed (a crash, not a reported failure)
        how = (f"killed by signal {signal.Signals(-p.returncode).name} ({signal.strsignal(-p.returncode)})"
               if p.returncode < 0 else f"exit status {p.returncode}")
        raise SweepError(f"{' '.join(full)}: {how}, no run folder written: {p.stderr.strip()}")
    try:
        return pumasim_io.read_stats(out)
    except pumasim_io.RunFolderError as e:
        raise SweepError(f"{' '.join(full)}: exit status {p.returncode}: {e}")


def execute(s, work, run, pinning=None, wait=True):
    """Runs one run (all repeats, pinned to this worker's CPU when `pinning`
    is given) unless complete with the same key; returns its summary, or
    None if another process is running it and wait is False.

    The run's lock (work/<rid>.lock) is held from the check for completeness
    to the summary, by this process and each pumasim it starts (so a pumasim
    left running by a killed sweep holds it until it ends): two sweeps never
    run one run at once, and the second finds it complete. Each repeat first
    removes the run's folder left by an earlier attempt (the sweep's own, as
    pumasim wrote it), so the folder read is the one this pumasim wrote."""
    rid, variant, tag, name, opts, repeats = run
    summary_path = os.path.join(work, rid + ".json")
    key = run_key(s, run)
    if (sm := complete(work, run, key)) is not None:
        return sm
    lock = _lock_run(work, rid, wait)
    if lock is None:
        return None
    try:
        if (sm := complete(work, run, key)) is not None:  # another process finished it meanwhile
            return sm
        out = os.path.join(work, rid)
        options = run_options(s, run)  # "--integrator", name, then the rest
        cmd = [PUMASIM, "run", scene_file(s)] + options[:2] + ["--out", out] + options[2:]
        walls = []
        full, preexec, cpu = pinning.wrap(cmd) if pinning else (cmd, None, None)
        for _ in range(repeats):
            st = _run_once(full, cmd, out, preexec, lock)
            # the run's wall time less its friction mode log's step classification (stats.json)
            walls.append(st["wall_time_s"] - (st.get("mode_log_wall_time_s") or 0.0))
            if not st["ok"]:
                break
        summary = {"id": rid, "variant": variant["label"], "value": variant["value"], "tag": tag,
                   "integrator": name, "options": opts, "stats": st, "wall_times_s": walls,
                   "wall_time_median_s": statistics.median(walls), "command": cmd,
                   "pinned_cpu": cpu, "pinning": pinning.method if cpu is not None else None,
                   "key": key, "program": program_identity(PUMASIM)}
        try:
            pumasim_io.write_json_atomic(summary_path, summary, indent=1)
        except OSError as e:
            raise SweepError(f"cannot write the run's summary {summary_path}: {e.strerror}")
        return summary
    finally:
        lock.release()


def trajectory(run_dir):
    """{column name without its unit: list of floats} of a run folder's trajectory.csv."""
    try:
        return pumasim_io.read_trajectory(run_dir).lists()
    except pumasim_io.RunFolderError as e:
        raise SweepError(f"merge: {e}")


QUATERNION = ("tool_qw", "tool_qx", "tool_qy", "tool_qz")


def rotation_angle(q1, q2):
    """Angle [rad] of the rotation between two unit quaternions (w, x, y, z):
    2 atan2(|vec(q1* q2)|, |scalar(q1* q2)|), in [0, pi], the same for q and -q
    and accurate near 0 (unlike 2 acos)."""
    w1, x1, y1, z1 = q1
    w2, x2, y2, z2 = q2
    # q1* q2 with q1* = (w1, -x1, -y1, -z1)
    w = w1 * w2 + x1 * x2 + y1 * y2 + z1 * z2
    x = w1 * x2 - x1 * w2 - y1 * z2 + z1 * y2
    y = w1 * y2 - y1 * w2 - z1 * x2 + x1 * z2
    z = w1 * z2 - z1 * w2 - x1 * y2 + y1 * x2
    return 2.0 * math.atan2(math.sqrt(x * x + y * y + z * z), abs(w))


def _max(values):
    """Largest value; nan if there is none or one is nan (an error that is
    not finite must not hide behind a smaller one)."""
    values = list(values)
    if not values or any(math.isnan(v) for v in values):
        return math.nan
    return max(values)


def compare(ref, run):
    """The error measures of `run` against `ref` on their common output times
    (the first min(len) rows of both; the runs share the scene's output grid):
    max and RMS tool (flange) position distance [mm] (columns x, y, z); max
    tool orientation angle [rad] (tool_qw..tool_qz; nan if absent); max
    joint-angle difference over every q column [rad]; max motor-current
    difference over every i_motor column [A] (nan without current states); and
    the final-state error max_i |dx_i| / max(1, |x_i|) over q, qd, i_motor,
    z_piv (nan unless both reached the same final time); the same over every
    common output row (max_state_error, the global error relative to the
    state's scale, which error_over_rtol divides by the tolerance). Keys: the
    CSV columns."""
    n = min(len(ref["t"]), len(run["t"]))
    d = [1e3 * math.dist((ref["x"][k], ref["y"][k], ref["z"][k]), (run["x"][k], run["y"][k], run["z"][k]))
         for k in range(n)]
    if all(c in ref and c in run for c in QUATERNION):
        rot = _max(rotation_angle([ref[c][k] for c in QUATERNION], [run[c][k] for c in QUATERNION])
                   for k in range(n))
    else:
        rot = math.nan
    joints = [h for h in ref if re.fullmatch(r"q\d+", h)]
    currents = [h for h in ref if re.fullmatch(r"i_motor\d+", h)]
    dq = _max(abs(ref[h][k] - run[h][k]) for h in joints for k in range(n))
    di = _max(abs(ref[h][k] - run[h][k]) for h in currents for k in range(n))
    states = [h for h in ref if re.fullmatch(r"(q|qd|i_motor|z_piv)\d+", h) and h in run]
    final = math.nan
    if len(ref["t"]) == len(run["t"]) and abs(ref["t"][-1] - run["t"][-1]) < 1e-9:
        final = _max(abs(ref[h][-1] - run[h][-1]) / max(1.0, abs(ref[h][-1])) for h in states)
    return {"max_tool_position_error_mm": _max(d),
            "rms_tool_position_error_mm": math.sqrt(sum(e * e for e in d) / n) if n else math.nan,
            "max_tool_orientation_error_rad": rot, "max_joint_error_rad": dq, "max_current_error_A": di,
            "final_state_error": final, "max_state_error": _max_state_error(ref, run, states, n)}


def _max_state_error(ref, run, states, n):
    """The global error relative to the state's scale: max over the first n
    output rows and the states of |x - x_ref| / max(1, |x_ref|) (nan without
    rows or states; experiments/observed_order.py's error of a run)."""
    if not (n and states):
        return math.nan
    worst = []
    for h in states:
        x, x_ref = np.asarray(run[h][:n], dtype=float), np.asarray(ref[h][:n], dtype=float)
        worst.append(float(np.max(np.abs(x - x_ref) / np.maximum(1.0, np.abs(x_ref)))))
    return _max(worst)


def wall_spread(walls):
    """Median, min, max of the repeats' wall times [s] and the interquartile
    range (quartiles by linear interpolation, statistics 'inclusive'; nan for
    fewer than 4 repeats)."""
    iqr = math.nan
    if len(walls) >= 4:
        q1, _, q3 = statistics.quantiles(walls, n=4, method="inclusive")
        iqr = q3 - q1
    return {"wall_time_median_s": statistics.median(walls), "wall_time_min_s": min(walls),
            "wall_time_max_s": max(walls), "wall_time_iqr_s": iqr}


def reference_too_weak(agreement, targets):
    """Measures (CSV columns) for which the reference and its cross-check
    differ by more than target / WEAK_REFERENCE_FACTOR: the reference cannot
    resolve errors near the target there. A measure without a target, or
    whose difference is nan (no such states), is not judged."""
    return [col for col, target in targets.items()
            if math.isfinite(agreement.get(col, math.nan)) and agreement[col] > target / WEAK_REFERENCE_FACTOR]


def below_reference_accuracy(error, agreement):
    """True if a run's ranking error is within BELOW_REFERENCE_FACTOR of the
    reference-vs-check difference in the same measure (the reference cannot
    tell it from zero); None if either is not finite (failed run, no such
    states)."""
    if not (math.isfinite(error) and math.isfinite(agreement)):
        return None
    return error <= BELOW_REFERENCE_FACTOR * agreement


STUCK_MARGIN = 2  # output samples trimmed from each end of a stuck interval


def stuck_intervals(run):
    """Per joint, the output-sample index ranges [a, b] over which the joint
    speed is exactly zero at every sample (the hybrid model holds a stuck
    joint at exactly zero speed), trimmed by STUCK_MARGIN samples at each end
    so that a model breaking away a little earlier or later is not counted."""
    out = {}
    n = len(run["t"])
    for h in run:
        if not re.fullmatch(r"qd\d+", h):
            continue
        qd, k, ivs = run[h], 0, []
        while k < n - 1:
            if qd[k] == 0.0 and qd[k + 1] == 0.0:
                a = k
                while k < n - 1 and qd[k + 1] == 0.0:
                    k += 1
                if k - STUCK_MARGIN > a + STUCK_MARGIN:
                    ivs.append((a + STUCK_MARGIN, k - STUCK_MARGIN))
            k += 1
        out["q" + h[2:]] = ivs
    return out


def creep(run, held):
    """Largest motion (max - min of the angle) of a joint of `run` over an
    interval in which the exact model holds that joint stuck: {rad, joint,
    from_s, to_s}, and the stuck time examined."""
    worst = {"rad": 0.0, "joint": None, "from_s": math.nan, "to_s": math.nan}
    total = 0.0
    for q, ivs in held.items():
        for a, b in ivs:
            seg = run[q][a:b + 1]
            total += run["t"][b] - run["t"][a]
            if max(seg) - min(seg) >= worst["rad"]:
                worst = {"rad": max(seg) - min(seg), "joint": q, "from_s": run["t"][a], "to_s": run["t"][b]}
    worst["stuck_time_s"] = total
    return worst


def measures_text(a):
    """'tool position 0.00226 mm, tool orientation 1e-07 rad, ...' of an agreement entry."""
    return ", ".join(f"{label[len('max '):-len(' error')]} {a[col]:.3g} {unit}"
                     for col, unit, _, label in MEASURES.values()) + f", final state {a['final_state_error']:.3g}"


def _pyplot():
    """matplotlib.pyplot on the Agg back-end (files only, no display)."""
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    return plt


def _ranking(s):
    """(CSV column, unit, label, target) of the sweep's ranking measure (sweep.rank_by)."""
    rcol, runit, _, rlabel = MEASURES[s["rank_by"]]
    return rcol, runit, rlabel, s["targets"][rcol]


def _usable(x):
    """True for a number that a log axis can show (finite, positive)."""
    return isinstance(x, (int, float)) and math.isfinite(x) and x > 0


def _complete_summaries(s, work):
    """{run id: summary} of every run of the sweep; SweepError if a run has no
    summary yet or one made with another key."""
    summaries = {}
    for run in run_list(s):
        p = os.path.join(work, run[0] + ".json")
        if not os.path.exists(p):
            raise SweepError(f"merge: run {run[0]} has no result yet ({p}); run the sweep (or its shards) first")
        summaries[run[0]] = complete(work, run, run_key(s, run))
        if summaries[run[0]] is None:
            raise SweepError(f"merge: run {run[0]} ({p}) was made from another scene, setting or program than "
                             "the sweep's now; run the sweep (or its shards) again")
    return summaries


def _reference_vs_check(work, v, summaries):
    """(the variant's reference trajectory, compare() of its cross-check
    against it); SweepError if either of the two runs failed."""
    vdir = slug(v["label"])
    ref_sum, chk_sum = summaries[f"{vdir}/reference"], summaries[f"{vdir}/check"]
    for which, sm in (("reference", ref_sum), ("check", chk_sum)):
        if not sm["stats"]["ok"]:
            raise SweepError(f"variant {v['label']}: the {which} run failed: {sm['stats']['failure']}")
    ref = trajectory(os.path.join(work, vdir, "reference"))
    return ref, compare(ref, trajectory(os.path.join(work, vdir, "check")))


def _agreement_entry(s, c, ref_stats):
    """A variant's agreement entry from compare()'s result c of its reference
    and cross-check (every measure, the final state, the measures in which the
    reference is too weak, the reference's steps and tracking error), and the
    CSV columns in which it is too weak."""
    a = {col: c[col] for col, *_ in MEASURES.values()}
    a["final_state_error"] = c["final_state_error"]
    a["max_state_error"] = c["max_state_error"]
    too_weak = reference_too_weak(a, s["targets"])
    a["reference_too_weak"] = [m for m, spec in MEASURES.items() if spec[0] in too_weak]
    a["reference_steps"] = ref_stats["steps"]
    a["tracking_mm"] = ref_stats["max_path_error_mm"]
    return a, too_weak


def rtol_of(opts):
    """A run's rtol, from its pumasim options; None for a fixed step."""
    return float(opts[opts.index("--rtol") + 1]) if "--rtol" in opts else None


def disqualified_by(row, targets):
    """The error measures (MEASURES' names, in its order) whose target
    (targets: {CSV column: target}) a finished run misses, its error above the
    target or not finite; ["failed"] for a run that did not finish. A run
    qualifies ("within target") only with none: within every target the
    sweep sets, not the ranking measure's alone."""
    if not row["ok"]:
        return ["failed"]
    return [m for m, (col, *_) in MEASURES.items()
            if col in targets and not (math.isfinite(row[col]) and row[col] <= targets[col])]


def variant_targets(targets, agreement, rcol):
    """The targets a variant's runs are judged on (disqualified_by): every
    target the sweep sets but those in a measure the variant has no states
    for, its reference-vs-check difference nan (agreement: its entry; the
    motor currents of a variant with La = 0), which, as in
    reference_too_weak, is not judged; the ranking measure's always."""
    return {col: t for col, t in targets.items() if col == rcol or math.isfinite(agreement.get(col, math.nan))}


def _run_row(work, run, sm, ref, columns, rcol, agreement_rank, targets):
    """One run's CSV row: its error measures against its variant's reference
    trajectory ref (nan in every one of `columns` if it failed), its global
    error over its rtol (adaptive runs), whether it is below the reference's
    accuracy (agreement_rank: reference vs check in the ranking measure
    rcol), whether it is within every target (and which it misses),
    wall-time spread, pinning, counters. The key '_pinning' (the pinning
    method) is for the summary, not the table."""
    st = sm["stats"]
    if st["ok"]:
        e = compare(ref, trajectory(os.path.join(work, run[0])))
    else:
        e = dict.fromkeys(columns, math.nan)
    flag = below_reference_accuracy(e[rcol], agreement_rank)
    rtol = rtol_of(run[4])
    missed = disqualified_by({"ok": st["ok"], **e}, targets)
    row = {
        "variant": run[1]["label"], "value": run[1]["value"], "integrator": sm["integrator"],
        "setting": re.sub(r"^(dt|rtol)", r"\1=", run[2][len(sm["integrator"]) + 1:]),
        "ok": st["ok"], "failure": st["failure"],
        **e,
        "error_over_rtol": "" if rtol is None else e["max_state_error"] / rtol,
        "below_reference_accuracy": "" if flag is None else flag,
        "within_targets": not missed, "disqualified_by": " ".join(missed),
        "max_path_error_mm": st["max_path_error_mm"] if st["ok"] else math.nan,
        **wall_spread(sm["wall_times_s"]),
        "wall_times_s": " ".join(f"{w:.6g}" for w in sm["wall_times_s"]),
        "repeats": len(sm["wall_times_s"]),
        "pinned_cpu": "" if sm.get("pinned_cpu") is None else sm["pinned_cpu"],
        "rhs_evaluations": st["rhs_evaluations"], "jacobian_evaluations": st["jacobian_evaluations"],
        "steps": st["steps"], "rejected_steps": st["rejected_steps"], "restarts": st["restarts"],
        "time_events": st["time_events"], "root_events": st["root_events"],
    }
    row["_pinning"] = sm.get("pinning")
    if "max_ledger_residual_J" in st:  # scenes with the energy ledger
        row["max_ledger_residual_J"] = st["max_ledger_residual_J"]
        row["ledger_energy_scale_J"] = st["ledger_energy_scale_J"]
    return row


def _variant_rows(s, work, v, summaries, ref, c, a, modes):
    """The CSV rows of a variant's runs (not its reference and cross-check),
    sorted by run id; ref, c, a: the variant's reference trajectory, compare()
    of its cross-check and its agreement entry; modes: _mode_reference()'s,
    whose mode columns each row gets (mode_sequence.columns) when it has one."""
    rcol = MEASURES[s["rank_by"]][0]
    rows = []
    for run in run_list(s):
        if run[1] is not v or run[2] in ("reference", "check"):
            continue
        rows.append(_run_row(work, run, summaries[run[0]], ref, c, rcol, a[rcol],
                             variant_targets(s["targets"], a, rcol)))
        if modes:
            events = mode_sequence.read_events(os.path.join(work, run[0])) if rows[-1]["ok"] else None
            # The hybrid model's own events against the reference's own; a
            # run classified by speed (the other laws, time-stepping) against
            # the reference classified the same way.
            own = summaries[run[0]].get("mode_log", "").startswith("hybrid")
            key = "" if own or not modes["events_speed"] else "_speed"
            rows[-1].update(mode_sequence.columns(modes["events" + key], modes["marks" + key], events))
    return rows


def _mode_reference(s, work):
    """The friction modes' yardstick: sweep.stuck_variant's reference events,
    its marginal decisions (mode_sequence.marginal against its cross-check),
    and each variant's own reference compared with it (the treatment itself,
    as finely integrated as the sweep has it); None without a stuck variant
    or without events."""
    if not s["stuck_variant"]:
        return None
    vdir = slug(s["stuck_variant"])
    try:
        ref = mode_sequence.read_events(os.path.join(work, vdir, "reference"))
        if ref is None:
            return None
        marks = mode_sequence.marginal(ref, mode_sequence.read_events(os.path.join(work, vdir, "check")) or [])
        speed = mode_sequence.read_events(os.path.join(work, vdir, "reference"), mode_sequence.EVENTS_SPEED)
        marks_speed = mode_sequence.marginal(speed, mode_sequence.read_events(
            os.path.join(work, vdir, "check"), mode_sequence.EVENTS_SPEED) or []) if speed else {}
        treatments = {}
        for v in s["variants"]:
            vref = mode_sequence.read_events(os.path.join(work, slug(v["label"]), "reference")) or []
            yardstick = ref if v["label"] == s["stuck_variant"] or not speed else speed
            treatments[v["label"]] = mode_sequence.compare(yardstick, vref)
    except mode_sequence.EventsError as e:
        raise SweepError(f"merge: {e}")
    return {"variant": s["stuck_variant"], "events": ref, "marks": marks, "treatments": treatments,
            "events_speed": speed, "marks_speed": marks_speed,
            "marginal_speed": [{"joint": j, "t": t, "why": w} for (j, t), w in sorted(marks_speed.items())],
            "reference_events_speed": len(speed or []),
            "min_duration_s": mode_sequence.MIN_DURATION, "torque_margin": mode_sequence.TORQUE_MARGIN,
            "marginal": [{"joint": j, "t": t, "why": w} for (j, t), w in sorted(marks.items())],
            "reference_events": len(ref)}


def _pinning(rows):
    """How many runs were pinned to a CPU, how, and to which CPUs; removes the
    rows' '_pinning' keys."""
    pinned = [r for r in rows if r["pinned_cpu"] != ""]
    pinning = {"pinned_runs": len(pinned), "runs": len(rows),
               "methods": sorted({r["_pinning"] for r in pinned if r["_pinning"]}),
               "cpus": sorted({r["pinned_cpu"] for r in pinned})}
    for r in rows:
        del r["_pinning"]
    return pinning


def _distance_to_limit(s, work):
    """{variant: its reference against sweep.limit_variant's, every measure}
    ({} without a limit variant)."""
    limit = {}
    if s["limit_variant"]:
        lim = trajectory(os.path.join(work, slug(s["limit_variant"]), "reference"))
        for v in s["variants"]:
            d = compare(lim, trajectory(os.path.join(work, slug(v["label"]), "reference")))
            limit[v["label"]] = {col: d[col] for col, *_ in MEASURES.values()}
    return limit


def _creep_by_variant(s, work):
    """{variant: creep() of its reference where sweep.stuck_variant's reference
    holds a joint stuck} ({} without a stuck variant)."""
    held_creep = {}
    if s["stuck_variant"]:
        held = stuck_intervals(trajectory(os.path.join(work, slug(s["stuck_variant"]), "reference")))
        for v in s["variants"]:
            held_creep[v["label"]] = creep(trajectory(os.path.join(work, slug(v["label"]), "reference")), held)
    return held_creep


def _table_comments(s, agreement, weak, limit, held_creep, pinning):
    """The CSV's comment lines: the sweep, its ranking and targets, the flags'
    and wall times' definitions, and per variant its reference vs cross-check."""
    rcol, runit, rlabel, rtarget = _ranking(s)
    targets_text = ", ".join(f"{t:g} {next(m[1] for m in MEASURES.values() if m[0] == col)} ({col})"
                             for col, t in s["targets"].items())
    comments = [
        f"sweep {s['file']}: scene {s['scene']}, reference {' '.join([s['reference'][0]] + s['reference'][1])}, "
        f"cross-check {' '.join([s['check'][0]] + s['check'][1])}",
        f"ranked by {rlabel} [{runit}] ({rcol}, sweep.rank_by = \"{s['rank_by']}\"), target {rtarget:g} "
        f"{runit}; targets: {targets_text}",
        f"below_reference_accuracy: the run's {rcol} is within {BELOW_REFERENCE_FACTOR}x its variant's "
        f"reference-vs-check difference in that measure (empty: not judged, failed run); a reference is too "
        f"weak where that difference exceeds target/{WEAK_REFERENCE_FACTOR}",
        f"within_targets: the run finished and is within every target above (disqualified_by: the measures "
        f"whose target it misses, or failed; a measure its variant has no states for, its reference vs check "
        f"nan, is not judged); error_over_rtol (adaptive runs): max_state_error, the max over the "
        f"output rows and the states q, qd, i_motor, z_piv of |x - x_ref| / max(1, |x_ref|), over the run's rtol; "
        f"per method the slope of log(error) against log(rtol) is in {s['name']}_precision.md",
        f"wall times: median [s] of the repeats (all in wall_times_s), min, max, interquartile range "
        f"(nan below 4 repeats); {pinning['pinned_runs']} of {pinning['runs']} runs pinned to one CPU "
        f"({', '.join(pinning['methods']) or 'none'}; pinned_cpu, empty: not pinned)"]
    for v in s["variants"]:
        lab, a = v["label"], agreement[v["label"]]
        comments.append(f"{lab}: reference {' '.join([v['reference'][0]] + v['reference'][1])} vs cross-check "
                        f"{' '.join([v['check'][0]] + v['check'][1])}: {measures_text(a)}"
                        + "".join(f"; REFERENCE TOO WEAK for {col}: {w['difference']:.3g} > target/"
                                  f"{WEAK_REFERENCE_FACTOR} = {w['limit']:.3g}" for col, w in weak.get(lab, {}).items())
                        + (f"; its reference vs {s['limit_variant']}'s: "
                           f"{limit[lab]['max_tool_position_error_mm']:.3g} mm" if limit else "")
                        + (f"; creep where {s['stuck_variant']} holds a joint stuck: {held_creep[lab]['rad']:.3g} rad"
                           if held_creep else ""))
    return comments


def _plot_lines(ax, pts, color, label):
    """One integrator's line through pts = [(x, y, hollow)], its markers
    hollow where hollow is True."""
    ax.plot([p[0] for p in pts], [p[1] for p in pts], "-", lw=1, color=color, label=label)
    for hollow in (False, True):
        sel = [p for p in pts if p[2] == hollow]
        if sel:
            ax.plot([p[0] for p in sel], [p[1] for p in sel], "o", ms=4, color=color,
                    mfc="none" if hollow else color)


def _plot_work_precision(plt, s, rows, agreement, colors, path):
    """<sweep>.png: the ranking error against wall time and against RHS
    evaluations, one line per integrator (colors: {integrator: color}, sorted
    by name), a panel row per variant."""
    from matplotlib.lines import Line2D
    rcol, runit, rlabel, rtarget = _ranking(s)
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
                             _usable(r[rcol]) and _usable(r[key]))
                if pts:
                    _plot_lines(ax, pts, colors[n], n)
            if math.isfinite(a[rcol]):
                ax.axhline(max(a[rcol], 1e-300), color="k", lw=0.8, ls=":", label="reference vs check")
            ax.axhline(rtarget, color="0.5", lw=0.8, ls="--", label=f"target {rtarget:g} {runit}")
            nfail = sum(1 for r in rows if r["variant"] == v["label"] and not r["ok"])
            ax.set(xscale="log", yscale="log", xlabel=label, ylabel=f"{rlabel} [{runit}]",
                   title=f"{v['label']}" + (f" ({nfail} failed runs, see CSV)" if nfail else "")
                   + (" — reference too weak" if s["rank_by"] in a["reference_too_weak"] else ""))
            ax.grid(True, which="major", lw=0.3)
    handles, labels = axes[0][1].get_legend_handles_labels()
    handles.append(Line2D([], [], ls="none", marker="o", ms=4, color="k", mfc="none"))
    labels.append(f"hollow: within {BELOW_REFERENCE_FACTOR}× of reference vs check (below its accuracy)")
    axes[0][1].legend(handles, labels, fontsize=6, ncol=2)
    fig.suptitle(f"{s['title']} — ranked by {rlabel}", fontsize=10)
    fig.tight_layout()
    fig.savefig(path, dpi=80, format="png")  # path: a temporary (.tmp)
    plt.close(fig)


def _cheapest(rows):
    """The row with the fewest RHS evaluations (None for no rows)."""
    return min(rows, key=lambda r: r["rhs_evaluations"]) if rows else None


def _cost_to_target(s, rows, agreement, integrators):
    """{integrator: per variant, its cheapest run (fewest RHS evaluations)
    within every target the sweep sets (within_targets: the ranking measure's
    and every other one's)} (variants without one left out; a cheaper run
    that misses another target is in disqualified_cheapest)."""
    rcol = _ranking(s)[0]
    cost = {}
    for n in integrators:
        for v in s["variants"]:
            best = _cheapest([r for r in rows if r["variant"] == v["label"] and r["integrator"] == n
                              and r["within_targets"]])
            if best:
                cost.setdefault(n, []).append({
                    "value": v["value"], "variant": v["label"], "rhs": best["rhs_evaluations"],
                    "setting": best["setting"], "wall_s": best["wall_time_median_s"],
                    "wall_min_s": best["wall_time_min_s"], "wall_max_s": best["wall_time_max_s"],
                    "error": best[rcol], "below_reference_accuracy": best["below_reference_accuracy"],
                    "reference_too_weak": s["rank_by"] in agreement[v["label"]]["reference_too_weak"]})
    return cost


def disqualified_cheapest(s, rows, integrators):
    """Per (integrator, variant) whose cheapest run within the ranking
    measure's target misses another target the sweep sets: that run's
    setting and RHS evaluations and the measures it misses, with its error
    and the target in each (a list: the summary's and the precision table's)."""
    rcol, _, _, rtarget = _ranking(s)
    out = []
    for n in integrators:
        for v in s["variants"]:
            r = _cheapest([r for r in rows if r["variant"] == v["label"] and r["integrator"] == n and
                           r["ok"] and math.isfinite(r[rcol]) and r[rcol] <= rtarget])
            if r is not None and not r["within_targets"]:
                out.append({"integrator": n, "variant": v["label"], "setting": r["setting"],
                            "rhs": r["rhs_evaluations"],
                            "measures": [{"measure": m, "error": r[MEASURES[m][0]],
                                          "target": s["targets"][MEASURES[m][0]]}
                                         for m in r["disqualified_by"].split()]})
    return out


def _plot_cost(plt, s, plottable, colors, path):
    """<sweep>_cost.png: the RHS evaluations of each integrator's cheapest run
    within every target, against the variant value."""
    _, runit, rlabel, rtarget = _ranking(s)
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
    ax.legend(fontsize=6, ncol=2)
    fig.tight_layout()
    fig.savefig(path, dpi=80, format="png")  # path: a temporary (.tmp)
    plt.close(fig)


def _summary(s, rows, agreement, weak, limit, held_creep, pinning, cost, has_cost_plot):
    """<sweep>_summary.json's content, for the report."""
    rcol, runit, rlabel, rtarget = _ranking(s)
    return {"name": s["name"], "title": s["title"], "file": s["file"], "scene": s["scene"], "x": s["x"],
            "target_mm": s["target_mm"], "findings": s["findings"],
            "rank_by": {"measure": s["rank_by"], "column": rcol, "label": rlabel, "unit": runit,
                        "target": rtarget},
            "measures": {m: {"column": col, "unit": unit, "label": label, "target": s["targets"].get(col)}
                         for m, (col, unit, _, label) in MEASURES.items()},
            "below_reference_factor": BELOW_REFERENCE_FACTOR, "weak_reference_factor": WEAK_REFERENCE_FACTOR,
            "agreement": agreement, "reference_too_weak": weak,
            "limit_variant": s["limit_variant"], "distance_to_limit": limit,
            "stuck_variant": s["stuck_variant"], "creep": held_creep,
            "variants": [{"label": v["label"], "value": v["value"]} for v in s["variants"]],
            "runs": len(rows), "failed": sum(1 for r in rows if not r["ok"]),
            "below_reference_accuracy": sum(1 for r in rows if r["below_reference_accuracy"] is True),
            "pinning": pinning,
            "cost_to_target": cost, "has_cost_plot": has_cost_plot}


def merge(s, work, out_dir):
    """Compares every run with its variant's reference, and each reference
    with its cross-check, and writes out_dir/<sweep>.csv, <sweep>.png,
    <sweep>_precision.md, <sweep>_cost.png (several variants only) and
    <sweep>_summary.json (the
    module's docstring describes them); returns the summary. SweepError if a
    run is missing, stale (another key) or a reference or check failed."""
    plt = _pyplot()
    rows, agreement, weak = [], {}, {}
    summaries = _complete_summaries(s, work)
    modes = _mode_reference(s, work)
    for v in s["variants"]:
        ref, c = _reference_vs_check(work, v, summaries)
        a, too_weak = _agreement_entry(s, c, summaries[f"{slug(v['label'])}/reference"]["stats"])
        agreement[v["label"]] = a
        if too_weak:
            weak[v["label"]] = {col: {"difference": a[col], "limit": s["targets"][col] / WEAK_REFERENCE_FACTOR}
                                for col in too_weak}
        rows += _variant_rows(s, work, v, summaries, ref, c, a, modes)
    pinning = _pinning(rows)
    limit = _distance_to_limit(s, work)
    held_creep = _creep_by_variant(s, work)
    return _write_outputs(s, work, out_dir, plt, rows, agreement, weak, limit, held_creep, pinning, modes)


def _merge_lock(work):
    """The sweep's merge lock (work/.merge.lock) once taken, so that two
    merges of one sweep write one after the other; None if the work folder is
    not writable (a read-only copy of the runs): two merges at once then
    still leave no undetected mismatch, as the summary carries its files'
    hashes."""
    lock = pumasim_io.FileLock(os.path.join(work, ".merge.lock"))
    try:
        return lock if lock.acquire() else None
    except OSError:
        return None


def _write_csv(path, text):
    with open(path, "w", newline="") as f:
        f.write(text)


def _write_outputs(s, work, out_dir, plt, rows, agreement, weak, limit, held_creep, pinning, modes=None):
    """Writes out_dir/<sweep>.csv, <sweep>.png, <sweep>_precision.md,
    <sweep>_cost.png (several variants only) and <sweep>_summary.json together
    (pumasim_io.write_output_set: temporaries first, then renamed into place,
    the summary last with the others' SHA-256, which the report checks), so
    that a merge killed at any instant never leaves a table beside a summary
    of another merge undetected; under the sweep's merge lock. Returns the
    summary; SweepError naming the file that cannot be written."""
    name = s["name"]
    comments = _table_comments(s, agreement, weak, limit, held_creep, pinning) + _mode_comments(s, modes)
    text = pumasim_io.table_text(rows, comments=comments, fmt=pumasim_io.fmt_6g)
    integrators = sorted({r["integrator"] for r in rows})
    colors = {n: plt.cm.tab20(k % 20) for k, n in enumerate(integrators)}
    cost = _cost_to_target(s, rows, agreement, integrators)
    disqualified = disqualified_cheapest(s, rows, integrators)
    slopes = precision_table.tolerance_slopes(rows, agreement, BELOW_REFERENCE_FACTOR)
    precision = precision_table.markdown(s, rows, slopes, cost, disqualified, MEASURES, BELOW_REFERENCE_FACTOR)
    plottable = {n: [p for p in pts if _usable(p["value"])] for n, pts in cost.items()}
    has_cost_plot = len(s["variants"]) > 1 and any(len(p) > 1 for p in plottable.values())
    files = {name + ".csv": lambda p: _write_csv(p, text),
             name + ".png": lambda p: _plot_work_precision(plt, s, rows, agreement, colors, p),
             name + "_precision.md": lambda p: _write_csv(p, precision)}
    if has_cost_plot:
        files[name + "_cost.png"] = lambda p: _plot_cost(plt, s, plottable, colors, p)
    summary = _summary(s, rows, agreement, weak, limit, held_creep, pinning, cost, has_cost_plot)
    summary["disqualified_cheapest"] = disqualified
    summary["tolerance_slopes"] = [{k: m[k] for k in ("variant", "integrator", "options", "slope", "used", "mark")}
                                   for m in slopes]
    summary["skipped_variants"] = s.get("skipped_variants", [])
    if modes:
        summary["modes"] = {k: v for k, v in modes.items() if k not in ("events", "marks", "events_speed", "marks_speed")}
        summary["modes"]["cheapest_match"] = mode_table.cheapest_matches(rows)
        md = mode_table.markdown(s, rows, summary["modes"])
        files[name + "_modes.md"] = lambda p: _write_csv(p, md)
    lock = _merge_lock(work)
    try:
        os.makedirs(out_dir, exist_ok=True)
        pumasim_io.remove_dead_temporaries(out_dir, [*files, name + "_summary.json"])
        return pumasim_io.write_output_set(out_dir, files, name + "_summary.json", summary)
    except OSError as e:
        raise SweepError(f"merge: cannot write {e.filename}: {e.strerror}")
    finally:
        if lock:
            lock.release()


def _mode_comments(s, modes):
    """The CSV's comment lines on the mode columns (none without them)."""
    if not modes:
        return [f"variants left out: {', '.join(s['skipped_variants'])}"] if s.get("skipped_variants") else []
    lines = [f"mode columns: each run's friction modes (events.csv) against {modes['variant']}'s reference "
             "(the hybrid model's runs against its own events; runs classified by speed -- the other laws, "
             "time-stepping -- against the reference classified the same way, events_speed.csv) "
             f"({modes['reference_events']} events), modes held under {modes['min_duration_s']:g} s dropped "
             "(experiments/mode_sequence.py): sequence match, first divergence (time, joint; divergence_marginal: "
             "at a decision the reference's cross-check does not share or within "
             f"{modes['torque_margin']:g} Fs of the static level), event-time error max and RMS over the matched "
             "events, sticks at speed reversals missed / in the reference",
             f"marginal decisions of {modes['variant']}'s reference: " +
             (", ".join(f"joint {m['joint']} at {m['t']:.6g} s ({m['why']})" for m in modes["marginal"]) or "none")]
    if s.get("skipped_variants"):
        lines.append(f"variants left out: {', '.join(s['skipped_variants'])}")
    return lines


def _print_run(sm):
    st = sm["stats"]
    print(f"  {sm['id']}: {'ok' if st['ok'] else 'FAILED'} {sm['wall_time_median_s']:.3g} s, "
          f"{st['rhs_evaluations']} RHS", flush=True)


def run_share(s, work, runs, jobs):
    """Runs the runs (of this share) that are not complete on `jobs` worker
    threads. A run that another process (another sweep.py on the same sweep)
    is running is left for later; when the others are done, this process
    waits for it and then finds it complete (or runs it, if that process
    ended without finishing it)."""
    todo = [r for r in runs if complete(work, r, run_key(s, r)) is None]
    print(f"{s['name']}: {len(runs)} runs in this share, {len(runs) - len(todo)} already complete", flush=True)
    pinning = CpuPinning()
    if todo and len(pinning.cpus) < min(jobs, len(todo)):
        print(f"  note: {jobs} workers on {len(pinning.cpus) or 'no'} pinnable CPUs: "
              "workers share CPUs, wall times are less comparable", flush=True)
    busy = []
    with concurrent.futures.ThreadPoolExecutor(max_workers=max(1, jobs)) as pool:
        for run, sm in zip(todo, pool.map(lambda r: execute(s, work, r, pinning, wait=False), todo)):
            if sm is None:
                busy.append(run)
            else:
                _print_run(sm)
        if busy:
            print(f"  {len(busy)} runs being run by another process: waiting for them", flush=True)
        for sm in pool.map(lambda r: execute(s, work, r, pinning, wait=True), busy):
            _print_run(sm)


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("sweep")
    ap.add_argument("--jobs", type=int, default=os.cpu_count() or 1)
    ap.add_argument("--shard", default=None, help="K/N: run only the K-th of N shares of the runs")
    ap.add_argument("--merge", action="store_true", help="only merge finished runs into results/")
    ap.add_argument("--reduced", action="store_true", help="CI: a small version, results outside results/")
    ap.add_argument("--out", default=None, help="results folder (default results/<sweep>)")
    ap.add_argument("--work", default=None, help="the runs' folder (default build/sweeps/<sweep>, "
                    "with --reduced build/sweeps-reduced/<sweep>)")
    args = ap.parse_args()
    # Relative to the caller's folder: pumasim runs with its working directory
    # at the project's root, where a relative --work would land otherwise.
    args.work = os.path.abspath(args.work) if args.work else None
    args.out = os.path.abspath(args.out) if args.out else None
    try:
        s = load_sweep(args.sweep, args.reduced)
        work = args.work or os.path.join(ROOT, "build", "sweeps-reduced" if args.reduced else "sweeps", s["name"])
        out_dir = args.out or os.path.join(ROOT, "build", "sweeps-reduced", "results", s["folder"]) \
            if args.reduced else (args.out or os.path.join(ROOT, "results", s["folder"]))
        runs = run_list(s)
        if not args.merge:
            if args.shard:
                try:
                    k, n = (int(x) for x in args.shard.split("/"))
                    assert 1 <= k <= n
                except (ValueError, AssertionError):
                    raise SweepError(f"--shard {args.shard}: expected K/N with 1 <= K <= N")
                runs = [r for i, r in enumerate(runs) if i % n == k - 1]
            run_share(s, work, runs, args.jobs)
            if args.shard:
                return 0
        summary = merge(s, work, out_dir)
        print(f"{s['name']}: {summary['runs']} runs ({summary['failed']} failed) -> "
              f"{os.path.relpath(out_dir, ROOT)}/")
        return 0
    except SweepError as e:
        print(f"sweep: {e}", file=sys.stderr)
        return 2
    except OSError as e:  # a file or folder that cannot be read or written: the path, not a traceback
        print(f"sweep: {e.filename}: {e.strerror}", file=sys.stderr)
        return 2


if __name__ == "__main__":
    sys.exit(main())
