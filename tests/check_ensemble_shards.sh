#!/usr/bin/env bash
# An ensemble split into shards past one process (issue 35): GNU parallel
# runs the four shards of a small ensemble (pumasim ensemble --shard K/4, one
# job each), pumasim merges their tables (--merge), and the merge must equal
# the table one process writes, every field but wall_time (the integration's
# own clock time), compared as text.
# Usage: check_ensemble_shards.sh PUMASIM SCENES_DIR
set -euo pipefail
bin=$1
scenes=$(realpath "$2")
work=$(mktemp -d /tmp/pumasim_shards.XXXXXX)
trap 'rm -rf "$work"' EXIT
cat > "$work/e.toml" <<TOML
scene = "$scenes/paper_slow_viscous.toml"
samples = 10
seed = 35
[run]
integrator = "cvode-bdf"
rtol = 1e-6
t_end = 0.05
[[vary]]
key = "amplifier.gain"
distribution = "uniform"
low = 3.5
high = 4.5
[[vary]]
key = "motor.resistance"
distribution = "normal"
mean = 2.0
sd = 0.2
TOML
"$bin" ensemble "$work/e.toml" --threads 1 --out "$work/whole.csv" -q
parallel --will-cite --halt now,fail=1 -j 2 \
  "$bin" ensemble "$work/e.toml" --shard {}/4 --threads 1 --out "$work/shard{}.csv" -q ::: 1 2 3 4
"$bin" ensemble "$work/e.toml" --merge "$work"/shard{4,2,3,1}.csv --out "$work/merged.csv" -q
/usr/bin/python3 - "$work/whole.csv" "$work/merged.csv" <<'PY'
import csv, sys
def rows(path):
    with open(path, newline="") as f:
        r = list(csv.reader(f))
    w = r[0].index("wall_time")
    return [row[:w] + row[w + 1:] for row in r]
a, b = rows(sys.argv[1]), rows(sys.argv[2])
if len(a) != 11:
    sys.exit(f"expected a header and 10 rows, got {len(a)} rows")
if a != b:
    bad = next(i for i in range(max(len(a), len(b))) if i >= len(a) or i >= len(b) or a[i] != b[i])
    sys.exit(f"the merged table differs from the single process's at line {bad + 1}")
print("check_ensemble_shards: 4 shards under GNU parallel merged into the single-process table (10 rows, every field but wall_time)")
PY
