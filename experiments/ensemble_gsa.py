#!/usr/bin/python3
"""Sobol indices of an ensemble's outputs over its factors (issue 35): the Saltelli design of
experiments/pumasim_exp/gsa.py on the ensemble file's [[vary]] factors (uniform, log-uniform, normal),
run by `pumasim ensemble --table`, and Jansen's first-order and total indices of each chosen output
column with bootstrap confidence (SALib's names: S1, S1_conf, ST, ST_conf).

    /usr/bin/python3 experiments/ensemble_gsa.py ENSEMBLE.toml [--n 256] [--outputs max_path_error,...]
        [--bin build/release/bin/pumasim] [--seed 1] [--out results/ensembles/NAME_sobol] [--range KEY=LOW:HIGH]

Writes OUT.json and OUT.md. N (a power of 2) is the Saltelli base size: N (d + 2) runs. When some runs
fail (a failed run has no outputs), the indices are those of the failure indicator `failed` instead.
"""
import argparse
import csv
import json
import os
import subprocess
import sys
import tempfile
import tomllib

import numpy as np

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from pumasim_exp import gsa  # noqa: E402

ROOT = os.path.normpath(os.path.join(os.path.dirname(os.path.abspath(__file__)), ".."))


def factors_of(path):
    with open(path, "rb") as fh:
        doc = tomllib.load(fh)
    factors = doc.get("vary", [])
    if not factors:
        sys.exit(f"ensemble_gsa: {path} has no [[vary]] factors")
    return factors


def with_ranges(factors, ranges):
    """The factors with each --range KEY=LOW:HIGH given in place of the file's low and high."""
    for text in ranges:
        key, _, bounds = text.partition("=")
        low, _, high = bounds.partition(":")
        f = next((f for f in factors if f["key"] == key and "low" in f), None)
        if f is None:
            sys.exit(f"ensemble_gsa: --range {text}: expected KEY=LOW:HIGH for a uniform or log-uniform factor")
        try:
            f["low"], f["high"] = float(low), float(high)
        except ValueError:
            sys.exit(f"ensemble_gsa: --range {text}: expected KEY=LOW:HIGH with numbers")
        f["range_given"] = True
    return factors


def ranged(factors):
    given = [f"{f['key']} from {f['low']:g} to {f['high']:g}" for f in factors if f.get("range_given")]
    return f" (with {', '.join(given)}, the --range given)" if given else ""


def first_failure(rows):
    row = next(r for r in rows if r["ok"] != "1")
    return f"sample {row['sample']}: {row['failure']}"


def output_columns(rows, outputs):
    """(failed runs, [(name, values)]): each output column's values, or, when some runs failed (a failed run
    has no outputs), the one column `failed`, 1 for a failed run and 0 else."""
    for col in outputs:
        if col not in rows[0]:
            sys.exit(f"ensemble_gsa: no output column '{col}'; expected one of: {', '.join(rows[0])}")
    failed = np.array([row["ok"] != "1" for row in rows], dtype=float)
    if failed.any():
        return int(failed.sum()), [("failed", failed)]
    return 0, [(col, np.array([float(row[col]) for row in rows])) for col in outputs]


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("ensemble")
    ap.add_argument("--n", type=int, default=256)
    ap.add_argument("--outputs", default="max_path_error,rms_path_error,steps")
    ap.add_argument("--bin", default=os.path.join(ROOT, "build", "release", "bin", "pumasim"))
    ap.add_argument("--seed", type=int, default=1)
    ap.add_argument("--bootstrap", type=int, default=1000)
    ap.add_argument("--out", default=None)
    ap.add_argument("--range", action="append", default=[], metavar="KEY=LOW:HIGH",
                    help="a uniform or log-uniform factor's range in place of the file's")
    args = ap.parse_args()
    name = os.path.splitext(os.path.basename(args.ensemble))[0]
    out = args.out or os.path.join(ROOT, "results", "ensembles", name + "_sobol")
    factors = with_ranges(factors_of(args.ensemble), args.range)
    d = len(factors)
    try:
        a, b, ab = gsa.saltelli(d, args.n, seed=args.seed)
        points = np.concatenate([a, b, ab.reshape(-1, d)])
        values = gsa.to_factors(points, factors)
    except gsa.GsaError as e:
        sys.exit(f"ensemble_gsa: {e}")
    with tempfile.TemporaryDirectory(prefix="pumasim_gsa_") as work:
        table = os.path.join(work, "design.csv")
        with open(table, "w", newline="") as fh:
            w = csv.writer(fh)
            w.writerow([f["key"] for f in factors])
            for row in values:
                w.writerow([f"{v:.17g}" for v in row])
        result = os.path.join(work, "runs.csv")
        r = subprocess.run([args.bin, "ensemble", args.ensemble, "--table", table, "--out", result, "-q"],
                           capture_output=True, text=True)
        if r.returncode != 0:
            sys.exit(f"ensemble_gsa: pumasim ensemble exit status {r.returncode}: {r.stderr.strip()}")
        with open(result) as fh:
            rows = list(csv.DictReader(fh))
        with open(result[:-4] + ".json") as fh:
            meta = json.load(fh)
    n = args.n
    doc = {"ensemble": os.path.relpath(args.ensemble, ROOT), "n": n, "runs": len(rows), "seed": args.seed,
           "factors": factors, "build": meta["build"], "wall_time": meta["wall_time"],
           "written_by": "experiments/ensemble_gsa.py", "indices": {}}
    md = ["<!-- Generated by experiments/ensemble_gsa.py; do not edit. -->",
          f"# Sobol indices: {name}", "",
          f"`{doc['ensemble']}`'s factors{ranged(factors)}, Saltelli design with N = {n} ({len(rows)} runs, seed {args.seed}), "
          f"Jansen's estimators, 95 % bootstrap half-widths ({args.bootstrap} resamples). Build: {meta['build']}; "
          f"the runs took {meta['wall_time']:.1f} s on {meta['threads']} threads.", ""]
    failures, sections = output_columns(rows, [c.strip() for c in args.outputs.split(",") if c.strip()])
    doc["failed_runs"] = failures
    if failures:
        md += [f"{failures} of {len(rows)} runs failed (first: {first_failure(rows)}). A failed run has no "
               "outputs, so the outputs' indices are not computed; the indices of `failed` (1 for a failed run, "
               "0 else) say which factors decide whether a run fails.", ""]
    for col, y in sections:
        try:
            ind = gsa.sobol_indices(y[:n], y[n:2 * n], y[2 * n:].reshape(d, n), bootstrap=args.bootstrap, seed=args.seed)
        except gsa.GsaError as e:
            md += [f"## {col}", "", f"No indices: {e}.", ""]
            continue
        doc["indices"][col] = {k: v.tolist() for k, v in ind.items()}
        md += [f"## {col}", "", "| factor | S1 | S1_conf | ST | ST_conf |", "|---|---|---|---|---|"]
        for i, f in enumerate(factors):
            md.append(f"| {f['key']} | {ind['S1'][i]:.3f} | {ind['S1_conf'][i]:.3f} | {ind['ST'][i]:.3f} | "
                      f"{ind['ST_conf'][i]:.3f} |")
        md.append("")
    os.makedirs(os.path.dirname(out), exist_ok=True)
    with open(out + ".json", "w") as fh:
        json.dump(doc, fh, indent=2)
        fh.write("\n")
    with open(out + ".md", "w") as fh:
        fh.write("\n".join(md))
    print("\n".join(md))


if __name__ == "__main__":
    main()
