#!/usr/bin/env bash
# A benchmark of this tree against the same benchmark at an earlier revision,
# interleaved (scripts/ab_bench.py): is a change faster, and by how much?
#
#   scripts/ab_revision.sh --base REV --bench NAME --filter RE [--rounds N] [--out FILE]
#
# Builds NAME (a Google Benchmark target, e.g. bench_dynamics) twice with the
# release preset (-O3 -march=native): at REV in a git worktree under
# build/ab-REV/ (made once, detached, removed with `git worktree remove`),
# and in this tree (build/release). Then runs both in turn, --rounds times
# each, and writes the table with a header naming the two revisions, the
# command, the date, the CPU and the load average before and after. FILE is
# written whole or not at all (written beside it, then renamed); without
# --out the table goes to stdout. Both builds use this machine's instruction
# set: the ratio is what this machine sees, not the portable build's.
set -euo pipefail
cd "$(dirname "$0")/.."
base="" bench="" filter="" rounds=7 out=""
while [ $# -gt 0 ]; do
  case "$1" in
    --base) base=$2; shift 2 ;;
    --bench) bench=$2; shift 2 ;;
    --filter) filter=$2; shift 2 ;;
    --rounds) rounds=$2; shift 2 ;;
    --out) out=$2; shift 2 ;;
    *) echo "ab_revision.sh: unknown option $1 (expected --base REV --bench NAME --filter RE [--rounds N] [--out FILE])" >&2
       exit 2 ;;
  esac
done
if [ -z "$base" ] || [ -z "$bench" ] || [ -z "$filter" ]; then
  echo "ab_revision.sh: --base, --bench and --filter are required" >&2
  exit 2
fi
rev=$(git rev-parse --short "$base^{commit}") || { echo "ab_revision.sh: '$base' is not a revision" >&2; exit 2; }
wt=build/ab-$rev
if [ ! -d "$wt" ]; then git worktree add --detach "$wt" "$rev" > /dev/null; fi
(cd "$wt" && cmake --preset release > /dev/null && cmake --build --preset release --target "$bench" -j "$(nproc)" > /dev/null)
scripts/configure.sh release > /dev/null
cmake --build --preset release --target "$bench" -j "$(nproc)" > /dev/null
cpu=$(grep -m1 'model name' /proc/cpuinfo | cut -d: -f2 | sed 's/^ //')
load_before=$(cut -d' ' -f1-3 /proc/loadavg)
table=$(/usr/bin/python3 scripts/ab_bench.py --old "$wt/build/release/bin/$bench" --new "build/release/bin/$bench" \
          --filter "$filter" --rounds "$rounds")
load_after=$(cut -d' ' -f1-3 /proc/loadavg)
head="# scripts/ab_revision.sh --base $rev --bench $bench --filter '$filter' --rounds $rounds
# old: $bench of $rev; new: $bench of $(git rev-parse --short HEAD)$(git diff --quiet HEAD -- . ':!results' || echo ' with uncommitted changes')
# release builds (-O3 -march=native), $(date -u +%Y-%m-%dT%H:%M:%SZ), $(nproc) CPUs ($cpu), load average $load_before before, $load_after after"
if [ -n "$out" ]; then
  printf '%s\n%s\n' "$head" "$table" > "$out.tmp"
  mv "$out.tmp" "$out"
else
  printf '%s\n%s\n' "$head" "$table"
fi
