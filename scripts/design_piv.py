#!/usr/bin/env python3
"""PIV gains for a scene's joints by pole placement on the decoupled joint model.

Usage: design_piv.py <scene.toml> [--bandwidth HZ] [--damping ZETA] [--pumasim BIN]

Any robot file: the scene is resolved by `pumasim check` (its robot file, held
joints, drive), the joint-space inertia M(q0) at the scene's start pose comes
from `pumasim dynamics` on that robot file (rotor inertia included unless the
scene removes it), and each simulated joint j gets, on the motor side (La
neglected, gravity and coupling taken as disturbances the integral removes):
    J w' = K i,   i = (K_A u - K w) / R_t,   R_t = R0 + R,   J = M_jj(q0) / Z^2
With u = Kp e + Ki z - Kv w + Kvff w_ref + Kaff a_ref (e, w motor side):
    closed loop  J s^2 + (K^2/R_t + b Kv) s + b Kp = 0,   b = K K_A / R_t
    Kp = J wn^2 / b,  Kv = (2 zeta wn J - K^2 / R_t) / b  (>= 0),  Ki = Kp wn / 10
    Kvff = Kv + K / K_A   (cancels velocity feedback and back-EMF on the reference)
    Kaff = J / b          (the reference acceleration's torque)
A prismatic joint is the same model in its own units: its gear ratio Z is in
rad/m (motor angle per metre), M_jj a mass [kg], so J = M_jj / Z^2 is again the
inertia the motor sees [kg m^2], and e, w stay motor-side angles.
Prints the [controller] gain lines for the scene.

A scene it cannot design for (no drive, another control law, a file pumasim
refuses) or a bad argument: a message on stderr and exit status 2, no traceback.
"""
import argparse
import json
import math
import os
import subprocess
import sys
import tomllib

ROOT = os.path.join(os.path.dirname(os.path.abspath(__file__)), "..")
PUMASIM = os.environ.get("PUMASIM", os.path.join(ROOT, "build", "release", "bin", "pumasim"))


class Refusal(Exception):
    """A scene or an argument this script cannot design for: exit status 2."""


def per_joint(v, n):
    return v if isinstance(v, list) else [v] * n


def pumasim(binary, args, what):
    try:
        r = subprocess.run([binary] + args, capture_output=True, text=True, check=False)
    except OSError as e:
        raise Refusal(f"cannot run pumasim ({binary}): {e.strerror}; build it (scripts/build.sh) "
                      "or name it with --pumasim") from None
    if r.returncode != 0:
        raise Refusal(f"{what}: pumasim {args[0]} refused it (exit {r.returncode}):\n{r.stderr.strip()}")
    return r.stdout


def resolve(binary, scene):
    """The scene as `pumasim check` resolves it, its initial state and its robot file."""
    out = pumasim(binary, ["check", scene], scene)
    toml_text, _, rest = out.partition("# state (")
    try:
        resolved = tomllib.loads(toml_text)
        names = rest.splitlines()[0].split(":", 1)[1].split()
        init = next(ln for ln in rest.splitlines() if ln.startswith("# initial state:"))
        x0 = [float(v) for v in init.split(":", 1)[1].split()]
        robot = next(ln for ln in rest.splitlines() if ln.startswith("# robot file: "))
        robot_file = robot[len("# robot file: "):].rsplit(" (", 1)[0]
    except (tomllib.TOMLDecodeError, IndexError, StopIteration, ValueError) as e:
        raise Refusal(f"{scene}: cannot read what `pumasim check` printed ({e})") from None
    return resolved, dict(zip(names, x0)), robot_file


def start_pose(scene, sc, state, robot):
    """Every joint of the robot at the start: the simulated ones, then the held ones."""
    n, dof = sc["scene"]["joints"], robot["dof"]
    held = list(sc["scene"].get("held", []))
    q = [state.get(f"q{j + 1}") for j in range(n)]
    if None in q:
        raise Refusal(f"{scene}: the state has no joint values q1..q{n}")
    q += held + [0.0] * (dof - n - len(held))
    if len(q) != dof:
        raise Refusal(f"{scene}: {n} simulated and {len(held)} held joints, the robot has {dof}")
    return q


def check_scene(scene, sc):
    if "amplifier" not in sc or "motor" not in sc:
        raise Refusal(f"{scene}: [amplifier], [motor]: expected a drive (PIV gains act through it), got none")
    law = sc.get("controller", {}).get("law", "piv")
    if law != "piv":
        raise Refusal(f"{scene}: controller.law: expected \"piv\" (these are PIV gains), got \"{law}\"")


def design(sc, robot, mass_matrix, args):
    n = sc["scene"]["joints"]
    amp, mot = sc["amplifier"], sc["motor"]
    KA, R0 = per_joint(amp["gain"], n), per_joint(amp.get("output_resistance", 0.0), n)
    R, K = per_joint(mot["resistance"], n), per_joint(mot["torque_constant"], n)
    wn = 2 * math.pi * args.bandwidth
    gains = {k: [] for k in ("kp", "ki", "kv", "kvff", "kaff")}
    for j in range(n):
        Z = robot["joints"][j]["gear_ratio"]
        J = mass_matrix[j][j] / Z ** 2
        Rt = R0[j] + R[j]
        b = K[j] * KA[j] / Rt
        kp = J * wn ** 2 / b
        kv = max(0.0, (2 * args.damping * wn * J - K[j] ** 2 / Rt) / b)
        gains["kp"].append(kp)
        gains["ki"].append(kp * wn / 10)
        gains["kv"].append(kv)
        gains["kvff"].append(kv + K[j] / KA[j])
        gains["kaff"].append(J / b)
    return gains


def positive(text):
    try:
        v = float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected a number, got {text!r}") from None
    if not (v > 0 and math.isfinite(v)):
        raise argparse.ArgumentTypeError(f"expected a finite number > 0, got {text}")
    return v


def main():
    ap = argparse.ArgumentParser(description="PIV gains for a scene (pole placement per joint).")
    ap.add_argument("scene")
    ap.add_argument("--bandwidth", type=positive, default=10.0, help="natural frequency [Hz]")
    ap.add_argument("--damping", type=positive, default=0.8)
    ap.add_argument("--pumasim", default=PUMASIM, help="the pumasim binary (default: $PUMASIM or the release build)")
    args = ap.parse_args()  # a bad argument: argparse's message and exit status 2
    try:
        sc, state, robot_file = resolve(args.pumasim, args.scene)
        check_scene(args.scene, sc)
        # The robot as pumasim reads it (a TOML or URDF file, its side file
        # included): no second parser here.
        robot = json.loads(pumasim(args.pumasim, ["robot", robot_file], robot_file))
        q = start_pose(args.scene, sc, state, robot)
        dyn_args = ["dynamics", "--robot", robot_file, "--backend", "crba", "--q=" + ",".join(repr(v) for v in q)]
        if not sc["scene"].get("rotor_inertia", True):
            dyn_args.append("--no-rotor-inertia")
        dyn = json.loads(pumasim(args.pumasim, dyn_args, robot_file))
        gains = design(sc, robot, dyn["mass_matrix"], args)
    except Refusal as e:
        print(f"design_piv.py: {e}", file=sys.stderr)
        return 2
    print(f"# designed by scripts/design_piv.py {os.path.relpath(args.scene, ROOT)} "
          f"--bandwidth {args.bandwidth:g} --damping {args.damping:g}")
    print(f"# (start pose q = [{', '.join(f'{v:.4f}' for v in q)}])")
    for k, v in gains.items():
        print(f"{k} = [{', '.join(f'{x:.6g}' for x in v)}]")
    return 0


if __name__ == "__main__":
    sys.exit(main())
