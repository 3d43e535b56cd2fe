#!/usr/bin/env bash
# The C++ lines changed since .clang-format came in follow it (issue 33, part 6).
#
#   scripts/check_format.sh [BASE]
#
# Checks, with git clang-format (Debian's clang-format 14), every line of a
# .cpp, .hpp or .h file that differs between BASE and the working tree; BASE
# defaults to the commit that added .clang-format, so that code written before
# the style is formatted when it is next touched, not all at once. Exit 0: they
# follow it; 1: they do not (the diff is printed, with the command that
# applies it); 77: nothing to check against (no git history holding BASE, or
# no clang-format), said on stderr: the CTest Format.ChangedLinesFollowClangFormat
# then shows as skipped, not as passed.
set -euo pipefail
cd "$(dirname "$0")/.."
if ! command -v git-clang-format >/dev/null || ! command -v clang-format >/dev/null; then
  echo "check_format: git-clang-format not found (Debian package clang-format; scripts/install-deps.sh)" >&2
  exit 77
fi
if ! git rev-parse --is-inside-work-tree >/dev/null 2>&1; then
  echo "check_format: not a git checkout; the changed lines are unknown" >&2
  exit 77
fi
base="${1:-$(git log --diff-filter=A --format=%H -- .clang-format | tail -n 1)}"
if [ -z "$base" ]; then
  # .clang-format not committed yet: the lines changed since HEAD.
  base=HEAD
fi
if ! git cat-file -e "$base^{commit}" 2>/dev/null; then
  echo "check_format: $base is not in this clone's history (a shallow clone?)" >&2
  exit 77
fi
diff="$(git clang-format --diff --extensions cpp,hpp,h "$base" -- 2>&1)"
case "$diff" in
  "" | "no modified files to format" | "clang-format did not modify any files")
    echo "check_format: the C++ lines changed since ${base:0:12} follow .clang-format"
    exit 0 ;;
esac
echo "$diff"
echo "check_format: the lines above do not follow .clang-format; apply with: git clang-format --extensions cpp,hpp,h $base (the extensions: clang-format would also rewrite JSON)" >&2
exit 1
