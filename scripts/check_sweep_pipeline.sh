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
again=$($PY experiments/sweep.py experiments/sweeps/sampled_control.toml --reduced | sed -n 1p)
# "<name>: N runs in this share, M already complete": a re-run must find M = N.
read -r total done_ <<< "$(sed -E 's/.*: ([0-9]+) runs in this share, ([0-9]+) already complete.*/\1 \2/' <<< "$again")"
if [ -z "$total" ] || [ "$total" != "$done_" ]; then
  echo "re-run did not skip the complete runs: $again" >&2; exit 1
fi
# Shards 1/2 and 2/2 of a fresh sweep together complete it.
rm -rf build/sweeps-reduced/sampled_control
$PY experiments/sweep.py experiments/sweeps/sampled_control.toml --reduced --shard 1/2 > /dev/null
$PY experiments/sweep.py experiments/sweeps/sampled_control.toml --reduced --shard 2/2 > /dev/null
$PY experiments/sweep.py experiments/sweeps/sampled_control.toml --reduced --merge > /dev/null
$PY experiments/stiffness_table.py --reduced > /dev/null
mkdir -p build/sweeps-reduced/results/stiffness
cp build/stiffness-reduced/*.csv build/sweeps-reduced/results/stiffness/
$PY experiments/planning.py --reduced --out build/sweeps-reduced/results/planning > /dev/null
# --omit-findings: the sweeps' hand-written findings describe the full tables, not these reduced ones.
$PY experiments/report.py --results build/sweeps-reduced/results --out build/sweeps-reduced/README.md --omit-findings > /dev/null
grep -q "Cheapest run per integrator" build/sweeps-reduced/README.md
grep -q "Stiffness diagnostics" build/sweeps-reduced/README.md
grep -q "Trajectory planning methods" build/sweeps-reduced/README.md
# Creep: the model that defines the stuck intervals does not move in them (an
# identity), and there are such intervals (the arm starts at rest, stuck).
$PY - <<'PY'
import json, sys
s = json.load(open("build/sweeps-reduced/results/stick_slip/stick_slip_summary.json"))
c = s["creep"][s["stuck_variant"]]
if not (c["stuck_time_s"] > 0 and c["rad"] == 0.0):
    sys.exit(f"creep of the stuck model itself: {c}")
PY
grep -q "Creep while stuck" build/sweeps-reduced/README.md
grep -q "Mode sequences and event times" build/sweeps-reduced/README.md
# Error measures: every reduced table has them, finite where the run is ok and
# the states exist; the flags and the weak-reference verdicts follow their
# definitions; wall-time spread and pinning are recorded.
$PY - <<'PY'
import csv, glob, json, math, os, sys
sys.path.insert(0, "experiments")
import sweep
bad = []
cols = ["max_tool_position_error_mm", "rms_tool_position_error_mm", "max_tool_orientation_error_rad",
        "max_joint_error_rad", "max_current_error_A", "final_state_error", "below_reference_accuracy",
        "wall_time_median_s", "wall_time_min_s", "wall_time_max_s", "wall_time_iqr_s", "wall_times_s", "pinned_cpu"]
summaries = glob.glob("build/sweeps-reduced/results/*/*_summary.json")
if len(summaries) != len(glob.glob("experiments/sweeps/*.toml")):
    bad.append(f"{len(summaries)} summaries for {len(glob.glob('experiments/sweeps/*.toml'))} sweep files")
for path in summaries:
    s = json.load(open(path))
    name, rank = s["name"], s["rank_by"]
    with open(path.replace("_summary.json", ".csv")) as f:
        text = f.read()
    if f"# ranked by {rank['label']}" not in text:
        bad.append(f"{name}: the CSV does not say what it ranks by")
    rows = list(csv.DictReader(l for l in text.splitlines() if not l.startswith("#")))
    missing = [c for c in cols if c not in rows[0]]
    if missing:
        bad.append(f"{name}: columns missing: {missing}")
        continue
    for lab, a in s["agreement"].items():
        weak = [m for m, spec in s["measures"].items() if spec["target"] is not None
                and a[spec["column"]] > spec["target"] / s["weak_reference_factor"]]
        if sorted(weak) != sorted(a["reference_too_weak"]) or bool(weak) != (lab in s["reference_too_weak"]):
            bad.append(f"{name} {lab}: too weak {a['reference_too_weak']}, expected {weak}")
        with open(f"build/sweeps-reduced/{name}/{sweep.slug(lab)}/reference/trajectory.csv") as f:
            has_current = "i_motor1 [A]" in f.readline()
        if not all(math.isfinite(a[c]) for c in ("max_tool_position_error_mm", "max_tool_orientation_error_rad",
                                                 "max_joint_error_rad")) or math.isfinite(a["max_current_error_A"]) != has_current:
            bad.append(f"{name} {lab}: reference vs check not finite where it should be: {a}")
        for r in rows:
            if r["variant"] != lab or r["ok"] != "True":
                continue
            v = {c: float(r[c]) for c in cols[:6]}
            if not all(math.isfinite(v[c]) for c in cols[:4]) or math.isfinite(v["max_current_error_A"]) != has_current:
                bad.append(f"{name} {lab} {r['integrator']} {r['setting']}: error measures {v}")
            flag = float(r[rank["column"]]) <= s["below_reference_factor"] * a[rank["column"]]
            if r["below_reference_accuracy"] != str(flag):
                bad.append(f"{name} {lab} {r['integrator']} {r['setting']}: below_reference_accuracy "
                           f"{r['below_reference_accuracy']}, expected {flag}")
            walls = [float(w) for w in r["wall_times_s"].split()]
            if not (len(walls) == int(r["repeats"]) and float(r["wall_time_min_s"]) == min(walls)
                    <= float(r["wall_time_median_s"]) <= float(r["wall_time_max_s"]) == max(walls)):
                bad.append(f"{name} {lab} {r['integrator']} {r['setting']}: wall-time spread {r}")
            if hasattr(os, "sched_getaffinity") and r["pinned_cpu"] == "":
                bad.append(f"{name} {lab} {r['integrator']} {r['setting']}: not pinned to a CPU")
    if s["pinning"]["pinned_runs"] != sum(r["pinned_cpu"] != "" for r in rows):
        bad.append(f"{name}: summary pinning {s['pinning']} disagrees with the CSV")
# paper_slow's reference differs from its check by more than target/100 over
# the reduced horizon too: it must come out too weak, in summary and report.
s = json.load(open("build/sweeps-reduced/results/work_precision/paper_slow_summary.json"))
if "max_tool_position_error_mm" not in s["reference_too_weak"].get("base", {}):
    bad.append(f"paper_slow: reference not reported too weak: {s['agreement']}")
# The functions themselves, on hand-made numbers.
t = {"max_tool_position_error_mm": 5e-3, "max_joint_error_rad": 1e-4}
if sweep.reference_too_weak({"max_tool_position_error_mm": 2.3e-3, "max_joint_error_rad": 1e-7}, t) \
        != ["max_tool_position_error_mm"] or sweep.reference_too_weak(
            {"max_tool_position_error_mm": 4e-5, "max_joint_error_rad": math.nan}, t) != []:
    bad.append("reference_too_weak")
if (sweep.below_reference_accuracy(0.02, 2.3e-3), sweep.below_reference_accuracy(0.03, 2.3e-3),
        sweep.below_reference_accuracy(math.nan, 1.0)) != (True, False, None):
    bad.append("below_reference_accuracy")
qz = lambda a: (math.cos(a / 2), 0.0, 0.0, math.sin(a / 2))
if not (abs(sweep.rotation_angle(qz(0.1), qz(0.4)) - 0.3) < 1e-15
        and abs(sweep.rotation_angle(qz(0.1), [-c for c in qz(0.4)]) - 0.3) < 1e-15
        and abs(sweep.rotation_angle(qz(1e-12), qz(0.0)) - 1e-12) < 1e-24):
    bad.append("rotation_angle")
if bad:
    sys.exit("error measures:\n  " + "\n  ".join(bad))
PY
grep -q "ranked by" build/sweeps-reduced/README.md
grep -q "Reference too weak" build/sweeps-reduced/README.md
# rank_by: the same runs merged again, ranked by the joint-angle error.
sed -e 's/^target_mm = .*/&\nrank_by = "joint"\ntarget_joint_rad = 1e-4/' experiments/sweeps/paper_slow.toml \
  > build/sweeps-reduced/paper_slow_by_joint.toml
$PY experiments/sweep.py build/sweeps-reduced/paper_slow_by_joint.toml --reduced --merge \
  --out build/sweeps-reduced/by_joint > /dev/null
grep -q "^# ranked by max joint-angle error \[rad\] (max_joint_error_rad" build/sweeps-reduced/by_joint/paper_slow.csv
$PY - <<'PY'
import json, sys
s = json.load(open("build/sweeps-reduced/by_joint/paper_slow_summary.json"))
if s["rank_by"]["column"] != "max_joint_error_rad" or s["rank_by"]["target"] != 1e-4 or \
        any(p["error"] > 1e-4 for pts in s["cost_to_target"].values() for p in pts):
    sys.exit(f"rank_by joint: {s['rank_by']}, {s['cost_to_target']}")
PY
$PY experiments/observed_order.py --reduced --out build/sweeps-reduced/observed_order > /dev/null; test -s build/sweeps-reduced/observed_order/observed_order.csv
# The output grid must not change an adaptive run's cost (dense output; the
# instrument issue's criterion: within 5 %), and --stop-at-outputs must (else
# the comparison shows nothing).
$PY experiments/output_grid.py --reduced --out build/sweeps-reduced/output_grid \
  --work build/sweeps-reduced/output_grid-runs > /dev/null
$PY - <<'PY'
import csv, sys
rows = list(csv.DictReader(l for l in open("build/sweeps-reduced/output_grid/output_grid.csv") if not l.startswith("#")))
for r in rows:
    spread = float(r["rhs_spread_percent"])
    if (r["mode"] == "dense") != (spread <= 5):
        sys.exit(f"output grid: {r['integrator']} {r['mode']}: RHS spread {spread} %")
PY
echo "sweep pipeline: ok"
