#!/usr/bin/env python3
"""The friction axis's decision table: per friction law, the cheapest method
to each tool-position target, with the facts that explain it.

Reads the friction-axis sweep (experiments/sweeps/friction_axis.toml): its
merged table results/friction_axis/friction_axis.csv and summary (tracking
error and creep per law), and its reference runs' friction modes under
build/sweeps/friction_axis/<law>/reference/ (events.csv: the hybrid law's
exact modes; the other laws classified by speed, |w_m| <= 1e-3 rad/s, as
mode_sequence.py reads them). Runs `pumasim stiffness` once per law (the
scene with the law's --set values, over the whole run, 48 Jacobians) for
the largest spectral radius and the state of its mode.

For each law and each pair of targets (tool position and motor current
against the law's own reference: the sweep's 0.005 mm and 0.05 A, and both
ten times looser, 0.05 mm and 0.5 A): the finished run within both
with the least median wall time, and the one with the fewest right-hand
sides. The reason column states the facts, each from the data: the events
the cheapest run located (stick/slip switches: roots), the stiffness (the
fastest mode's time constant and state), and the failed runs of the
explicit and of the implicit methods (chattering: the implicit ones fail
too; stiff: only the explicit ones). Then what each law
predicts: the reference's tracking error, its stick time over the joints,
and the creep while the hybrid law holds a joint stuck.

Writes results/friction_axis/decision.md and decision.csv.
"""
import argparse
import csv
import json
import math
import os
import subprocess
import sys
import tempfile

import mode_sequence
from pumasim_exp import io as pumasim_io
from pumasim_exp.io import PUMASIM, ROOT
from pumasim_exp.specs import load_sweep

SPEC = os.path.join(ROOT, "experiments", "sweeps", "friction_axis.toml")
# (tool position [mm], motor current [A]): the sweep's targets, and both ten times looser.
TARGETS = ((5e-3, 5e-2), (5e-2, 5e-1))
FIELDS = ["variant", "target_mm", "target_current_A", "cheapest_wall", "wall_setting", "wall_time_median_s", "wall_rhs",
          "cheapest_rhs", "rhs_setting", "rhs_evaluations", "root_events", "spectral_radius_per_s", "fastest_state",
          "explicit_failed", "explicit_runs", "implicit_failed", "implicit_runs", "verdict",
          "reference_vs_check_mm", "tracking_mm",
          "stick_time_s", "creep_rad"]


def read_rows(path):
    with open(path) as f:
        return list(csv.DictReader(line for line in f if not line.startswith("#")))


def fnum(x):
    try:
        return float(x)
    except (TypeError, ValueError):
        return math.nan


def within(r, target, current):
    """Finished, within the tool-position target and within the motor-current target."""
    return (r["ok"] == "True" and fnum(r["max_tool_position_error_mm"]) <= target
            and fnum(r["max_current_error_A"]) <= current)


def stiffness(scene, variant):
    """(largest spectral radius [1/s], its fastest mode's state) over the run."""
    with tempfile.TemporaryDirectory() as tmp:
        out = os.path.join(tmp, "s.csv")
        cmd = [PUMASIM, "stiffness", scene, "--t-end", "24", "--samples", "48", "--csv", out]
        for k in variant.get("unset", []):
            cmd += ["--unset", k]
        for o in variant["set"]:
            cmd += ["--set", o]
        subprocess.run(cmd, check=True, capture_output=True, text=True, cwd=ROOT)
        rows = read_rows(out)
    best = max(rows, key=lambda r: fnum(r["spectral_radius [1/s]"]))
    return fnum(best["spectral_radius [1/s]"]), best["fastest_state"]


def stick_time(run_dir):
    """Time stuck, summed over the joints, in the run's friction modes (0 if it has none)."""
    with open(os.path.join(run_dir, "stats.json")) as f:
        t_end = float(json.load(f)["t_reached"])
    events = mode_sequence.read_events(run_dir)
    if not events:
        return 0.0
    total = 0.0
    for seq in mode_sequence.by_joint(events).values():
        for k, e in enumerate(seq):
            if e["mode"] == "stick":
                total += (seq[k + 1]["t"] if k + 1 < len(seq) else t_end) - e["t"]
    return total


def implicit_methods():
    """The registry's implicit methods (`pumasim integrators --json`)."""
    out = subprocess.run([PUMASIM, "integrators", "--json"], check=True, capture_output=True, text=True).stdout
    return {e["name"] for e in json.loads(out) if e["implicit"]}


def verdict(explicit_failed, explicit_runs, implicit_failed, implicit_runs):
    """Chattering when the implicit methods fail too; stiff when only the explicit ones do."""
    if implicit_runs and 2 * implicit_failed >= implicit_runs:
        return "chattering: most implicit runs fail too"
    if explicit_runs and 2 * explicit_failed >= explicit_runs:
        return "stiff: most explicit runs fail, most implicit ones finish"
    return ""


def reason(row):
    parts = []
    if row["root_events"]:
        parts.append(f"{row['root_events']} events located by the cheapest run")
    parts.append(f"fastest mode tau = {1 / row['spectral_radius_per_s']:.2g} s ({row['fastest_state']})")
    parts.append(f"failed: explicit {row['explicit_failed']} of {row['explicit_runs']}, implicit "
                 f"{row['implicit_failed']} of {row['implicit_runs']} runs")
    if row["verdict"]:
        parts.append(f"**{row['verdict']}**")
    if row["reference_vs_check_mm"] != "":
        parts.append(f"not conclusive: the law's reference and its cross-check differ by "
                     f"{row['reference_vs_check_mm']:.2g} mm, more than the sweep allows a reference (a hundredth of "
                     "the 0.005 mm target)")
    return "; ".join(parts)


def decide(rows, label, target, current, implicit):
    mine = [r for r in rows if r["variant"] == label]
    ok = [r for r in mine if within(r, target, current)]
    wall = min(ok, key=lambda r: fnum(r["wall_time_median_s"])) if ok else None
    rhs = min(ok, key=lambda r: fnum(r["rhs_evaluations"])) if ok else None
    exp = [r for r in mine if r["integrator"] not in implicit]
    imp = [r for r in mine if r["integrator"] in implicit]
    counts = {"explicit_failed": sum(1 for r in exp if r["ok"] != "True"), "explicit_runs": len(exp),
              "implicit_failed": sum(1 for r in imp if r["ok"] != "True"), "implicit_runs": len(imp)}
    return {"cheapest_wall": wall["integrator"] if wall else "", "wall_setting": wall["setting"] if wall else "",
            "wall_time_median_s": fnum(wall["wall_time_median_s"]) if wall else "",
            "wall_rhs": int(fnum(wall["rhs_evaluations"])) if wall else "",
            "cheapest_rhs": rhs["integrator"] if rhs else "", "rhs_setting": rhs["setting"] if rhs else "",
            "rhs_evaluations": int(fnum(rhs["rhs_evaluations"])) if rhs else "",
            "root_events": int(fnum(wall["root_events"])) if wall and not math.isnan(fnum(wall["root_events"]))
            else 0, **counts, "verdict": verdict(*counts.values())}


def gather(results_dir, work):
    s = load_sweep(SPEC, reduced=False)
    rows = read_rows(os.path.join(results_dir, "friction_axis.csv"))
    with open(os.path.join(results_dir, "friction_axis_summary.json")) as f:
        summary = json.load(f)
    scene = os.path.join(ROOT, "experiments", "scenes", s["scene"] + ".toml")
    implicit = implicit_methods()
    out = []
    for v in s["variants"]:
        label = v["label"]
        if not any(r["variant"] == label for r in rows):
            continue
        rho, state = stiffness(scene, v)
        weak = summary["reference_too_weak"].get(label, {}).get("max_tool_position_error_mm")
        facts = {"spectral_radius_per_s": rho, "fastest_state": state,
                 "reference_vs_check_mm": weak["difference"] if weak else "",
                 "tracking_mm": summary["agreement"].get(label, {}).get("tracking_mm", ""),
                 "stick_time_s": stick_time(os.path.join(work, label, "reference")),
                 "creep_rad": summary["creep"].get(label, {}).get("rad", "")}
        for target, current in TARGETS:
            out.append({"variant": label, "target_mm": target, "target_current_A": current,
                        **decide(rows, label, target, current, implicit), **facts})
    return out


def fmt(v, spec):
    return "–" if v == "" else format(v, spec)


def readme(rows, cmd):
    lines = ["# The friction axis: which method for which law", "",
             f"Generated by `{cmd}` into `decision.csv` from `friction_axis.csv` and its summary (the sweep "
             "`experiments/sweeps/friction_axis.toml`); every number below is read from `decision.csv`.", "",
             "Per law and pair of targets (max tool position error and max motor-current error against the "
             "law's own reference: the sweep's 0.005 mm and 0.05 A, and both ten times looser): the finished "
             "run within both with the least median wall time, and the one with the fewest right-hand sides. "
             "Reason: the events its cheapest run located, the fastest mode along the run (`pumasim "
             "stiffness`, the largest spectral radius of the exact Jacobian over 48 samples), and how many of "
             "the law's runs failed (a step budget, or unstable), explicit methods against implicit ones: the "
             "verdict reads chattering when most implicit runs fail too, stiff when only the explicit ones do.",
             "",
             "| law | targets [mm, A] | least wall time: method (setting), wall [s] | fewest RHS: method (setting), "
             "RHS | reason |", "|---|---:|---|---|---|"]
    for r in rows:
        wall = (f"`{r['cheapest_wall']}` ({r['wall_setting']}), {fmt(r['wall_time_median_s'], '.3g')}"
                if r["cheapest_wall"] else "none within the target")
        rhs = (f"`{r['cheapest_rhs']}` ({r['rhs_setting']}), {r['rhs_evaluations']:,}" if r["cheapest_rhs"]
               else "–")
        lines.append(f"| {r['variant']} | {r['target_mm']:g}, {r['target_current_A']:g} | {wall} | {rhs} | "
                     f"{reason(r)} |")
    lines += ["", "## What each law predicts", "",
              "From `results/friction_axis/decision.csv`, the law's reference run: its tracking error (tool position against the planned path), the time "
              "its joints spend stuck (summed over the six; hybrid: its exact modes, the others classified by "
              "speed), and the creep, the largest joint motion while the hybrid law holds that joint stuck. "
              "Moreau-Jean solves the hybrid law's set-valued friction: its reference is the hybrid one.", "",
              "| law | tracking error [mm] | stick time [s] | creep [rad] |", "|---|---:|---:|---:|"]
    for r in rows[::len(TARGETS)]:
        lines.append(f"| {r['variant']} | {fmt(r['tracking_mm'], '.4g')} | {r['stick_time_s']:.3g} | "
                     f"{fmt(r['creep_rad'], '.3g')} |")
    return "\n".join(lines) + "\n"


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--results", default=os.path.join(ROOT, "results", "friction_axis"))
    ap.add_argument("--work", default=os.path.join(ROOT, "build", "sweeps", "friction_axis"))
    args = ap.parse_args()
    rows = gather(args.results, args.work)
    pumasim_io.write_table(os.path.join(args.results, "decision.csv"), rows, FIELDS, lineterminator="\n")
    pumasim_io.write_text_atomic(os.path.join(args.results, "decision.md"),
                                 readme(rows, "experiments/friction_decision.py"))
    return 0


if __name__ == "__main__":
    sys.exit(main())
