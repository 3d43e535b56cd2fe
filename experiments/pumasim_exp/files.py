"""The file primitives of the experiments package: atomic writes (a
temporary beside the target, then a rename), JSON, locks (fcntl.flock),
output sets (files that belong together and their summary, written so that a
killed writer never leaves a mismatch undetected) and a private copy of the
pumasim binary. The io module re-exports them: scripts import io alone."""
import fcntl
import hashlib
import json
import os
import shutil
import socket
import subprocess
import time


# ---------------------------------------------------------------- atomic writes

def write_text_atomic(path, text):
    """Writes text to path through path + '.tmp' and a rename (the temporary
    removed again if it cannot be written: a full disk)."""
    tmp = path + ".tmp"
    try:
        with open(tmp, "w") as f:
            f.write(text)
    except OSError:
        if os.path.exists(tmp):
            os.remove(tmp)
        raise
    os.replace(tmp, path)


def write_json_atomic(path, doc, indent=None, newline=False):
    """json.dump(doc, indent=indent) to path, atomically; newline: end with '\\n'."""
    write_text_atomic(path, json.dumps(doc, indent=indent) + ("\n" if newline else ""))


def read_json(path):
    with open(path) as f:
        return json.load(f)


# ---------------------------------------------------------------- locks and output sets

class FileLock:
    """An exclusive lock (fcntl.flock) on the file at path, created empty if
    absent and never removed (removing a lock file while another process
    waits on it would let a third one lock a new file). The lock belongs to
    the open file: it ends when every process holding it (a child started
    with pass_fds=(lock.fd,) holds it too) has released it or exited, so a
    killed process leaves at most the empty file, which locks nothing."""

    def __init__(self, path):
        self.path, self.fd = path, None

    def acquire(self, wait=True):
        """Takes the lock (wait: until it is free); False if another process
        holds it and wait is False. OSError if the file cannot be created."""
        try:
            fd = os.open(self.path, os.O_RDWR | os.O_CREAT, 0o644)
        except PermissionError:  # another user's lock file: flock needs no write access
            fd = os.open(self.path, os.O_RDONLY)
        try:
            fcntl.flock(fd, fcntl.LOCK_EX | (0 if wait else fcntl.LOCK_NB))
        except BlockingIOError:
            os.close(fd)
            return False
        self.fd = fd
        return True

    def release(self):
        if self.fd is not None:
            os.close(self.fd)  # the last descriptor of the open file: the lock ends
            self.fd = None


def sha256_file(path):
    """The SHA-256 (hex) of the file at path."""
    h = hashlib.sha256()
    with open(path, "rb") as f:
        for block in iter(lambda: f.read(1 << 20), b""):
            h.update(block)
    return h.hexdigest()


def _temporary_name(folder, name):
    """folder/.NAME.HOST.PID.tmp: this process's temporary for folder/name."""
    return os.path.join(folder, f".{name}.{socket.gethostname()}.{os.getpid()}.tmp")


def remove_dead_temporaries(folder, names):
    """Removes this host's temporaries (_temporary_name) of the files `names`
    in folder whose process no longer runs: what a killed writer left."""
    host = socket.gethostname()
    try:
        entries = os.listdir(folder)
    except FileNotFoundError:
        return
    for e in entries:
        for n in names:
            head = f".{n}.{host}."
            pid = e[len(head):-len(".tmp")] if e.startswith(head) and e.endswith(".tmp") else ""
            if pid.isdigit() and int(pid) != os.getpid() and not _alive(int(pid)):
                os.remove(os.path.join(folder, e))


def _alive(pid):
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    except PermissionError:  # another user's process
        return True
    return True


def write_output_set(folder, files, summary_name, summary):
    """Writes a set of files that belong together (a sweep's table and plots)
    and their summary into folder: `files` {name: a function writing the file
    at the path it is given}, `summary` a JSON document. Every file is written
    to a temporary of this process first; then the summary gets 'outputs':
    {name: SHA-256} of each; then the files are renamed into place, the
    summary last. A process killed at any instant leaves the earlier set, or a
    summary whose hashes do not match its files (check_outputs refuses it),
    and temporaries that remove_dead_temporaries removes. OSError (its
    filename: the file in folder) if a file cannot be written; the
    temporaries are removed then and nothing in folder changed."""
    tmps = {}
    try:
        for name, write in files.items():
            tmps[name] = _temporary_name(folder, name)
            _as_target(write, tmps[name], os.path.join(folder, name))
        summary = {**summary, "outputs": {n: sha256_file(t) for n, t in tmps.items()}}
        tmps[summary_name] = _temporary_name(folder, summary_name)
        _as_target(lambda p: _write_text(p, json.dumps(summary, indent=1)), tmps[summary_name],
                   os.path.join(folder, summary_name))
        for name in files:
            os.replace(tmps[name], os.path.join(folder, name))
        os.replace(tmps[summary_name], os.path.join(folder, summary_name))
    except BaseException:
        for t in tmps.values():
            if os.path.exists(t):
                os.remove(t)
        raise
    return summary


def _write_text(path, text):
    with open(path, "w") as f:
        f.write(text)


def _as_target(write, tmp, target):
    """write(tmp); an OSError it raises names target instead of tmp."""
    try:
        write(tmp)
    except OSError as e:
        raise OSError(e.errno, e.strerror, target) from None


class OutputsMismatch(Exception):
    """A summary and the files it describes were not written by one merge."""


def check_outputs(folder, summary):
    """Raises OutputsMismatch unless every file the summary's 'outputs' lists
    (write_output_set) is in folder with that SHA-256."""
    if "outputs" not in summary:
        raise OutputsMismatch("the summary lists no hashes of its files (written before they were checked)")
    for name, digest in summary["outputs"].items():
        path = os.path.join(folder, name)
        if not os.path.exists(path):
            raise OutputsMismatch(f"{path} is missing")
        if sha256_file(path) != digest:
            raise OutputsMismatch(f"{path} is not the file the summary describes (another merge wrote it, "
                                  "or a merge was interrupted)")


def private_copy(pumasim, work):
    """Copies the pumasim binary to work/pumasim (retrying for up to two
    minutes while it is missing or being relinked, until the copy runs), so
    that every run of an experiment uses one program even if the build
    changes meanwhile; returns the copy's path."""
    os.makedirs(work, exist_ok=True)
    dest = os.path.join(work, "pumasim")
    for attempt in range(60):
        try:
            shutil.copy2(pumasim, dest + ".tmp")
            subprocess.run([dest + ".tmp", "integrators"], capture_output=True, check=True)
            break
        except (OSError, subprocess.CalledProcessError):
            if attempt == 59:
                raise
            time.sleep(2)
    os.replace(dest + ".tmp", dest)
    return dest


# ---------------------------------------------------------------- a program's output folder

class ProgramFolder:
    """The output folder of a program that writes a fixed set of files (experiments/identify.py,
    experiments/tune_piv.py): `out` is a new folder, or with force one the program wrote (its marker
    file there). refusal() says why not, before any work. Within `with ProgramFolder(...) as tmp`, the
    files are written into a temporary sibling folder; on leaving without an error it becomes `out`
    (renamed whole, with the umask's mode rather than mkdtemp's 0700) or, into a folder the program
    wrote, its files replace the earlier ones and those of `files` it did not write this time are
    removed (stale against the new ones); another file there is left alone. On an error the
    temporary folder is removed and `out` is untouched."""

    def __init__(self, out, files, marker, program):
        self.out, self.files, self.marker, self.program = os.path.abspath(out), tuple(files), marker, program
        self.tmp = None

    def refusal(self, force):
        if not os.path.exists(self.out):
            return None
        if not force:
            return f"{self.out}: exists; give a new folder, or --force to replace a folder {self.program} wrote"
        if not os.path.isfile(os.path.join(self.out, self.marker)):
            return f"{self.out}: not a folder {self.program} wrote (no {self.marker}): refused, even with --force"
        return None

    def __enter__(self):
        import tempfile

        parent = os.path.dirname(self.out)
        os.makedirs(parent, exist_ok=True)
        self.tmp = tempfile.mkdtemp(prefix=f".{self.program}-", dir=parent)
        return self.tmp

    def __exit__(self, kind, value, traceback):
        try:
            if kind is None:
                self._publish()
        finally:
            if os.path.isdir(self.tmp):
                shutil.rmtree(self.tmp)
        return False

    def _publish(self):
        for name in os.listdir(self.tmp):
            if name not in self.files:
                os.remove(os.path.join(self.tmp, name))
        umask = os.umask(0)
        os.umask(umask)
        os.chmod(self.tmp, 0o777 & ~umask)
        if not os.path.exists(self.out):
            os.rename(self.tmp, self.out)
            return
        for name in self.files:
            new, old = os.path.join(self.tmp, name), os.path.join(self.out, name)
            if os.path.exists(new):
                os.replace(new, old)
            elif os.path.exists(old):
                os.remove(old)
        os.rmdir(self.tmp)


def import_pumasim(folder, default):
    """The pumasim module from `folder` (default: `default`, the release build's python/)."""
    import sys

    sys.path.insert(0, folder or default)
    import pumasim

    return pumasim
