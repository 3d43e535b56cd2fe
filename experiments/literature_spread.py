#!/usr/bin/python3
"""The literature spread (issue 35): the paper's tracking error across the published PUMA 560 parameter sets.

    /usr/bin/python3 experiments/literature_spread.py [--bin PUMASIM] [--jobs N] [--t-end S] [--out DIR]

The parameter sets that can be read with their sources (models/robots/puma560_sources.md,
sections 2, 3 and 8): the Robotics Toolbox's standard model (models/robots/puma560.toml,
RTB-M mdl_puma560.m, the parameters of Corke & Armstrong-Helouvry 1994) and the Armstrong,
Khatib & Burdick 1986 set as the toolbox gives it (models/robots/puma560_akb.toml, RTB-M
mdl_puma560akb.m, modified DH); and the two cross combinations that separate their rotor
inertias Jm (the largest difference between them) from the rest: RTB's links with AKB86's
Jm, AKB86's links with RTB's Jm (robot files written from the two, under WORK/robots/).
Where a scene has Coulomb friction (the paper's stick-slip rule), the friction levels of
Sokolov & Toth 1999 (static 0.146, kinetic 0.124 N m, motor side: the scenes') against the
Robotics Toolbox's Tc (motor side; no stiction there, so static = kinetic; its asymmetric
Tc+, Tc- symmetrised to their mean magnitude, chosen, with the larger and the smaller
magnitude as bounds on the two published sets).

Scenes: experiments/scenes/paper_slow_viscous.toml, paper_slow.toml, paper_fast.toml.
Held the same for every set: the drive, the viscous B (RTB's; AKB86 gives none), the PIV
gains (designed for RTB's model), the path and its timing: all chosen but B. Every set
follows the path through the numerical inverse kinematics (reference.ik = "numerical",
started at the closed-form solution's first pose, moved by the joint-angle map
q_akb = q_rtb + (pi, -pi, pi, 0, 0, 0) for the AKB kinematics); the path error is
Cartesian, so the sets stay comparable; a check row runs RTB's model with the scene's
closed-form inverse kinematics. Each row twice: AB2 at 0.5 ms (the scenes' and the
paper's method) and converged (rk4 at 2e-5 s; rk4 at 1e-5 s checks it on RTB's row).

Writes OUT/literature_spread.md and OUT/literature_spread.json (OUT: results/ensembles;
with --t-end and no --out, WORK instead); runs go to WORK = build/literature_spread/.
"""
import argparse
import json
import math
import os
import subprocess
import sys
from concurrent.futures import ThreadPoolExecutor

from pumasim_exp import io as pumasim_io
from pumasim_exp.io import ROOT, PUMASIM

WORK = os.path.join(ROOT, "build", "literature_spread")
OUT = os.path.join(ROOT, "results", "ensembles")
ROBOTS = os.path.join(ROOT, "models", "robots")
SCENES = [  # name, has Coulomb friction, what
    ("paper_slow_viscous", False, "the paper's slow run, viscous friction only (smooth)"),
    ("paper_slow", True, "the paper's slow run (0.1 m/s, 24 s), its stick-slip rule"),
    ("paper_fast", True, "the fast variant (0.4 m/s, chosen; 6 s), its stick-slip rule"),
]
AKB_FROM_RTB = (math.pi, -math.pi, math.pi)  # the joint-angle map, joints 1-3 (puma560_sources.md, sec. 8)
PAPER_DT, CONVERGED_DT, CHECK_DT = 5e-4, 2e-5, 1e-5
JM_RTB = [200e-6, 200e-6, 200e-6, 33e-6, 33e-6, 33e-6]  # RTB-M mdl_puma560.m (sec. 3)
JM_AKB = [291e-6, 409e-6, 299e-6, 35e-6, 35e-6, 35e-6]  # RTB-M mdl_puma560akb.m, AKB86 (sec. 2)
TC_PLUS = [0.395, 0.126, 0.132]  # RTB-M Tc+, joints 1-3 [N m], motor side (sec. 3)
TC_MINUS = [0.435, 0.071, 0.105]  # the magnitude of Tc-
ST99 = (0.146, 0.124)  # static, kinetic [N m], motor side (ST99 sec. 4; the scenes' values)
# key, label, base robot file, rotor inertias (None: the file's), kinematics, source, short source
SETS = [
    ("rtb", "RTB standard model", "puma560.toml", None, "rtb",
     "RTB-M `mdl_puma560.m` (CA94): kinematics, links, Jm; `models/robots/puma560.toml`",
     "`mdl_puma560.m` (CA94)"),
    ("akb", "AKB86", "puma560_akb.toml", None, "akb",
     "RTB-M `mdl_puma560akb.m` after AKB86: kinematics, links, Jm; `models/robots/puma560_akb.toml`",
     "`mdl_puma560akb.m` (AKB86)"),
    ("rtb_jm_akb", "RTB links, AKB86 Jm", "puma560.toml", JM_AKB, "rtb",
     "`puma560.toml` with `mdl_puma560akb.m`'s Jm (cross combination)", "CA94 links, AKB86 Jm"),
    ("akb_jm_rtb", "AKB86 links, RTB Jm", "puma560_akb.toml", JM_RTB, "akb",
     "`puma560_akb.toml` with `mdl_puma560.m`'s Jm (cross combination)", "AKB86 links, CA94 Jm"),
]
# key, label, static and kinetic levels per joint (None: the scene's), source, sets it runs on
FRICTION = [
    ("st99", "ST99", None, "Sokolov & Toth 1999: static 0.146, kinetic 0.124 N m (the scenes')", "all"),
    ("rtb_tc", "RTB Tc", [(p + m) / 2 for p, m in zip(TC_PLUS, TC_MINUS)],
     "RTB-M Tc, the mean magnitude of Tc+ and Tc- (chosen), static = kinetic", "all"),
    ("rtb_tc_max", "RTB Tc, larger", [max(p, m) for p, m in zip(TC_PLUS, TC_MINUS)],
     "RTB-M Tc, the larger magnitude of Tc+ and Tc-, static = kinetic", "published"),
    ("rtb_tc_min", "RTB Tc, smaller", [min(p, m) for p, m in zip(TC_PLUS, TC_MINUS)],
     "RTB-M Tc, the smaller magnitude of Tc+ and Tc-, static = kinetic", "published"),
]
MEASURES = ("max_path_error_mm", "rms_path_error_mm", "max_path_deviation_mm")


def variant_robot(key, base, jm):
    """The robot file of a set: a shipped file, or one written from it with other rotor inertias."""
    src = os.path.join(ROBOTS, base)
    if jm is None:
        return src
    with open(src) as f:
        lines = f.read().split("\n")
    out, k = [], 0
    for line in lines:
        if line.startswith("rotor_inertia ="):
            line = f"rotor_inertia = {jm[k]!r}   # [kg m^2], motor side: the other set's Jm (literature_spread.py)"
            k += 1
        elif line.startswith("name = "):
            line = f'name = "{key}"'
        out.append(line)
    if k != 6:
        sys.exit(f"literature_spread.py: {src}: expected 6 rotor_inertia lines, found {k}")
    path = os.path.join(WORK, "robots", f"{key}.toml")
    os.makedirs(os.path.dirname(path), exist_ok=True)
    header = f"# Written by experiments/literature_spread.py from models/robots/{base}, Jm replaced.\n"
    pumasim_io.write_text_atomic(path, header + "\n".join(out))
    return path


def run(binary, scene, label, sets, integrator, dt, t_end):
    """One `pumasim run`; its stats (a failed run's too)."""
    out = os.path.join(WORK, "runs", scene, label, f"{integrator}-{dt!r}")
    cmd = [binary, "run", os.path.join(ROOT, "experiments", "scenes", scene + ".toml"), "--integrator", integrator,
           "--dt", repr(dt), "--out", out, "--force", "--quiet"]
    for s in sets:
        cmd += ["--unset", s[1:]] if s.startswith("-") else ["--set", s]
    if t_end:
        cmd += ["--t-end", repr(t_end)]
    p = subprocess.run(cmd, capture_output=True, text=True, cwd=ROOT)
    if p.returncode not in (0, 1):
        sys.exit(f"literature_spread.py: {' '.join(cmd)} exited {p.returncode}: {p.stderr.strip()}")
    return pumasim_io.read_stats(out), out


def start_pose(binary, t_end):
    """RTB's closed-form inverse kinematics at the path's start (the scenes share the path)."""
    _, out = run(binary, "paper_slow_viscous", "rtb-closed-form", [], "ab2", PAPER_DT, t_end)
    tr = pumasim_io.read_trajectory(out)
    return [float(tr[f"q_ref{j}"][0]) for j in (1, 2, 3)]


def overrides(robot, kinematics, friction, q_rtb):
    """--set / --unset (a leading '-') values of a row."""
    guess = q_rtb if kinematics == "rtb" else [q + c for q, c in zip(q_rtb, AKB_FROM_RTB)]
    s = [f"scene.robot={json.dumps(robot)}", 'reference.ik="numerical"',
         "reference.ik_guess=[" + ", ".join(repr(g) for g in guess) + "]", "-reference.arm", "-reference.elbow"]
    if friction is not None:
        s += ["friction.static_torque=" + json.dumps(friction), "friction.kinetic_torque=" + json.dumps(friction)]
    return s


def rows_of(scene, coulomb):
    """The rows of a scene: (set, friction) pairs."""
    if not coulomb:
        return [(s, None) for s in SETS]
    return [(s, f) for f in FRICTION for s in SETS if f[4] == "all" or s[0] in ("rtb", "akb")]


def measure(task):
    binary, scene, st, fr, robot, q_rtb, t_end = task
    key = st[0] + ("" if fr is None else "+" + fr[0])
    sets = overrides(robot, st[4], None if fr is None else fr[2], q_rtb)
    row = {"scene": scene, "row": key, "set": st[0], "set_label": st[1], "source": st[5], "short_source": st[6],
           "friction": "viscous only" if fr is None else fr[1]}
    for name, integrator, dt in (("ab2", "ab2", PAPER_DT), ("converged", "rk4", CONVERGED_DT)):
        stats, _ = run(binary, scene, key, sets, integrator, dt, t_end)
        ok = bool(stats["ok"])
        row[f"{name}_ok"] = ok
        row[f"{name}_failure"] = stats.get("failure", "")
        for m in MEASURES:
            row[f"{name}_{m}"] = float(stats[m]) if ok else math.nan
        row[f"{name}_peak_current_A"] = [float(x) for x in stats["peak_current_A"]] if ok else [math.nan] * 3
    return row


def dynamics_at(binary, robot, q):
    """H's diagonal and g at q (6 joints: the wrist at the scenes' held 0) from `pumasim dynamics`."""
    cmd = [binary, "dynamics", "--robot", robot, "--backend", "crba", "--q=" + ",".join(repr(x) for x in q)]
    p = subprocess.run(cmd, capture_output=True, text=True, cwd=ROOT)
    if p.returncode != 0:
        sys.exit(f"literature_spread.py: {' '.join(cmd)} exited {p.returncode}: {p.stderr.strip()}")
    d = json.loads(p.stdout)
    return [d["mass_matrix"][j][j] for j in range(3)], d["gravity"][:3]


def spread(rows, key):
    """min, max, max/min over the rows that finished; the rows at the ends."""
    v = [(r[key], r["row"]) for r in rows if not math.isnan(r[key])]
    if not v:
        return None
    lo, hi = min(v), max(v)
    return {"min": lo[0], "min_row": lo[1], "max": hi[0], "max_row": hi[1],
            "max_over_min": hi[0] / lo[0] if lo[0] > 0 else math.inf, "finished": len(v), "rows": len(rows)}


def checks(binary, q_rtb, t_end):
    """Per scene: RTB's model with the closed-form inverse kinematics (AB2), and its converged row at half the step."""
    out = {}
    for scene, _, _ in SCENES:
        closed, _ = run(binary, scene, "rtb-closed-form", [], "ab2", PAPER_DT, t_end)
        robot = os.path.join(ROBOTS, "puma560.toml")
        half, _ = run(binary, scene, "rtb-check", overrides(robot, "rtb", None, q_rtb), "rk4", CHECK_DT, t_end)
        out[scene] = {"closed_form_ab2_max_path_error_mm": closed["max_path_error_mm"] if closed["ok"] else math.nan,
                      "check_rk4_max_path_error_mm": half["max_path_error_mm"] if half["ok"] else math.nan}
    return out


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--bin", default=PUMASIM)
    ap.add_argument("--jobs", type=int, default=os.cpu_count() or 1)
    ap.add_argument("--t-end", type=float, default=None, help="shorter runs [s] (written to WORK unless --out)")
    ap.add_argument("--out", default=None)
    args = ap.parse_args()
    out = args.out or (WORK if args.t_end else OUT)
    robots = {st[0]: variant_robot(st[0], st[2], st[3]) for st in SETS}
    q_rtb = start_pose(args.bin, args.t_end)
    tasks = [(args.bin, scene, st, fr, robots[st[0]], q_rtb, args.t_end)
             for scene, coulomb, _ in SCENES for st, fr in rows_of(scene, coulomb)]
    with ThreadPoolExecutor(max_workers=max(1, args.jobs)) as ex:
        rows = list(ex.map(measure, tasks))
    check = checks(args.bin, q_rtb, args.t_end)
    start = {}
    for st in SETS:  # each set's own start pose: its AB2 run of paper_slow_viscous, first row
        guess = q_rtb if st[4] == "rtb" else [q + c for q, c in zip(q_rtb, AKB_FROM_RTB)]
        run_dir = os.path.join(WORK, "runs", "paper_slow_viscous", st[0], f"ab2-{PAPER_DT!r}")
        q0 = [float(pumasim_io.read_trajectory(run_dir)[f"q{j}"][0]) for j in (1, 2, 3)]
        H, g = dynamics_at(args.bin, robots[st[0]], q0 + [0.0, 0.0, 0.0])
        start[st[0]] = {"q": q0, "ik_guess": guess, "H_diag": H, "g": g}
    for r in rows:
        print(f"{r['scene']:20s} {r['row']:22s} AB2 {r['ab2_max_path_error_mm']:.4f}"
              f" converged {r['converged_max_path_error_mm']:.4f} mm")
    meta = pumasim_io.read_meta(os.path.join(WORK, "runs", "paper_slow_viscous", "rtb-closed-form",
                                             f"ab2-{PAPER_DT!r}"))
    write(out, rows, check, start, q_rtb, meta, args.t_end)


def summary(rows, check):
    """Per scene: the spreads of every measure and peak current, for both integrators."""
    doc = {}
    for scene, _, _ in SCENES:
        rs = [r for r in rows if r["scene"] == scene]
        doc[scene] = {"check": check[scene]}
        for name in ("ab2", "converged"):
            for m in MEASURES:
                doc[scene][f"{name}_{m}"] = spread(rs, f"{name}_{m}")
            for j in range(3):
                for r in rs:
                    r[f"{name}_peak_current{j + 1}_A"] = r[f"{name}_peak_current_A"][j]
                doc[scene][f"{name}_peak_current{j + 1}_A"] = spread(rs, f"{name}_peak_current{j + 1}_A")
            doc[scene][f"{name}_failed"] = [r["row"] for r in rs if not r[f"{name}_ok"]]
    return doc


def finite(x):
    """x with every NaN or infinity replaced by None (JSON has neither)."""
    if isinstance(x, float):
        return x if math.isfinite(x) else None
    if isinstance(x, dict):
        return {k: finite(v) for k, v in x.items()}
    if isinstance(x, (list, tuple)):
        return [finite(v) for v in x]
    return x


def g3(x):
    """Three significant digits (a dash for a run that did not finish)."""
    return "–" if x is None or (isinstance(x, float) and math.isnan(x)) else f"{x:#.3g}"


def write(out, rows, check, start, q_rtb, meta, t_end):
    spreads = summary(rows, check)
    os.makedirs(out, exist_ok=True)
    doc = {"written_by": "experiments/literature_spread.py", "t_end": t_end, "ab2_dt": PAPER_DT,
           "converged": f"rk4 dt={CONVERGED_DT!r}", "check": f"rk4 dt={CHECK_DT!r}",
           "joint_map_akb_from_rtb": list(AKB_FROM_RTB) + [0.0, 0.0, 0.0], "start_pose_rtb": q_rtb,
           "sets": [{"key": s[0], "label": s[1], "base_robot": "models/robots/" + s[2],
                     "rotor_inertia": s[3] or "the file's", "source": s[5]} for s in SETS],
           "friction": [{"key": f[0], "label": f[1], "levels": f[2] or list(ST99), "source": f[3]} for f in FRICTION],
           "start": start, "rows": rows, "spread": spreads, "revision": pumasim_io.revision_line(meta)}
    pumasim_io.write_text_atomic(os.path.join(out, "literature_spread.json"), json.dumps(finite(doc), indent=2) + "\n")
    pumasim_io.write_text_atomic(os.path.join(out, "literature_spread.md"),
                                 markdown(rows, spreads, start, q_rtb, meta, t_end))
    print(f"wrote {os.path.relpath(os.path.join(out, 'literature_spread.md'), ROOT)}")


def markdown(rows, spreads, start, q_rtb, meta, t_end):
    lines = [
        "<!-- Generated by experiments/literature_spread.py; do not edit. -->",
        "# The literature spread: the paper's tracking error across the published PUMA 560 parameter sets",
        "",
        "Issue 35. The parameter sets that can be read with their sources "
        "(`models/robots/puma560_sources.md`, sections 2, 3 and 8), run on the paper's scenes with everything "
        "else held: the drive, the viscous friction B (the Robotics Toolbox's, for every set: AKB86 gives none), "
        "the PIV gains (designed for RTB's model), the path and its timing; none of these has a PUMA source "
        "but B, all are chosen, and all are the same for every set. Every set follows the path through the "
        "numerical inverse kinematics, started at the closed-form solution's first pose (moved by the "
        "joint-angle map q_akb = q_rtb + (π, −π, π, 0, 0, 0) for the AKB86 kinematics); the path error is "
        "Cartesian, so the sets stay comparable. Each row twice: AB2 at 0.5 ms (the scenes' and the paper's "
        f"method) and converged (rk4 at {CONVERGED_DT:g} s). *Max path error*: the largest distance from the "
        "reference point at the same time (the paper's measure); *path deviation*: the largest distance from "
        "the path wherever along it; peak currents: the largest |i| of each motor.",
        "",
        pumasim_io.revision_line(meta) + ("" if not t_end else f" Runs cut at t_end = {t_end:g} s."),
        "",
    ]
    lines += sets_section(start)
    for scene, coulomb, what in SCENES:
        lines += scene_section(scene, what, [r for r in rows if r["scene"] == scene], spreads[scene])
    lines += prior_section(rows, spreads)
    return "\n".join(lines) + "\n"


def sets_section(start):
    lines = ["## The sets", "",
             "| set | source | Jm, joints 1–6 [10⁻⁶ kg m²] | H11, H22, H33 at the start [kg m²] |"
             " g2, g3 at the start [N m] |", "|---|---|---|---|---|"]
    for key, label, _, jm, kin, source, _ in SETS:
        jm = jm or (JM_RTB if key == "rtb" else JM_AKB)
        s = start[key]
        lines.append(f"| {label} | {source} | " + ", ".join(f"{1e6 * x:g}" for x in jm) + " | "
                     + ", ".join(f"{x:.4g}" for x in s["H_diag"]) + " | " + ", ".join(f"{x:.4g}" for x in s["g"][1:])
                     + " |")
    lines += ["", "H and g (rotor inertia included, wrist at the scenes' held 0) from "
              "`pumasim dynamics --backend crba` at each set's start pose. Friction levels where a scene has "
              "Coulomb friction (motor side, joints 1–3, static / kinetic):", "",
              "| friction | levels [N m] | source |", "|---|---|---|"]
    for key, label, levels, source, _ in FRICTION:
        lv = f"{ST99[0]:g} / {ST99[1]:g} each" if levels is None else ", ".join(f"{x:g}" for x in levels)
        lines.append(f"| {label} | {lv} | {source} |")
    return lines + [""]


def scene_section(scene, what, rs, sp):
    lines = [f"## {scene}", "", f"`experiments/scenes/{scene}.toml`: {what}.", "",
             "| set | source | friction | max path error, AB2 [mm] | converged [mm] | RMS path error, converged [mm] |"
             " max path deviation, converged [mm] | peak currents 1, 2, 3, converged [A] | failed |",
             "|---|---|---|---:|---:|---:|---:|---:|---|"]
    for r in rs:
        failed = [n for n in ("ab2", "converged") if not r[f"{n}_ok"]]
        lines.append(f"| {r['set_label']} | {r['short_source']} | {r['friction']} | {g3(r['ab2_max_path_error_mm'])} |"
                     f" {g3(r['converged_max_path_error_mm'])} | {g3(r['converged_rms_path_error_mm'])} |"
                     f" {g3(r['converged_max_path_deviation_mm'])} | "
                     + ", ".join(g3(x) for x in r["converged_peak_current_A"]) + " | "
                     + (", ".join(f"{n}: {r[n + '_failure']}" for n in failed) or "no") + " |")
    lines += ["", "| spread over the rows | min | max | max / min |", "|---|---:|---:|---:|"]
    for key, label in (("ab2_max_path_error_mm", "max path error, AB2 [mm]"),
                       ("converged_max_path_error_mm", "max path error, converged [mm]"),
                       ("converged_rms_path_error_mm", "RMS path error, converged [mm]"),
                       ("converged_max_path_deviation_mm", "max path deviation, converged [mm]"),
                       ("converged_peak_current1_A", "peak current 1, converged [A]"),
                       ("converged_peak_current2_A", "peak current 2, converged [A]"),
                       ("converged_peak_current3_A", "peak current 3, converged [A]")):
        s = sp[key]
        lines.append(f"| {label} | {g3(s['min'])} | {g3(s['max'])} | {s['max_over_min']:.3f} |" if s else
                     f"| {label} | – | – | – |")
    c = sp["check"]
    rtb = next(r for r in rs if r["set"] == "rtb" and r["friction"] in ("viscous only", "ST99"))
    lines += ["", "Checks on RTB's row with the scene's friction (max path error "
              f"{rtb['ab2_max_path_error_mm']:.6g} mm with AB2, {rtb['converged_max_path_error_mm']:.6g} mm "
              "converged): with the scene's closed-form "
              f"inverse kinematics instead, AB2, {c['closed_form_ab2_max_path_error_mm']:.6g} mm; converged at rk4 "
              f"{CHECK_DT:g} s instead of {CONVERGED_DT:g} s, {c['check_rk4_max_path_error_mm']:.6g} mm. "
              "Runs that failed: "
              + (", ".join(sp["ab2_failed"] + sp["converged_failed"]) or "none") + ".", ""]
    return lines


def prior_section(rows, spreads):
    lines = ["## Prior", "",
             "Over every row of a scene (the two published sets, the two cross combinations and, where the "
             "scene has Coulomb friction, the friction levels), converged runs; the two sets as published with "
             "the scene's own friction beside it.", ""]
    for scene, _, _ in SCENES:
        key = "converged_max_path_error_mm"
        rs = [r for r in rows if r["scene"] == scene]
        own = [r for r in rs if r["friction"] in ("viscous only", "ST99")]  # the scene's own friction
        s, so = spreads[scene][key], spread(own, key)
        pub = {r["set"]: r[key] for r in own}
        if s is None or so is None:
            lines.append(f"- Prior {scene}: no run finished.")
            continue
        lines.append(f"- Prior {scene}: across the published sets the tracking error spans {g3(s['min'])} to "
                     f"{g3(s['max'])} mm (max / min {s['max_over_min']:.2f}, {s['finished']} rows; lowest "
                     f"{s['min_row']}, highest {s['max_row']}).")
        lines.append(f"  - Own-friction {scene}: with the scene's own friction, over the four arms, "
                     f"{g3(so['min'])} to {g3(so['max'])} mm (max / min {so['max_over_min']:.2f}).")
        lines.append(f"  - As-published {scene}: RTB standard model {g3(pub.get('rtb'))} mm, "
                     f"AKB86 {g3(pub.get('akb'))} mm (the scene's own friction).")
        rtb = next(r for r in own if r["set"] == "rtb")
        lines.append(f"  - Integration {scene}: AB2 at 0.5 ms against converged, RTB's row: "
                     f"{g3(abs(rtb['ab2_max_path_error_mm'] - rtb[key]))} mm.")
    return lines + [""]


if __name__ == "__main__":
    main()
