#!/usr/bin/python3
"""Writes the fuzz harnesses' seed corpora (README.md, "Sanitizers and fuzzing") from every shipped file.

  robot/  every robot file (models/robots/*.toml)
  scene/  every scene file (experiments/scenes/*.toml)
  set/    for every scene, its name alone; for every sweep (experiments/sweeps/*.toml), its
          scene's name followed by one variant's --set arguments, one a line (the input
          format of tests/fuzz/fuzz_set.cpp)
and, in each, the committed regression inputs (tests/fuzz/regressions/<harness>/).

  /usr/bin/python3 scripts/fuzz_seeds.py OUT_DIR
"""
import glob
import os
import shutil
import sys
import tomllib

ROOT = os.path.normpath(os.path.join(os.path.dirname(os.path.abspath(__file__)), ".."))


def copy_all(pattern, out):
    """Copies every file matching pattern (relative to the repository) into out; returns the count."""
    files = sorted(glob.glob(os.path.join(ROOT, pattern)))
    for f in files:
        shutil.copy(f, os.path.join(out, os.path.basename(f)))
    return len(files)


def set_seeds(out):
    """The --set harness's seeds: scene names, and each sweep variant's overrides."""
    count = 0
    for scene in sorted(glob.glob(os.path.join(ROOT, "experiments/scenes/*.toml"))):
        name = os.path.splitext(os.path.basename(scene))[0]
        with open(os.path.join(out, "scene-" + name), "w", encoding="utf-8") as f:
            f.write(name)
        count += 1
    for sweep in sorted(glob.glob(os.path.join(ROOT, "experiments/sweeps/*.toml"))):
        with open(sweep, "rb") as f:
            doc = tomllib.load(f)
        scene = doc["sweep"]["scene"]
        stem = os.path.splitext(os.path.basename(sweep))[0]
        for i, variant in enumerate(doc.get("variant", [])):
            if variant.get("set"):
                with open(os.path.join(out, f"sweep-{stem}-{i}"), "w", encoding="utf-8") as f:
                    f.write("\n".join([scene] + variant["set"]))
                count += 1
    return count


def main():
    if len(sys.argv) != 2:
        sys.exit(__doc__)
    out = sys.argv[1]
    counts = {}
    for harness in ("robot", "scene", "set"):
        d = os.path.join(out, harness)
        shutil.rmtree(d, ignore_errors=True)
        os.makedirs(d)
        counts[harness] = copy_all(f"tests/fuzz/regressions/{harness}/*", d)
    counts["robot"] += copy_all("models/robots/*.toml", os.path.join(out, "robot"))
    counts["scene"] += copy_all("experiments/scenes/*.toml", os.path.join(out, "scene"))
    counts["set"] += set_seeds(os.path.join(out, "set"))
    print("fuzz seeds: " + ", ".join(f"{h} {n}" for h, n in counts.items()))


if __name__ == "__main__":
    main()
