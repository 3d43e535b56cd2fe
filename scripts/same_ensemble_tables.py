#!/usr/bin/python3
"""Whether two ensemble tables hold the same rows in every field but wall_time (a merge of shards
against the single process's table: tests/check_ensemble_shards.sh, scripts/slurm_one_node.sh).

    /usr/bin/python3 scripts/same_ensemble_tables.py WHOLE.csv MERGED.csv [--samples N]

Exit status 0 when they are the same (and, with --samples, hold N rows), else 1 with the first
line that differs.
"""
import argparse
import csv
import sys


def rows(path):
    with open(path, newline="") as f:
        r = list(csv.reader(f))
    w = r[0].index("wall_time")
    return [row[:w] + row[w + 1:] for row in r]


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("whole")
    ap.add_argument("merged")
    ap.add_argument("--samples", type=int, default=None)
    args = ap.parse_args()
    a, b = rows(args.whole), rows(args.merged)
    if args.samples is not None and len(a) != args.samples + 1:
        sys.exit(f"expected a header and {args.samples} rows, got {len(a)} rows")
    if a != b:
        bad = next(i for i in range(max(len(a), len(b))) if i >= len(a) or i >= len(b) or a[i] != b[i])
        sys.exit(f"the merged table differs from the single process's at line {bad + 1}")
    print(f"{len(b) - 1} samples, the same in every field but wall_time")


if __name__ == "__main__":
    main()
