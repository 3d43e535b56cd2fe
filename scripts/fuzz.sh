#!/usr/bin/env bash
# Fuzzes the parsers of user input with libFuzzer (tests/fuzz/, docs/developer-guide/sanitizers-and-fuzzing.md):
# builds the preset asan (clang, AddressSanitizer + UndefinedBehaviorSanitizer),
# writes the seed corpora from every shipped file (scripts/fuzz_seeds.py), then runs
# each harness -- robot, scene, set, urdf, joint_csv, open_loop_csv -- for a time or
# a number of inputs, up to one harness per core at a time. A crash, a sanitizer
# report, an exception other than ConfigError, a hang (an input over 10 s) or an
# input over 2 GB fails the run;
# libFuzzer writes the input to build/asan/fuzz/artifacts/<harness>/.
#
#   scripts/fuzz.sh --smoke                 CI: 10 s per harness (six harnesses, two at a
#                                           time; its total: commit 5f5797c); that the harnesses
#                                           build and run, not a search (the long runs are)
#   scripts/fuzz.sh --time 3600             a long run, an hour per harness
#   scripts/fuzz.sh --runs 1000000 robot    one million inputs, the robot harness only
#   --record                                also write the summary to results/fuzz/long_run.json
#                                           (the run docs/developer-guide/sanitizers-and-fuzzing.md quotes): the harnesses run
#                                           replace their entries, the others' stay, each
#                                           entry with its own command, date and revision
#
# The corpus each run grows is kept in build/asan/fuzz/corpus/<harness>/ (a later
# run starts from it); each harness's log is build/asan/fuzz/<harness>.log.
set -euo pipefail
cd "$(dirname "$0")/.."

limit=(-max_total_time=600)
harnesses=()
record=0
command="scripts/fuzz.sh $*"
# The revision the harnesses are built from (taken now: commits may land while they run),
# marked when the work tree differs from it.
revision=$(git rev-parse --short HEAD 2>/dev/null || echo unknown)
if [ -n "$(git status --porcelain --untracked-files=no 2>/dev/null)" ]; then revision+=" with uncommitted changes"; fi
while [ $# -gt 0 ]; do
  case "$1" in
    --smoke) limit=(-max_total_time=10) ;;
    --time) limit=(-max_total_time="$2"); shift ;;
    --runs) limit=(-runs="$2"); shift ;;
    --record) record=1 ;;
    robot|scene|set|urdf|joint_csv|open_loop_csv) harnesses+=("$1") ;;
    *) echo "fuzz.sh: unknown argument '$1'; expected --smoke, --time SECONDS, --runs N," \
            "robot, scene, set, urdf, joint_csv, open_loop_csv" >&2
       exit 2 ;;
  esac
  shift
done
[ ${#harnesses[@]} -gt 0 ] || harnesses=(robot scene set urdf joint_csv open_loop_csv)

scripts/configure.sh asan >/dev/null
cmake --build --preset asan -j "$(nproc)" --target "${harnesses[@]/#/fuzz_}"

out=build/asan/fuzz
/usr/bin/python3 scripts/fuzz_seeds.py "$out/seeds"

run_one() {
  local h=$1
  mkdir -p "$out/corpus/$h" "$out/artifacts/$h"
  # The first directory is the corpus libFuzzer adds to; the seeds are read only.
  "build/asan/bin/fuzz_$h" "${limit[@]}" -timeout=10 -rss_limit_mb=2048 -print_final_stats=1 \
    -artifact_prefix="$out/artifacts/$h/" "$out/corpus/$h" "$out/seeds/$h" >"$out/$h.log" 2>&1 \
    && echo 0 >"$out/$h.status" || echo $? >"$out/$h.status"
}

for h in "${harnesses[@]}"; do
  rm -f "$out/$h.status"
  while [ "$(jobs -rp | wc -l)" -ge "$(nproc)" ]; do sleep 1; done
  run_one "$h" &
done
wait
failed=0
entries=()
for h in "${harnesses[@]}"; do
  status=$(cat "$out/$h.status")
  runs=$(sed -n 's/^stat::number_of_executed_units: *//p' "$out/$h.log")
  seconds=$(sed -n 's/^Done [0-9]* runs in \([0-9]*\) second.*/\1/p' "$out/$h.log")
  entries+=("$(printf '"%s": {"inputs": %s, "seconds": %s, "exit_status": %s, "corpus_files": %s}' \
    "$h" "${runs:-null}" "${seconds:-null}" "$status" "$(ls "$out/corpus/$h" | wc -l)")")
  if [ "$status" -eq 0 ]; then
    echo "fuzz $h: ${runs:-?} inputs, no finding (corpus $(ls "$out/corpus/$h" | wc -l) files)"
  else
    failed=1
    echo "fuzz $h: FAILED (exit $status) after ${runs:-?} inputs; log $out/$h.log:" >&2
    grep -E "ERROR|SUMMARY|==[0-9]+==|Test unit written|terminate called|runtime error" "$out/$h.log" | head -20 >&2 || true
  fi
done
joined=""
sep=$',\n    '
for e in "${entries[@]}"; do joined+="${joined:+$sep}$e"; done
summary=$(printf '{\n  "command": "%s",\n  "date": "%s",\n  "revision": "%s",\n  "compiler": "%s",\n  "limit": "%s",\n  "harnesses": {\n    %s\n  }\n}' \
  "$command" "$(date -u +%Y-%m-%dT%H:%M:%SZ)" "$revision" \
  "$(clang++ --version | head -1)" "${limit[*]}" "$joined")
echo "$summary" >"$out/summary.json"
if [ "$record" -eq 1 ]; then
  mkdir -p results/fuzz
  # Merged: this run's harnesses replace their entries, the others' stay; each
  # entry carries the command, date, revision, compiler and limit of its run.
  /usr/bin/python3 - "$out/summary.json" results/fuzz/long_run.json <<'EOF'
import json, os, sys
run_file, record_file = sys.argv[1:]
with open(run_file) as f:
    run = json.load(f)
old = {}
if os.path.exists(record_file):
    with open(record_file) as f:
        old = json.load(f)
keys = ("command", "date", "revision", "compiler", "limit")
entries = {}
for source in (old, run):  # an older file's entries take its top-level fields
    for name, entry in source.get("harnesses", {}).items():
        entries[name] = {**entry, **{k: source[k] for k in keys if k in source and k not in entry}}
lines = ",\n".join(f"    {json.dumps(name)}: {json.dumps(entry)}" for name, entry in entries.items())
tmp = record_file + ".tmp"
with open(tmp, "w") as f:
    f.write('{\n  "note": "one entry per harness, each from its own run of scripts/fuzz.sh --record",\n'
            '  "harnesses": {\n' + lines + "\n  }\n}\n")
os.replace(tmp, record_file)
EOF
  echo "fuzz: summary of ${harnesses[*]} written to results/fuzz/long_run.json"
fi
exit $failed
