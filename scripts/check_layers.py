#!/usr/bin/python3
"""Fails (exit 1) when a source file includes a header from a layer above its own.

The layers, lowest first (each a folder and a CMake target; ARCHITECTURE.md):
  core              the time rule, the registries' shape, error types, invariants, the Cholesky (std and Eigen only)
  models/dynamics   chain, RNEA/CRBA/ABA/probing/Lagrange, scalars (Eigen only)
  models/robot      robot files, random chains, kinematics, drive parameters
  models/reference  paths, timing laws, time-optimal planning
  models/plant      the plant ODE
  models/scene      scene files (TOML)
  integrators       the ODE interface, methods, registry: no model code
  simulation        the front door (run), the driver and run folders: models and integrators
  experiments, tests       anything below
  python           the Python module (pybind11): anything below but tests

Run by the build (the check_layers target) and by hand:
  /usr/bin/python3 scripts/check_layers.py
"""
import os
import re
import sys

ROOT = os.path.normpath(os.path.join(os.path.dirname(os.path.abspath(__file__)), ".."))
MODELS = ["core", "models/dynamics", "models/robot", "models/reference", "models/plant", "models/scene"]
# Folder -> the project folders its files may include from (longest prefix wins).
ALLOWED = {MODELS[k]: MODELS[:k + 1] for k in range(len(MODELS))}
ALLOWED["integrators"] = ["core", "integrators"]
ALLOWED["simulation"] = MODELS + ["integrators", "simulation"]
ALLOWED["experiments"] = MODELS + ["integrators", "simulation", "experiments"]
ALLOWED["tests"] = MODELS + ["integrators", "simulation", "experiments", "tests"]
ALLOWED["python"] = MODELS + ["integrators", "simulation", "experiments", "python"]
INCLUDE = re.compile(r'^\s*#\s*include\s+"([^"]+)"', re.M)


def folder_of(path, folders):
    """The longest folder in folders that holds path (None if none)."""
    best = None
    for f in folders:
        if (path == f or path.startswith(f + "/")) and (best is None or len(f) > len(best)):
            best = f
    return best


def main():
    bad = []
    checked = 0
    for top in ("core", "models", "integrators", "simulation", "experiments", "tests", "python"):
        for d, _, names in os.walk(os.path.join(ROOT, top)):
            for n in sorted(names):
                if not n.endswith((".hpp", ".cpp", ".h")):
                    continue
                rel = os.path.relpath(os.path.join(d, n), ROOT)
                own = folder_of(rel, ALLOWED)
                if own is None:
                    bad.append(f"{rel}: in no layer (scripts/check_layers.py lists them)")
                    continue
                checked += 1
                with open(os.path.join(d, n), encoding="utf-8") as fh:
                    text = fh.read()
                for m in INCLUDE.finditer(text):
                    inc = m.group(1)
                    if not inc.startswith(("core/", "models/", "integrators/", "experiments/", "tests/", "python/")):
                        continue  # a sibling or a system header
                    target = folder_of(inc, ALLOWED) or inc.split("/")[0]
                    if folder_of(inc, ALLOWED[own]) is None:
                        line = text.count("\n", 0, m.start()) + 1
                        bad.append(f"{rel}:{line}: includes {inc} ({target}), above its layer {own}; "
                                   f"allowed: {', '.join(ALLOWED[own])}")
    for b in bad:
        print("check_layers: " + b, file=sys.stderr)
    if bad:
        return 1
    print(f"check_layers: {checked} files, every include points down or sideways")
    return 0


if __name__ == "__main__":
    sys.exit(main())
