#!/usr/bin/env bash
# The README's main command leaves a fresh clone clean (issue 31): the tracked
# files of this tree (as they are now, committed or not) are copied into a new
# repository, scripts/run.sh --quick runs there on the programs already built
# (PUMASIM_BIN; --quick: a two-second benchmark), and then `git status` must
# show nothing changed or added outside the ignored folders, and the claims
# check must pass on the copy's README and results.
#
#   tests/check_main_job.sh BIN_DIR
set -euo pipefail
bin=$(cd "$1" && pwd)
root=$(cd "$(dirname "$0")/.." && pwd)
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
(cd "$root" && git ls-files -z | tar --null -T - -cf -) | tar -xf - -C "$work"
cd "$work"
git init -q
git add -A
git -c user.name=check -c user.email=check@localhost commit -qm "the tree under test"
PUMASIM_BIN="$bin" scripts/run.sh --quick > run.log 2>&1 || { cat run.log; echo "check_main_job: scripts/run.sh failed" >&2; exit 1; }
rm run.log
status=$(git status --porcelain --untracked-files=all)
if [ -n "$status" ]; then
  echo "check_main_job: the main job changed the clone (it may write only under ignored folders):" >&2
  echo "$status" >&2
  exit 1
fi
for f in runs/paper_slow/trajectory.csv runs/paper/README.md runs/bench/dynamics_backends.md; do
  [ -s "$f" ] || { echo "check_main_job: the main job wrote no $f" >&2; exit 1; }
done
/usr/bin/python3 scripts/check_claims.py
echo "check_main_job: the main job wrote only under runs/ and build/; the claims check passes"
