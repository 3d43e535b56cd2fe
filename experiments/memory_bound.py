#!/usr/bin/python3
"""The memory a `pumasim run` takes does not grow with its output (docs/user-guide/limits.md):
the six-joint hybrid scene over 1 s at a 1e-5 s output
interval (100001 rows) run under an address-space limit (RLIMIT_AS, what
`ulimit -v` sets) of 64 MiB, with its peak resident memory and the size of
the trajectory it wrote. The test tests/check_memory_bound.sh asserts the same
run under the same limit; this records the figures.

    /usr/bin/python3 experiments/memory_bound.py --bin build/release/bin/pumasim \
        --out results/reliability/memory_bound.json
"""
import argparse
import json
import os
import resource
import shutil
import subprocess
import tempfile

ROOT = os.path.normpath(os.path.join(os.path.dirname(os.path.abspath(__file__)), ".."))
SCENE = "experiments/scenes/paper_slow_6dof_hybrid.toml"
LIMIT_MIB = 64


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--bin", default=os.path.join(ROOT, "build", "release", "bin", "pumasim"))
    ap.add_argument("--out", default=os.path.join(ROOT, "results", "reliability", "memory_bound.json"))
    a = ap.parse_args()
    work = tempfile.mkdtemp(prefix="pumasim_memory_")
    try:
        out = os.path.join(work, "run")
        args = [a.bin, "run", os.path.join(ROOT, SCENE), "--t-end", "1", "--set", "scene.output_interval=1e-5",
                "--out", out, "--quiet"]

        def limit():
            resource.setrlimit(resource.RLIMIT_AS, (LIMIT_MIB << 20, LIMIT_MIB << 20))

        p = subprocess.run(args, preexec_fn=limit, capture_output=True, text=True)
        if p.returncode != 0:
            raise SystemExit(f"memory_bound: the run under {LIMIT_MIB} MiB exited {p.returncode}: {p.stderr}")
        peak_kib = resource.getrusage(resource.RUSAGE_CHILDREN).ru_maxrss
        path = os.path.join(out, "trajectory.csv")
        with open(path) as f:
            header = f.readline()
            rows = sum(1 for _ in f)
        summary = {
            "command": "experiments/memory_bound.py",
            "scene": SCENE,
            "arguments": "--t-end 1 --set scene.output_interval=1e-5",
            "address_space_limit_mib": LIMIT_MIB,
            "rows": rows,
            "columns": header.count(",") + 1,
            "trajectory_mb": round(os.path.getsize(path) / 1e6, 1),
            "peak_rss_mb": round(peak_kib * 1024 / 1e6, 1),
        }
    finally:
        shutil.rmtree(work, ignore_errors=True)
    os.makedirs(os.path.dirname(a.out), exist_ok=True)
    with open(a.out + ".tmp", "w") as f:
        json.dump(summary, f, indent=2)
        f.write("\n")
    os.replace(a.out + ".tmp", a.out)
    print(json.dumps(summary))


if __name__ == "__main__":
    main()
