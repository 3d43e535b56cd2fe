#!/usr/bin/python3
"""How far the shipped Panda (models/robots/panda.toml: the per-link set p^ of
Gaz et al. 2019's supplementary Tables VIII/IX) is from the authors' own
model code, which holds their least-squares coefficients pi^_R-E instead
(tests/reference/panda_gaz2019_authors_code.json: the numbers, with the
repository, commit, files and how they were computed).

    /usr/bin/python3 experiments/panda_vs_authors.py [PUMASIM] [--out results/panda/authors_code_difference.md]

Prints, per configuration, the largest |difference| in H(q), g(q) and
C(q, qd) qd, and the largest |value| for scale, from `pumasim dynamics --robot
panda --backend crba`. (The friction law is the same set in both:
tests/test_reference_values.cpp checks it against the authors' code to 1e-15.)
"""
import argparse
import json
import os
import subprocess
import sys

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
REF = os.path.join(ROOT, "tests", "reference", "panda_gaz2019_authors_code.json")


def dynamics(pumasim, q, qd=None):
    cmd = [pumasim, "dynamics", "--robot", "panda", "--backend", "crba", "--q=" + ",".join(map(repr, q))]
    if qd is not None:
        cmd.append("--qd=" + ",".join(map(repr, qd)))
    return json.loads(subprocess.run(cmd, capture_output=True, text=True, check=True).stdout)


def biggest(a):
    return max(abs(x) for row in a for x in (row if isinstance(row, list) else [row]))


def diff(a, b):
    if isinstance(a[0], list):
        return max(abs(x - y) for ra, rb in zip(a, b) for x, y in zip(ra, rb))
    return max(abs(x - y) for x, y in zip(a, b))


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("pumasim", nargs="?", default=os.path.join(ROOT, "build", "release", "bin", "pumasim"))
    ap.add_argument("--out", help="also write the table to this file, and its numbers to the same name with .json")
    a = ap.parse_args()
    ref = json.load(open(REF))
    cfg = ref["configurations"]
    lines = ["# The shipped Panda against the authors' model code", "",
             "`models/robots/panda.toml` holds p^ (Gaz et al. 2019, supplementary Tables VIII/IX); the authors'",
             f"model code ({ref['repository']}, commit {ref['commit'][:8]}) holds pi^_R-E (supplementary Table III,",
             "column 2). Largest |pumasim - authors' code| over the entries, with the largest |entry| of the",
             "authors' values for scale. Written by `experiments/panda_vs_authors.py` (stage panda of `scripts/results.sh`),",
             "the numbers in full in `results/panda/authors_code_difference.json`.", "",
             "| quantity | configuration | max abs difference | max abs value |", "|---|---|---|---|"]
    rows = []
    for k in ["q_a", "q_b", "q_c", "q_d"]:
        d = dynamics(a.pumasim, cfg[k])
        rows.append(("H(q) [kg m^2]", k, diff(d["mass_matrix"], ref["mass_matrix"][k]), biggest(ref["mass_matrix"][k])))
        rows.append(("g(q) [N m]", k, diff(d["gravity"], ref["gravity_vector"][k]), biggest(ref["gravity_vector"][k])))
    for q, qd in [("q_b", "qd_b"), ("q_c", "qd_c")]:
        d = dynamics(a.pumasim, cfg[q], cfg[qd])
        cqd = [h - g for h, g in zip(d["bias"], d["gravity"])]
        r = ref["coriolis_times_qd"][f"{q}_{qd}"]
        rows.append(("C(q, qd) qd [N m]", f"{q}, {qd}", diff(cqd, r), biggest(r)))
    for what, where, dv, big in rows:
        lines.append(f"| {what} | {where} | {dv:.3g} | {big:.3g} |")
    text = "\n".join(lines) + "\n"
    sys.stdout.write(text)
    if a.out:
        with open(a.out, "w") as f:
            f.write(text)
        with open(os.path.splitext(a.out)[0] + ".json", "w") as f:
            json.dump([{"quantity": w, "configuration": c, "max_abs_difference": dv, "max_abs_value": big}
                       for w, c, dv, big in rows], f, indent=1)
            f.write("\n")


if __name__ == "__main__":
    main()
