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
root=$(cd "$(dirname "$0")/.." && pwd)
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
/usr/bin/python3 "$root/scripts/same_ensemble_tables.py" "$work/whole.csv" "$work/merged.csv" --samples 10 > /dev/null
echo "check_ensemble_shards: 4 shards under GNU parallel merged into the single-process table (10 rows, every field but wall_time)"
