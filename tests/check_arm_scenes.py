#!/usr/bin/python3
"""Every integrator on a scene of the two non-PUMA arms (models/robots/planar2.toml,
models/robots/stanford.toml): each run ends ok and agrees with a tight reference.

    /usr/bin/python3 tests/check_arm_scenes.py PUMASIM SCENE [--t-end S] [--min-order K]

SCENE is a file under experiments/scenes/. Each integrator of `pumasim
integrators` (of order K or more, when --min-order is given) runs it for --t-end seconds (the fixed-step methods at DT, the
adaptive ones at RTOL, ATOL = 1e-2 RTOL), and once more cvode-bdf at rtol
1e-11 (atol 1e-13) as the reference. Every run must

- end with exit status 0, stats.json ok, t_reached = t_end and a finite last
  state (tests/check_extreme_runs.py's judge);
- agree with the reference in every joint, at every output time, to AGREE
  (0.1 %) of the largest joint excursion of the reference run: a method that
  solves another ODE (a wrong coefficient, a lost term) misses by a sizeable
  fraction of the motion, while at these settings a correct one of order >= 1
  is far inside (Euler's global error at 1e-4 s is of order DT |q''| t_end).

A scene with the energy ledger (a passive arm: no drive, viscous friction
only) must also keep its energy: the mechanical energy E = T + V loses power
B w^2 >= 0 to the friction and gains none, so E(t) never rises above its
running minimum and E(t) - E(0) = -e_friction(t); each by at most AGREE of the
energy the reference run dissipates (the ledger_residual column is the second).

A scene under computed torque with La = 0 (planar2_tracking) must also stay
within the error bound of its control law: with an exact model the joint
error e = q_ref - q obeys e'' + kd e' + kp e = H^-1 Z^2 B q' (the only torque not
cancelled is the viscous friction, Z^2 B q' link side), with e(0) = e'(0) = 0 and
kd = 2 sqrt(kp) (critically damped: impulse response t exp(-sqrt(kp) t) >= 0,
integral 1/kp), so |e_j(t)| <= sup |H^-1 Z^2 B q'|_j / kp. H = H_link + diag(Z^2 Im)
with H_link positive semi-definite, so |H^-1 v| <= |v| / min_j(Z_j^2 Im_j), and
    |e_j| <= max_j(Z_j^2 B_j) / min_j(Z_j^2 Im_j) * max_t |q'(t)|_2 / kp,
checked with the run's own speeds (plus AGREE's allowance for its error).
"""
import argparse
import json
import math
import os
import shutil
import subprocess
import sys
import tempfile
import tomllib

import numpy as np

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.normpath(os.path.join(HERE, ".."))
sys.path.insert(0, os.path.join(ROOT, "experiments"))
sys.path.insert(0, HERE)
from pumasim_exp import io as pumasim_io  # noqa: E402
from check_extreme_runs import integrators, judge  # noqa: E402

SCENES_DIR = os.path.join(ROOT, "experiments", "scenes")
DT = 1e-4                    # [s] the fixed-step methods' step
RTOL = 1e-8                  # the adaptive methods' rtol; atol = 1e-2 rtol
REFERENCE = ("cvode-bdf", ["--rtol", "1e-11", "--atol", "1e-13"])
AGREE = 1e-3                 # relative agreement with the reference (see above)


def run(pumasim, scene, work, name, options, t_end):
    """Runs the scene; returns (problem or '', trajectory or None)."""
    out = os.path.join(work, name)
    cmd = [pumasim, "run", scene, "--t-end", repr(t_end), "--out", out, "--quiet"] + options
    p = subprocess.run(cmd, capture_output=True, text=True, timeout=600)
    kind, why = judge(p, out, t_end)
    if kind != "ok":
        return f"{kind}: {why}", None
    return "", pumasim_io.read_trajectory(out)


def joint_names(traj):
    return [c for c in traj.names if c.startswith("q") and c[1:].isdigit()]


def agreement(traj, ref):
    """The largest joint difference over the common rows, and the allowed one."""
    qs = joint_names(ref)
    n = min(len(traj), len(ref))
    if not np.allclose(traj["t"][:n], ref["t"][:n], rtol=0, atol=1e-12):
        return math.inf, 0.0
    diff = max(float(np.max(np.abs(traj[q][:n] - ref[q][:n]))) for q in qs)
    excursion = max(float(np.ptp(ref[q])) for q in qs)
    return diff, AGREE * excursion


def energy_problems(traj, ref):
    """The passive arm's energy: never rising, and the ledger balanced."""
    E, Eref = traj["E_mech"], ref["E_mech"]
    tol = AGREE * (Eref[0] - Eref[-1])
    if not tol > 0:
        return [f"the reference dissipates no energy (E(0) - E(T) = {Eref[0] - Eref[-1]:.6g} J)"]
    out = []
    rise = float(np.max(E - np.minimum.accumulate(E)))
    if rise > tol:
        out.append(f"the energy rises by {rise:.3g} J above its running minimum (allowed {tol:.3g} J)")
    res = float(np.max(np.abs(traj["ledger_residual"])))
    if res > tol:
        out.append(f"E(t) - E(0) + e_friction(t) reaches {res:.3g} J (allowed {tol:.3g} J)")
    return out


def resolved(pumasim, scene):
    """The scene as `pumasim check` resolves it (every default filled in) and its robot file."""
    out = subprocess.run([pumasim, "check", scene], capture_output=True, text=True, check=True).stdout
    robot = next(ln for ln in out.splitlines() if ln.startswith("# robot file: "))
    return tomllib.loads(out.partition("# state (")[0]), robot[len("# robot file: "):].rsplit(" (", 1)[0]


def tracking_bound(sc, robot_file):
    """The computed-torque bound's factor max(Z^2 B) / (min(Z^2 Im) min(kp)), or None where it does not apply."""
    ctl, mot = sc.get("controller", {}), sc.get("motor", {})
    la = mot.get("inductance", 1.0)
    if ctl.get("law") != "computed_torque" or "reference" not in sc or \
            any(v != 0 for v in (la if isinstance(la, list) else [la])):
        return None
    kp, kd = ctl["kp"], ctl["kd"]  # resolved: one per joint
    if any(abs(d - 2 * math.sqrt(p)) > 1e-12 * d for p, d in zip(kp, kd)):
        return None  # not critically damped: the bound's impulse response is not t exp(-sqrt(kp) t)
    with open(robot_file, "rb") as f:
        joints = tomllib.load(f)["joint"][:sc["scene"]["joints"]]
    B = sc["friction"]["viscous"]
    zb = max(j["gear_ratio"] ** 2 * b for j, b in zip(joints, B))
    zi = min(j["gear_ratio"] ** 2 * j["rotor_inertia"] for j in joints)
    return zb / zi / min(kp)


def tracking_error(traj, factor):
    """The largest joint error |q_ref - q| and the computed-torque bound on it."""
    qs = joint_names(traj)
    speed = np.sqrt(sum(traj["qd" + q[1:]] ** 2 for q in qs))
    worst = max(float(np.max(np.abs(traj["q_ref" + q[1:]] - traj[q]))) for q in qs)
    return worst, factor * float(np.max(speed))


def orders(pumasim):
    """The registry's order of each integrator for general scenes (`pumasim integrators --json`; not those
    that integrate only a lossless, unforced arm, conservative_only: the arm scenes have friction or a drive)."""
    p = subprocess.run([pumasim, "integrators", "--json"], capture_output=True, text=True, check=True)
    return {entry["name"]: entry["order"] for entry in json.loads(p.stdout) if not entry["conservative_only"]}


def check(pumasim, scene, t_end, work, min_order=1):
    """(lines to print, problems) for every integrator of order >= min_order on the scene."""
    sc, robot_file = resolved(pumasim, scene)
    problem, ref = run(pumasim, scene, work, "reference", ["--integrator", REFERENCE[0]] + REFERENCE[1], t_end)
    if problem:
        return [], [f"reference {REFERENCE[0]}: {problem}"]
    factor = tracking_bound(sc, robot_file)
    lines, problems = [], []
    order = orders(pumasim)
    for integ, fixed in integrators(pumasim):
        if order[integ] < min_order:
            lines.append(f"  {integ:20s} not run (order {order[integ]} < --min-order {min_order})")
            continue
        opts = ["--integrator", integ] + (["--dt", repr(DT)] if fixed else
                                          ["--rtol", repr(RTOL), "--atol", repr(1e-2 * RTOL)])
        problem, traj = run(pumasim, scene, work, integ, opts, t_end)
        found = [problem] if problem else []
        if traj is not None:
            diff, allowed = agreement(traj, ref)
            lines.append(f"  {integ:20s} max |q - q_ref run| = {diff:.3g} (allowed {allowed:.3g})")
            if not diff <= allowed:
                found.append(f"joints differ from the reference by {diff:.3g} (allowed {allowed:.3g})")
            if "E_mech" in traj:
                found += energy_problems(traj, ref)
            if factor is not None:
                worst, bound = tracking_error(traj, factor)
                lines[-1] += f", joint error {worst:.4g} (bound {bound:.4g})"
                if not worst <= bound + allowed:
                    found.append(f"joint error {worst:.4g} above the computed-torque bound {bound:.4g} "
                                 f"+ {allowed:.3g}")
        problems += [f"{integ}: {p}" for p in found]
    return lines, problems


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("pumasim")
    ap.add_argument("scene", help="a file under experiments/scenes/")
    ap.add_argument("--t-end", type=float, default=1.0)
    ap.add_argument("--min-order", type=int, default=1,
                    help="run only the integrators of at least this order (a scene whose nearby "
                         "trajectories part fast leaves first-order methods at DT outside AGREE)")
    a = ap.parse_args()
    scene = os.path.join(SCENES_DIR, a.scene)
    work = tempfile.mkdtemp(prefix="pumasim_arm_scenes_")
    try:
        lines, problems = check(a.pumasim, scene, a.t_end, work, a.min_order)
    finally:
        shutil.rmtree(work, ignore_errors=True)
    print(f"{a.scene}, t_end = {a.t_end} s:")
    print("\n".join(lines))
    if problems:
        sys.exit("check_arm_scenes: FAILED\n  " + "\n  ".join(problems))
    which = "every integrator" + (f" of order >= {a.min_order}" if a.min_order > 1 else "")
    print(f"check_arm_scenes: {which} ended ok on {a.scene} and agreed with the reference")


if __name__ == "__main__":
    main()
