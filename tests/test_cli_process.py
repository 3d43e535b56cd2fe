"""`pumasim run` as a process, as a user sees it on a terminal and in a pipe:
stdout carries the JSON document alone (`pumasim run ... | jq` works); the
progress line appears on stderr only when stderr is a terminal (a pty here),
refreshed by wall-clock time while the integrator steps (not only at output
times), and never with --quiet.

    PUMASIM=build/release/bin/pumasim /usr/bin/python3 -m pytest -q tests/test_cli_process.py
"""
import fcntl
import json
import os
import pty
import re
import shutil
import struct
import subprocess
import sys
import termios

import pytest

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "experiments"))
from pumasim_exp import io as pumasim_io  # noqa: E402

SCENES = os.path.join(pumasim_io.ROOT, "experiments", "scenes")
SCENE = os.path.join(SCENES, "paper_slow.toml")
# RK4 steps of 2 us on 4 s (2,000,000 steps) with one output at the end: the
# progress line must come from the step loop, as no output falls in between.
# The run must last more than a second (the first progress report comes after
# one; with the reference tabulated a shorter scene ran in less: measured,
# commit 5f3ec5a); the sanitizer build, much slower (commit 03f83b1), shortens
# it with PUMASIM_TEST_LONG_RUN_T_END (tests/CMakeLists.txt).
LONG_T_END = os.environ.get("PUMASIM_TEST_LONG_RUN_T_END", "4")
LONG_RUN = [os.path.join(SCENES, "paper_slow_viscous.toml"), "--integrator", "rk4", "--dt", "2e-6",
            "--t-end", LONG_T_END, "--set", f"scene.output_interval={LONG_T_END}"]


def run_on_a_terminal(args, columns=200):
    """Runs pumasim with stderr on a pseudo-terminal `columns` wide, stdout on a pipe: (status, stdout, stderr bytes)."""
    master, slave = pty.openpty()
    fcntl.ioctl(slave, termios.TIOCSWINSZ, struct.pack("HHHH", 24, columns, 0, 0))
    p = subprocess.Popen([pumasim_io.PUMASIM] + args, stdout=subprocess.PIPE, stderr=slave, stdin=subprocess.DEVNULL)
    os.close(slave)
    err = b""
    while True:
        try:
            chunk = os.read(master, 4096)
        except OSError:  # EIO: the child closed the terminal
            break
        if not chunk:
            break
        err += chunk
    os.close(master)
    out = p.stdout.read()
    p.wait()
    return p.returncode, out, err


def test_stdout_is_the_json_document_alone_through_jq(tmp_path):
    if not shutil.which("jq"):
        pytest.skip("jq is not installed")
    scene = os.path.join(SCENES, "paper_slow.toml")
    cmd = f"'{pumasim_io.PUMASIM}' run '{scene}' --t-end 0.05 --out '{tmp_path / 'run'}' | jq -e -r .scene"
    p = subprocess.run(["bash", "-o", "pipefail", "-c", cmd], capture_output=True, text=True)
    assert p.returncode == 0, p.stderr
    assert p.stdout == "paper_slow\n"
    assert p.stderr == f"results: {tmp_path / 'run'}/\n"


def test_no_progress_line_when_stderr_is_not_a_terminal(tmp_path):
    p = subprocess.run([pumasim_io.PUMASIM, "run"] + LONG_RUN + ["--out", str(tmp_path / "run")],
                       capture_output=True, text=True)
    assert p.returncode == 0, p.stderr
    assert json.loads(p.stdout)["ok"] is True
    assert p.stderr == f"results: {tmp_path / 'run'}/\n"


def test_a_progress_line_on_a_terminal_refreshed_between_outputs(tmp_path):
    status, out, err = run_on_a_terminal(["run"] + LONG_RUN + ["--out", str(tmp_path / "run")])
    assert status == 0, err
    doc = json.loads(out)  # stdout untouched by the progress line
    text = err.decode()
    lines = [s for s in text.split("\r") if s.startswith("pumasim run paper_slow_viscous: ")]
    assert lines, text
    pattern = re.compile(r"pumasim run paper_slow_viscous: t = ([0-9.e+-]+) / " + re.escape(LONG_T_END) +
                         r" s \(\d+%\), (\d+) steps, "
                         r"h = 2e-06 s, ([0-9.]+) s elapsed *$")
    seen = []
    for line in lines:
        m = pattern.match(line)
        assert m, line
        seen.append((float(m[1]), int(m[2]), float(m[3])))
    assert all(0 < t < float(LONG_T_END) for t, _, _ in seen), seen  # between the outputs at 0 and the end
    assert seen[0][2] >= 1.0, "the first report after a second"
    assert all(b[1] > a[1] and b[0] > a[0] for a, b in zip(seen, seen[1:])), seen
    assert seen[-1][1] <= doc["steps"]
    # The line is cleared before the last message.
    assert text.endswith("\r" + " " * len(lines[-1].rstrip()) + f"\rresults: {tmp_path / 'run'}/\r\n"), repr(text[-300:])


def test_the_progress_line_fits_a_narrow_terminal(tmp_path):
    # A line as wide as the terminal would wrap, and \r would rewind only its last row.
    status, out, err = run_on_a_terminal(["run"] + LONG_RUN + ["--out", str(tmp_path / "run")], columns=60)
    assert status == 0, err
    lines = [s for s in err.decode().split("\r") if s.startswith("pumasim run paper_slow_viscous: ")]
    assert lines
    assert all(len(line) <= 59 for line in lines), [len(line) for line in lines]


def test_quiet_has_no_progress_line_on_a_terminal(tmp_path):
    status, out, err = run_on_a_terminal(["run"] + LONG_RUN + ["--out", str(tmp_path / "run"), "--quiet"])
    assert status == 0, err
    assert json.loads(out)["ok"] is True
    assert err == b""


def _small_file_limit(limit_bytes):
    """A preexec_fn: files the child writes stop at limit_bytes, and a write
    past it fails with EFBIG instead of killing the child (SIGXFSZ ignored,
    which exec keeps): what a full disk looks like to the program."""
    import resource
    import signal

    def apply():
        signal.signal(signal.SIGXFSZ, signal.SIG_IGN)
        resource.setrlimit(resource.RLIMIT_FSIZE, (limit_bytes, limit_bytes))
    return apply


def test_a_full_disk_is_an_error_naming_the_file_and_leaves_no_run_folder(tmp_path):
    # The reliability issue: with a 256 KiB tmpfs, pumasim run exited 0 and
    # left trajectory.csv cut at 256 KiB and empty stats.json, meta.json and
    # scene.resolved.toml. paper_slow's trajectory is far above 256 KiB.
    out = tmp_path / "run"
    p = subprocess.run([pumasim_io.PUMASIM, "run", SCENE, "--out", str(out), "--quiet"],
                       capture_output=True, text=True, preexec_fn=_small_file_limit(256 * 1024))
    assert p.returncode == 2, p.stderr
    assert "could not write" in p.stderr and "trajectory.csv" in p.stderr, p.stderr
    assert "no run folder written" in p.stderr, p.stderr
    assert p.stdout == ""
    assert os.listdir(tmp_path) == [], os.listdir(tmp_path)  # neither the folder nor its .partial


def test_an_output_location_that_cannot_be_a_folder_is_an_error_naming_it(tmp_path):
    blocker = tmp_path / "file"
    blocker.write_text("not a folder\n")
    p = subprocess.run([pumasim_io.PUMASIM, "run", SCENE, "--out", str(blocker / "run"), "--quiet", "--t-end", "0.01"],
                       capture_output=True, text=True)
    assert p.returncode == 2, p.stderr
    assert str(blocker / "run") in p.stderr, p.stderr
    assert "internal error" not in p.stderr, p.stderr
    assert sorted(os.listdir(tmp_path)) == ["file"]


@pytest.mark.skipif(not os.path.exists("/dev/full"), reason="no /dev/full to stand for a full disk")
@pytest.mark.parametrize("args", [["dynamics", "--robot", "puma560", "--backend", "crba", "--q=qn"],
                                  ["check", SCENE]])
def test_a_write_error_on_stdout_is_exit_2_naming_the_output(args):
    """Issue 32: `pumasim dynamics ... > full_disk/out.json` exited 0 with an
    empty file. /dev/full fails every write with ENOSPC."""
    with open("/dev/full", "w") as full:
        p = subprocess.run([pumasim_io.PUMASIM] + args, stdout=full, stderr=subprocess.PIPE, text=True)
    assert p.returncode == 2, p.stderr
    assert "standard output" in p.stderr and "write error" in p.stderr, p.stderr
