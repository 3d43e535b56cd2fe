#!/usr/bin/env bash
# scripts/check_format.sh sees what it claims to: in a scratch git repository
# holding the project's .clang-format, a badly formatted line added after the
# commit that brought the style fails the check (exit 1), the same line
# formatted passes (0), and a badly formatted line that was there before the
# style came in is left alone (0: the check covers changed lines only).
set -euo pipefail
root="$(cd "$(dirname "$0")/.." && pwd)"
command -v git-clang-format >/dev/null || { echo "git-clang-format not found" >&2; exit 77; }
tmp="$(mktemp -d)"
trap 'rm -rf "$tmp"' EXIT
cd "$tmp"
git init -q .
git config user.email test@pumasim.invalid
git config user.name test
mkdir scripts
cp "$root/scripts/check_format.sh" scripts/
printf 'int   old_code( int  x ){return x;}\n' > old.cpp
git add . && git commit -qm "before the style"
cp "$root/.clang-format" .
git add .clang-format && git commit -qm "the style"
scripts/check_format.sh >/dev/null || { echo "FAIL: untouched old code was checked" >&2; exit 1; }
printf 'int   new_code( int  x ){return x;}\n' > new.cpp
git add new.cpp  # a new file counts once git knows it (as in a commit)
if scripts/check_format.sh >/dev/null 2>&1; then echo "FAIL: a badly formatted new line passed" >&2; exit 1; fi
printf 'int new_code(int x) { return x; }\n' > new.cpp
scripts/check_format.sh >/dev/null || { echo "FAIL: a formatted new line failed" >&2; exit 1; }
printf 'int   old_code( int  x ){return x + 1;}\n' > old.cpp
if scripts/check_format.sh >/dev/null 2>&1; then echo "FAIL: a badly formatted changed line passed" >&2; exit 1; fi
echo "check_format: old lines left alone, new and changed lines checked"
