"""Every file a scene reads is known by its content (issue 31, stale results):

- no source under models/ opens a file except through read_input_file
  (models/robot/input_files.cpp), which records it: a reader of a new
  file-valued scene key is recorded with no other edit;
- `pumasim check` under strace opens no file outside the system's folders
  that its footer does not list with a hash, for every shipped scene and for
  a URDF robot with its side file;
- editing any of those files changes the footer, and `pumasim run`'s
  meta.json lists the same files with the same hashes.

    PUMASIM=build/release/bin/pumasim /usr/bin/python3 -m pytest -q tests/test_input_files.py
"""
import glob
import json
import os
import re
import shutil
import subprocess

import pytest

ROOT = os.path.normpath(os.path.join(os.path.dirname(os.path.abspath(__file__)), ".."))
PUMASIM = os.path.abspath(os.environ.get("PUMASIM", os.path.join(ROOT, "build", "release", "bin", "pumasim")))
SCENES = os.path.join(ROOT, "experiments", "scenes")
ROBOTS = os.path.join(ROOT, "models", "robots")
SYSTEM = ("/usr/", "/lib", "/etc/", "/proc/", "/sys/", "/dev/", "/bin/", "/sbin/", "/opt/", "/tmp/.X")

# A file is opened by something other than read_input_file: a stream, a C
# FILE, a POSIX descriptor, a mapping.
OPENS = re.compile(r"\b(std::)?(i|o)?fstream\b|\bfopen\s*\(|(?<![\w.:])open\s*\(|\bmmap\s*\(|"
                   r"\bparse_file\s*\(|\bparseURDFFile\s*\(|\bloadFile\s*\(|\bLoadFile\s*\(")


def test_no_model_source_opens_a_file_another_way():
    found = []
    for path in sorted(glob.glob(os.path.join(ROOT, "models", "**", "*.[ch]pp"), recursive=True)):
        if path.endswith(os.path.join("robot", "input_files.cpp")):
            continue
        with open(path) as f:
            for number, line in enumerate(f, 1):
                code = line.split("//", 1)[0]
                if OPENS.search(code):
                    found.append(f"{os.path.relpath(path, ROOT)}:{number}: {line.strip()}")
    assert not found, "read files through read_input_file (models/robot/input_files.hpp):\n" + "\n".join(found)


def footer(text):
    """{path: hash} of the `# input file:` lines."""
    files = {}
    for line in text.splitlines():
        m = re.match(r"# input file: (.*) \(fnv1a64 ([0-9a-f]{16}), (\d+) bytes\)$", line)
        if m:
            files[m.group(1)] = m.group(2)
    return files


def check(scene, *sets, cwd=ROOT):
    cmd = [PUMASIM, "check", str(scene)]
    for s in sets:
        cmd += ["--set", s]
    p = subprocess.run(cmd, capture_output=True, text=True, cwd=cwd)
    assert p.returncode == 0, p.stderr
    return p.stdout


def opened_user_files(cmd, cwd):
    """The regular files a command opened successfully (strace -f), outside
    the system's folders and other than the program itself."""
    log = os.path.join(cwd, "strace.log")
    # LeakSanitizer cannot run under ptrace (the sanitizer build's binary):
    # leaks are checked by every other run of it, not by the traced ones.
    env = dict(os.environ, ASAN_OPTIONS=(os.environ.get("ASAN_OPTIONS", "") + ":detect_leaks=0").lstrip(":"))
    p = subprocess.run(["strace", "-f", "-qq", "-e", "trace=open,openat,openat2,creat", "-o", log] + cmd,
                       capture_output=True, text=True, cwd=cwd, env=env)
    assert p.returncode == 0, p.stderr
    opened = set()
    with open(log) as f:
        for line in f:
            m = re.search(r'open(?:at2?)?\((?:AT_FDCWD|\d+)?,? ?"([^"]*)".*\) = \d+$', line)
            if not m:
                continue
            path = os.path.normpath(os.path.join(cwd, m.group(1)))
            if path.startswith(SYSTEM) or not os.path.isfile(path) or path == log:
                continue
            if os.path.realpath(path) == os.path.realpath(cmd[0]):
                continue
            opened.add(path)
    os.remove(log)
    return opened


def urdf_scene(tmp_path):
    for f in ("puma560.urdf", "puma560.urdf.toml"):
        shutil.copy(os.path.join(ROBOTS, f), tmp_path / f)
    scene = tmp_path / "passive_arm.toml"
    text = open(os.path.join(SCENES, "passive_arm.toml")).read()
    scene.write_text(text.replace('robot = "puma560"', f'robot = "{tmp_path / "puma560.urdf"}"'))
    return scene


@pytest.mark.skipif(shutil.which("strace") is None, reason="strace is not installed (scripts/install-deps.sh)")
@pytest.mark.parametrize("scene", sorted(os.path.basename(p) for p in glob.glob(os.path.join(SCENES, "*.toml"))))
def test_every_file_check_opens_is_in_its_footer(tmp_path, scene):
    path = os.path.join(SCENES, scene)
    opened = opened_user_files([PUMASIM, "check", path], str(tmp_path))
    listed = footer(check(path))
    assert opened, "strace saw no file opened: the test would prove nothing"
    assert opened <= set(listed), f"opened but not hashed: {sorted(opened - set(listed))}"


@pytest.mark.skipif(shutil.which("strace") is None, reason="strace is not installed (scripts/install-deps.sh)")
def test_a_urdf_robot_and_its_side_file_are_opened_and_hashed(tmp_path):
    scene = urdf_scene(tmp_path)
    opened = opened_user_files([PUMASIM, "check", str(scene)], str(tmp_path))
    listed = set(footer(check(scene)))
    expected = {str(scene), str(tmp_path / "puma560.urdf"), str(tmp_path / "puma560.urdf.toml")}
    assert expected <= opened
    assert opened <= listed, f"opened but not hashed: {sorted(opened - listed)}"


@pytest.mark.skipif(shutil.which("strace") is None, reason="strace is not installed (scripts/install-deps.sh)")
def test_every_file_a_run_reads_is_in_its_meta(tmp_path):
    """`pumasim run`, not only `check`: every user file it opens (but the run
    folder it writes) is among meta.json's input files."""
    scene = urdf_scene(tmp_path)
    out = tmp_path / "run"
    opened = opened_user_files([PUMASIM, "run", str(scene), "--t-end", "0.01", "--out", str(out), "--quiet"],
                               str(tmp_path))
    meta = json.load(open(out / "meta.json"))
    listed = {f["path"] for f in meta["input_files"]}
    opened = {p for p in opened if not p.startswith(str(out)) and os.path.basename(os.path.dirname(p)) != "run"}
    assert str(tmp_path / "puma560.urdf.toml") in opened
    assert opened <= listed, f"opened but not hashed: {sorted(opened - listed)}"


def fnv1a64(data):
    # FNV-1a 64 (offset basis 0xcbf29ce484222325, prime 0x100000001b3), as
    # published by its authors; computed here independently of the program.
    h = 0xcbf29ce484222325
    for b in data:
        h = ((h ^ b) * 0x100000001b3) & 0xFFFFFFFFFFFFFFFF
    return f"{h:016x}"


@pytest.mark.parametrize("name,csv", [("joint_space_csv.toml", "joint_space_csv.csv"),
                                      ("open_loop_voltage.toml", "open_loop_voltage.csv")])
def test_the_footer_hashes_each_csv_by_content_and_follows_an_edit(tmp_path, name, csv):
    for f in (name, csv):
        shutil.copy(os.path.join(SCENES, f), tmp_path / f)
    before = footer(check(tmp_path / name))
    data = (tmp_path / csv).read_bytes()
    assert before[str(tmp_path / csv)] == fnv1a64(data)
    # One digit of a value changed: the same size, another hash.
    i = data.index(b".", data.index(b"\n", data.index(b"\n") + 1)) + 1
    edited = data[:i] + bytes([ord("0") + (data[i] - ord("0") + 1) % 10]) + data[i + 1:]
    (tmp_path / csv).write_bytes(edited)
    after = footer(check(tmp_path / name))
    assert after[str(tmp_path / csv)] == fnv1a64(edited) != before[str(tmp_path / csv)]
    assert after[str(tmp_path / name)] == before[str(tmp_path / name)]


def test_run_meta_lists_the_same_files_as_the_footer(tmp_path):
    scene = urdf_scene(tmp_path)
    listed = footer(check(scene))
    out = tmp_path / "run"
    p = subprocess.run([PUMASIM, "run", str(scene), "--t-end", "0.01", "--out", str(out), "--quiet"],
                       capture_output=True, text=True, cwd=ROOT)
    assert p.returncode == 0, p.stderr
    meta = json.load(open(out / "meta.json"))
    assert {f["path"]: f["fnv1a64"] for f in meta["input_files"]} == listed
    resolved = (out / "scene.resolved.toml").read_text()
    assert footer(resolved) == listed
    for path, h in listed.items():
        assert fnv1a64(open(path, "rb").read()) == h, path
