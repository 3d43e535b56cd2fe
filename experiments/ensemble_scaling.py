#!/usr/bin/python3
"""Ensemble scaling and overhead (issue 35): N samples of paper_slow_viscous (t_end 4 s, cvode-bdf at
rtol 1e-6, the drive parameters of experiments/ensembles/paper_slow_viscous_drive.toml), run serially
and on every core, as interleaved pairs; the median ratio of the ensemble's wall-clock times, and the
set-up and output per sample against the integration's own time (the runs' wall_time column).

    /usr/bin/python3 experiments/ensemble_scaling.py [--bin build/release/bin/pumasim] [--samples 1000]
        [--pairs 5] [--out results/ensembles]

Then the overhead's two parts: serial runs at output intervals of 0.01 s (the scene's), 0.05 s and
0.2 s (400, 80 and 20 rows per sample), interleaved, --repeats each; a least-squares line through the
median overhead per sample against the rows per sample gives the set-up per sample (its intercept) and
the cost of an output row (its slope: the flange pose, the path error and deviation, the drive signals).

Writes OUT/scaling.json and OUT/scaling.md (the figures, the machine's cores and its load average
before and after: the machine is shared, and a loaded one scales less).
"""
import argparse
import csv
import json
import os
import statistics
import subprocess
import sys
import tempfile

ROOT = os.path.normpath(os.path.join(os.path.dirname(os.path.abspath(__file__)), ".."))
SPEC = os.path.join(ROOT, "experiments", "ensembles", "paper_slow_viscous_drive.toml")


def one(binary, spec, threads, work):
    out = os.path.join(work, f"t{threads}.csv")
    r = subprocess.run([binary, "ensemble", spec, "--threads", str(threads), "--out", out, "--force", "-q"],
                       capture_output=True, text=True)
    if r.returncode != 0:
        sys.exit(f"ensemble_scaling: {binary} ensemble exit status {r.returncode}: {r.stderr.strip()}")
    with open(out[:-4] + ".json") as fh:
        meta = json.load(fh)
    with open(out) as fh:
        rows = list(csv.DictReader(fh))
    failed = sum(row["ok"] != "1" for row in rows)
    if failed:
        sys.exit(f"ensemble_scaling: {failed} of {len(rows)} samples failed")
    integration = sum(float(row["wall_time"]) for row in rows)
    return meta["wall_time"], integration, len(rows)


INTERVALS = (0.01, 0.05, 0.2)  # [s] output intervals: the scene's, then fewer rows
T_END = 4.0  # [s] the spec's [run] t_end


def rows_split(args, text, work):
    """Serial runs at each output interval, interleaved: median overhead per sample [s] and rows."""
    specs = {}
    for dt in INTERVALS:
        marker = "seed = 1999\n"
        assert marker in text, "the ensemble file's seed line moved"
        specs[dt] = os.path.join(work, f"rows_{dt}.toml")
        with open(specs[dt], "w") as fh:
            fh.write(text.replace(marker, marker + f'set = ["scene.output_interval={dt}"]\n', 1))
    runs = {dt: [] for dt in INTERVALS}
    for _ in range(args.repeats):
        for dt in INTERVALS:
            wall, integration, n = one(args.bin, specs[dt], 1, work)
            runs[dt].append({"wall": wall, "integration": integration,
                             "overhead_per_sample_s": (wall - integration) / n, "ratio": (wall - integration) / integration})
    out = []
    for dt in INTERVALS:
        out.append({"output_interval_s": dt, "rows_per_sample": round(T_END / dt) + 1, "runs": runs[dt],
                    "median_overhead_per_sample_s": statistics.median(r["overhead_per_sample_s"] for r in runs[dt]),
                    "median_ratio": statistics.median(r["ratio"] for r in runs[dt])})
    xs = [o["rows_per_sample"] for o in out]
    ys = [o["median_overhead_per_sample_s"] for o in out]
    mx, my = statistics.fmean(xs), statistics.fmean(ys)
    slope = sum((x - mx) * (y - my) for x, y in zip(xs, ys)) / sum((x - mx) ** 2 for x in xs)
    return {"points": out, "per_row_s": slope, "setup_per_sample_s": my - slope * mx}


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--bin", default=os.path.join(ROOT, "build", "release", "bin", "pumasim"))
    ap.add_argument("--samples", type=int, default=1000)
    ap.add_argument("--pairs", type=int, default=5)
    ap.add_argument("--out", default=os.path.join(ROOT, "results", "ensembles"))
    ap.add_argument("--repeats", type=int, default=3)
    args = ap.parse_args()
    cores = os.cpu_count() or 1
    build = subprocess.run([args.bin, "--version"], capture_output=True, text=True).stdout.strip()
    load_before = os.getloadavg()
    with tempfile.TemporaryDirectory(prefix="pumasim_scaling_") as work:
        spec = os.path.join(work, "spec.toml")
        with open(SPEC) as fh:
            text = fh.read()
        text = text.replace('scene = "../scenes/', 'scene = "' + os.path.join(ROOT, "experiments", "scenes") + "/")
        text = text.replace("samples = 64", f"samples = {args.samples}")
        with open(spec, "w") as fh:
            fh.write(text)
        pairs = []
        intervals = rows_split(args, text, work)
        for _ in range(args.pairs):
            s_wall, s_int, n = one(args.bin, spec, 1, work)
            p_wall, p_int, _ = one(args.bin, spec, cores, work)
            pairs.append({"serial_wall": s_wall, "serial_integration": s_int, "parallel_wall": p_wall,
                          "parallel_integration": p_int, "ratio": p_wall / s_wall,
                          "overhead": (s_wall - s_int) / s_int})
    load_after = os.getloadavg()
    ratio = statistics.median(p["ratio"] for p in pairs)
    overhead = statistics.median(p["overhead"] for p in pairs)
    per_sample_int = statistics.median(p["serial_integration"] for p in pairs) / args.samples
    per_sample_wall = statistics.median(p["serial_wall"] for p in pairs) / args.samples
    doc = {"samples": args.samples, "pairs": pairs, "cores": cores, "threads": cores,
           "median_ratio_parallel_to_serial": ratio, "median_overhead_serial": overhead,
           "median_integration_per_sample_s": per_sample_int, "median_wall_per_sample_serial_s": per_sample_wall,
           "load_average_before": load_before, "load_average_after": load_after, "output_rows": intervals,
           "build": build, "written_by": "experiments/ensemble_scaling.py"}
    os.makedirs(args.out, exist_ok=True)
    with open(os.path.join(args.out, "scaling.json"), "w") as fh:
        json.dump(doc, fh, indent=2)
        fh.write("\n")
    md = [
        "<!-- Generated by experiments/ensemble_scaling.py; do not edit. -->",
        "# Ensemble scaling and overhead",
        "",
        f"{args.samples} samples of paper_slow_viscous (t_end 4 s, cvode-bdf at rtol 1e-6, the drive parameters of "
        "`experiments/ensembles/paper_slow_viscous_drive.toml`), `pumasim ensemble` with 1 thread and with "
        f"{cores} (the machine's cores), {args.pairs} interleaved pairs. Load average (1, 5, 15 min) before: "
        + ", ".join(f"{x:.2f}" for x in load_before) + "; after: " + ", ".join(f"{x:.2f}" for x in load_after)
        + f". Binary: {build}.",
        "",
        "| pair | serial wall [s] | parallel wall [s] | parallel / serial | serial set-up and output / integration |",
        "|---|---|---|---|---|",
    ]
    for k, p in enumerate(pairs):
        md.append(f"| {k + 1} | {p['serial_wall']:.3f} | {p['parallel_wall']:.3f} | {p['ratio']:.3f} | "
                  f"{p['overhead']:.2f} |")
    md += ["", f"- Median parallel / serial: {ratio:.3f}.",
           f"- Median set-up and output per sample, against the integration's own time (serial runs): {overhead:.2f}.",
           f"- Per sample (serial, medians): {1e3 * per_sample_wall:.2f} ms in all.",
           f"- Of which integrating: {1e3 * per_sample_int:.2f} ms.", "",
           "## Set-up and output rows",
           "",
           f"Serial runs at three output intervals, {args.repeats} each, interleaved (the integration's steps do not "
           "stop at outputs, so only the rows change):",
           "",
           "| output interval [s] | rows per sample | set-up and output per sample [ms] | against the integration |",
           "|---|---|---|---|"]
    for o in intervals["points"]:
        md.append(f"| {o['output_interval_s']} | {o['rows_per_sample']} | "
                  f"{1e3 * o['median_overhead_per_sample_s']:.3f} | {o['median_ratio']:.2f} |")
    md += ["", f"- Least squares through the medians: {1e6 * intervals['setup_per_sample_s']:.0f} us of set-up per "
           f"sample and {1e6 * intervals['per_row_s']:.2f} us per output row.", ""]
    with open(os.path.join(args.out, "scaling.md"), "w") as fh:
        fh.write("\n".join(md))
    print("\n".join(md))


if __name__ == "__main__":
    main()
