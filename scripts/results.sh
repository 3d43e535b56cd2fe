#!/usr/bin/env bash
# Regenerates the committed results under results/ (the only script that
# writes there; the README's main command, scripts/run.sh, writes runs/).
#
#   scripts/results.sh [--jobs N] [STAGE ...]     (default: every stage but fuzz, in this order)
#
# Stages:
#   sweeps      every sweep in experiments/sweeps/ (work-precision on the paper's
#               scenes and the Stanford arm's tracking scene, the dynamics back-ends
#               inside the ODE, the stiff scenes, stick-slip)
#   stiffness   the stiffness tables (experiments/stiffness_table.py)
#   planning    the planning methods (experiments/planning.py)
#   order       the observed orders (experiments/observed_order.py) and their
#               rounding spread (experiments/rounding_spread.py)
#   testset     the IVP test set (experiments/testset.py)
#   outputgrid  cost against the output grid (experiments/output_grid.py)
#   extreme     extreme but valid scenes x every integrator (tests/check_extreme_runs.py), and
#               a long run's memory under an address-space limit (experiments/memory_bound.py)
#   rosenbrock  rosenbrock4's error estimate against its true local error
#   buildspread adaptive counts of the native build against the portable one
#               (experiments/build_spread.py)
#   paper       the paper's experiment re-run (experiments/paper_experiment.py)
#   bench       the dynamics back-end benchmark (scripts/bench_dynamics.sh)
#   report      results/README.md from all of the above (experiments/report.py)
#   fuzz        only when named: the long fuzz run, scripts/fuzz.sh --runs 1000000 --record
#               (one million inputs per harness, in the sanitizer build, build/asan;
#               results/fuzz/long_run.json). About half an hour for the six harnesses on
#               2 cores, hence not in the default run; FUZZ_HARNESSES="urdf joint_csv"
#               runs only those (their entries replaced, the others' kept).
#
# Every figure but the fuzz stage's comes from the portable build (preset portable: the x86-64
# baseline, no -march=native), so that results/ does not depend on this
# machine's instruction set; each run's meta.json and the benchmark's table
# record the flags and the CPU. (The native release build is built too: the
# buildspread stage compares the two.) A fresh full run takes about 20 minutes
# on 2 cores (the report's header states how long its last full run took).
# Runs already complete under build/sweeps/ are skipped: delete that folder
# for a fresh run. Uses private copies of the binaries (build/results-bin/),
# so that rebuilding meanwhile does not change the program under measurement.
set -euo pipefail
cd "$(dirname "$0")/.."
jobs=$(nproc)
all=(sweeps stiffness planning order testset outputgrid extreme rosenbrock buildspread paper panda bench report)
named_only=(fuzz)
stages=()
while [ $# -gt 0 ]; do
  case "$1" in
    --jobs) jobs=$2; shift 2 ;;
    *)
      if [[ " ${all[*]} ${named_only[*]} " != *" $1 "* ]]; then
        echo "results.sh: unknown stage '$1' (expected --jobs N or one of: ${all[*]} ${named_only[*]})" >&2
        exit 2
      fi
      stages+=("$1"); shift ;;
  esac
done
full=0
if [ ${#stages[@]} -eq 0 ]; then stages=("${all[@]}"); full=1; fi
if [ "${stages[*]}" = fuzz ]; then
  # The fuzz stage alone needs neither release build: scripts/fuzz.sh builds build/asan.
  # shellcheck disable=SC2086
  exec scripts/fuzz.sh --runs 1000000 --record ${FUZZ_HARNESSES:-}
fi
scripts/build.sh > /dev/null   # the dependencies, and the native build (buildspread)
cmake --preset portable > /dev/null
cmake --build --preset portable -j "$(nproc)" > /dev/null
mkdir -p build/results-bin
for b in pumasim testset rosenbrock_local_error bench_dynamics; do
  cp "build/portable/bin/$b" "build/results-bin/$b.tmp" && mv "build/results-bin/$b.tmp" "build/results-bin/$b"
done
cp build/release/bin/pumasim build/results-bin/pumasim-native.tmp && mv build/results-bin/pumasim-native.tmp build/results-bin/pumasim-native
export PUMASIM=$PWD/build/results-bin/pumasim PUMASIM_BIN=$PWD/build/results-bin
start=$(date +%s)

stage_sweeps() {
  # The work-precision sweeps (wall time is their headline) run one at a time,
  # so that no run shares the machine with another; the others in parallel.
  for f in experiments/sweeps/*.toml; do
    local j=$jobs
    if grep -q '^folder = "work_precision"' "$f"; then j=1; fi
    /usr/bin/python3 experiments/sweep.py "$f" --jobs "$j"
  done
}
stage_stiffness() { /usr/bin/python3 experiments/stiffness_table.py; }
stage_planning() { /usr/bin/python3 experiments/planning.py; }
stage_order() {
  /usr/bin/python3 experiments/observed_order.py
  /usr/bin/python3 experiments/rounding_spread.py   # steps of the same run over the back-ends (rounding-level changes of f)
}
stage_testset() { /usr/bin/python3 experiments/testset.py --bin "$PUMASIM_BIN/testset"; }
stage_outputgrid() { /usr/bin/python3 experiments/output_grid.py; }
stage_extreme() {
  # extreme but valid scenes x every integrator end within their budgets (docs/user-guide/limits.md)
  /usr/bin/python3 tests/check_extreme_runs.py "$PUMASIM" --jobs "$jobs" --out results/reliability > /dev/null
  # a long run's memory under a 64 MiB address-space limit (docs/user-guide/limits.md)
  /usr/bin/python3 experiments/memory_bound.py --bin "$PUMASIM" --out results/reliability/memory_bound.json > /dev/null
}
stage_rosenbrock() {
  # rosenbrock4's error estimate against its true local error (docs/science/instrument.md)
  for lam in -1050 -1e4; do
    "$PUMASIM_BIN/rosenbrock_local_error" "$lam" > "results/testset/rosenbrock_local_error_lambda$lam.tsv.tmp"
    mv "results/testset/rosenbrock_local_error_lambda$lam.tsv.tmp" "results/testset/rosenbrock_local_error_lambda$lam.tsv"
  done
}
stage_buildspread() {
  /usr/bin/python3 experiments/build_spread.py --native "$PUMASIM_BIN/pumasim-native" --portable "$PUMASIM"
}
stage_paper() { /usr/bin/python3 experiments/paper_experiment.py --out results/paper; }
stage_panda() { /usr/bin/python3 experiments/panda_vs_authors.py "$PUMASIM" --out results/panda/authors_code_difference.md; }
stage_bench() { scripts/bench_dynamics.sh --out results; }
# shellcheck disable=SC2086
stage_fuzz() { scripts/fuzz.sh --runs 1000000 --record ${FUZZ_HARNESSES:-}; }
stage_report() {
  if [ $full -eq 1 ]; then
    /usr/bin/python3 experiments/report.py --minutes $(( ($(date +%s) - start + 30) / 60 ))
  else
    /usr/bin/python3 experiments/report.py   # not a full run: the header quotes the last full run's time (report_run.json)
  fi
}
for s in "${stages[@]}"; do
  echo "results.sh: stage $s" >&2
  "stage_$s"
done
