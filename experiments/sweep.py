#!/usr/bin/python3
"""Sweeps: variants of a scene x integrators x settings, as independent runs.

    /usr/bin/python3 experiments/sweep.py experiments/sweeps/<name>.toml
        [--jobs N] [--shard K/N] [--merge] [--reduced] [--out DIR]

A sweep file (experiments/sweeps/README.md has the format) names a base scene,
its variants (scene overrides, as `pumasim run --set`), a reference and a
cross-check method, and the integrators with their settings. Every (variant,
method, setting) is one run of `pumasim run`, written by pumasim atomically
into build/sweeps/<sweep>/<variant>/<run>/ and repeated for the wall-time
median; then a summary <run>.json is written atomically (temporary file and
rename). A run with a summary is complete and is skipped on a re-run; an
interrupted run leaves no summary and is redone.

Without --shard the runs go to N local processes (--jobs, default: the
number of cores) and the results are merged at the end. --shard K/N takes only
the runs whose index in the sorted run list is K-1 modulo N, so one sweep
splits over machines: as a Slurm job array

    #SBATCH --array=1-8
    python3 experiments/sweep.py S --shard $SLURM_ARRAY_TASK_ID/8 --jobs 1

or under GNU parallel: `parallel python3 experiments/sweep.py S --shard {}/8
--jobs 1 ::: 1 2 3 4 5 6 7 8`; then one `sweep.py S --merge` over the shared
build/sweeps/ writes the table. --merge compares each run with its variant's
reference at the output times and writes results/<sweep>/: <sweep>.csv (every
run, failures with their reason), <sweep>.png (error against wall time and
against right-hand-side evaluations, one line per integrator and a panel row
per variant), <sweep>_cost.png when the sweep has several variants (the RHS
evaluations each integrator needs to reach the sweep's accuracy target, against
the variant value) and summary.json for the report.

--reduced (CI): the first and last variants, two settings per method, one
repeat, short horizon, into build/sweeps-reduced/ and --out (default
build/sweeps-reduced/results/<folder>): checks the pipeline end to end,
writes nothing under results/.
"""
import argparse
import concurrent.futures
import csv
import json
import math
import os
import re
import statistics
import subprocess
import sys
import tomllib

ROOT = os.path.normpath(os.path.join(os.path.dirname(os.path.abspath(__file__)), ".."))
PUMASIM = os.environ.get("PUMASIM", os.path.join(ROOT, "build", "release", "bin", "pumasim"))


class SweepError(Exception):
    pass


def load_sweep(path, reduced):
    with open(path, "rb") as f:
        try:
            doc = tomllib.load(f)
        except tomllib.TOMLDecodeError as e:
            raise SweepError(f"{path}: TOML syntax error: {e}")

    def need(table, key, kind, where):
        if key not in table:
            raise SweepError(f"{path}: {where}: missing required key '{key}'")
        if not isinstance(table[key], kind):
            raise SweepError(f"{path}: {where}.{key}: expected {kind.__name__}, got {type(table[key]).__name__}")
        return table[key]

    known = {"sweep", "reference", "check", "variant", "method"}
    for k in doc:
        if k not in known:
            raise SweepError(f"{path}: unknown table '{k}'; expected one of: {', '.join(sorted(known))}")
    sw = need(doc, "sweep", dict, "(top level)")
    for k in sw:
        if k not in {"name", "title", "scene", "folder", "t_end", "reduced_t_end", "repeats", "x", "target_mm",
                     "findings", "set", "max_steps", "limit_variant", "stuck_variant"}:
            raise SweepError(f"{path}: unknown key 'sweep.{k}'")
    s = {
        "name": need(sw, "name", str, "sweep"),
        "title": sw.get("title", sw["name"]),
        "scene": need(sw, "scene", str, "sweep"),
        "t_end": float(sw["t_end"]) if "t_end" in sw else None,
        "repeats": int(sw.get("repeats", 3)),
        "x": sw.get("x", "variant"),
        "target_mm": float(sw.get("target_mm", 1e-3)),
        "findings": sw.get("findings", ""),
        "set": list(sw.get("set", [])),
        "folder": sw.get("folder", sw["name"]),
        "max_steps": int(sw.get("max_steps", 0)),
        "limit_variant": sw.get("limit_variant"),
        "stuck_variant": sw.get("stuck_variant"),
        "file": os.path.relpath(path, ROOT),
    }

    def method_of(t, where):
        for k in t:
            if k not in ("integrator", "options"):
                raise SweepError(f"{path}: unknown key '{where}.{k}'; expected integrator, options")
        return (need(t, "integrator", str, where), [str(o) for o in t.get("options", [])])

    for key in ("reference", "check"):
        s[key] = method_of(need(doc, key, dict, "(top level)"), key)
    variants = doc.get("variant", [{"label": "base", "set": []}])
    s["variants"] = []
    for k, v in enumerate(variants):
        for key in v:
            if key not in ("label", "value", "set", "reference", "check"):
                raise SweepError(f"{path}: unknown key 'variant[{k}].{key}'")
        lab = need(v, "label", str, f"variant[{k}]")
        s["variants"].append({"label": lab, "value": v.get("value", k), "set": list(v.get("set", [])),
                              "reference": method_of(v["reference"], f"variant[{k}].reference")
                              if "reference" in v else s["reference"],
                              "check": method_of(v["check"], f"variant[{k}].check") if "check" in v else s["check"]})
    for key in ("limit_variant", "stuck_variant"):
        if s[key] and s[key] not in [v["label"] for v in s["variants"]]:
            raise SweepError(f"{path}: sweep.{key}: expected one of the variants' labels")
    methods = []
    for k, m in enumerate(need(doc, "method", list, "(top level)")):
        names = need(m, "integrator", list, f"method[{k}]")
        if "dt" in m:
            settings = [("dt", float(d), ["--dt", repr(float(d))]) for d in m["dt"]]
        elif "rtol" in m:
            fac = float(m.get("atol_factor", 1e-3))
            settings = [("rtol", float(r), ["--rtol", repr(float(r)), "--atol", repr(float(r) * fac)])
                        for r in m["rtol"]]
        else:
            raise SweepError(f"{path}: method[{k}]: expected 'dt' or 'rtol'")
        extra = [str(o) for o in m.get("options", [])]
        for name in names:
            methods.append((name, settings, extra))
    s["methods"] = methods
    if reduced:
        s["variants"] = [s["variants"][0]] + ([s["variants"][-1]] if len(s["variants"]) > 1 else [])
        s["methods"] = [(n, st[:2], ex) for n, st, ex in methods]
        s["repeats"] = 1
        labels = [v["label"] for v in s["variants"]]
        for key in ("limit_variant", "stuck_variant"):
            if s[key] not in labels:
                s[key] = None
        if "reduced_t_end" in sw:
            s["t_end"] = float(sw["reduced_t_end"])
    return s


def slug(text):
    return "".join(c if c.isalnum() or c in "-._" else "_" for c in text)


def run_list(s):
    """Every run of the sweep, sorted by id: (id, variant, tag, integrator, options, repeats)."""
    runs = []
    for v in s["variants"]:
        vdir = slug(v["label"])
        runs.append((f"{vdir}/reference", v, "reference", *v["reference"], 1))
        runs.append((f"{vdir}/check", v, "check", *v["check"], 1))
        for name, settings, extra in s["methods"]:
            for kind, value, opts in settings:
                tag = f"{name}_{kind}{value:g}" + ("_" + slug(" ".join(o.lstrip("-") for o in extra)) if extra else "")
                runs.append((f"{vdir}/{tag}", v, tag, name, opts + extra, s["repeats"]))
    return sorted(runs, key=lambda r: r[0])


def scene_file(s):
    return os.path.join(ROOT, "experiments", "scenes", s["scene"] + ".toml")


def execute(s, work, run):
    """Runs one run (all repeats) unless complete; returns its summary."""
    rid, variant, tag, name, opts, repeats = run
    summary_path = os.path.join(work, rid + ".json")
    if os.path.exists(summary_path):
        with open(summary_path) as f:
            return json.load(f)
    out = os.path.join(work, rid)
    cmd = [PUMASIM, "run", scene_file(s), "--integrator", name, "--out", out] + opts
    for o in s["set"] + variant["set"]:
        cmd += ["--set", o]
    if s["t_end"]:
        cmd += ["--t-end", repr(s["t_end"])]
    # The sweep's budget is for adaptive methods and not for the references;
    # a fixed-step run's count is t_end / dt, known in advance: no budget.
    if s["max_steps"] and tag not in ("reference", "check") and "--rtol" in opts:
        cmd += ["--max-steps", str(s["max_steps"])]
    if "--dt" in opts:  # no budget: the step count is t_end / dt
        cmd += ["--max-steps", "0"]
    walls = []
    for _ in range(repeats):
        p = subprocess.run(cmd, capture_output=True, text=True, cwd=ROOT)
        if p.returncode == 2:  # bad input: the sweep file is wrong, not the method
            raise SweepError(f"{' '.join(cmd)}: {p.stderr.strip()}")
        stats = os.path.join(out, "stats.json")
        if not os.path.exists(stats):  # pumasim itself failed (a crash, not a reported failure)
            raise SweepError(f"{' '.join(cmd)}: exit status {p.returncode}, no stats.json: {p.stderr.strip()}")
        with open(stats) as f:
            st = json.load(f)
        walls.append(st["wall_time_s"])
        if not st["ok"]:
            break
    summary = {"id": rid, "variant": variant["label"], "value": variant["value"], "tag": tag,
               "integrator": name, "options": opts, "stats": st, "wall_times_s": walls,
               "wall_time_median_s": statistics.median(walls), "command": cmd}
    tmp = summary_path + ".tmp"
    os.makedirs(os.path.dirname(summary_path), exist_ok=True)
    with open(tmp, "w") as f:
        json.dump(summary, f, indent=1)
    os.replace(tmp, summary_path)
    return summary


def trajectory(run_dir):
    with open(os.path.join(run_dir, "trajectory.csv")) as f:
        rows = list(csv.reader(f))
    head = [h.split(" [")[0] for h in rows[0]]
    return {h: [float(r[i]) for r in rows[1:]] for i, h in enumerate(head)}


def compare(ref, run):
    """Max and RMS end-effector distance [mm], max joint difference [rad] on the
    common output times, and the final-state error max_i |dx_i| / max(1, |x_i|)
    (nan unless both reached the same final time)."""
    n = min(len(ref["t"]), len(run["t"]))
    d = [1e3 * math.dist((ref["x"][k], ref["y"][k], ref["z"][k]), (run["x"][k], run["y"][k], run["z"][k]))
         for k in range(n)]
    joints = [h for h in ref if h.startswith("q") and h[1:].isdigit()]
    dq = max(abs(ref[h][k] - run[h][k]) for h in joints for k in range(n))
    states = [h for h in ref if re.fullmatch(r"(q|qd|i_motor|z_piv)\d+", h) and h in run]
    final = math.nan
    if len(ref["t"]) == len(run["t"]) and abs(ref["t"][-1] - run["t"][-1]) < 1e-9:
        final = max(abs(ref[h][-1] - run[h][-1]) / max(1.0, abs(ref[h][-1])) for h in states)
    return max(d), math.sqrt(sum(e * e for e in d) / n), dq, final


STUCK_MARGIN = 2  # output samples trimmed from each end of a stuck interval


def stuck_intervals(run):
    """Per joint, the output-sample index ranges [a, b] over which the joint
    speed is exactly zero at every sample (the hybrid model holds a stuck
    joint at exactly zero speed), trimmed by STUCK_MARGIN samples at each end
    so that a model breaking away a little earlier or later is not counted."""
    out = {}
    n = len(run["t"])
    for h in run:
        if not re.fullmatch(r"qd\d+", h):
            continue
        qd, k, ivs = run[h], 0, []
        while k < n - 1:
            if qd[k] == 0.0 and qd[k + 1] == 0.0:
                a = k
                while k < n - 1 and qd[k + 1] == 0.0:
                    k += 1
                if k - STUCK_MARGIN > a + STUCK_MARGIN:
                    ivs.append((a + STUCK_MARGIN, k - STUCK_MARGIN))
            k += 1
        out["q" + h[2:]] = ivs
    return out


def creep(run, held):
    """Largest motion (max - min of the angle) of a joint of `run` over an
    interval in which the exact model holds that joint stuck: {rad, joint,
    from_s, to_s}, and the stuck time examined."""
    worst = {"rad": 0.0, "joint": None, "from_s": math.nan, "to_s": math.nan}
    total = 0.0
    for q, ivs in held.items():
        for a, b in ivs:
            seg = run[q][a:b + 1]
            total += run["t"][b] - run["t"][a]
            if max(seg) - min(seg) >= worst["rad"]:
                worst = {"rad": max(seg) - min(seg), "joint": q, "from_s": run["t"][a], "to_s": run["t"][b]}
    worst["stuck_time_s"] = total
    return worst


def merge(s, work, out_dir):
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    os.makedirs(out_dir, exist_ok=True)
    rows, agreement = [], {}
    summaries = {}
    for run in run_list(s):
        p = os.path.join(work, run[0] + ".json")
        if not os.path.exists(p):
            raise SweepError(f"merge: run {run[0]} has no result yet ({p}); run the sweep (or its shards) first")
        with open(p) as f:
            summaries[run[0]] = json.load(f)
    for v in s["variants"]:
        vdir = slug(v["label"])
        ref_sum, chk_sum = summaries[f"{vdir}/reference"], summaries[f"{vdir}/check"]
        for which, sm in (("reference", ref_sum), ("check", chk_sum)):
            if not sm["stats"]["ok"]:
                raise SweepError(f"variant {v['label']}: the {which} run failed: {sm['stats']['failure']}")
        ref = trajectory(os.path.join(work, vdir, "reference"))
        ee, _, dq, fin = compare(ref, trajectory(os.path.join(work, vdir, "check")))
        agreement[v["label"]] = {"ee_mm": ee, "joint_rad": dq, "final": fin,
                                 "reference_steps": ref_sum["stats"]["steps"],
                                 "tracking_mm": ref_sum["stats"]["max_path_error_mm"]}
        for run in run_list(s):
            if run[1] is not v or run[2] in ("reference", "check"):
                continue
            sm = summaries[run[0]]
            st = sm["stats"]
            if st["ok"]:
                ee, rms, dq, fin = compare(ref, trajectory(os.path.join(work, run[0])))
            else:
                ee = rms = dq = fin = math.nan
            rows.append({
                "variant": v["label"], "value": v["value"], "integrator": sm["integrator"],
                "setting": re.sub(r"^(dt|rtol)", r"\1=", run[2][len(sm["integrator"]) + 1:]),
                "ok": st["ok"], "failure": st["failure"],
                "max_ee_error_mm": ee, "rms_ee_error_mm": rms, "max_joint_error_rad": dq,
                "final_state_error": fin, "max_path_error_mm": st["max_path_error_mm"] if st["ok"] else math.nan,
                "wall_time_median_s": sm["wall_time_median_s"], "repeats": len(sm["wall_times_s"]),
                "rhs_evaluations": st["rhs_evaluations"], "jacobian_evaluations": st["jacobian_evaluations"],
                "steps": st["steps"], "rejected_steps": st["rejected_steps"], "restarts": st["restarts"],
                "time_events": st["time_events"], "root_events": st["root_events"],
            })
            if "max_ledger_residual_J" in st:  # scenes with the energy ledger
                rows[-1]["max_ledger_residual_J"] = st["max_ledger_residual_J"]
                rows[-1]["ledger_energy_scale_J"] = st["ledger_energy_scale_J"]
    limit = {}
    if s["limit_variant"]:
        lim = trajectory(os.path.join(work, slug(s["limit_variant"]), "reference"))
        for v in s["variants"]:
            ee, _, dq, _ = compare(lim, trajectory(os.path.join(work, slug(v["label"]), "reference")))
            limit[v["label"]] = {"ee_mm": ee, "joint_rad": dq}
    held_creep = {}
    if s["stuck_variant"]:
        held = stuck_intervals(trajectory(os.path.join(work, slug(s["stuck_variant"]), "reference")))
        for v in s["variants"]:
            held_creep[v["label"]] = creep(trajectory(os.path.join(work, slug(v["label"]), "reference")), held)
    name = s["name"]
    with open(os.path.join(out_dir, name + ".csv"), "w", newline="") as f:
        f.write(f"# sweep {s['file']}: scene {s['scene']}, reference {' '.join([s['reference'][0]] + s['reference'][1])}, "
                f"cross-check {' '.join([s['check'][0]] + s['check'][1])}\n")
        for v in s["variants"]:
            lab, a = v["label"], agreement[v["label"]]
            f.write(f"# {lab}: reference {' '.join([v['reference'][0]] + v['reference'][1])} vs cross-check "
                    f"{' '.join([v['check'][0]] + v['check'][1])}: {a['ee_mm']:.3g} mm, {a['joint_rad']:.3g} rad"
                    + (f"; its reference vs {s['limit_variant']}'s: {limit[lab]['ee_mm']:.3g} mm" if limit else "")
                    + (f"; creep where {s['stuck_variant']} holds a joint stuck: {held_creep[lab]['rad']:.3g} rad"
                       if held_creep else "")
                    + "\n")
        keys = []
        for r in rows:
            keys += [k for k in r if k not in keys]
        w = csv.DictWriter(f, fieldnames=keys)
        w.writeheader()
        for r in rows:
            w.writerow({k: (f"{x:.6g}" if isinstance(x, float) else x) for k, x in r.items()})
    integrators = sorted({r["integrator"] for r in rows})
    colors = {n: plt.cm.tab20(k % 20) for k, n in enumerate(integrators)}
    nv = len(s["variants"])
    fig, axes = plt.subplots(nv, 2, figsize=(11, 3.6 * nv), squeeze=False)
    for i, v in enumerate(s["variants"]):
        for j, (key, label) in enumerate((("wall_time_median_s", "wall time [s] (median)"),
                                          ("rhs_evaluations", "right-hand-side evaluations"))):
            ax = axes[i][j]
            for n in integrators:
                pts = sorted((r[key], r["max_ee_error_mm"]) for r in rows
                             if r["variant"] == v["label"] and r["integrator"] == n and r["ok"] and
                             r["max_ee_error_mm"] > 0 and r[key] > 0)
                if pts:
                    ax.plot(*zip(*pts), "o-", ms=3, lw=1, color=colors[n], label=n)
            ax.axhline(max(agreement[v["label"]]["ee_mm"], 1e-12), color="k", lw=0.8, ls=":",
                       label="reference vs check")
            nfail = sum(1 for r in rows if r["variant"] == v["label"] and not r["ok"])
            ax.set(xscale="log", yscale="log", xlabel=label, ylabel="max end-effector error [mm]",
                   title=f"{v['label']}" + (f" ({nfail} failed runs, see CSV)" if nfail else ""))
            ax.grid(True, which="major", lw=0.3)
    axes[0][1].legend(fontsize=6, ncol=2)
    fig.suptitle(s["title"], fontsize=10)
    fig.tight_layout()
    fig.savefig(os.path.join(out_dir, name + ".png"), dpi=80)
    plt.close(fig)
    cost = {}
    for n in integrators:
        for v in s["variants"]:
            ok = [r for r in rows if r["variant"] == v["label"] and r["integrator"] == n and r["ok"] and
                  r["max_ee_error_mm"] <= s["target_mm"]]
            if ok:
                best = min(ok, key=lambda r: r["rhs_evaluations"])
                cost.setdefault(n, []).append((v["value"], best["rhs_evaluations"], best["setting"],
                                               best["wall_time_median_s"]))
    plottable = {n: [p for p in pts if isinstance(p[0], (int, float)) and math.isfinite(p[0]) and p[0] > 0]
                 for n, pts in cost.items()}
    has_cost_plot = nv > 1 and any(len(p) > 1 for p in plottable.values())
    if has_cost_plot:
        fig, ax = plt.subplots(figsize=(7, 4.5))
        for n, pts in sorted(plottable.items()):
            if pts:
                ax.plot([p[0] for p in pts], [p[1] for p in pts], "o-", ms=3, lw=1, color=colors[n], label=n)
        ax.set(xscale="log", yscale="log", xlabel=s["x"], ylabel="RHS evaluations (cheapest run within target)",
               title=f"{s['title']}: cost to reach {s['target_mm']:g} mm")
        ax.grid(True, which="major", lw=0.3)
        ax.legend(fontsize=6, ncol=2)
        fig.tight_layout()
        fig.savefig(os.path.join(out_dir, name + "_cost.png"), dpi=80)
        plt.close(fig)
    summary = {"name": name, "title": s["title"], "file": s["file"], "scene": s["scene"], "x": s["x"],
               "target_mm": s["target_mm"], "findings": s["findings"], "agreement": agreement,
               "limit_variant": s["limit_variant"], "distance_to_limit": limit,
               "stuck_variant": s["stuck_variant"], "creep": held_creep,
               "variants": [{"label": v["label"], "value": v["value"]} for v in s["variants"]],
               "runs": len(rows), "failed": sum(1 for r in rows if not r["ok"]),
               "cost_to_target": {n: [{"value": p[0], "rhs": p[1], "setting": p[2], "wall_s": p[3]} for p in pts]
                                  for n, pts in cost.items()},
               "has_cost_plot": has_cost_plot}
    with open(os.path.join(out_dir, name + "_summary.json"), "w") as f:
        json.dump(summary, f, indent=1)
    return summary


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("sweep")
    ap.add_argument("--jobs", type=int, default=os.cpu_count() or 1)
    ap.add_argument("--shard", default=None, help="K/N: run only the K-th of N shares of the runs")
    ap.add_argument("--merge", action="store_true", help="only merge finished runs into results/")
    ap.add_argument("--reduced", action="store_true", help="CI: a small version, results outside results/")
    ap.add_argument("--out", default=None, help="results folder (default results/<sweep>)")
    args = ap.parse_args()
    try:
        s = load_sweep(args.sweep, args.reduced)
        work = os.path.join(ROOT, "build", "sweeps-reduced" if args.reduced else "sweeps", s["name"])
        out_dir = args.out or os.path.join(ROOT, "build", "sweeps-reduced", "results", s["folder"]) \
            if args.reduced else (args.out or os.path.join(ROOT, "results", s["folder"]))
        runs = run_list(s)
        if not args.merge:
            if args.shard:
                try:
                    k, n = (int(x) for x in args.shard.split("/"))
                    assert 1 <= k <= n
                except (ValueError, AssertionError):
                    raise SweepError(f"--shard {args.shard}: expected K/N with 1 <= K <= N")
                runs = [r for i, r in enumerate(runs) if i % n == k - 1]
            todo = [r for r in runs if not os.path.exists(os.path.join(work, r[0] + ".json"))]
            print(f"{s['name']}: {len(runs)} runs in this share, {len(runs) - len(todo)} already complete",
                  flush=True)
            with concurrent.futures.ThreadPoolExecutor(max_workers=max(1, args.jobs)) as pool:
                for sm in pool.map(lambda r: execute(s, work, r), todo):
                    st = sm["stats"]
                    print(f"  {sm['id']}: {'ok' if st['ok'] else 'FAILED'} "
                          f"{sm['wall_time_median_s']:.3g} s, {st['rhs_evaluations']} RHS", flush=True)
            if args.shard:
                return 0
        summary = merge(s, work, out_dir)
        print(f"{s['name']}: {summary['runs']} runs ({summary['failed']} failed) -> "
              f"{os.path.relpath(out_dir, ROOT)}/")
        return 0
    except SweepError as e:
        print(f"sweep: {e}", file=sys.stderr)
        return 2


if __name__ == "__main__":
    sys.exit(main())
