"""experiments/sweep.py under faults (the reliability issue): a pumasim that
crashes, two sweep processes on one sweep, a sweep killed mid-way, a merge
killed at random instants and between its renames, a read-only or full
output location. A tiny reduced sweep (passive_arm, 20 ms, six runs) in a
temporary folder stands in for a real one; a wrapper script stands in for
pumasim where a crash, a slow run or a log of the runs started is needed.
Nothing here needs the checkout to be readable by another user: the suite
passes from a clone in a private (0700) folder, as root too (issue 31).

    PUMASIM=build/release/bin/pumasim /usr/bin/python3 -m pytest -q tests/test_sweep_faults.py
"""
import os
import ctypes
import random
import resource
import shutil
import signal
import subprocess
import sys
import tempfile
import time

import pytest

ROOT = os.path.normpath(os.path.join(os.path.dirname(os.path.abspath(__file__)), ".."))
sys.path.insert(0, os.path.join(ROOT, "experiments"))
from pumasim_exp import io as pumasim_io  # noqa: E402

PY = "/usr/bin/python3"
SWEEP_PY = os.path.join(ROOT, "experiments", "sweep.py")
REPORT_PY = os.path.join(ROOT, "experiments", "report.py")
REAL = os.environ.get("PUMASIM", os.path.join(ROOT, "build", "release", "bin", "pumasim"))

SWEEP = """
[sweep]
name = "{name}"
scene = "passive_arm"
t_end = 0.02
reduced_t_end = {t_end}
repeats = 1
target_mm = {target}

[reference]
integrator = "cvode-bdf"
options = ["--rtol", "1e-8", "--atol", "1e-10"]

[check]
integrator = "rk4"
options = ["--dt", "5e-4"]

[[method]]
integrator = ["ab2", "rk4"]
dt = [0.002, 0.001]
"""
RUNS = ["base/ab2_dt0.001", "base/ab2_dt0.002", "base/check", "base/reference", "base/rk4_dt0.001",
        "base/rk4_dt0.002"]

# Stands in for pumasim: logs "start OUT PID TIME" before and "end OUT PID TIME
# STATUS" after each `pumasim run` (OUT: its --out relative to the sweep's folder),
# waits FAKE_DELAY seconds before it and crashes (SIGSEGV, nothing written)
# instead of it while FAKE_CRASH is set; passes everything else on.
WRAPPER = """#!/usr/bin/python3
import os, signal, subprocess, sys, time
real, log, work = {real!r}, {log!r}, {work!r}
a = sys.argv[1:]
if a[:1] != ["run"]:
    os.execv(real, [real] + a)
out = os.path.relpath(a[a.index("--out") + 1], work)
with open(log, "a") as f:
    f.write(f"start {{out}} {{os.getpid()}} {{time.time()}}\\n")
time.sleep(float(os.environ.get("FAKE_DELAY", "0")))
if os.environ.get("FAKE_CRASH"):
    os.kill(os.getpid(), signal.SIGSEGV)
rc = subprocess.call([real] + a)
with open(log, "a") as f:
    f.write(f"end {{out}} {{os.getpid()}} {{time.time()}} {{rc}}\\n")
sys.exit(rc)
"""


class Sweep:
    """A tiny sweep of its own in a fresh folder `base`: the sweep file, the
    wrapper and its log; the runs in `work`, the merge output in `out` (with a
    file the program did not write)."""

    def __init__(self):
        self.name = "faults"
        self.base = tempfile.mkdtemp(prefix="pumasim_faults_")
        self.work = os.path.join(self.base, "work")
        self.out = os.path.join(self.base, "results", "folder")
        self.file = os.path.join(self.base, self.name + ".toml")
        self.log = os.path.join(self.base, "runs.log")
        self.wrapper = os.path.join(self.base, "pumasim")
        os.makedirs(self.out)
        with open(os.path.join(self.out, "notes.txt"), "w") as f:
            f.write("not the program's\n")
        with open(self.wrapper, "w") as f:
            f.write(WRAPPER.format(real=os.path.abspath(REAL), log=self.log, work=self.work))
        os.chmod(self.wrapper, 0o755)
        self.write()

    def write(self, t_end=0.02, target=1.0):
        with open(self.file, "w") as f:
            f.write(SWEEP.format(name=self.name, t_end=t_end, target=target))

    def args(self, *extra):
        return [PY, SWEEP_PY, self.file, "--reduced", "--work", self.work, "--out", self.out, *extra]

    def env(self, fake=True, **kw):
        """The environment of sweep.py: PUMASIM the wrapper (fake) or the real binary."""
        return {**os.environ, "PUMASIM": self.wrapper if fake else REAL, **{k: str(v) for k, v in kw.items()}}

    def run(self, *extra, fake=True, **kw):
        return subprocess.run(self.args(*extra), capture_output=True, text=True, env=self.env(fake, **kw))

    def starts(self):
        """The log's entries: [(what, run, process id, time)] (what: 'start' or 'end')."""
        if not os.path.exists(self.log):
            return []
        with open(self.log) as f:
            return [(w[0], w[1], int(w[2]), float(w[3])) for w in (line.split() for line in f)]

    def summaries(self):
        """{run: its summary's text} of the runs with a summary."""
        found = {}
        for r in RUNS:
            p = os.path.join(self.work, r + ".json")
            if os.path.exists(p):
                with open(p) as f:
                    found[r] = f.read()
        return found

    def clean(self):
        shutil.rmtree(self.base, ignore_errors=True)


@pytest.fixture
def sw():
    s = Sweep()
    yield s
    s.clean()


def no_traceback(p):
    assert "Traceback" not in p.stderr, p.stderr


def test_a_crashed_pumasim_is_a_crash_not_the_earlier_attempts_folder(sw):
    p = sw.run()
    assert p.returncode == 0, p.stderr
    # A longer horizon: every run's key changes, the folders of the 20 ms runs stay.
    sw.write(t_end=0.03)
    p = sw.run("--jobs", "1", FAKE_CRASH=1)
    assert p.returncode != 0, "a pumasim that crashed without writing anything was taken as a result"
    no_traceback(p)
    assert "killed by signal SIGSEGV" in p.stderr and "no run folder written" in p.stderr, p.stderr
    # No run of the new horizon is complete: no summary carries a 30 ms run's stats.
    for r, text in sw.summaries().items():
        assert '"t_end": 0.02' in text and '"t_end": 0.03' not in text, r
    # The real pumasim then completes them, at the new horizon.
    p = sw.run(fake=False)
    assert p.returncode == 0, p.stderr
    assert all(pumasim_io.read_stats(os.path.join(sw.work, r))["t_end"] == 0.03 for r in RUNS)


def test_two_sweeps_at_once_run_each_run_once_and_both_finish(sw):
    procs = [subprocess.Popen(sw.args("--jobs", "2"), stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
                              env=sw.env(FAKE_DELAY=0.5)) for _ in range(2)]
    outs = [p.communicate(timeout=120) for p in procs]
    for p, (o, e) in zip(procs, outs):
        assert p.returncode == 0, e
    started = sorted(r for w, r, *_ in sw.starts() if w == "start")
    assert started == RUNS, f"runs started by the two sweeps: {started}"
    table = pumasim_io.read_table(os.path.join(sw.out, sw.name + ".csv"))
    assert len(table) == 4 and all(r["ok"] == "True" for r in table)
    summary = pumasim_io.read_json(os.path.join(sw.out, sw.name + "_summary.json"))
    assert summary["runs"] == 4
    pumasim_io.check_outputs(sw.out, summary)
    with open(os.path.join(sw.out, "notes.txt")) as f:
        assert f.read() == "not the program's\n"


def overlapping(entries, killed_at):
    """Runs with two pumasim processes on them at once (a process that logged
    no end was killed: it ended at killed_at)."""
    spans = {}
    for w, r, pid, t in entries:
        spans.setdefault(r, {}).setdefault(pid, [t, killed_at])[w == "end"] = t
    bad = []
    for r, by_pid in spans.items():
        ss = sorted(by_pid.values())
        if any(ss[k + 1][0] < ss[k][1] for k in range(len(ss) - 1)):
            bad.append(r)
    return bad


@pytest.mark.parametrize("trial", range(4))
def test_a_killed_sweep_rerun_completes_every_run_exactly_once(sw, trial):
    """Trials 0, 2: the sweep and its pumasim killed together (a job killed);
    1, 3: the sweep alone, its pumasim running on."""
    rng = random.Random(trial)
    p = subprocess.Popen(sw.args("--jobs", "1"), stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL,
                         env=sw.env(FAKE_DELAY=1.5), start_new_session=True)
    n = 1 + 2 * (trial // 2)  # kill during the 2nd or the 4th run
    while sum(w == "start" for w, *_ in sw.starts()) <= n and p.poll() is None:
        time.sleep(0.02)
    time.sleep(rng.uniform(0.0, 0.2))  # early in the run (1.5 s: the wrapper's delay)
    assert p.poll() is None, f"the sweep ended (status {p.returncode}) before the kill"
    if trial % 2 == 0:
        os.killpg(p.pid, signal.SIGKILL)
    else:
        p.send_signal(signal.SIGKILL)
    p.wait()
    killed_at = time.time()
    done = sw.summaries()
    assert 0 < len(done) < len(RUNS), f"the kill did not land mid-way: {sorted(done)} complete"
    before = len(sw.starts())
    p = sw.run(FAKE_DELAY=0.1)
    assert p.returncode == 0, p.stderr
    again = sorted(r for w, r, *_ in sw.starts()[before:] if w == "start")
    assert again == sorted(set(RUNS) - set(done)), f"re-run ran {again}; complete before: {sorted(done)}"
    after = sw.summaries()
    assert sorted(after) == RUNS and all(after[r] == done[r] for r in done)
    assert overlapping(sw.starts(), killed_at) == [], "two pumasim processes on one run folder at once"
    for r in RUNS:  # each summary describes the run folder beside it, not one another process wrote later
        assert pumasim_io.read_json(os.path.join(sw.work, r + ".json"))["stats"] == \
            pumasim_io.read_stats(os.path.join(sw.work, r)), r


def outputs_agree(out, name):
    """True if the table and the summary in out were written by one merge:
    the table's target comment names the summary's target."""
    summary = pumasim_io.read_json(os.path.join(out, name + "_summary.json"))
    table = pumasim_io.read_table(os.path.join(out, name + ".csv"))
    return any(f"target {summary['target_mm']:g} mm" in c for c in table.comments)


def report_after_kill(sw, trial):
    """'agree' if the table and the summary belong together and the report
    reads them, 'refused' if the report refuses them (saying to re-run
    --merge); fails if they disagree and the report reads them."""
    r = subprocess.run([PY, REPORT_PY, "--results", os.path.dirname(sw.out),
                        "--out", os.path.join(sw.base, "README.md")], capture_output=True, text=True)
    no_traceback(r)
    if outputs_agree(sw.out, sw.name) and r.returncode == 0:
        return "agree"
    assert r.returncode != 0, f"{trial}: the table and the summary disagree and the report read them"
    assert "--merge" in r.stderr, r.stderr
    return "refused"


def finish_merge(sw):
    """A last merge completes: table and summary agree, no temporary is left, notes.txt untouched."""
    assert sw.run("--merge", fake=False).returncode == 0
    assert outputs_agree(sw.out, sw.name)
    assert sorted(os.listdir(sw.out)) == sorted(["notes.txt", sw.name + ".csv", sw.name + ".png", sw.name + ".pdf",
                                                 sw.name + "_precision.md", sw.name + "_summary.json"]), \
        "leftover temporaries"
    with open(os.path.join(sw.out, "notes.txt")) as f:
        assert f.read() == "not the program's\n"


MERGE_KILLS = 8


def test_a_merge_killed_at_random_instants_leaves_no_undetected_mismatch(sw):
    assert sw.run(fake=False).returncode == 0  # the runs, and a first merge: a table and its summary
    t0 = time.monotonic()
    assert sw.run("--merge", fake=False).returncode == 0
    whole = time.monotonic() - t0
    rng = random.Random(18)
    seen = {"agree": 0, "refused": 0}
    for trial in range(MERGE_KILLS):
        sw.write(target=[2.0, 1.0][trial % 2])  # each merge's table and summary differ from the last ones
        p = subprocess.Popen(sw.args("--merge"), stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL,
                             env=sw.env(fake=False))
        time.sleep(rng.uniform(0.3, 1.0) * whole)
        p.send_signal(signal.SIGKILL)
        p.wait()
        seen[report_after_kill(sw, f"trial {trial}")] += 1
    print(f"{MERGE_KILLS} merges killed: {seen}")
    finish_merge(sw)


# sweep.py --merge, killed (SIGKILL) right after its K-th rename of a file into the results folder.
KILL_AT_RENAME = """
import os, signal, sys
sys.path.insert(0, {experiments!r})
sys.argv = {argv!r}
import sweep
real, renames = os.replace, []
def replace(a, b):
    real(a, b)
    if os.path.dirname(os.path.abspath(b)) == {out!r}:
        renames.append(b)
        if len(renames) == {k}:
            os.kill(os.getpid(), signal.SIGKILL)
os.replace = replace
sys.exit(sweep.main())
"""


def test_a_merge_killed_between_its_renames_leaves_no_undetected_mismatch(sw):
    """The instants a random kill rarely hits: after the table is in place
    and before the summary is, and so on for every rename into the folder."""
    assert sw.run(fake=False).returncode == 0
    for k in (1, 2, 3, 4, 5):  # the table, the precision table, the plot (.png, .pdf), the summary
        sw.write(target=1.0 + k)  # each merge's files differ from every earlier one's
        code = KILL_AT_RENAME.format(experiments=os.path.join(ROOT, "experiments"), out=sw.out, k=k,
                                     argv=sw.args("--merge")[1:])
        p = subprocess.run([PY, "-c", code], capture_output=True, text=True, env=sw.env(fake=False))
        no_traceback(p)
        outcome = report_after_kill(sw, f"killed after rename {k}")
        assert outcome == ("agree" if k == 5 else "refused"), f"killed after rename {k}: {outcome}"
    finish_merge(sw)


CAP_DAC_OVERRIDE = 1  # linux/capability.h
CAP_SETPCAP = 8
PR_CAPBSET_DROP = 24  # linux/prctl.h


def can_drop_dac_override():
    """True unless this process is root without CAP_SETPCAP (which dropping a
    capability from the bounding set needs)."""
    if os.geteuid() != 0:
        return True
    with open("/proc/self/status") as f:
        eff = next(int(line.split()[1], 16) for line in f if line.startswith("CapEff:"))
    return bool(eff >> CAP_SETPCAP & 1)


def read_only_for_root():
    """In a child of root, before it execs: drops CAP_DAC_OVERRIDE from its
    capability bounding set, so that neither the program it runs nor that
    program's children (sweep.py's pumasim) have it. Root then obeys a folder's
    mode 0555 like any owner: writing into it fails with EACCES, as for a user
    in a read-only location. Root keeps its identity and CAP_DAC_READ_SEARCH,
    so it still reads the checkout wherever it lies: a checkout in a private
    (0700) folder is not readable by another user, which running the child as
    nobody needed (issue 31). A no-op for other users (the folders' modes
    already bind them)."""
    if os.geteuid() == 0:
        libc = ctypes.CDLL(None, use_errno=True)
        if libc.prctl(PR_CAPBSET_DROP, CAP_DAC_OVERRIDE, 0, 0, 0) != 0:
            raise OSError(ctypes.get_errno(), "prctl(PR_CAPBSET_DROP, CAP_DAC_OVERRIDE)")


def file_size_limit():
    """A full disk, as near as a test gets without mounting one: in the child,
    a write beyond 300 bytes fails (EFBIG, SIGXFSZ ignored; a pumasim that
    sweep.py starts gets SIGXFSZ's default back from subprocess and is killed
    by it, without a run folder)."""
    signal.signal(signal.SIGXFSZ, signal.SIG_IGN)
    resource.setrlimit(resource.RLIMIT_FSIZE, (300, 300))


def run_limited(sw, preexec, *extra):
    mpl = tempfile.mkdtemp(prefix="pumasim_faults_mpl_")  # matplotlib's cache, writable by the child
    env = {**sw.env(fake=False), "MPLCONFIGDIR": mpl}
    try:
        return subprocess.run(sw.args(*extra), capture_output=True, text=True, env=env, preexec_fn=preexec)
    finally:
        shutil.rmtree(mpl, ignore_errors=True)


@pytest.mark.parametrize("fault", ["read-only", "full"])
def test_a_read_only_or_full_output_location_is_a_clear_error(sw, fault):
    """read-only: the folder's mode 0555 (root's child without
    CAP_DAC_OVERRIDE, read_only_for_root); full: a file size limit."""
    if fault == "read-only" and not can_drop_dac_override():
        pytest.skip("root without CAP_SETPCAP: cannot make a folder read-only to its child")
    preexec = read_only_for_root if fault == "read-only" else file_size_limit
    os.makedirs(sw.work)
    if fault == "read-only":
        os.chmod(sw.work, 0o555)
    # The run folders' location.
    p = run_limited(sw, preexec)
    os.chmod(sw.work, 0o755)
    assert p.returncode != 0
    no_traceback(p)
    assert sw.work in p.stderr, p.stderr
    assert sw.summaries() == {}
    # The merge's location, the runs complete.
    assert sw.run(fake=False).returncode == 0
    before = {f: open(os.path.join(sw.out, f), "rb").read() for f in os.listdir(sw.out)}
    sw.write(target=2.0)
    if fault == "read-only":
        os.chmod(sw.out, 0o555)
    p = run_limited(sw, preexec, "--merge")
    os.chmod(sw.out, 0o755)
    assert p.returncode != 0
    no_traceback(p)
    assert sw.out in p.stderr, p.stderr
    assert {f: open(os.path.join(sw.out, f), "rb").read() for f in os.listdir(sw.out)} == before, \
        "a failed merge changed or left files"


def test_the_read_only_case_passes_from_a_checkout_in_a_private_folder():
    """Issue 31: the repository cloned into a fresh `mktemp -d` folder (0700,
    here as whoever runs the suite, root in CI) with its build inside. A copy
    of experiments/, of this file and of the binary in such a folder runs the
    read-only case there."""
    if not can_drop_dac_override():
        pytest.skip("root without CAP_SETPCAP: cannot make a folder read-only to its child")
    private = tempfile.mkdtemp(prefix="pumasim_private_checkout_")  # mode 0700, like mktemp -d
    try:
        shutil.copytree(os.path.join(ROOT, "experiments"), os.path.join(private, "experiments"),
                        ignore=shutil.ignore_patterns("__pycache__", "*.cpp", "*.hpp"))
        os.makedirs(os.path.join(private, "tests"))
        test_copy = shutil.copy(os.path.abspath(__file__), os.path.join(private, "tests"))
        binary = os.path.join(private, "build", "release", "bin", "pumasim")
        os.makedirs(os.path.dirname(binary))
        shutil.copy2(REAL, binary)
        node = test_copy + "::test_a_read_only_or_full_output_location_is_a_clear_error[read-only]"
        p = subprocess.run([PY, "-m", "pytest", "-q", "-p", "no:cacheprovider", "-rs", node], capture_output=True,
                           text=True, cwd=private, env={**os.environ, "PUMASIM": binary})
        assert p.returncode == 0 and "1 passed" in p.stdout, p.stdout + p.stderr
    finally:
        shutil.rmtree(private, ignore_errors=True)
