#!/usr/bin/python3
"""The joint-torque regressor's table: its cost both ways and the base parameters.

Runs bench_identification (the regressor, direct and by probing, and the RNEA,
in one run: ratios within it) and `pumasim base-parameters --json` on the
PUMA 560 and the Panda with and without the rotor and friction columns, and
writes results/identification/regressor.md and the benchmark's JSON beside it.

  experiments/regressor_table.py --bench BIN/bench_identification --bin BIN/pumasim [--out DIR] [--quick]
"""
import argparse
import json
import os
import subprocess
import sys
import tempfile

ROBOTS = ("puma560", "panda", "random12", "random24")
COLUMN_SETS = (("rigid links", ["--no-rotor", "--no-friction"]), ("+ rotors", ["--no-friction"]),
               ("+ friction", ["--no-rotor"]), ("+ rotors + friction", []))


def repetitions(quick):
    return 2 if quick else 5


def bench(binary, quick, json_path):
    reps = [f"--benchmark_repetitions={repetitions(quick)}",
            "--benchmark_min_time=0.01" if quick else "--benchmark_min_time=0.2"]
    subprocess.run([binary, *reps, "--benchmark_report_aggregates_only=true",
                    f"--benchmark_out={json_path}", "--benchmark_out_format=json"],
                   check=True, stdout=subprocess.DEVNULL)
    with open(json_path, encoding="utf-8") as f:
        doc = json.load(f)
    rows = {}
    for b in doc["benchmarks"]:
        if b.get("aggregate_name") != "median":
            continue
        _, robot, way = b["run_name"].split("/")
        rows.setdefault(robot, {})[way] = b
    return doc["context"], rows


def base_counts(pumasim, robot):
    out = {}
    for label, flags in COLUMN_SETS:
        r = subprocess.run([pumasim, "base-parameters", robot, "--json", *flags], check=True,
                           capture_output=True, text=True)
        out[label] = json.loads(r.stdout)
    return out


def cost_section(context, rows, reps):
    lines = ["## Cost: direct against probing\n",
             "One evaluation of Y(q, qd, qdd) with the rotor and friction columns (14 per joint), at a fixed "
             f"random state; `id` is one inverse dynamics (the RNEA) of the same arm. Medians of {reps} repetitions "
             f"of `bench_identification` ({context.get('pumasim_build_type', '?')}, flags "
             f"`{context.get('pumasim_flags', '?')}`, revision {context.get('pumasim_git_revision', '?')}, "
             f"{context.get('num_cpus', '?')} CPUs at {context.get('mhz_per_cpu', '?')} MHz).\n",
             "| robot | n | columns | direct [ns] | probing [ns] | probing / direct | direct / id |",
             "|---|---|---|---|---|---|---|"]
    for robot in ROBOTS:
        r = rows[robot]
        d, p, i = (r[w]["real_time"] for w in ("direct", "probing", "id"))
        lines.append(f"| {robot} | {int(r['direct']['n'])} | {int(r['direct']['columns'])} | {d:.0f} | {p:.0f} | "
                     f"{p / d:.1f} | {d / i:.1f} |")
    lines.append("\nProbing computes the joint transforms once, then runs one RNEA pass per column on a chain "
                 "whose parameters are that column's unit vector (the paper's probing for H, applied to the "
                 "parameters, as the rnea-probing-shared back-end does it); the direct form shares one outward "
                 "pass and carries each link's 6 x 10 wrench block inwards.\n")
    return lines


def base_section(robot, counts):
    lines = [f"## Base parameters: {robot}\n",
             f"`pumasim base-parameters {robot}` (rank tolerance {counts['rigid links']['tolerance']:g} of the "
             f"largest singular value of the column-scaled regressor at {counts['rigid links']['samples']} "
             "random states; the gap is the smallest kept singular value over the largest dropped).\n",
             "| columns | standard | base | gap |", "|---|---|---|---|"]
    for label, _ in COLUMN_SETS:
        c = counts[label]
        gap = "inf" if c["gap"] is None else f"{c['gap']:.2g}"
        lines.append(f"| {label} | {len(c['columns'])} | {c['rank']} | {gap} |")
    full = counts["+ rotors"]
    lines.append(f"\nWith the rotors, the regrouping and the shipped {robot}'s values (SI units; inertias about "
                 "the joint frames' origins, first moments in them):\n")
    lines.append("```")
    for b in full["base"]:
        text = b["name"] if b["name"] == b["definition"] else f"{b['name']} = {b['definition']}"
        lines.append(f"{text}    [{b['value']:.6g}]")
    lines.append("no effect: " + " ".join(full["no_effect"]))
    lines.append("```\n")
    return lines


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--bench", required=True)
    ap.add_argument("--bin", required=True, help="the pumasim binary")
    ap.add_argument("--out", default="results/identification")
    ap.add_argument("--quick", action="store_true", help="short benchmark runs (a smoke test)")
    a = ap.parse_args()
    os.makedirs(a.out, exist_ok=True)
    fd, tmp_json = tempfile.mkstemp(suffix=".json", dir=a.out, prefix=".regressor_bench.")
    os.close(fd)
    try:
        context, rows = bench(a.bench, a.quick, tmp_json)
        lines = ["# The joint-torque regressor\n",
                 "tau = Y(q, qd, qdd) pi with 10 inertial parameters per link (XX XY XZ YY YZ ZZ about the "
                 "joint frame's origin, MX MY MZ, M), the rotor inertia Ia = Z^2 Im and viscous, Coulomb and "
                 "offset friction (Fv, Fc, Fo) per joint: `models/dynamics/regressor.hpp`, base parameters in "
                 "`models/robot/base_parameters.hpp`. Generated by `scripts/results.sh identification` "
                 "(experiments/regressor_table.py); do not edit.\n"]
        lines += cost_section(context, rows, repetitions(a.quick))
        for robot in ("puma560", "panda"):
            lines += base_section(robot, base_counts(a.bin, robot))
        lines.append("The PUMA's and the Panda's counts follow Khalil's grouping rules, worked out in "
                     "tests/test_regressor.cpp (BaseParameters.CountsFollowKhalilsGroupingRules), which "
                     "asserts them.\n")
        md = os.path.join(a.out, "regressor.md")
        with open(md + ".tmp", "w", encoding="utf-8") as f:
            f.write("\n".join(lines))
        os.replace(md + ".tmp", md)
        os.chmod(tmp_json, 0o644)
        os.replace(tmp_json, os.path.join(a.out, "regressor_bench.json"))
    finally:
        if os.path.exists(tmp_json):
            os.remove(tmp_json)
    return 0


if __name__ == "__main__":
    sys.exit(main())
