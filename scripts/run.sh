#!/usr/bin/env bash
# The README's main command: install what is missing, build, run the default job.
#
# Default job: the default scene (the paper's slow experiment) simulated with
# RK4, the PUMA 560 dynamics at the nominal pose `qn` with every back-end,
# then the dynamics back-end benchmark, which rewrites
# results/bench/dynamics.json and results/dynamics_backends.md.
set -euo pipefail
cd "$(dirname "$0")/.."
scripts/build.sh
bin=build/release/bin

echo "== default scene: experiments/scenes/paper_slow.toml (RK4, dt = 0.5 ms) =="
"$bin/pumasim" simulate experiments/scenes/paper_slow.toml

echo "== PUMA 560 at qn, forward dynamics with tau = 0, every back-end =="
"$bin/pumasim" backends | cut -f1 | while read -r b; do
  printf '%-20s qdd = ' "$b"
  "$bin/pumasim" dynamics --robot puma560 --backend "$b" --q=qn --tau=0,0,0,0,0,0 |
    python3 -c 'import json,sys; print(" ".join(f"{x:+.6f}" for x in json.load(sys.stdin)["qdd"]))'
done

echo "== dynamics back-end benchmark (a few minutes) =="
scripts/bench_dynamics.sh
echo "results: results/dynamics_backends.md (table), results/bench/dynamics.json (raw)"
