#!/usr/bin/env python3
"""Every shipped scene run by two pumasim binaries: are the trajectories the same, byte for byte?

For a change that must not move any number (a redesign: issue 33's const plant), run the
binary built before it and the one built after on every scene under experiments/scenes/
(the scene's own integrator, or each --integrator given, and its output grid, up to
--t-end seconds), and compare the files
each run wrote (trajectory.csv, events.csv when there is one). Exit status 0 when every
pair is identical, 1 otherwise (each difference named: the file, its first differing line).

    scripts/compare_trajectories.py --old /tmp/base/build/release/bin/pumasim \\
        --new build/release/bin/pumasim [--t-end 2] [--scene paper_slow ...]
"""
import argparse
import pathlib
import subprocess
import sys
import tempfile

ROOT = pathlib.Path(__file__).resolve().parent.parent
SCENES = ROOT / "experiments" / "scenes"
COMPARED = ("trajectory.csv", "events.csv")


def run(binary, scene, integrator, t_end, out):
    cmd = [binary, "run", str(scene), "--out", str(out), "--quiet"]
    if integrator:
        cmd += ["--integrator", integrator]
    if t_end is not None:
        cmd += ["--t-end", repr(t_end)]
    p = subprocess.run(cmd, capture_output=True, text=True)
    return p.returncode, p.stderr.strip()


def first_difference(a, b):
    la, lb = a.read_bytes().split(b"\n"), b.read_bytes().split(b"\n")
    for k, (x, y) in enumerate(zip(la, lb)):
        if x != y:
            return f"line {k + 1}"
    return f"length ({len(la)} against {len(lb)} lines)"


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--old", required=True, help="the pumasim binary before the change")
    ap.add_argument("--new", required=True, help="the pumasim binary after it")
    ap.add_argument("--t-end", type=float, default=None,
                    help="stop each run here [s] (default: each scene's own duration)")
    ap.add_argument("--scene", action="append", default=[], help="a scene's name (default: every shipped scene)")
    ap.add_argument("--integrator", action="append", default=[],
                    help="run each scene with this integrator (repeatable; default: the scene's own)")
    args = ap.parse_args()
    scenes = [SCENES / f"{s}.toml" for s in args.scene] or sorted(SCENES.glob("*.toml"))
    differ = 0
    cases = [(scene, integ) for scene in scenes for integ in (args.integrator or [None])]
    with tempfile.TemporaryDirectory() as tmp:
        for scene, integ in cases:
            runs = {}
            label = scene.stem + (f" {integ}" if integ else "")
            for tag, binary in (("old", args.old), ("new", args.new)):
                out = pathlib.Path(tmp) / f"{scene.stem}-{integ or 'own'}-{tag}"
                runs[tag] = (out,) + run(binary, scene, integ, args.t_end, out)
            (a, ra, ea), (b, rb, eb) = runs["old"], runs["new"]
            notes = []
            if ra != rb:
                notes.append(f"exit status {ra} against {rb} ({ea or eb})")
            for name in COMPARED:
                fa, fb = a / name, b / name
                if fa.exists() != fb.exists():
                    notes.append(f"{name} written by one run only")
                elif fa.exists() and fa.read_bytes() != fb.read_bytes():
                    notes.append(f"{name} differs from {first_difference(fa, fb)}")
            if ra != 0 and ra == rb and not notes:
                notes_text = f"same (both exit {ra})"
            else:
                notes_text = "; ".join(notes) if notes else "identical"
            rows = sum(1 for _ in open(a / "trajectory.csv")) - 1 if (a / "trajectory.csv").exists() else 0
            print(f"{label:44s} {rows:8d} rows  {notes_text}")
            differ += bool(notes)
    print(f"{len(cases) - differ} of {len(cases)} runs identical")
    return 1 if differ else 0


if __name__ == "__main__":
    sys.exit(main())
