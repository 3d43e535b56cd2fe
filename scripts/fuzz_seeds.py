#!/usr/bin/python3
"""Writes the fuzz harnesses' seed corpora (docs/developer-guide/sanitizers-and-fuzzing.md) from every shipped file.

  robot/  every robot file (models/robots/*.toml)
  scene/  every scene file (experiments/scenes/*.toml)
  set/    for every scene, its name alone; for every sweep (experiments/sweeps/*.toml), its
          scene's name followed by one variant's --set arguments, one a line (the input
          format of tests/fuzz/fuzz_set.cpp)
  urdf/   every URDF file (models/robots/*.urdf, tests/robots/*.urdf), alone and, when it
          has one, followed by SIDE_FILE_MARKER and its side file <file>.urdf.toml (the
          input format of tests/fuzz/fuzz_urdf.cpp)
  joint_csv/      every CSV file a scene reads as its joint-space reference (reference.joints)
  open_loop_csv/  every CSV file a scene reads as its open-loop input (controller.file)
and, in each, the committed regression inputs (tests/fuzz/regressions/<harness>/).

  /usr/bin/python3 scripts/fuzz_seeds.py OUT_DIR
"""
import glob
import os
import shutil
import sys
import tomllib

ROOT = os.path.normpath(os.path.join(os.path.dirname(os.path.abspath(__file__)), ".."))
HARNESSES = ("robot", "scene", "set", "urdf", "joint_csv", "open_loop_csv")
# Where a urdf input's URDF ends and its side file starts (tests/fuzz/fuzz_urdf.cpp).
SIDE_FILE_MARKER = b"\n==== side file ====\n"


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


def urdf_seeds(out):
    """The urdf harness's seeds: each shipped URDF alone, and with its side file."""
    count = 0
    for pattern in ("models/robots/*.urdf", "tests/robots/*.urdf"):
        for urdf in sorted(glob.glob(os.path.join(ROOT, pattern))):
            name = os.path.basename(urdf)
            with open(urdf, "rb") as f:
                text = f.read()
            with open(os.path.join(out, name), "wb") as f:
                f.write(text)
            count += 1
            if os.path.exists(urdf + ".toml"):
                with open(urdf + ".toml", "rb") as f:
                    side = f.read()
                with open(os.path.join(out, name + "+side"), "wb") as f:
                    f.write(text + SIDE_FILE_MARKER + side)
                count += 1
    return count


def scene_csv_seeds(section, key, out):
    """Every CSV file a shipped scene names at [section] key, relative to the scene."""
    count = 0
    for scene in sorted(glob.glob(os.path.join(ROOT, "experiments/scenes/*.toml"))):
        with open(scene, "rb") as f:
            doc = tomllib.load(f)
        name = doc.get(section, {}).get(key)
        if isinstance(name, str) and name.endswith(".csv"):
            shutil.copy(os.path.join(os.path.dirname(scene), name), os.path.join(out, os.path.basename(name)))
            count += 1
    return count


def main():
    if len(sys.argv) != 2:
        sys.exit(__doc__)
    out = sys.argv[1]
    counts = {}
    for harness in HARNESSES:
        d = os.path.join(out, harness)
        shutil.rmtree(d, ignore_errors=True)
        os.makedirs(d)
        counts[harness] = copy_all(f"tests/fuzz/regressions/{harness}/*", d)
    counts["robot"] += copy_all("models/robots/*.toml", os.path.join(out, "robot"))
    counts["scene"] += copy_all("experiments/scenes/*.toml", os.path.join(out, "scene"))
    counts["set"] += set_seeds(os.path.join(out, "set"))
    counts["urdf"] += urdf_seeds(os.path.join(out, "urdf"))
    counts["joint_csv"] += scene_csv_seeds("reference", "joints", os.path.join(out, "joint_csv"))
    counts["open_loop_csv"] += scene_csv_seeds("controller", "file", os.path.join(out, "open_loop_csv"))
    print("fuzz seeds: " + ", ".join(f"{h} {n}" for h, n in counts.items()))


if __name__ == "__main__":
    main()
