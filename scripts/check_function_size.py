#!/usr/bin/python3
"""Fails (exit 1) when a Python or C++ function is longer than a limit (issues 14, 33).

Python: every def (functions, methods, nested functions; async too) in the
repository's *.py files counts, from its first line (decorators included) to
its last. C++ (--language cpp): every function body at namespace or class
scope in *.cpp, *.hpp and *.h files, from the first line of its head to its
closing brace, found lexically (scripts/cpp_functions.py: lambdas inside a
body are part of it). Files under build/ (and build-*/), .git/, __pycache__/
and any folder named generated/ (the SymPy-generated kernels) are skipped.
Prints each function over the limit as path:line name (lines), longest first.

  /usr/bin/python3 scripts/check_function_size.py [--language python|cpp] [--limit N] [PATH ...]

The paths (files or folders) default to the repository's root; the limit to
80 lines in either language.
"""
import argparse
import ast
import os
import sys

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import cpp_functions  # noqa: E402

ROOT = os.path.normpath(os.path.join(os.path.dirname(os.path.abspath(__file__)), ".."))
SKIP_DIRS = {".git", "build", "generated", "__pycache__"}


def source_files(paths, suffixes):
    """The files with one of `suffixes` under paths (files or folders), sorted, skipping SKIP_DIRS."""
    found = []
    for path in paths:
        if os.path.isfile(path):
            found.append(path)
            continue
        for folder, dirs, files in os.walk(path):
            dirs[:] = [d for d in dirs if d not in SKIP_DIRS and not d.startswith("build-")]
            found += [os.path.join(folder, f) for f in files if f.endswith(suffixes)]
    return sorted(found)


def cpp_function_lengths(path):
    """(line, name, length in lines) of every C++ function body in the file at path."""
    with open(path, encoding="utf-8") as f:
        return cpp_functions.functions(f.read())


def function_lengths(path):
    """(line, name, length in lines) of every def in the file at path."""
    with open(path, encoding="utf-8") as f:
        tree = ast.parse(f.read(), filename=path)
    out = []
    for node in ast.walk(tree):
        if isinstance(node, (ast.FunctionDef, ast.AsyncFunctionDef)):
            first = min([node.lineno] + [d.lineno for d in node.decorator_list])
            out.append((node.lineno, node.name, node.end_lineno - first + 1))
    return out


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--language", choices=["python", "cpp"], default="python")
    ap.add_argument("--limit", type=int, default=80, help="longest allowed function, in lines")
    ap.add_argument("paths", nargs="*", default=[ROOT], help="files or folders (default: the repository)")
    args = ap.parse_args()
    cpp = args.language == "cpp"
    files = source_files(args.paths, (".cpp", ".hpp", ".h") if cpp else (".py",))
    lengths = cpp_function_lengths if cpp else function_lengths
    too_long = []
    for path in files:
        for line, name, length in lengths(path):
            if length > args.limit:
                too_long.append((length, os.path.relpath(path, ROOT), line, name))
    for length, path, line, name in sorted(too_long, key=lambda t: (-t[0], t[1], t[2])):
        print(f"{path}:{line} {name} ({length} lines)")
    if too_long:
        print(f"check_function_size: {len(too_long)} function(s) over {args.limit} lines", file=sys.stderr)
        return 1
    print(f"check_function_size: no {args.language} function over {args.limit} lines in {len(files)} files")
    return 0


if __name__ == "__main__":
    sys.exit(main())
