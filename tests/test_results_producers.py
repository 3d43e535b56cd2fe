"""Every file under results/ is written by a stage of scripts/results.sh
(issue 33): a committed result that no stage regenerates goes stale unseen.
A static check, no simulation.

Each stage's function in scripts/results.sh has `# writes:` lines right
above it naming what it writes: paths relative to the root, a path ending in
'/' for a folder and everything in it, shell-style wildcards ('*'), and
{folder} and {name} for every sweep file's [sweep] folder (default: its
name) and name (experiments/sweeps/*.toml). Checked here:
  - the stages the script accepts (its `all` and `named_only` lists), its
    stage_ functions and the stages with `# writes:` lines are the same set;
  - every script a stage runs (experiments/, scripts/ or tests/ .py and .sh)
    exists, and every stage runs at least one program;
  - every file under results/ (what git tracks there, and any new file not
    ignored) is matched by some stage's paths, but for HAND_WRITTEN;
  - every path a stage declares matches at least one file there (a stale
    declaration fails too).

    /usr/bin/python3 -m pytest -q tests/test_results_producers.py
"""
import fnmatch
import glob
import os
import re
import subprocess
import tomllib

ROOT = os.path.normpath(os.path.join(os.path.dirname(os.path.abspath(__file__)), ".."))
RESULTS_SH = os.path.join(ROOT, "scripts", "results.sh")
# Files under results/ that no program writes, each with its reason. Keep it
# empty where possible: a file here is a file no stage can regenerate.
HAND_WRITTEN = {
    "results/work_precision/README.md": "prose on how the work-precision sweeps were last run, by hand",
}
STAGE_FUNCTION = re.compile(r"^stage_([a-z]+)\(\)\s*\{")
WRITES = re.compile(r"^# writes: (.+)$")
SCRIPT = re.compile(r"(?<![\w/.])((?:experiments|scripts|tests)/[\w/.-]+\.(?:py|sh))\b")


def _text():
    with open(RESULTS_SH, encoding="utf-8") as f:
        return f.read()


def _array(text, name):
    """The words of the bash array `name=(...)` (which may span lines)."""
    m = re.search(rf"^{name}=\(([^)]*)\)", text, re.M)
    assert m, f"scripts/results.sh: no array {name}=(...)"
    return m.group(1).split()


def stages(text):
    """{stage: (its `# writes:` paths, its function's body)} of scripts/results.sh."""
    lines = text.splitlines()
    out = {}
    for k, line in enumerate(lines):
        m = STAGE_FUNCTION.match(line)
        if not m:
            continue
        writes, j = [], k - 1
        while j >= 0 and lines[j].startswith("#"):
            w = WRITES.match(lines[j])
            if w:
                writes = w.group(1).split() + writes
            j -= 1
        body, j = [line], k  # a one-line function ends on its line, any other at a line '}'
        while not (j == k and line.rstrip().endswith("}")) and lines[j].rstrip() != "}":
            j += 1
            body.append(lines[j])
        out[m.group(1)] = (writes, "\n".join(body))
    return out


def sweep_names():
    """[(folder, name)] of every experiments/sweeps/*.toml's [sweep] table."""
    out = []
    for path in sorted(glob.glob(os.path.join(ROOT, "experiments", "sweeps", "*.toml"))):
        with open(path, "rb") as f:
            sw = tomllib.load(f)["sweep"]
        out.append((sw.get("folder", sw["name"]), sw["name"]))
    return out


def expand(pattern):
    """The patterns a declared path stands for ({folder}, {name}: one per sweep file)."""
    if "{" not in pattern:
        return [pattern]
    return sorted({pattern.format(folder=folder, name=name) for folder, name in sweep_names()})


def matches(pattern, path):
    """True if the file `path` (relative to the root) is one that `pattern` declares."""
    if pattern.endswith("/"):
        return path.startswith(pattern)
    return fnmatch.fnmatchcase(path, pattern)


def results_files():
    """Every file under results/ that git tracks, and every new one it does not ignore."""
    p = subprocess.run(["git", "ls-files", "-z", "--cached", "--others", "--exclude-standard", "results"],
                       cwd=ROOT, capture_output=True)
    if p.returncode == 0:
        return sorted({f for f in p.stdout.decode().split("\0") if f and os.path.exists(os.path.join(ROOT, f))})
    return sorted(os.path.relpath(os.path.join(d, f), ROOT)
                  for d, _, fs in os.walk(os.path.join(ROOT, "results")) for f in fs)


def test_every_stage_has_a_function_and_declares_what_it_writes():
    text = _text()
    accepted = _array(text, "all") + _array(text, "named_only")
    found = stages(text)
    assert len(set(accepted)) == len(accepted), f"a stage listed twice: {accepted}"
    assert sorted(found) == sorted(accepted), \
        f"stages accepted {sorted(accepted)}, stage_ functions {sorted(found)}"
    undeclared = [s for s, (writes, _) in found.items() if not writes]
    assert not undeclared, f"stages without a '# writes:' line above their function: {undeclared}"


def test_every_stage_runs_programs_that_exist():
    for stage, (_, body) in stages(_text()).items():
        scripts = SCRIPT.findall(body)
        binaries = re.findall(r"\"\$PUMASIM_BIN/[\w-]+\"", body)
        assert scripts or binaries, f"stage {stage} runs no program: {body}"
        missing = [s for s in scripts if not os.path.isfile(os.path.join(ROOT, s))]
        assert not missing, f"stage {stage} runs {missing}, which do not exist"


def test_every_file_under_results_has_a_producer():
    declared = [(stage, p) for stage, (writes, _) in stages(_text()).items() for w in writes for p in expand(w)]
    files = results_files()
    assert files, "no files under results/"
    orphans = [f for f in files if f not in HAND_WRITTEN and not any(matches(p, f) for _, p in declared)]
    assert not orphans, ("files under results/ that no stage of scripts/results.sh writes (add the producer "
                         "to a stage and its path to that stage's '# writes:' line): " + ", ".join(orphans))
    gone = [h for h in HAND_WRITTEN if h not in files]
    assert not gone, f"HAND_WRITTEN names files that are not under results/: {gone}"


def test_every_declared_path_names_a_file_that_is_there():
    files = results_files()
    stale = []
    for stage, (writes, _) in stages(_text()).items():
        for w in writes:
            if not w.startswith("results/"):
                stale.append(f"{stage}: {w} (not under results/)")
            elif not any(matches(p, f) for p in expand(w) for f in files):
                stale.append(f"{stage}: {w}")
    assert not stale, "declared but no such file under results/: " + "; ".join(stale)
