#!/usr/bin/env python3
"""Two builds of a Google Benchmark binary, interleaved: is the new one slower?

Runs OLD and NEW in turn (OLD, NEW, NEW, OLD, ... so that neither always goes
first), --rounds times each, with the same --benchmark_filter, and prints for
every benchmark the median time per iteration of each and their ratio
new / old, with the spread of the per-round ratios (min, max). On a shared,
noisy machine only a ratio well outside that spread means anything.

    scripts/ab_bench.py --old /tmp/base/build/release/bin/bench_plant \\
        --new build/release/bin/bench_plant --filter 'rhs/|fd/' --rounds 7
"""
import argparse
import json
import statistics
import subprocess
import sys


def run(binary, flt, min_time):
    cmd = [binary, f"--benchmark_filter={flt}", "--benchmark_format=json", f"--benchmark_min_time={min_time}"]
    out = subprocess.run(cmd, capture_output=True, text=True, check=True).stdout
    return {b["name"]: b["real_time"] for b in json.loads(out)["benchmarks"] if b.get("run_type") == "iteration"}


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--old", required=True)
    ap.add_argument("--new", required=True)
    ap.add_argument("--filter", default=".")
    ap.add_argument("--rounds", type=int, default=7)
    ap.add_argument("--min-time", default="0.2", help="--benchmark_min_time per run [s]")
    args = ap.parse_args()
    times = {"old": [], "new": []}
    for r in range(args.rounds):
        order = ("old", "new") if r % 2 == 0 else ("new", "old")
        for tag in order:
            times[tag].append(run(getattr(args, tag), args.filter, args.min_time))
    names = [n for n in times["old"][0] if n in times["new"][0]]
    print(f"{'benchmark':40s} {'old [ns]':>10s} {'new [ns]':>10s} {'new/old':>8s}  per-round range")
    for n in names:
        o = [t[n] for t in times["old"]]
        w = [t[n] for t in times["new"]]
        ratios = [b / a for a, b in zip(o, w)]
        print(f"{n:40s} {statistics.median(o):10.1f} {statistics.median(w):10.1f} "
              f"{statistics.median(w) / statistics.median(o):8.3f}  [{min(ratios):.3f}, {max(ratios):.3f}]")
    return 0


if __name__ == "__main__":
    sys.exit(main())
