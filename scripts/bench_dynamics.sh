#!/usr/bin/env bash
# Runs the dynamics benchmark and regenerates results/dynamics_backends.md and
# results/dynamics_cost_vs_n.png from its JSON (Debian's python3, with matplotlib).
set -euo pipefail
cd "$(dirname "$0")/.."
mkdir -p results/bench
tmp=$(mktemp results/bench/.dynamics.XXXXXX.json)
trap 'rm -f "$tmp"' EXIT
build/release/bin/bench_dynamics --benchmark_repetitions=5 --benchmark_report_aggregates_only=true \
  --benchmark_min_time=0.1 --benchmark_out="$tmp" --benchmark_out_format=json >/dev/null
chmod 644 "$tmp"
mv "$tmp" results/bench/dynamics.json   # complete results only: nothing half-written
/usr/bin/python3 scripts/dynamics_table.py results/bench/dynamics.json results/dynamics_backends.md
