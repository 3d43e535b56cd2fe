"""Running a sweep's runs: each (variant, method, setting) one `pumasim run`
into its own run folder, repeated for the wall-time median, pinned to a CPU
per worker, then its summary written atomically; a run complete with the
same key (a SHA-256 of everything that determines it: the resolved scene,
pumasim run's options, the repeats and the program) is reused, under a lock
per run so that two sweep.py processes share one sweep's runs. The stats are
read from the run folders through the io module (stats.json), never from
pumasim's printed text."""
import concurrent.futures
import functools
import hashlib
import json
import os
import shutil
import signal
import statistics
import subprocess
import threading

from . import io as pumasim_io
from .io import PUMASIM, ROOT
from .specs import SweepError, run_list


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
    for o in variant.get("unset", []):
        args += ["--unset", o]
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
def resolved_scene(pumasim, scene, sets, unsets=()):
    """The scene as pumasim resolves it with the --unset keys `unsets` and the
    --set values `sets` (tuples): `pumasim check`'s text (every default, the state layout, and the
    hash of every file the scene read: the footer's `# input file:` lines)
    without the paths, so that the key says what a run computes, not where
    its files lie (the scene file's path; each input file's path, its hash
    kept)."""
    cmd = [pumasim, "check", scene]
    for o in unsets:
        cmd += ["--unset", o]
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
           "scene": resolved_scene(PUMASIM, scene_file(s), tuple(s["set"] + variant["set"]),
                                   tuple(variant.get("unset", []))),
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


def complete_summaries(s, work):
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
