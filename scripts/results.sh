#!/usr/bin/env bash
# Regenerates the committed results under results/ (the only script that
# writes there; the README's main command, scripts/run.sh, writes runs/).
#
#   scripts/results.sh [--jobs N] [STAGE ...]     (default: every stage but fuzz, cost and ci, in this order)
#
# Stages:
#   sweeps      every sweep in experiments/sweeps/ (work-precision on the paper's
#               scenes and the Stanford arm's tracking scene, the dynamics back-ends
#               inside the ODE, the stiff scenes, stick-slip)
#   energygrowth  the lossless arm's energy error over 10^4 s, symplectic-midpoint against RK4 and
#               the adaptive methods: drift or bounded (experiments/energy_growth.py)
#   implicit    IDA on the plant's implicit form (inverse dynamics on the speeds' rows) against CVODE's
#               BDF on the ODE, per evaluation and per run (experiments/implicit_form.py)
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
#   sensitivity the paper's experiment against its unpublished parameters
#               (experiments/sensitivity.py; long: converged runs at every point)
#   partitioned the paper's scheme, monolithic and partitioned Adams-Bashforth
#               (experiments/partitioned.py; long: rk4 references at 1e-5 s)
#   filippov    the paper's friction rule in Filippov terms (experiments/filippov.py)
#   panda       the Panda's dynamics against its authors' code (experiments/panda_vs_authors.py)
#   bench       the dynamics back-end benchmark (experiments/bench_dynamics.sh)
#   identification  the joint-torque regressor, direct against probing, and the base parameters
#               of the PUMA 560 and the Panda (experiments/regressor_table.py); what forward
#               sensitivities cost against one run and 2p difference runs (experiments/sensitivity_cost.py);
#               identification on the simulated PUMA and Panda (experiments/identify.py, Monte Carlo)
#   tuning      PIV gains tuned on the full model against design_piv.py's pole placement, on the
#               paper's slow and fast paths with smooth friction (experiments/tune_piv.py)
#   ensembles   ensemble scaling (1 thread against every core) and set-up overhead (experiments/ensemble_scaling.py),
#               Sobol indices of the drive ensemble and of the paper's experiment over five unpublished
#               inputs (experiments/ensemble_gsa.py)
#   literature  the paper's scenes across the published PUMA 560 parameter sets (RTB's, AKB86's, crossed)
#               and friction levels (experiments/literature_spread.py)
#   report      results/README.md from all of the above (experiments/report.py)
#   fuzz        only when named: the long fuzz run, scripts/fuzz.sh --runs 1000000 --record
#               (one million inputs per harness, in the sanitizer build, build/asan;
#               results/fuzz/long_run.json). About half an hour for the six harnesses on
#               2 cores, hence not in the default run; FUZZ_HARNESSES="urdf joint_csv"
#               runs only those (their entries replaced, the others' kept).
#   cost        only when named: where a run's wall time goes (experiments/cost_breakdown.py,
#               the release build against the profiled one, preset profile, which it
#               builds); records the label COST_LABEL (default main) in
#               results/cost_breakdown.json, the other labels kept.
#   ci          only when named: CI's wall time on a fresh clone (scripts/measure_ci.sh;
#               as long as CI, on a committed tree with nothing else running).
#   abjacobian  only when named: the exact forward-dynamics Jacobian's benchmark rows, this tree's
#               release build against revision 4331408's (scripts/ab_revision.sh builds it in a git worktree
#               under build/; scripts/ab_bench.py interleaves the two, 7 rounds), on -march=native builds;
#               results/bench/ab_jacobian_large_n.txt. Needs an otherwise idle machine.
#   slurm       only when named: an ensemble as a job array on a one-node Slurm on localhost
#               (scripts/slurm_one_node.sh: as root, it installs slurm-wlm and munge when missing and
#               writes /etc/slurm/slurm.conf when absent; the release build's binary).
#
# What each stage writes is the `# writes:` line above its function (a path
# ending in '/' is the folder and everything in it; {folder} and {name} stand
# for every sweep file's [sweep] folder and name): every file under results/
# must be written by a stage (the CTest Python.ResultsHaveProducers checks it,
# without running anything).
#
# Every figure but the fuzz, cost and ci stages' and those of the Python module (experiments/identify.py,
# experiments/tune_piv.py: the native release build's) comes from the portable build (preset portable: the x86-64
# baseline, no -march=native), so that results/ does not depend on this
# machine's instruction set; each run's meta.json and the benchmark's table
# record the flags and the CPU. (The native release build is built too: the
# buildspread stage compares the two.) A fresh full run on 2 cores, before
# sensitivity and partitioned, is long: the report's header states how long
# its last full run took (an earlier figure: commit d593645).
# Runs already complete under build/sweeps/ are skipped: delete that folder
# for a fresh run. Uses private copies of the binaries (build/results-bin/),
# so that rebuilding meanwhile does not change the program under measurement.
set -euo pipefail
cd "$(dirname "$0")/.."
jobs=$(nproc)
all=(sweeps energygrowth implicit stiffness planning order testset outputgrid extreme rosenbrock buildspread paper sensitivity
     partitioned filippov panda bench identification tuning ensembles literature report)
named_only=(fuzz cost ci slurm abjacobian)
own_builds=(fuzz ci)  # stages that need neither release build: they build (or clone) what they run
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

# writes: results/{folder}/{name}.csv results/{folder}/{name}.png results/{folder}/{name}_cost.png
# writes: results/{folder}/{name}.pdf results/{folder}/{name}_cost.pdf
# writes: results/{folder}/{name}_precision.md results/{folder}/{name}_modes.md results/{folder}/{name}_summary.json
# writes: results/friction_axis/decision.md results/friction_axis/decision.csv
stage_sweeps() {
  # The work-precision sweeps and the friction axis (wall time is their headline) run one at a time,
  # so that no run shares the machine with another; the others in parallel.
  for f in experiments/sweeps/*.toml; do
    local j=$jobs
    if grep -Eq '^folder = "(work_precision|friction_axis)"' "$f"; then j=1; fi
    /usr/bin/python3 experiments/sweep.py "$f" --jobs "$j"
  done
  /usr/bin/python3 experiments/friction_decision.py   # the friction axis: which method for which law
}
# writes: results/energy_long_time/energy_growth.csv results/energy_long_time/energy_growth.md
# writes: results/energy_long_time/energy_growth.png
stage_energygrowth() { /usr/bin/python3 experiments/energy_growth.py; }
# writes: results/implicit_form/
stage_implicit() { /usr/bin/python3 experiments/implicit_form.py; }
# writes: results/stiffness/
stage_stiffness() { /usr/bin/python3 experiments/stiffness_table.py; }
# writes: results/planning/
stage_planning() { /usr/bin/python3 experiments/planning.py; }
# writes: results/observed_order/README.md results/observed_order/observed_order.csv
# writes: results/observed_order/ladder.csv results/observed_order/references.csv results/observed_order/*.png
# writes: results/observed_order/*.pdf
# writes: results/observed_order/rounding_spread.csv results/observed_order/rounding_spread.md
stage_order() {
  /usr/bin/python3 experiments/observed_order.py
  /usr/bin/python3 experiments/rounding_spread.py   # steps of the same run over the back-ends (rounding-level changes of f)
}
# writes: results/testset/README.md results/testset/testset.csv results/testset/problems.csv
# writes: results/testset/observed_slopes.csv results/testset/*.png results/testset/*.pdf
# writes: results/testset/radau5_vs_scipy.csv results/testset/radau5_vs_scipy.md
stage_testset() {
  /usr/bin/python3 experiments/testset.py --bin "$PUMASIM_BIN/testset"
  /usr/bin/python3 experiments/radau_scipy.py --bin "$PUMASIM_BIN/testset"   # radau5 against scipy's Radau
}
# writes: results/output_grid/
stage_outputgrid() { /usr/bin/python3 experiments/output_grid.py; }
# writes: results/reliability/extreme_runs.csv results/reliability/extreme_runs_summary.csv
# writes: results/reliability/memory_bound.json
stage_extreme() {
  # extreme but valid scenes x every integrator end within their budgets (docs/user-guide/limits.md)
  /usr/bin/python3 tests/check_extreme_runs.py "$PUMASIM" --jobs "$jobs" --out results/reliability > /dev/null
  # a long run's memory under a 64 MiB address-space limit (docs/user-guide/limits.md)
  /usr/bin/python3 experiments/memory_bound.py --bin "$PUMASIM" --out results/reliability/memory_bound.json > /dev/null
}
# writes: results/testset/rosenbrock_local_error_lambda*.tsv
stage_rosenbrock() {
  # rosenbrock4's error estimate against its true local error (docs/science/instrument.md)
  for lam in -1050 -1e4; do
    "$PUMASIM_BIN/rosenbrock_local_error" "$lam" > "results/testset/rosenbrock_local_error_lambda$lam.tsv.tmp"
    mv "results/testset/rosenbrock_local_error_lambda$lam.tsv.tmp" "results/testset/rosenbrock_local_error_lambda$lam.tsv"
  done
}
# writes: results/observed_order/build_spread.csv results/observed_order/build_spread.md
stage_buildspread() {
  /usr/bin/python3 experiments/build_spread.py --native "$PUMASIM_BIN/pumasim-native" --portable "$PUMASIM"
}
# writes: results/paper/README.md results/paper/paper_fast/ results/paper/paper_slow/ results/paper/paper_*.png
# writes: results/paper/paper_*.pdf
stage_paper() { /usr/bin/python3 experiments/paper_experiment.py --out results/paper; }
# writes: results/paper/sensitivity.csv results/paper/sensitivity.md
stage_sensitivity() { /usr/bin/python3 experiments/sensitivity.py --jobs "$jobs"; }
# writes: results/paper/partitioned.csv results/paper/partitioned.md
stage_partitioned() { /usr/bin/python3 experiments/partitioned.py; }
# writes: results/stick_slip/filippov.md results/stick_slip/filippov.json
stage_filippov() { /usr/bin/python3 experiments/filippov.py --out results/stick_slip/filippov.md; }
# writes: results/panda/authors_code_difference.md results/panda/authors_code_difference.json
stage_panda() { /usr/bin/python3 experiments/panda_vs_authors.py "$PUMASIM" --out results/panda/authors_code_difference.md; }
# writes: results/bench/dynamics.json results/dynamics_backends.md results/dynamics_cost_vs_n.png
# writes: results/dynamics_cost_vs_n.pdf
stage_bench() { experiments/bench_dynamics.sh --out results; }
# writes: results/identification/regressor.md results/identification/regressor_bench.json
# writes: results/identification/sensitivity_cost.md
# writes: results/identification/puma560/table.md results/identification/puma560/identify.json
# writes: results/identification/puma560/estimates.csv
# writes: results/identification/puma560/experiment.toml
# writes: results/identification/panda/table.md results/identification/panda/identify.json
# writes: results/identification/panda/estimates.csv results/identification/panda/experiment.toml
stage_identification() {
  /usr/bin/python3 experiments/regressor_table.py --bench "$PUMASIM_BIN/bench_identification" --bin "$PUMASIM" \
    --out results/identification
  /usr/bin/python3 experiments/sensitivity_cost.py --bin "$PUMASIM" --out results/identification
  # The Python module: the native release build (scripts/build.sh above; the portable preset has none).
  /usr/bin/python3 experiments/identify.py experiments/identification/puma560.toml \
    --module "$PWD/build/release/python" --out results/identification/puma560 --force --quiet --no-knots
  /usr/bin/python3 experiments/identify.py experiments/identification/panda.toml \
    --module "$PWD/build/release/python" --out results/identification/panda --force --quiet --no-knots
}
# writes: results/tuning/paper_slow_viscous/tune.json results/tuning/paper_slow_viscous/summary.md
# writes: results/tuning/paper_slow_viscous/tuned.toml
# writes: results/tuning/paper_fast_viscous/tune.json results/tuning/paper_fast_viscous/summary.md
# writes: results/tuning/paper_fast_viscous/tuned.toml
stage_tuning() {
  # The Python module: the native release build (scripts/build.sh; the portable preset has none).
  local m="$PWD/build/release/python"
  /usr/bin/python3 experiments/tune_piv.py experiments/scenes/paper_slow_viscous.toml --module "$m" \
    --out results/tuning/paper_slow_viscous --force --quiet
  # The paper's fast path with the slow scene's smooth friction (the sensitivities refuse the paper's rule).
  /usr/bin/python3 experiments/tune_piv.py experiments/scenes/paper_fast.toml --module "$m" \
    --set 'friction.model="viscous"' --unset friction.static_torque --unset friction.kinetic_torque \
    --unset friction.zero_speed --iterations 60 --out results/tuning/paper_fast_viscous --force --quiet
}
# writes: results/ensembles/scaling.json results/ensembles/scaling.md
# writes: results/ensembles/paper_slow_viscous_drive_sobol.json results/ensembles/paper_slow_viscous_drive_sobol.md
# writes: results/ensembles/paper_slow_unpublished_sobol.json results/ensembles/paper_slow_unpublished_sobol.md
# writes: results/ensembles/paper_slow_unpublished_stable_sobol.json results/ensembles/paper_slow_unpublished_stable_sobol.md
stage_ensembles() {
  /usr/bin/python3 experiments/ensemble_scaling.py --bin "$PUMASIM"
  /usr/bin/python3 experiments/ensemble_gsa.py experiments/ensembles/paper_slow_viscous_drive.toml --n 1024 \
    --bin "$PUMASIM"
  # The paper's experiment over five unpublished inputs (AB2 at 0.5 ms, 24 s): which decide whether it
  # diverges, and, where it does not, which drive its tracking error.
  /usr/bin/python3 experiments/ensemble_gsa.py experiments/ensembles/paper_slow_unpublished.toml --n 1024 \
    --outputs max_path_error,max_path_deviation --bin "$PUMASIM"
  /usr/bin/python3 experiments/ensemble_gsa.py experiments/ensembles/paper_slow_unpublished.toml --n 1024 \
    --outputs max_path_error,max_path_deviation --bin "$PUMASIM" --range motor.inductance=0.0025:0.008 \
    --out results/ensembles/paper_slow_unpublished_stable_sobol
}
# writes: results/ensembles/literature_spread.md results/ensembles/literature_spread.json
stage_literature() { /usr/bin/python3 experiments/literature_spread.py --bin "$PUMASIM" --jobs "$jobs"; }
# writes: results/fuzz/long_run.json
# shellcheck disable=SC2086
stage_fuzz() { scripts/fuzz.sh --runs 1000000 --record ${FUZZ_HARNESSES:-}; }
# writes: results/cost_breakdown.json results/cost_breakdown.md
stage_cost() {
  scripts/configure.sh profile > /dev/null   # the timers (PUMASIM_PROFILE) beside scripts/build.sh's release build
  cmake --build --preset profile --target pumasim -j "$(nproc)" > /dev/null
  /usr/bin/python3 experiments/cost_breakdown.py --label "${COST_LABEL:-main}" \
    --revision "release and profiled builds of $(git rev-parse --short HEAD)"
}
# writes: results/reliability/ci_phases.txt
stage_ci() { scripts/measure_ci.sh; }
# writes: results/bench/ab_jacobian_large_n.txt
stage_abjacobian() {
  scripts/ab_revision.sh --base 4331408 --bench bench_dynamics --rounds 7 \
    --filter 'jacobian/(puma560|puma560-3|random(6|12|24|48))/|plant_' --out results/bench/ab_jacobian_large_n.txt
}
# writes: results/ensembles/slurm_one_node.log
stage_slurm() { scripts/slurm_one_node.sh; }
# writes: results/README.md results/report_run.json
stage_report() {
  if [ $full -eq 1 ]; then
    /usr/bin/python3 experiments/report.py --minutes $(( ($(date +%s) - start + 30) / 60 ))
  else
    /usr/bin/python3 experiments/report.py   # not a full run: the header quotes the last full run's time (report_run.json)
  fi
}

run_stages() {
  for s in "${stages[@]}"; do
    echo "results.sh: stage $s" >&2
    "stage_$s"
  done
}

own=1
for s in "${stages[@]}"; do
  if [[ " ${own_builds[*]} " != *" $s "* ]]; then own=0; fi
done
if [ $own -eq 1 ]; then
  # Only stages that build (fuzz: build/asan) or clone (ci) what they run: no release build needed.
  run_stages
  exit 0
fi
scripts/build.sh > /dev/null   # the dependencies, and the native build (buildspread, cost)
scripts/configure.sh portable > /dev/null
cmake --build --preset portable -j "$(nproc)" > /dev/null
mkdir -p build/results-bin
for b in pumasim testset rosenbrock_local_error bench_dynamics bench_identification bench_plant; do
  cp "build/portable/bin/$b" "build/results-bin/$b.tmp" && mv "build/results-bin/$b.tmp" "build/results-bin/$b"
done
cp build/release/bin/pumasim build/results-bin/pumasim-native.tmp && mv build/results-bin/pumasim-native.tmp build/results-bin/pumasim-native
export PUMASIM=$PWD/build/results-bin/pumasim PUMASIM_BIN=$PWD/build/results-bin
start=$(date +%s)
run_stages
