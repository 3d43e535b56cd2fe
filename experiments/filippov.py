#!/usr/bin/python3
"""The paper's friction rule in Filippov terms, measured on the stick-slip scene.

    /usr/bin/python3 experiments/filippov.py [--out results/stick_slip/filippov.md] [--work build/filippov]

Runs pumasim on experiments/scenes/stick_slip.toml (run folders under
--work) and writes --out, every figure with the command that measured it:

1. The torque the rule resists. At "zero" speed the rule (and Karnopp's band)
   balances the applied torque K i - h_j / Z_j (models/plant/plant.hpp): the
   row j of H qdd = tau - h with qdd_j = 0 but the other joints' accelerations
   left out. Filippov's solution on the sliding surface w_j = 0 (the exact
   constrained dynamics, which the hybrid model integrates) needs instead
   K i_j - (h_j + sum_k H_jk qdd_k) / Z_j, the qdd_k of the moving joints.
   On the hybrid reference run, at every output row where a joint is stuck
   (speed exactly 0) while another moves, both are computed from the row's
   state (H and h from `pumasim dynamics`, the moving joints' friction
   Fk sign(w) + B w) and compared.
2. The effective static level: the applied torque (the rule's) at each
   break-away of a paper-rule run (events.csv: the first accepted step
   classified slipping after a stick), against Fs and Fk.
3. Why adaptive methods grind: steps, rejected steps, shortest step and the
   joint speeds' sign changes over the accepted steps (stats.json) of
   adaptive and fixed-step runs on the rule and on the hybrid model.
"""
import argparse
import json
import os
import shlex
import subprocess
import sys
import tomllib

import numpy as np

import mode_sequence
from pumasim_exp import io as pumasim_io
from pumasim_exp.io import PUMASIM, ROOT

SCENE = os.path.join("experiments", "scenes", "stick_slip.toml")
BUDGET = 200000  # steps, as experiments/sweeps/stick_slip.toml's max_steps


def _run(work, name, integrator, options, sets=()):
    """A run folder of the scene (made unless it exists), its stats and the command."""
    out = os.path.join(work, name)
    cmd = [PUMASIM, "run", SCENE, "--integrator", integrator, "--out", os.path.relpath(out, ROOT), "--force",
           "--quiet"] + list(options)
    for s in sets:
        cmd += ["--set", s]
    if not os.path.exists(os.path.join(out, "stats.json")):
        p = subprocess.run(cmd, cwd=ROOT, capture_output=True, text=True)
        if p.returncode not in (0, 1):  # 1: a reported failure (a budget), with its run folder
            sys.exit(f"filippov: {shlex.join(cmd)}: exit status {p.returncode}: {p.stderr.strip()}")
    shown = ["pumasim"] + cmd[1:]
    return out, pumasim_io.read_stats(out), shlex.join(shown)


def _drive(run_dir):
    """(K, Fs, Fk, B, Z per joint, n, the held joints' angles) from the run's resolved scene and robot file."""
    with open(os.path.join(run_dir, "scene.resolved.toml"), "rb") as f:
        sc = tomllib.load(f)
    n = int(sc["scene"]["joints"])

    def per_joint(v):
        return np.array(v if isinstance(v, list) else [v] * n, dtype=float)

    robot = sc["scene"]["robot"]
    path = robot if robot.endswith(".toml") else os.path.join(ROOT, "models", "robots", robot + ".toml")
    with open(path, "rb") as f:
        Z = np.array([j["gear_ratio"] for j in tomllib.load(f)["joint"][:n]], dtype=float)
    fr = sc["friction"]
    return (per_joint(sc["motor"]["torque_constant"]), per_joint(fr["static_torque"]),
            per_joint(fr["kinetic_torque"]), per_joint(fr["viscous"]), Z, n,
            np.array(sc["scene"].get("held", [0.0] * (6 - n)), dtype=float))


def _dynamics(q, qd):
    """H (rotor inertia included) and h = C qd + g of the PUMA at 6-joint q, qd."""
    cmd = [PUMASIM, "dynamics", "--robot", "puma560", "--backend", "crba",
           "--q", ",".join(repr(float(x)) for x in q), "--qd", ",".join(repr(float(x)) for x in qd)]
    p = subprocess.run(cmd, capture_output=True, text=True, check=True)
    d = json.loads(p.stdout)
    return np.array(d["mass_matrix"]), np.array(d["bias"])


def coupling(run_dir):
    """Part 1 on the hybrid run's output rows: per row with a stuck joint and
    a moving one, the rule's and the exact applied torque of the stuck joint."""
    K, Fs, Fk, B, Z, n, held = _drive(run_dir)
    tr = pumasim_io.read_trajectory(run_dir).lists()
    rows = []
    for r in range(len(tr["t"])):
        qd = np.array([tr[f"qd{j + 1}"][r] for j in range(n)])
        stuck, moving = np.flatnonzero(qd == 0.0), np.flatnonzero(qd != 0.0)
        if len(stuck) == 0 or len(moving) == 0:
            continue
        q = np.array([tr[f"q{j + 1}"][r] for j in range(n)])
        i = np.array([tr[f"i_motor{j + 1}"][r] for j in range(n)])
        H6, h6 = _dynamics(np.r_[q, held], np.r_[qd, np.zeros(6 - n)])  # held joints: at rest
        H, h = H6[:n, :n], h6[:n]
        w = Z * qd
        tau = Z * (K * i - (Fk * np.sign(w) + B * w))
        F = moving
        qdd_F = np.linalg.solve(H[np.ix_(F, F)], tau[F] - h[F])
        for j in stuck:
            rule = K[j] * i[j] - h[j] / Z[j]
            exact = rule - H[j, F] @ qdd_F / Z[j]
            rows.append({"t": tr["t"][r], "joint": int(j) + 1, "rule": rule, "exact": exact, "fs": Fs[j]})
    return rows


def breakaways(run_dir):
    """Part 2: |applied| / Fs at each stick -> slip event of the run's events.csv."""
    ev = mode_sequence.by_joint(mode_sequence.read_events(run_dir) or [])
    out = []
    for j, seq in ev.items():
        for a, b in zip(seq, seq[1:]):
            if a["mode"] == "stick" and b["mode"] != "stick":
                out.append({"t": b["t"], "joint": j, "ratio": abs(b["applied"]) / b["fs"]})
    return out


def _coupling_lines(rows, cmd):
    d = np.array([abs(r["exact"] - r["rule"]) / r["fs"] for r in rows])
    worst = rows[int(np.argmax(d))]
    exact_max = max(abs(r["exact"]) / r["fs"] for r in rows)
    released = [r for r in rows if abs(r["rule"]) > r["fs"] >= abs(r["exact"])]
    return [
        "## 1. The torque the rule balances at zero speed", "",
        f"Measured on `{cmd}` (the exact hybrid model, every output row with a joint stuck while another "
        f"moves: {len(rows)} joint-rows).", "",
        "| measure | value |", "|---|---|",
        f"| max \\|exact - rule\\| / Fs (the coupling H_jk qdd_k / Z_j the rule leaves out) | {d.max():.3g} "
        f"(joint {worst['joint']} at t = {worst['t']:.3g} s: rule {worst['rule']:.4g} N m, exact "
        f"{worst['exact']:.4g} N m) |",
        f"| median \\|exact - rule\\| / Fs | {np.median(d):.3g} |",
        f"| joint-rows where it exceeds 1 % of Fs | {int(np.sum(d > 0.01))} of {len(d)} |",
        f"| joint-rows the rule would release (\\|rule\\| > Fs) that the exact model holds | {len(released)} |",
        f"| max \\|exact\\| / Fs (the hybrid model holds these joints: <= 1) | {exact_max:.4g} |", "",
        f"Reading: where a joint should stick while another accelerates, the rule balances a torque that differs "
        f"from Filippov's (the exact constrained one) by the coupling H_jk qdd_k / Z_j it leaves out: here up to "
        f"{d.max():.3g} Fs, a median of {np.median(d):.3g} Fs; at these output rows it "
        + ("never" if not released else f"{len(released)} times") + " puts a joint the exact model holds past "
        "Fs. (The last row checks the computation: the hybrid model holds these joints, so the exact torque "
        "must stay within Fs.) Between the rows (10 ms apart) the differences near a switch may be larger.", ""]


def _breakaway_lines(by_run, Fk_over_Fs):
    lines = ["## 2. The effective static level", "",
             f"\\|applied torque\\| / Fs at each break-away (a stick followed by a slip in events.csv; the rule's "
             f"applied torque for the rule, the exact one for the hybrid model). Fk / Fs = {Fk_over_Fs:.3g}.", "",
             "| run | break-aways | min | median | max |", "|---|---:|---:|---:|---:|"]
    for cmd, b in by_run:
        r = np.array([x["ratio"] for x in b]) if b else np.array([np.nan])
        lines.append(f"| `{cmd}` | {len(b)} | {np.nanmin(r):.3g} | {np.nanmedian(r):.3g} | {np.nanmax(r):.3g} |")
    rule = [b for cmd, b in by_run if "paper" in cmd and "1e-5" in cmd]
    if rule and rule[0]:
        r = np.array([x["ratio"] for x in rule[0]])
        lines += ["", f"Reading: with RK4 at 1e-5 s the rule lets joints break away at {r.min():.3g}-{r.max():.3g} Fs "
                  f"(median {np.median(r):.3g}), about Fk / Fs = {Fk_over_Fs:.3g}, and the figure depends on the "
                  "step (the RK4 1e-4 s row). Two instruments meet here, and the reading is limited by them: the "
                  "rule's break-aways are those of events.csv's classification (stuck below 1e-3 rad/s), a band a "
                  "thousand times wider than the rule's own (zero_speed = 1e-6 rad/s), so a joint creeping below "
                  "1e-3 rad/s with an applied torque near Fk (the exact model creeps so at some of these times) "
                  "counts as stuck and then as breaking away at Fk; the hybrid row comes from its root functions "
                  "(Fs by construction). What is shown: under the rule the joints leave rest with an applied "
                  "torque near Fk, not Fs -- its stick branch holds only while |w_m| <= zero_speed, and once "
                  "the speed leaves that band (moved through H by the other joints' accelerations) the friction "
                  "is Fk. How often the rule's own band releases a joint below Fs is not separated here."]
    return lines + [""]


def _grind_lines(runs, first_switch):
    lines = ["## 3. Why adaptive methods grind", "",
             "Over the accepted steps (stats.json): steps, rejected steps, shortest step, and the sign changes of "
             "the joint speeds (summed over the joints), with the step budget of the sweep "
             f"({BUDGET} steps).", "",
             "| run | ok (or where it stopped) | steps | rejected | shortest step [s] | speed sign changes |",
             "|---|---|---:|---:|---:|---:|"]
    for cmd, st in runs:
        where = "ok" if st["ok"] else st["failure"].split(" exhausted at ")[-1].split(" (")[0]
        lines.append(f"| `{cmd}` | {where} | {st['steps']} | {st['rejected_steps']} | "
                     f"{st.get('shortest_step_s', float('nan')):.3g} | {st.get('speed_sign_changes', '–')} |")
    lines += ["Reading: on the rule the adaptive methods stop within their budget at the first break-aways "
              f"(the exact model's first is at {first_switch:.3g} s): at zero speed the friction jumps between the clamped "
              "applied torque and +-Fk as the speed crosses the 1e-6 rad/s band. For the explicit method "
              "(dopri5) the counts above show the mechanism: the error estimate sees the jump in every step "
              "that straddles it and rejects the step, and the speed changes sign again and again. For BDF "
              "(cvode-bdf) they do not: few rejections and few sign changes, yet the step collapses to the "
              "shortest step above; its limiter is not the error test (CVODE's nonlinear-solver failures "
              "and the step-size cap that follows them are likely, not measured here). The hybrid model's "
              "events restart the method at each switch and it passes with a few thousand steps. The "
              "fixed-step methods do not reject: they apply the jump once per step and chatter (the sign "
              "changes), finishing at a cost set by the step."]
    return lines + [""]


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--out", default=os.path.join(ROOT, "results", "stick_slip", "filippov.md"))
    ap.add_argument("--work", default=os.path.join(ROOT, "build", "filippov"))
    args = ap.parse_args()
    paper = ['friction.model="paper"', "friction.zero_speed=1e-6"]
    hyb_dir, _, hyb_cmd = _run(args.work, "hybrid_ref", "cvode-bdf", ["--rtol", "1e-10", "--atol", "1e-13"])
    rule_runs = [_run(args.work, f"paper_rk4_{dt}", "rk4", ["--dt", dt, "--max-steps", "0"], paper)
                 for dt in ("1e-4", "1e-5")]
    grind = [_run(args.work, f"{lab}_{m}", m, ["--rtol", "1e-6", "--atol", "1e-9", "--max-steps", str(BUDGET)], sets)
             for m in ("cvode-bdf", "odeint-dopri5") for lab, sets in (("hybrid", ()), ("paper", paper))]
    _, Fs, Fk, _, _, _, _ = _drive(hyb_dir)
    text = ["# The paper's friction rule in Filippov terms (stick_slip scene)", "",
            f"Generated by `/usr/bin/python3 experiments/filippov.py` (pumasim at "
            f"{pumasim_io.read_meta(hyb_dir)['git_revision']}); the module docstring says what is measured and "
            "how.", ""]
    rows = coupling(hyb_dir)
    breaks = [(c, breakaways(d)) for d, _, c in [(hyb_dir, None, hyb_cmd)] + rule_runs]
    text += _coupling_lines(rows, hyb_cmd)
    text += _breakaway_lines(breaks, float(Fk[0] / Fs[0]))
    first = min(e["t"] for e in mode_sequence.read_events(hyb_dir) if e["t"] > 0)
    text += _grind_lines([(c, st) for _, st, c in rule_runs + grind], first)
    pumasim_io.write_text_atomic(args.out, "\n".join(text))
    keep = ("ok", "failure", "steps", "rejected_steps", "rhs_evaluations", "shortest_step_s", "speed_sign_changes")
    pumasim_io.write_json_atomic(os.path.splitext(args.out)[0] + ".json", {
        "coupling_rows": rows, "breakaways": dict(breaks),
        "runs": {c: {k: st.get(k) for k in keep} for _, st, c in rule_runs + grind}}, indent=1)
    print(f"filippov: {os.path.relpath(args.out, ROOT)}")


if __name__ == "__main__":
    main()
