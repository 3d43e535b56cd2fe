#!/usr/bin/env bash
# CI's wall time, measured as CI runs it: a fresh clone of HEAD in a temporary
# folder runs .ci/run (scripts/test.sh) there, timed as a whole, and the phase
# times scripts/test.sh prints go to results/reliability/ci_phases.txt with
# the revision, the date, the machine's cores and the tests counts. Run it on
# a machine with nothing else running (the figure is what CI's budget, 30
# minutes on 2 cores, is checked against); it takes as long as CI.
#
#   scripts/measure_ci.sh            measure and write results/reliability/ci_phases.txt
#   scripts/measure_ci.sh --dry      measure, print, write nothing under results/
#
# The clone and its log are removed at the end unless the run failed (then the
# log's path is printed). Exit status: that of .ci/run.
set -euo pipefail
cd "$(dirname "$0")/.."
write=1
case "${1:-}" in
  "") ;;
  --dry) write=0 ;;
  *) echo "measure_ci.sh: unknown argument '$1'; expected nothing or --dry" >&2; exit 2 ;;
esac
if [ -n "$(git status --porcelain --untracked-files=no)" ]; then
  echo "measure_ci.sh: the work tree has uncommitted changes; CI runs a clean checkout of HEAD, so commit first" >&2
  exit 2
fi
revision=$(git rev-parse --short HEAD)
work=$(mktemp -d /tmp/pumasim_ci.XXXXXX)
git clone -q . "$work/clone"
log="$work/ci.log"
start=$(date +%s)
status=0
(cd "$work/clone" && .ci/run) >"$log" 2>&1 || status=$?
total=$(($(date +%s) - start))
phases=$(sed -n 's/^test\.sh: \(.*\) took \([0-9]*\) s$/\1: \2 s/p' "$log")
counts=$(grep -E '^[0-9]+% tests passed' "$log" || true)
report=$(cat <<EOF
# .ci/run (scripts/test.sh) on a fresh clone of $revision, $(nproc) cores, $(date -u +%Y-%m-%d),
# written by scripts/measure_ci.sh. Each phase's wall time as scripts/test.sh prints it;
# total: the whole .ci/run, timed around it. Exit status $status.
$phases
tests: $(echo "$counts" | tr '\n' ';' | sed 's/;$//; s/;/; /g')
total: $total s ($((total / 60)) min $((total % 60)) s)
EOF
)
echo "$report"
if [ "$status" -ne 0 ]; then
  echo "measure_ci.sh: .ci/run failed (exit $status); its log: $log" >&2
  exit "$status"
fi
if [ "$write" -eq 1 ]; then
  echo "$report" > results/reliability/ci_phases.txt
fi
rm -rf "$work"
