#!/usr/bin/python3
"""Accuracy against cost from Python: three integrators at a few tolerances on one scene.

    PYTHONPATH=build/release/python /usr/bin/python3 examples/python_integrators.py [OUT.png] [--scene FILE]

Writes OUT.png (default: python_integrators.png in the current folder): the largest joint-angle
error over the run's outputs against the right-hand-side evaluations, one line per integrator.
A sketch, not a result: the sweeps (experiments/sweeps/) are the measured comparison.
"""
import argparse
import os

import matplotlib
matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

import pumasim  # noqa: E402

ROOT = os.path.normpath(os.path.join(os.path.dirname(os.path.abspath(__file__)), ".."))

# %% The scene, and a reference run far tighter than any run below
parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
parser.add_argument("out", nargs="?", default="python_integrators.png", help="the PNG to write")
parser.add_argument("--scene", default=os.path.join(ROOT, "experiments", "scenes", "paper_slow_viscous.toml"))
parser.add_argument("--t-end", type=float, default=4.0, help="the runs' end [s]")
args = parser.parse_args()

scene = pumasim.Scene.load(args.scene)
n = sum(name.startswith("q") and not name.startswith("qd") for name in scene.state_names)  # joint angles
print(f"{scene.name}: {scene.size} states ({', '.join(scene.state_names)}), {args.t_end} s")
reference = pumasim.run(scene, integrator="cvode-bdf", rtol=1e-11, atol=1e-14, t_end=args.t_end)
check = pumasim.run(scene, integrator="odeint-rodas4p", rtol=1e-11, atol=1e-14, t_end=args.t_end)  # another method
assert reference.ok and check.ok, reference.failure + check.failure
print(f"reference (cvode-bdf) against its cross-check (odeint-rodas4p): "
      f"{np.abs(reference.x[:, :n] - check.x[:, :n]).max():.2g} rad")

# %% Three integrators at a few tolerances (atol = 1e-3 rtol per unit of each state's typical size)
integrators = ["cvode-bdf", "arkode-dirk", "odeint-rodas4p"]
tolerances = [1e-3, 1e-4, 1e-5, 1e-6, 1e-7]
fig, ax = plt.subplots(figsize=(6.4, 4.4))
for name in integrators:
    cost, error = [], []
    for rtol in tolerances:
        run = pumasim.run(scene, integrator=name, rtol=rtol, atol=1e-3 * rtol, t_end=args.t_end)
        if not run.ok:
            print(f"  {name} rtol {rtol:g}: failed ({run.failure})")
            continue
        err = np.abs(run.x[:, :n] - reference.x[:, :n]).max()  # [rad], over every output and joint
        cost.append(run.stats["rhs_evaluations"])
        error.append(err)
        print(f"  {name:15s} rtol {rtol:7.0e}: {cost[-1]:7d} right-hand sides, error {err:.3g} rad, "
              f"{1e3 * run.stats['wall_time_s']:.1f} ms")
    ax.loglog(cost, error, "o-", label=name)

# %% The plot
ax.set_xlabel("right-hand-side evaluations")
ax.set_ylabel("largest joint-angle error [rad]")
ax.set_title(f"{scene.name}, {args.t_end:g} s: error against cost")
ax.grid(True, which="both", alpha=0.3)
ax.legend()
fig.tight_layout()
fig.savefig(args.out, dpi=120)
print(f"wrote {args.out}")
