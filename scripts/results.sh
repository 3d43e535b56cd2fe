#!/usr/bin/env bash
# Regenerates results/README.md and everything it reads: every sweep in
# experiments/sweeps/ (work-precision on the paper's scenes and on the Stanford
# arm's tracking scene, the dynamics back-ends inside the ODE, the stiff
# scenes), the stiffness tables, the
# planning methods (experiments/planning.py), the observed orders and their
# rounding spread (experiments/rounding_spread.py), the test set,
# the output-grid table (experiments/output_grid.py), the extreme runs
# (tests/check_extreme_runs.py, results/reliability/), and the report. A fresh run
# takes about 20 minutes on 2 cores (the report's header states how long its
# last run took). Runs already complete under build/sweeps/ are skipped:
# delete that folder for a fresh run. Uses a private copy of the pumasim binary, so that
# rebuilding meanwhile does not change the program under measurement.
#
#   scripts/results.sh [--jobs N]      (default: the number of cores)
set -euo pipefail
cd "$(dirname "$0")/.."
jobs=$(nproc)
if [ "${1:-}" = "--jobs" ]; then jobs=$2; fi
scripts/build.sh > /dev/null
mkdir -p build/results-bin
cp build/release/bin/pumasim build/results-bin/pumasim
export PUMASIM=$PWD/build/results-bin/pumasim
start=$(date +%s)
# The work-precision sweeps (wall time is their headline) run one at a time,
# so that no run shares the machine with another; the others in parallel.
for f in experiments/sweeps/*.toml; do
  j=$jobs
  if grep -q '^folder = "work_precision"' "$f"; then j=1; fi
  /usr/bin/python3 experiments/sweep.py "$f" --jobs "$j"
done
/usr/bin/python3 experiments/stiffness_table.py
/usr/bin/python3 experiments/planning.py
/usr/bin/python3 experiments/observed_order.py
/usr/bin/python3 experiments/rounding_spread.py   # steps of the same run over the back-ends (rounding-level changes of f)
/usr/bin/python3 experiments/testset.py
/usr/bin/python3 experiments/output_grid.py
# extreme but valid scenes x every integrator end within their budgets (README, the reliability checks)
/usr/bin/python3 tests/check_extreme_runs.py "$PUMASIM" --jobs "$jobs" --out results/reliability > /dev/null
# rosenbrock4's error estimate against its true local error (README, "Is the instrument right?")
for lam in -1050 -1e4; do
  build/release/bin/rosenbrock_local_error "$lam" > "results/testset/rosenbrock_local_error_lambda$lam.tsv.tmp"
  mv "results/testset/rosenbrock_local_error_lambda$lam.tsv.tmp" "results/testset/rosenbrock_local_error_lambda$lam.tsv"
done
minutes=$(( ($(date +%s) - start + 30) / 60 ))
/usr/bin/python3 experiments/report.py --minutes "$minutes"
