#!/usr/bin/env bash
# Runs the dynamics benchmark and writes DIR/dynamics_backends.md and
# DIR/dynamics_cost_vs_n.png from its JSON (DIR/bench/dynamics.json; Debian's
# python3, with matplotlib).
#
#   experiments/bench_dynamics.sh [--out DIR] [--quick]
#
# DIR is results/ by default (scripts/results.sh); the README's main command
# (scripts/run.sh) writes runs/bench/, which git ignores. --quick: two
# repetitions of 10 ms per benchmark, for a smoke test of the pipeline (its
# figures are not for reading).
set -euo pipefail
cd "$(dirname "$0")/.."
out=results
reps=(--benchmark_repetitions=5 --benchmark_report_aggregates_only=true --benchmark_min_time=0.1)
bin=${PUMASIM_BIN:-build/release/bin}
while [ $# -gt 0 ]; do
  case "$1" in
    --out) out=$2; shift 2 ;;
    --quick) reps=(--benchmark_repetitions=2 --benchmark_report_aggregates_only=true --benchmark_min_time=0.01); shift ;;
    *) echo "bench_dynamics.sh: unknown option $1 (expected --out DIR, --quick)" >&2; exit 2 ;;
  esac
done
mkdir -p "$out/bench"
tmp=$(mktemp "$out/bench/.dynamics.XXXXXX.json")
trap 'rm -f "$tmp"' EXIT
"$bin/bench_dynamics" "${reps[@]}" --benchmark_out="$tmp" --benchmark_out_format=json >/dev/null
chmod 644 "$tmp"
mv "$tmp" "$out/bench/dynamics.json"   # complete results only: nothing half-written
/usr/bin/python3 experiments/dynamics_table.py "$out/bench/dynamics.json" "$out/dynamics_backends.md"
