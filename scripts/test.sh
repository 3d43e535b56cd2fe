#!/usr/bin/env bash
# The README's test command: install what is missing, build, run every test;
# then the sanitizer build (preset asan) and its tests, and a one-minute fuzz
# run of each parser (scripts/fuzz.sh --smoke).
set -euo pipefail
cd "$(dirname "$0")/.."
scripts/build.sh
ctest --preset release -j "$(nproc)"
cmake --preset asan >/dev/null
cmake --build --preset asan -j "$(nproc)"
ctest --preset asan -j "$(nproc)"
scripts/fuzz.sh --smoke
