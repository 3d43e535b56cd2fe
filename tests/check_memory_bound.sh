#!/usr/bin/env bash
# The memory a run may use does not grow with its output (issue 32): pumasim
# run streams trajectory.csv to its folder in chunks (run_recorder.hpp), so
# that the six-joint hybrid scene over 1 s at a 1e-5 s output interval --
# 100001 rows of 55 columns, a file larger than the whole address space
# allowed -- runs under `ulimit -v` at the bound docs/user-guide/limits.md states (64 MiB).
# Sizes derived from the scene are refused before anything is allocated, under
# the same bound: rows x columns above 1e8, and a reference whose duration
# (path length / max_speed) would need 1e9 table pieces.
#
#   tests/check_memory_bound.sh PUMASIM
set -euo pipefail
pumasim=$1
root=$(cd "$(dirname "$0")/.." && pwd)
scenes=$root/experiments/scenes
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
bound_kib=65536  # 64 MiB: docs/user-guide/limits.md

status=0
(ulimit -v $bound_kib
 "$pumasim" run "$scenes/paper_slow_6dof_hybrid.toml" --t-end 1 --set scene.output_interval=1e-5 \
   --out "$work/run" --quiet >"$work/stats.json" 2>"$work/err") || status=$?
if [ $status -ne 0 ]; then
  echo "check_memory_bound: the run under ulimit -v $bound_kib KiB exited $status: $(cat "$work/err")" >&2
  exit 1
fi
rows=$(($(wc -l <"$work/run/trajectory.csv") - 1))
bytes=$(stat -c %s "$work/run/trajectory.csv")
[ "$rows" -eq 100001 ] || { echo "check_memory_bound: $rows rows, expected 100001 (1 s / 1e-5 s + 1)" >&2; exit 1; }
if [ "$bytes" -le $((bound_kib * 1024)) ]; then
  echo "check_memory_bound: trajectory.csv is $bytes bytes, not above the bound: the check proves nothing" >&2
  exit 1
fi
echo "check_memory_bound: $rows rows, $bytes bytes of trajectory.csv written under ulimit -v $bound_kib KiB"

# Refused before allocating, with exit status 2 and the key named.
refused() {
  local why=$1; shift
  status=0
  (ulimit -v $bound_kib; "$pumasim" "$@" >/dev/null 2>"$work/err") || status=$?
  if [ $status -ne 2 ] || ! grep -q "$why" "$work/err"; then
    echo "check_memory_bound: '$*' exited $status, expected 2 naming '$why': $(cat "$work/err")" >&2
    exit 1
  fi
  echo "check_memory_bound: refused under the bound: $(head -c 160 "$work/err")"
}
refused "numbers in trajectory.csv" check "$scenes/paper_slow_6dof_hybrid.toml" \
  --set scene.duration=5 --set scene.output_interval=1e-6
refused "reference.max_speed" check "$scenes/paper_slow.toml" --set reference.max_speed=1e-9
