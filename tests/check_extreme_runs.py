#!/usr/bin/python3
"""Every `pumasim run` ends within its budgets, on extreme but valid scenes,
with every integrator of the registry (the reliability issue, 18).

    /usr/bin/python3 tests/check_extreme_runs.py PUMASIM [--jobs N] [--t-end S] [--out DIR]

The scenes are shipped scenes pushed to their limits with --set and --unset:
armature inductance 1e-12 H, the PIV gains times 1e6, a sampled controller at
the shortest servo period the step budget allows, the wrist singularity on
the path, a pose held at the elbow and wrist singularities at once, and the
hybrid stick-slip model with no friction at all. Each runs through every
integrator with small budgets (--max-steps, --max-wall, a short --t-end).
Each run must end within --max-wall plus a start-up allowance, with

- exit status 0, stats.json ok, t_reached = t_end and every state of the
  last trajectory row finite; or
- exit status 1, stats.json not ok, and a failure that names a time
  ("t = <number>") and a state component (a name of the scene's state); or
- exit status 2 before the run, from a method that integrates the plant's
  residual form (ida), on a scene whose friction law has none (the paper's
  rule): the refusal names the joint and the law ("refused").

Anything else (a crash, a hang, exit status 2 on a valid scene, a non-finite
state reported ok, a failure naming no time or state) fails the test. A
servo period just below the shortest one must be refused up front (exit
status 2, the message naming controller.servo_period and the step budget).
It prints the grid (scenes x integrators) and the outcomes, per kind; with
--out DIR it also writes them as DIR/extreme_runs.csv (one row per run) and
DIR/extreme_runs_summary.csv (the counts), which results/reliability/ keeps.
"""
import argparse
import concurrent.futures
import json
import math
import os
import re
import shutil
import subprocess
import sys
import tempfile
import time
import tomllib

ROOT = os.path.normpath(os.path.join(os.path.dirname(os.path.abspath(__file__)), ".."))
sys.path.insert(0, os.path.join(ROOT, "experiments"))
from pumasim_exp import io as pumasim_io  # noqa: E402

SCENES_DIR = os.path.join(ROOT, "experiments", "scenes")
MAX_STEPS = 20000
MAX_WALL = 1.0          # [s] --max-wall of every run
STARTUP_ALLOWANCE = 20  # [s] loading the scene and writing the folder, on a loaded machine
DT = 1e-4               # [s] the fixed-step methods' step
TIME = re.compile(r"\bt = [-+0-9.eE]+")


def scaled_gains(scene, factor):
    """--set overrides multiplying every PIV gain of `scene` by factor."""
    with open(os.path.join(SCENES_DIR, scene), "rb") as f:
        ctl = tomllib.load(f)["controller"]
    out = []
    for key in ("kp", "ki", "kv", "kvff", "kaff"):
        v = ctl[key]
        v = [x * factor for x in v] if isinstance(v, list) else v * factor
        out += ["--set", f"controller.{key}={v!r}"]
    return out


def scenes(t_end):
    """(name, scene file, arguments): the extreme cases."""
    shortest = t_end / MAX_STEPS  # samples = t_end / period may not exceed --max-steps
    return [
        ("inductance_1e-12", "stiff_armature.toml", ["--set", "motor.inductance=1e-12"]),
        ("gains_x1e6", "high_gain.toml", scaled_gains("high_gain.toml", 1e6)),
        ("servo_period_shortest", "sampled_control.toml",
         ["--set", 'controller.mode="sampled"', "--set", f"controller.servo_period={shortest!r}"]),
        ("wrist_singular_path", "stiff_singular.toml", []),
        ("hold_at_qs_singular", "paper_fast_6dof.toml",
         ["--unset", "reference", "--set", 'initial.pose="qs"', "--set", f"scene.duration={t_end!r}"]),
        ("hybrid_no_friction", "paper_slow_6dof_hybrid.toml",
         ["--set", "friction.static_torque=0", "--set", "friction.kinetic_torque=0",
          "--set", "friction.viscous=0"]),
    ]


def integrators(pumasim):
    """(name, fixed step?) of every registry entry for general scenes (not those that integrate only a
    lossless, unforced arm: conservative_only; they refuse these driven scenes before running)."""
    p = subprocess.run([pumasim, "integrators", "--json"], capture_output=True, text=True, check=True)
    return [(entry["name"], entry["kind"] == "fixed-step") for entry in json.loads(p.stdout)
            if not entry["conservative_only"]]


def run_one(pumasim, work, scene, method, t_end):
    """Runs one cell of the grid; returns (kind, detail, elapsed seconds)."""
    name, file, args = scene
    integ, fixed = method
    out = os.path.join(work, f"{name}.{integ}")
    cmd = [pumasim, "run", os.path.join(SCENES_DIR, file), *args, "--integrator", integ,
           "--t-end", repr(t_end), "--max-steps", str(MAX_STEPS), "--max-wall", repr(MAX_WALL),
           "--out", out, "--quiet"] + (["--dt", repr(DT)] if fixed else [])
    t0 = time.monotonic()
    try:
        p = subprocess.run(cmd, capture_output=True, text=True, timeout=MAX_WALL + STARTUP_ALLOWANCE)
    except subprocess.TimeoutExpired:
        return "hang", f"no end within {MAX_WALL + STARTUP_ALLOWANCE} s: {' '.join(cmd)}", time.monotonic() - t0
    elapsed = time.monotonic() - t0
    return (*judge(p, out, t_end), elapsed)


def judge(p, out, t_end):
    """(kind, detail) of a finished run: 'ok', a failure kind, 'refused' or 'bad: ...'."""
    if p.returncode == 2 and "integrates the plant's residual form, which this scene has not: joint" in p.stderr:
        return "refused", p.stderr.strip()[-200:]
    if p.returncode not in (0, 1):
        return "bad", f"exit status {p.returncode}: {p.stderr.strip()[-400:]}"
    try:
        stats = pumasim_io.read_stats(out)
        traj = pumasim_io.read_trajectory(out)
    except (OSError, pumasim_io.RunFolderError, ValueError) as e:
        return "bad", f"exit status {p.returncode}, no readable run folder: {e}"
    states = list(stats["atol_per_component"])
    if p.returncode == 0:
        last = traj.data[-1]
        cols = [traj.names.index(s) for s in states]
        bad = [s for s, c in zip(states, cols) if not math.isfinite(last[c])]
        if not stats["ok"] or stats["failure"] or bad:
            return "bad", f"exit 0 but ok={stats['ok']}, failure={stats['failure']!r}, non-finite {bad}"
        if stats["t_reached"] is None or abs(stats["t_reached"] - t_end) > 1e-9 * max(1.0, t_end):
            return "bad", f"exit 0 but t_reached = {stats['t_reached']}, not {t_end}"
        return "ok", ""
    why = stats["failure"]
    if stats["ok"] or not why:
        return "bad", f"exit 1 but ok={stats['ok']}, failure={why!r}"
    named = [s for s in states if re.search(r"\b" + re.escape(s) + r"\b", why)]
    if not TIME.search(why) or not named:
        return "bad", f"a failure that names no time or no state component: {why!r}"
    return failure_kind(why), why


def failure_kind(why):
    """The kind of a named failure, for the summary."""
    for kind, words in (("unstable (past a physical bound)", "unstable at t = "), ("step budget", "step budget"),
                        ("wall-clock budget", "wall-clock budget"),
                        ("non-finite state", "non-finite"), ("step size", "step size"),
                        ("step size", "h ="), ("convergence", "converge"), ("error test", "error test")):
        if words in why:
            return "failure: " + kind
    return "failure: other"


def check_refusal(pumasim, work, t_end):
    """A servo period just below the shortest allowed is refused up front."""
    period = t_end / MAX_STEPS * (1 - 1e-6)
    p = subprocess.run([pumasim, "run", os.path.join(SCENES_DIR, "sampled_control.toml"),
                        "--set", 'controller.mode="sampled"', "--set", f"controller.servo_period={period!r}",
                        "--t-end", repr(t_end), "--max-steps", str(MAX_STEPS),
                        "--out", os.path.join(work, "refused"), "--quiet"],
                       capture_output=True, text=True, timeout=60)
    ok = (p.returncode == 2 and "controller.servo_period" in p.stderr and
          f"more than the step budget of {MAX_STEPS} steps" in p.stderr and
          not os.path.exists(os.path.join(work, "refused")))
    return ok, f"exit {p.returncode}: {p.stderr.strip()}"


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("pumasim")
    ap.add_argument("--jobs", type=int, default=2)
    ap.add_argument("--t-end", type=float, default=0.1)
    ap.add_argument("--out", help="folder for extreme_runs.csv and extreme_runs_summary.csv")
    a = ap.parse_args()
    work = tempfile.mkdtemp(prefix="pumasim_extreme_")
    try:
        t0 = time.monotonic()
        refused, detail = check_refusal(a.pumasim, work, a.t_end)
        grid = [(s, m) for s in scenes(a.t_end) for m in integrators(a.pumasim)]
        with concurrent.futures.ThreadPoolExecutor(a.jobs) as pool:
            results = list(pool.map(lambda c: run_one(a.pumasim, work, c[0], c[1], a.t_end), grid))
        report(grid, results, time.monotonic() - t0)
        if a.out:
            write_tables(a.out, grid, results, a.t_end)
        problems = [f"{s[0]} x {m[0]}: {kind}: {why}" for (s, m), (kind, why, _) in zip(grid, results)
                    if kind in ("bad", "hang")]
        if not refused:
            problems.append(f"a servo period below the shortest was not refused up front: {detail}")
        if problems:
            sys.exit("check_extreme_runs: FAILED\n  " + "\n  ".join(problems))
        print("check_extreme_runs: every run ended in time with ok or a named failure; "
              "the shorter servo period was refused up front")
    finally:
        shutil.rmtree(work, ignore_errors=True)


def outcome_counts(results):
    """{kind: number of runs}, sorted by kind."""
    counts = {}
    for kind, _, _ in results:
        counts[kind] = counts.get(kind, 0) + 1
    return dict(sorted(counts.items()))


def write_tables(folder, grid, results, t_end):
    """DIR/extreme_runs.csv and DIR/extreme_runs_summary.csv."""
    os.makedirs(folder, exist_ok=True)
    rows = [{"scene": s[0], "integrator": m[0], "outcome": kind, "wall_s": f"{el:.3f}", "failure": why}
            for (s, m), (kind, why, el) in zip(grid, results)]
    comments = [f"check_extreme_runs.py: --t-end {t_end!r} --max-steps {MAX_STEPS} --max-wall {MAX_WALL} "
                f"(fixed-step methods --dt {DT!r}); wall_s is the process's, on the machine that ran it"]
    pumasim_io.write_table(os.path.join(folder, "extreme_runs.csv"), rows, comments=comments)
    counts = outcome_counts(results)
    summary = [{"outcome": "runs", "count": len(results)},
               {"outcome": "scenes", "count": len(dict.fromkeys(s[0] for s, _ in grid))},
               {"outcome": "integrators", "count": len(dict.fromkeys(m[0] for _, m in grid))}]
    summary += [{"outcome": k, "count": v} for k, v in counts.items()]
    summary.append({"outcome": "failure: named (all kinds)",
                    "count": sum(v for k, v in counts.items() if k.startswith("failure"))})
    pumasim_io.write_table(os.path.join(folder, "extreme_runs_summary.csv"), summary, comments=comments)


def report(grid, results, seconds):
    """Prints the grid, each cell's outcome, and the counts per kind."""
    scene_names = list(dict.fromkeys(s[0] for s, _ in grid))
    methods = list(dict.fromkeys(m[0] for _, m in grid))
    print(f"check_extreme_runs: {len(scene_names)} scenes x {len(methods)} integrators = {len(grid)} runs, "
          f"--t-end and budgets --max-steps {MAX_STEPS} --max-wall {MAX_WALL}; {seconds:.1f} s in all")
    for (s, m), (kind, why, el) in zip(grid, results):
        print(f"  {s[0]:24s} {m[0]:20s} {el:6.2f} s  {kind}" + (f": {why[:160]}" if why else ""))
    counts = outcome_counts(results)
    print("check_extreme_runs: outcomes: " + ", ".join(f"{k} {v}" for k, v in counts.items()) +
          f"; slowest run {max(el for _, _, el in results):.2f} s")


if __name__ == "__main__":
    main()
