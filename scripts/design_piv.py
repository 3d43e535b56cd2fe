#!/usr/bin/env python3
"""PIV gains for a scene's joints by pole placement on the decoupled joint model.

Usage: design_piv.py <scene.toml> [--bandwidth HZ] [--damping ZETA]

Model of joint j on the motor side (La neglected, gravity and coupling taken
as disturbances the integral removes):
    J w' = K i,   i = (K_A u - K w) / R_t,   R_t = R0 + R,   J = M_jj(q0) / Z^2
with M_jj from `pumasim dynamics` at the scene's start pose (rotor inertia
included). With u = Kp e + Ki z - Kv w + Kvff w_ref + Kaff a_ref (e, w motor side):
    closed loop  J s^2 + (K^2/R_t + b Kv) s + b Kp = 0,   b = K K_A / R_t
    Kp = J wn^2 / b,  Kv = (2 zeta wn J - K^2 / R_t) / b  (>= 0),  Ki = Kp wn / 10
    Kvff = Kv + K / K_A   (cancels velocity feedback and back-EMF on the reference)
    Kaff = J / b          (the reference acceleration's torque)
Prints the [controller] gain lines for the scene.
"""
import argparse
import json
import math
import os
import subprocess
import sys
import tomllib

ROOT = os.path.join(os.path.dirname(os.path.abspath(__file__)), "..")
PUMASIM = os.path.join(ROOT, "build", "release", "bin", "pumasim")


def per_joint(v, n):
    return v if isinstance(v, list) else [v] * n


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("scene")
    ap.add_argument("--bandwidth", type=float, default=10.0, help="natural frequency [Hz]")
    ap.add_argument("--damping", type=float, default=0.8)
    args = ap.parse_args()
    with open(args.scene, "rb") as f:
        sc = tomllib.load(f)
    n = sc["scene"]["joints"]
    check = subprocess.run([PUMASIM, "check", args.scene], capture_output=True, text=True, check=True)
    x0 = [float(v) for v in check.stdout.strip().splitlines()[-1].split(":")[1].split()]
    held = sc["scene"].get("held", [])
    q = x0[:n] + list(held) + [0.0] * (6 - n - len(held))
    dyn = json.loads(subprocess.run(
        [PUMASIM, "dynamics", "--robot", sc["scene"]["robot"], "--backend", "crba",
         "--q=" + ",".join(repr(v) for v in q)], capture_output=True, text=True, check=True).stdout)
    with open(os.path.join(ROOT, "models", "robots", sc["scene"]["robot"] + ".toml"), "rb") as f:
        robot = tomllib.load(f)
    amp, mot = sc["amplifier"], sc["motor"]
    KA, R0 = per_joint(amp["gain"], n), per_joint(amp.get("output_resistance", 0.0), n)
    R, K = per_joint(mot["resistance"], n), per_joint(mot["torque_constant"], n)
    wn = 2 * math.pi * args.bandwidth
    gains = {k: [] for k in ("kp", "ki", "kv", "kvff", "kaff")}
    for j in range(n):
        Z = robot["joint"][j]["gear_ratio"]
        J = dyn["mass_matrix"][j][j] / Z ** 2
        Rt = R0[j] + R[j]
        b = K[j] * KA[j] / Rt
        kp = J * wn ** 2 / b
        kv = max(0.0, (2 * args.damping * wn * J - K[j] ** 2 / Rt) / b)
        gains["kp"].append(kp)
        gains["ki"].append(kp * wn / 10)
        gains["kv"].append(kv)
        gains["kvff"].append(kv + K[j] / KA[j])
        gains["kaff"].append(J / b)
    print(f"# designed by scripts/design_piv.py {os.path.relpath(args.scene, ROOT)} "
          f"--bandwidth {args.bandwidth:g} --damping {args.damping:g}")
    print(f"# (start pose q = [{', '.join(f'{v:.4f}' for v in q)}])")
    for k, v in gains.items():
        print(f"{k} = [{', '.join(f'{x:.6g}' for x in v)}]")


if __name__ == "__main__":
    sys.exit(main())
