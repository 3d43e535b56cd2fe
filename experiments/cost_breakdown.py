#!/usr/bin/python3
"""Cost breakdown of two runs: where the integration's wall time goes.

The scenes (issue 17):
  6-joint hybrid scene, cvode-adams at rtol 1e-3:
    pumasim run experiments/scenes/paper_slow_6dof_hybrid.toml --integrator cvode-adams --rtol 1e-3
  3-joint paper scene, the paper's rule, AB2 at 0.5 ms:
    pumasim run experiments/scenes/paper_slow.toml --integrator ab2 --dt 5e-4

For each, three measurements:
  1. the normal (release) build, run --repeats times: the integration wall time
     (stats.json, the fastest run) and the counts (f, steps, Jacobians); and
     the process around the run: each process's wall from start to exit
     against its own wall_time_s (the median of the runs' ratios);
  2. the profiled build (preset "profile", option PUMASIM_PROFILE: timers in
     the plant and the driver, models/plant/profile.hpp), run --repeats
     times, each entry's smallest value over the runs kept: exclusive time per context
     (the integrator's own work between its calls into the plant, f, the exact
     Jacobian, the root functions, the discrete events, the output) and part
     (reference, controller, drive, friction, dynamics, the rest);
  3. with perf (if installed and allowed), the normal build sampled over the
     --repeats runs: the integrator's own work (SUNDIALS, and the Newton
     systems' LU and matrix operations in integrators/sundials_dense_lu.cpp)
     split by symbol (dense LU and solve, matrix copies, vector operations and
     norms, the rest).
Besides: the 6-joint scene on other back-ends (rounding-level changes of f:
how far its step count and path error move with no change of the model),
and bench_plant's rows (one f beside the forward dynamics) when built.
The timers cost some 20-40 ns a scope: the profiled run is slower, so the
report gives its parts as fractions and as those fractions of the normal
build's wall time.

Each invocation records one labelled measurement (--label, with the revisions
it measured) in results/cost_breakdown.json and rewrites
results/cost_breakdown.md from every label recorded there.

  experiments/cost_breakdown.py --label before --revision "release aac608c, profile 1f6fa6a" \\
      --release-bin /tmp/pumasim_release_before --profile-bin /tmp/pumasim_profile_before
  experiments/cost_breakdown.py --label after --revision "$(git rev-parse --short HEAD)"
(build first: cmake --build --preset release --target pumasim;
 cmake --preset profile && cmake --build --preset profile --target pumasim)
"""
import argparse
import json
import os
import re
import shutil
import statistics
import subprocess
import time
import sys
import tempfile

ROOT = os.path.normpath(os.path.join(os.path.dirname(os.path.abspath(__file__)), ".."))
SCENES = [
    ("6-joint hybrid scene, cvode-adams rtol 1e-3",
     ["experiments/scenes/paper_slow_6dof_hybrid.toml", "--integrator", "cvode-adams", "--rtol", "1e-3"]),
    ("3-joint paper scene, AB2 at 0.5 ms",
     ["experiments/scenes/paper_slow.toml", "--integrator", "ab2", "--dt", "5e-4"]),
]
CONTEXTS = ["loop", "rhs", "jacobian", "roots", "events", "output"]
CONTEXT_NAMES = {"loop": "integrator's own work", "rhs": "f (right-hand side)", "jacobian": "exact Jacobian",
                 "roots": "root functions", "events": "events and restarts", "output": "output (dense output, rows)"}
PARTS = ["own", "reference", "controller", "drive", "friction", "dynamics"]
# perf symbol classes of the integrator's own work: SUNDIALS' (libsundials_*,
# each symbol's own samples) and, in pumasim's binary, the Newton systems'
# dense LU and matrix operations (integrators/sundials_dense_lu.cpp: the
# newton_* functions with everything they call, Eigen's kernels included,
# from the call graph).
SUNDIALS_CLASSES = [
    ("dense LU factor and solve", re.compile(r"denseGETR|SUNLinSol|GETRF|GETRS|newton_lu_")),
    ("Newton matrix I - gamma J (copy, scale-add)", re.compile(r"SUNMat|newton_matrix_")),
    ("vector operations, error norms", re.compile(r"^N_V")),
]
PUMASIM_NEWTON = re.compile(r"pumasim::detail::\(anonymous namespace\)::newton_\w+")
OTHER_SUNDIALS = "other SUNDIALS (CVODE's step, error test, root finding)"


def run(binary, args, out, env=None, timed=None):
    """The run's stats.json; with timed (a list), the process's wall time [s]
    from start to exit (Python's subprocess: its fork and exec included) appended."""
    start = time.perf_counter()
    subprocess.run([binary, "run", *args, "--out", out, "--force", "-q"], cwd=ROOT, check=True,
                   stdout=subprocess.DEVNULL, env=env)
    if timed is not None:
        timed.append(time.perf_counter() - start)
    with open(os.path.join(out, "stats.json"), encoding="utf-8") as f:
        return json.load(f)


def release_runs(binary, args, repeats, tmp):
    best, process, walls = None, [], []
    for _ in range(repeats):
        s = run(binary, args, os.path.join(tmp, "release"), timed=process)
        walls.append(s["wall_time_s"])
        if best is None or s["integration_wall_time_s"] < best["integration_wall_time_s"]:
            best = s
    keys = ["integration_wall_time_s", "rhs_evaluations", "steps", "jacobian_evaluations", "linear_solves",
            "rejected_steps", "restarts", "root_events", "time_events", "max_path_error_mm", "rms_path_error_mm"]
    out = {k: best[k] for k in keys}
    # The process around the run: its wall against the run's own wall_time_s (stats.json), run by run.
    out["process_wall_s"] = statistics.median(process)
    out["run_wall_time_s"] = statistics.median(walls)
    ratios = [p / w for p, w in zip(process, walls)]
    out["process_over_run"] = statistics.median(ratios)
    out["process_over_run_range"] = [min(ratios), max(ratios)]
    return out


def profile_runs(binary, args, repeats, tmp):
    """Each entry's smallest value over the runs: a run preempted on the shared
    machine charges the pause to whatever part was running, so a single run's
    table can hold one inflated entry."""
    best = None
    for _ in range(repeats):
        path = os.path.join(tmp, "profile.txt")
        run(binary, args, os.path.join(tmp, "profile"), dict(os.environ, PUMASIM_PROFILE_OUT=path))
        ns, calls = {}, {}
        with open(path, encoding="utf-8") as f:
            for line in f:
                a, b, v = line.split()
                if a == "calls":
                    calls[b] = int(v)
                else:
                    ns[f"{a}.{b}"] = float(v)
        if best is None:
            best = {"ns": ns, "calls": calls}
        else:
            best["ns"] = {k: min(v, ns.get(k, v)) for k, v in best["ns"].items()}
    best["total_ns"] = sum(best["ns"].values())
    return best


def perf_split(binary, args, repeats, tmp):
    """Shares of the process's cpu-clock samples in SUNDIALS, by class; None without perf."""
    if not shutil.which("perf"):
        return None
    data = os.path.join(tmp, "perf.data")
    loop = "; ".join(f"{binary} run {' '.join(args)} --out {tmp}/perf --force -q >/dev/null" for _ in range(repeats))
    # DWARF call graphs: the release build keeps no frame pointers.
    rec = subprocess.run(["perf", "record", "-e", "cpu-clock", "-F", "5000", "--call-graph", "dwarf,16384",
                          "-o", data, "--", "sh", "-c", loop],
                         cwd=ROOT, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    if rec.returncode != 0:
        return None
    line_rx = re.compile(r"\s*([\d.]+)%\s+(?:([\d.]+)%\s+)?(\S+)\s+\[.\]\s+(.+?)\s*$")
    shares = {name: 0.0 for name, _ in SUNDIALS_CLASSES}
    shares[OTHER_SUNDIALS] = 0.0
    sundials = 0.0
    # SUNDIALS' own samples, symbol by symbol.
    rep = subprocess.run(["perf", "report", "-i", data, "--no-children", "--sort", "dso,sym", "--stdio", "-g", "none"],
                         capture_output=True, text=True)
    for line in rep.stdout.splitlines():
        m = line_rx.match(line)
        if not m or "sundials" not in m.group(3):
            continue
        pct, sym = float(m.group(1)), m.group(4)
        cls = next((name for name, rx in SUNDIALS_CLASSES if rx.search(sym)), OTHER_SUNDIALS)
        sundials += pct
        shares[cls] += pct
    # pumasim's Newton functions with their callees (the children column).
    rep = subprocess.run(["perf", "report", "-i", data, "--children", "--sort", "dso,sym", "--stdio", "-g", "none"],
                         capture_output=True, text=True)
    for line in rep.stdout.splitlines():
        m = line_rx.match(line)
        if not m or not m.group(2) or not PUMASIM_NEWTON.search(m.group(4)):
            continue
        pct, sym = float(m.group(1)), m.group(4)
        cls = next(name for name, rx in SUNDIALS_CLASSES if rx.search(sym))
        sundials += pct
        shares[cls] += pct
    if sundials == 0:
        return None
    return {k: v / sundials for k, v in shares.items()}


# Rounding-level changes of f (another back-end computing the same dynamics)
# and the 6-joint scene's step count and path error: how far they move
# without any change of the model.
OTHER_BACKENDS = ["aba", "rnea-probing", "lagrange-euler", "crba-symbolic"]


def backend_spread(binary, args, tmp):
    out = {}
    for be in OTHER_BACKENDS:
        s = run(binary, args + ["--backend", be], os.path.join(tmp, "backend"))
        out[be] = {k: s[k] for k in ["steps", "rhs_evaluations", "max_path_error_mm", "rms_path_error_mm"]}
    return out


def bench_plant(binary):
    """bench_plant's rows (ns per call, ratio to fd), or None without the binary."""
    if not binary or not os.path.exists(binary):
        return None
    r = subprocess.run([binary, "--benchmark_format=json", "--benchmark_repetitions=3",
                        "--benchmark_report_aggregates_only=true"], capture_output=True, text=True, check=True)
    rows = {}
    for b in json.loads(r.stdout)["benchmarks"]:
        if b.get("aggregate_name") != "median":
            continue
        rows[b["run_name"]] = {"real_ns": b["real_time"], "cpu_ns": b["cpu_time"],
                               "ratio_to_fd": b.get("ratio_to_fd")}
    return rows


def measure(args_ns):
    out = {}
    with tempfile.TemporaryDirectory() as tmp:
        out["backend_spread"] = backend_spread(args_ns.release_bin, SCENES[0][1], tmp)
        out["bench_plant"] = bench_plant(args_ns.bench_bin)
        for title, args in SCENES:
            out[title] = {
                "command": "pumasim run " + " ".join(args),
                "release": release_runs(args_ns.release_bin, args, args_ns.repeats, tmp),
                "profile": profile_runs(args_ns.profile_bin, args, args_ns.repeats, tmp),
                "perf": perf_split(args_ns.release_bin, args, args_ns.repeats, tmp) if "cvode" in title else None,
            }
    return out


def scene_section(title, m):
    rel, prof = m["release"], m["profile"]
    ns, calls, total = prof["ns"], prof["calls"], prof["total_ns"]
    wall_us = rel["integration_wall_time_s"] * 1e6
    scale = wall_us / (total / 1e3)  # the profiled run's microseconds to the normal build's
    nf = max(rel["rhs_evaluations"], 1)
    lines = [f"#### {title}", "", f"`{m['command']}`", "",
             f"Normal build: integration wall {wall_us / 1e3:.1f} ms (fastest of the runs), "
             f"{rel['rhs_evaluations']} f, {rel['steps']} steps, {rel['jacobian_evaluations']} Jacobians, "
             f"{rel['linear_solves']} Newton matrix set-ups, {rel['restarts']} restarts, "
             f"{rel['root_events']} roots; {wall_us / nf:.2f} us of wall per f. "
             f"Path error max {rel['max_path_error_mm']:.6g} mm, rms {rel['rms_path_error_mm']:.6g} mm." +
             (f" The process (`pumasim run` from start to exit, through Python's subprocess): median "
              f"{rel['process_wall_s'] * 1e3:.1f} ms against the run's own wall_time_s median "
              f"{rel['run_wall_time_s'] * 1e3:.1f} ms, {rel['process_over_run']:.2f}x (median of the runs' ratios; "
              f"{rel['process_over_run_range'][0]:.2f}-{rel['process_over_run_range'][1]:.2f})."
              if "process_wall_s" in rel else ""),
             f"Profiled build: {total / 1e6:.1f} ms in all (each entry's minimum over the runs; the timers' own cost included); "
             "\"normal\" columns scale its times by the two walls' ratio "
             f"({scale:.2f}).", "",
             "| context | calls | " + " | ".join(PARTS) + " | total ms | % | normal us per call |",
             "|---|---:|" + "---:|" * len(PARTS) + "---:|---:|---:|"]
    for c in CONTEXTS:
        row = [ns.get(f"{c}.{p}", 0.0) for p in PARTS]
        tot = sum(row)
        if tot == 0:
            continue
        n = calls.get(c, 0)
        per = f"{tot / 1e3 * scale / n:.3f}" if n else "-"
        lines.append(f"| {CONTEXT_NAMES[c]} | {n if n else '-'} | " + " | ".join(f"{v / 1e6:.2f}" for v in row) +
                     f" | {tot / 1e6:.2f} | {100 * tot / total:.1f} | {per} |")
    # Per f: the parts of f, whichever context asked for it (f inside the roots and events too).
    nrhs = calls.get("rhs", 0)
    if nrhs:
        parts = [ns.get(f"rhs.{p}", 0.0) / nrhs / 1e3 * scale for p in PARTS]
        lines += ["", "Per f (normal-build us, from the f context): " +
                  ", ".join(f"{p} {v:.3f}" for p, v in zip(PARTS, parts)) + f"; total {sum(parts):.3f}."]
    if rel["jacobian_evaluations"] and not calls.get("jacobian"):
        lines.append("The Jacobians are CVODE's difference quotients: each is one f per state column inside the "
                     "f row (counted among the f), plus the Newton matrix's LU in the integrator's own work.")
    if m.get("perf"):
        lines += ["", "Integrator's own work (SUNDIALS, and the Newton systems' dense LU and matrix operations "
                  "where pumasim supplies them), shares of its perf samples (normal build): " +
                  ", ".join(f"{k} {100 * v:.0f} %" for k, v in m["perf"].items()) + "."]
    return lines + [""]


def write_markdown(db, path):
    lines = ["# Cost breakdown of the whole run", "",
             "Generated by `experiments/cost_breakdown.py` from `results/cost_breakdown.json` beside it (do not edit; "
             "see the script's docstring for the method); one section per "
             "measurement, each naming the revisions it measured. Exclusive wall time per context (who asked: "
             "the integrator between its calls, f, the exact Jacobian, the root functions, events and restarts, "
             "the output) and part (what the plant was doing: reference = inverse kinematics, Jacobians and "
             "timing law; controller; drive = amplifier and motor; friction; dynamics = the back-end's mass "
             "matrix, bias and solve; own = the rest). Times in ms of the profiled run unless said. The machine "
             "is shared (2 cores, other jobs running): walls vary by tens of per cent from run to run.", ""]
    for label, entry in db.items():
        lines += [f"## {label}: {entry['revision']}", ""]
        for title, m in entry["scenes"].items():
            if title == "backend_spread":
                lines += ["The 6-joint scene on other back-ends (the same dynamics, f changed at rounding level; "
                          "`--backend B` added to its command): " +
                          "; ".join(f"{be}: {v['steps']} steps, {v['rhs_evaluations']} f, path error max "
                                    f"{v['max_path_error_mm']:.7g} mm, rms {v['rms_path_error_mm']:.7g} mm"
                                    for be, v in m.items()) + ".", ""]
            elif title == "bench_plant":
                if m:
                    lines += ["`bench_plant` (median of 3 repetitions; ns per call, wall and CPU): " +
                              "; ".join(f"{k} {v['real_ns']:.0f} / {v['cpu_ns']:.0f}" +
                                        (f" (ratio to fd {v['ratio_to_fd']:.2f})" if v.get("ratio_to_fd") else "")
                                        for k, v in m.items()) + ".", ""]
            else:
                lines += scene_section(title, m)
    with open(path, "w", encoding="utf-8") as f:
        f.write("\n".join(lines))


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--label", required=True)
    ap.add_argument("--revision", required=True, help="the revisions measured, as the report shall name them")
    ap.add_argument("--release-bin", default=os.path.join(ROOT, "build/release/bin/pumasim"))
    ap.add_argument("--profile-bin", default=os.path.join(ROOT, "build/profile/bin/pumasim"))
    ap.add_argument("--bench-bin", default=os.path.join(ROOT, "build/release/bin/bench_plant"),
                    help="bench_plant (\"\" to skip)")
    ap.add_argument("--repeats", type=int, default=7)
    ap.add_argument("--json", default=os.path.join(ROOT, "results/cost_breakdown.json"))
    ap.add_argument("--md", default=os.path.join(ROOT, "results/cost_breakdown.md"))
    a = ap.parse_args()
    db = {}
    if os.path.exists(a.json):
        with open(a.json, encoding="utf-8") as f:
            db = json.load(f)
    db[a.label] = {"revision": a.revision, "scenes": measure(a)}
    with open(a.json, "w", encoding="utf-8") as f:
        json.dump(db, f, indent=1)
    write_markdown(db, a.md)
    print(f"cost_breakdown: {a.label} written to {a.md}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
