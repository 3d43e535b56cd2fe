#!/usr/bin/python3
"""Test comments cite files that exist in the repository.

    /usr/bin/python3 scripts/check_citations.py [FILE...]

Reads the comments of tests/*.cpp, tests/*.hpp and tests/*.py (or the FILEs
given): C++ // and /* */ comments (string and character literals skipped),
Python # comments and triple-quoted strings. In them, a repository path is a
token such as `models/robots/puma560.toml` or `../shared/reference/x.md`:
one whose first component is a top-level entry of the repository (models,
tests, scripts, ...), '.' or '..', or an absolute path to a file of a kind
the project cites (.md .toml .cpp .hpp .h .py .sh .csv .tsv .json .txt).
Each must name a file or folder inside the repository, relative to its root
or to the citing file's folder; a cited reference that lives elsewhere
(another checkout, a shared folder) is copied into the repository with its
source, and the comment cites the copy (tests/reference/). A bare file name
with a source extension (.cpp .hpp .h .py .sh), such as `odeint.cpp`, must be
the name of a file in the repository. Build outputs (build/, runs/) are not
checked, and neither are URLs (a first component with a dot, or '://').

Prints every bad citation as file:line: path: why, and exits 1 if there is
one; 0 otherwise.
"""
import glob
import io
import os
import re
import subprocess
import sys
import tokenize

ROOT = os.path.normpath(os.path.join(os.path.dirname(os.path.abspath(__file__)), ".."))
CITED_EXT = (".md", ".toml", ".cpp", ".hpp", ".h", ".py", ".sh", ".csv", ".tsv", ".json", ".txt")
SOURCE_EXT = (".cpp", ".hpp", ".h", ".py", ".sh")
GENERATED = ("build", "runs")  # ignored by git: written by the build and by `pumasim run`
SYSTEM = ("/tmp/", "/dev/", "/usr/", "/proc/", "/etc/")
TOKEN = re.compile(r"[A-Za-z0-9_.~+\-/:]*[A-Za-z0-9_/]")


def repo_files():
    """Every file git tracks (or, outside a git checkout, every file under ROOT), relative to ROOT."""
    try:
        out = subprocess.run(["git", "ls-files", "-z", "--cached", "--others", "--exclude-standard"],
                             cwd=ROOT, capture_output=True, check=True).stdout
        return [p for p in out.decode().split("\0") if p]
    except (OSError, subprocess.CalledProcessError):
        return [os.path.relpath(os.path.join(d, f), ROOT) for d, _, fs in os.walk(ROOT) for f in fs]


def cpp_comments(text):
    """(line, comment text) of every // and /* */ comment, literals skipped."""
    out, i, line, n = [], 0, 1, len(text)
    while i < n:
        c = text[i]
        if c == "\n":
            line += 1
            i += 1
        elif text.startswith("//", i):
            j = text.find("\n", i)
            j = n if j < 0 else j
            out.append((line, text[i + 2:j]))
            i = j
        elif text.startswith("/*", i):
            j = text.find("*/", i + 2)
            j = n if j < 0 else j
            for k, part in enumerate(text[i + 2:j].split("\n")):
                out.append((line + k, part))
            line += text.count("\n", i, j)
            i = j + 2
        elif c == "R" and text.startswith('R"', i) and (i == 0 or not (text[i - 1].isalnum() or text[i - 1] == "_")):
            m = re.match(r'R"([^(\s]*)\(', text[i:])
            if not m:
                i += 1
                continue
            end = text.find(")" + m.group(1) + '"', i)
            end = n if end < 0 else end + len(m.group(1)) + 2
            line += text.count("\n", i, end)
            i = end
        elif c in "\"'":
            j = i + 1
            while j < n and text[j] != c and text[j] != "\n":
                j += 2 if text[j] == "\\" else 1
            i = j + 1
        else:
            i += 1
    return out


def py_comments(text):
    """(line, text) of every # comment and every line of a triple-quoted string."""
    out = []
    for tok in tokenize.generate_tokens(io.StringIO(text).readline):
        if tok.type == tokenize.COMMENT:
            out.append((tok.start[0], tok.string[1:]))
        elif tok.type == tokenize.STRING and re.match(r"^[rRbBuUfF]*('''|\"\"\")", tok.string):
            for k, part in enumerate(tok.string.split("\n")):
                out.append((tok.start[0] + k, part))
    return out


def check_token(tok, citing_dir, top, basenames):
    """'' if tok is no repository path or an existing one, else why not."""
    tok = re.sub(r"(:\d+)+$", "", tok.rstrip(".:"))  # file:line cites the file
    if "://" in tok or tok.startswith("//"):
        return ""
    if "/" not in tok:
        if tok.endswith(SOURCE_EXT) and re.fullmatch(r"[A-Za-z0-9_\-.]+", tok) and not tok.startswith("."):
            return "" if tok in basenames else "no file of that name in the repository"
        return ""
    first = tok.split("/")[0]
    if tok.startswith("/"):
        if not tok.endswith(CITED_EXT) or tok.startswith(SYSTEM):
            return ""
        inside = os.path.commonpath([ROOT, os.path.normpath(tok)]) == ROOT
        return "" if inside and os.path.exists(tok) else "an absolute path outside the repository"
    if first in GENERATED:
        return ""
    if first not in top and first not in (".", ".."):
        return ""  # not a repository path: a URL (github.com/...), a unit (N m/A), a ratio (h/dt)
    for base in (ROOT, citing_dir):
        p = os.path.normpath(os.path.join(base, tok))
        if os.path.commonpath([ROOT, p]) == ROOT and os.path.exists(p):
            return ""
    outside = os.path.commonpath([ROOT, os.path.normpath(os.path.join(ROOT, tok))]) != ROOT
    return ("outside the repository: copy what the test uses into it (tests/reference/) with its source, "
            "and cite the copy") if outside else "no such file or folder in the repository"


def check_file(path, top, basenames):
    with open(path, encoding="utf-8") as f:
        text = f.read()
    comments = py_comments(text) if path.endswith(".py") else cpp_comments(text)
    bad = []
    for line, comment in comments:
        for tok in TOKEN.findall(comment):
            why = check_token(tok, os.path.dirname(os.path.abspath(path)), top, basenames)
            if why:
                bad.append(f"{os.path.relpath(path, ROOT)}:{line}: {tok}: {why}")
    return bad


def main(argv):
    files = argv or sorted(glob.glob(os.path.join(ROOT, "tests", "*.cpp")) +
                           glob.glob(os.path.join(ROOT, "tests", "*.hpp")) +
                           glob.glob(os.path.join(ROOT, "tests", "*.py")))
    tracked = repo_files()
    top = {p.split("/")[0] for p in tracked}
    basenames = {os.path.basename(p) for p in tracked}
    bad = [b for f in files for b in check_file(f, top, basenames)]
    for b in bad:
        print(b)
    print(f"check_citations: {len(files)} files, {len(bad)} bad citations", file=sys.stderr)
    return 1 if bad else 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
