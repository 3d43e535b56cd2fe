#!/usr/bin/env bash
# The README's main command: install what is missing, build, run the default job.
#
# Default job: the default scene (the paper's slow experiment) through
# `pumasim run` into runs/paper_slow/ (a run folder, replaced each time) with its plots, the paper's runs into
# results/paper/, the PUMA 560 dynamics at the pose `qn` with every back-end,
# then the dynamics back-end benchmark (results/dynamics_backends.md).
set -euo pipefail
cd "$(dirname "$0")/.."
scripts/build.sh
bin=build/release/bin

echo "== default scene: experiments/scenes/paper_slow.toml =="
"$bin/pumasim" run experiments/scenes/paper_slow.toml --out runs/paper_slow --force
/usr/bin/python3 scripts/plot_run.py runs/paper_slow

echo "== the paper's experiment: results/paper/ =="
/usr/bin/python3 experiments/paper_experiment.py

echo "== PUMA 560 at qn, forward dynamics with tau = 0, every back-end =="
"$bin/pumasim" backends | cut -f1 | while read -r b; do
  printf '%-20s qdd = ' "$b"
  "$bin/pumasim" dynamics --robot puma560 --backend "$b" --q=qn --tau=0,0,0,0,0,0 |
    python3 -c 'import json,sys; print(" ".join(f"{x:+.6f}" for x in json.load(sys.stdin)["qdd"]))'
done

echo "== dynamics back-end benchmark (a few minutes) =="
scripts/bench_dynamics.sh
echo "results: runs/paper_slow/ (default scene), results/paper/README.md (the paper's experiment),"
echo "         results/dynamics_backends.md (back-end benchmark)"
