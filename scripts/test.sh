#!/usr/bin/env bash
# The README's test command: install what is missing, build, run every test;
# then the proof that an integrator or a back-end is one file plus one row
# (scripts/check_extension.py, in a scratch copy of the tree); then the
# sanitizer build (preset asan) and its tests, a 10-second fuzz run of each
# parser (scripts/fuzz.sh --smoke), and the threading tests under
# ThreadSanitizer (preset tsan, which builds them alone). Each phase's wall
# time goes to stderr.
set -euo pipefail
cd "$(dirname "$0")/.."
phase() {
  local start=$SECONDS
  "$@"
  echo "test.sh: $* took $((SECONDS - start)) s" >&2
}
phase scripts/build.sh
phase ctest --preset release -j "$(nproc)"
phase /usr/bin/python3 scripts/check_extension.py --jobs "$(nproc)"
phase scripts/configure.sh asan >/dev/null
phase cmake --build --preset asan -j "$(nproc)"
phase ctest --preset asan -j "$(nproc)"
phase scripts/fuzz.sh --smoke
phase scripts/configure.sh tsan >/dev/null
phase cmake --build --preset tsan -j "$(nproc)"
phase ctest --preset tsan -j "$(nproc)"
