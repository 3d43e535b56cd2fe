#!/bin/bash
# CI's end-to-end check of the results pipeline (the full regeneration,
# scripts/results.sh, takes longer than CI): every sweep file parses and its
# reduced version runs and merges (first and last variants, two settings per
# method, short horizon), the stiffness tables run on one case each, the
# planning comparison runs cut short, the report is assembled -- all under
# build/, nothing under results/. A re-run must find every run complete
# (resumability).
set -euo pipefail
cd "$(dirname "$0")/.."
PY=/usr/bin/python3
rm -rf build/sweeps-reduced build/stiffness-reduced
for f in experiments/sweeps/*.toml; do
  $PY experiments/sweep.py "$f" --reduced --jobs 2 > /dev/null
done
again=$($PY experiments/sweep.py experiments/sweeps/stiff_sampling.toml --reduced | sed -n 1p)
# "<name>: N runs in this share, M already complete": a re-run must find M = N.
read -r total done_ <<< "$(sed -E 's/.*: ([0-9]+) runs in this share, ([0-9]+) already complete.*/\1 \2/' <<< "$again")"
if [ -z "$total" ] || [ "$total" != "$done_" ]; then
  echo "re-run did not skip the complete runs: $again" >&2; exit 1
fi
# Shards 1/2 and 2/2 of a fresh sweep together complete it.
rm -rf build/sweeps-reduced/stiff_sampling
$PY experiments/sweep.py experiments/sweeps/stiff_sampling.toml --reduced --shard 1/2 > /dev/null
$PY experiments/sweep.py experiments/sweeps/stiff_sampling.toml --reduced --shard 2/2 > /dev/null
$PY experiments/sweep.py experiments/sweeps/stiff_sampling.toml --reduced --merge > /dev/null
$PY experiments/stiffness_table.py --reduced > /dev/null
mkdir -p build/sweeps-reduced/results/stiffness
cp build/stiffness-reduced/*.csv build/sweeps-reduced/results/stiffness/
$PY experiments/planning.py --reduced --out build/sweeps-reduced/results/planning > /dev/null
$PY experiments/report.py --results build/sweeps-reduced/results --out build/sweeps-reduced/README.md > /dev/null
grep -q "Cheapest run per integrator" build/sweeps-reduced/README.md
grep -q "Stiffness diagnostics" build/sweeps-reduced/README.md
grep -q "Trajectory planning methods" build/sweeps-reduced/README.md
# Creep: the model that defines the stuck intervals does not move in them (an
# identity), and there are such intervals (the arm starts at rest, stuck).
$PY - <<'PY'
import json, sys
s = json.load(open("build/sweeps-reduced/results/stiff_stick_slip/stiff_stick_slip_summary.json"))
c = s["creep"][s["stuck_variant"]]
if not (c["stuck_time_s"] > 0 and c["rad"] == 0.0):
    sys.exit(f"creep of the stuck model itself: {c}")
PY
grep -q "Creep while stuck" build/sweeps-reduced/README.md
echo "sweep pipeline: ok"
