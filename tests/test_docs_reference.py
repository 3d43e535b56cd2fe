#!/usr/bin/python3
"""The generated reference pages are current, and the docs' links resolve.

    /usr/bin/python3 tests/test_docs_reference.py PUMASIM      # both checks (CTest Docs.ReferenceIsCurrent)
    /usr/bin/python3 tests/test_docs_reference.py --links-only # the links alone (CTest Docs.LinksResolve)

Reference: scripts/gen_reference.py writes docs/reference/integrators.md,
docs/reference/backends.md and docs/reference/scene-keys.md from `PUMASIM
integrators --json`, `PUMASIM backends --json` and `PUMASIM keys --json`;
here it writes them into a temporary folder, and each must equal the
committed file byte for byte (else: run the generator, as the message says,
and commit what it writes).

Links: every relative link of README.md and of every .md under docs/
(`[text](target)`, `![alt](target)`, outside fenced code and inline code)
must name a file or folder of the tree, resolved against the page's folder;
a `#anchor` on a Markdown page must be one of that page's headings, by
GitHub's rule (lower case, punctuation dropped, spaces as hyphens, a repeated
heading numbered). URLs (with a scheme) and mail addresses are not checked.

Exit status 1 on any difference or broken link, each printed; 0 otherwise.
Standard library only.
"""
import difflib
import os
import re
import subprocess
import sys
import tempfile

ROOT = os.path.normpath(os.path.join(os.path.dirname(os.path.abspath(__file__)), ".."))
GENERATED = ("integrators.md", "backends.md", "scene-keys.md")
LINK_RE = re.compile(r"!?\[(?:[^\]\\]|\\.)*\]\(\s*<?([^)\s>]+)>?(?:\s+\"[^\"]*\")?\s*\)")
FENCE_RE = re.compile(r"^[ \t]*(```|~~~).*?^[ \t]*\1[^\n]*$", re.M | re.S)
CODE_RE = re.compile(r"(`+)(?:(?!\n\s*\n).)+?\1", re.S)
HEADING_RE = re.compile(r"^#{1,6}[ \t]+(.+?)[ \t]*#*[ \t]*$", re.M)


def reference_differences(pumasim):
    """Messages for each generated page that differs from what the generator writes now."""
    out = []
    with tempfile.TemporaryDirectory() as tmp:
        p = subprocess.run([sys.executable, os.path.join(ROOT, "scripts", "gen_reference.py"), pumasim,
                            "--out", tmp], capture_output=True, text=True)
        if p.returncode != 0:
            return [f"scripts/gen_reference.py failed (exit status {p.returncode}): {p.stderr.strip()}"]
        for name in GENERATED:
            committed = os.path.join(ROOT, "docs", "reference", name)
            with open(os.path.join(tmp, name), encoding="utf-8") as f:
                fresh = f.read()
            try:
                with open(committed, encoding="utf-8") as f:
                    old = f.read()
            except FileNotFoundError:
                out.append(f"docs/reference/{name}: missing")
                continue
            if old != fresh:
                diff = "".join(difflib.unified_diff(old.splitlines(True), fresh.splitlines(True),
                                                    f"docs/reference/{name} (committed)", "generated now", n=1))
                out.append(f"docs/reference/{name} is not what the registry prints now; run "
                           f"/usr/bin/python3 scripts/gen_reference.py {pumasim}\n{diff}")
    return out


def pages():
    """README.md and every .md under docs/, relative to the root."""
    found = ["README.md"]
    for dirpath, _, names in sorted(os.walk(os.path.join(ROOT, "docs"))):
        found += [os.path.relpath(os.path.join(dirpath, n), ROOT) for n in sorted(names) if n.endswith(".md")]
    return found


def blank(m):
    return "".join("\n" if c == "\n" else " " for c in m.group(0))


def slug(heading):
    """GitHub's anchor for a heading's text."""
    text = re.sub(r"`([^`]*)`", r"\1", heading)
    text = re.sub(r"\[([^\]]*)\]\([^)]*\)", r"\1", text)
    return re.sub(r"[^\w\- ]", "", text.strip().lower()).replace(" ", "-")


def anchors(path):
    """The anchors of a Markdown page's headings (repeats numbered -1, -2, ...)."""
    with open(path, encoding="utf-8") as f:
        text = FENCE_RE.sub(blank, f.read())
    seen, out = {}, set()
    for m in HEADING_RE.finditer(text):
        s = slug(m.group(1))
        n = seen.get(s, 0)
        out.add(s if n == 0 else f"{s}-{n}")
        seen[s] = n + 1
    return out


def link_problem(page, target):
    """Why a link target of page does not resolve ('' if it does)."""
    if re.match(r"^[a-zA-Z][a-zA-Z0-9+.-]*:", target) or target.startswith("//"):
        return ""  # a URL or mailto:
    path, _, anchor = target.partition("#")
    full = os.path.normpath(os.path.join(ROOT, os.path.dirname(page), path)) if path else os.path.join(ROOT, page)
    if not full.startswith(ROOT + os.sep) and full != ROOT:
        return "points outside the repository"
    if not os.path.exists(full):
        return "no such file or folder"
    if anchor and full.endswith(".md") and anchor not in anchors(full):
        return f"no heading with the anchor #{anchor} in {os.path.relpath(full, ROOT)}"
    return ""


def broken_links():
    """page:line: target: why, for every link that does not resolve."""
    out = []
    for page in pages():
        with open(os.path.join(ROOT, page), encoding="utf-8") as f:
            text = f.read()
        prose = CODE_RE.sub(blank, FENCE_RE.sub(blank, text))
        for m in LINK_RE.finditer(prose):
            why = link_problem(page, m.group(1))
            if why:
                out.append(f"{page}:{prose.count(chr(10), 0, m.start()) + 1}: {m.group(1)}: {why}")
    return out


def main(argv):
    if len(argv) != 2:
        print(__doc__.strip().splitlines()[2], file=sys.stderr)
        return 2
    problems = [] if argv[1] == "--links-only" else reference_differences(argv[1])
    problems += broken_links()
    for p in problems:
        print(p)
    n = len(pages())
    print(f"test_docs_reference: {n} pages, {len(problems)} problems")
    return 1 if problems else 0


if __name__ == "__main__":
    sys.exit(main(sys.argv))
