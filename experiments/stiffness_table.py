#!/usr/bin/python3
"""Stiffness tables: `pumasim stiffness --bisect` over the stiff scenes' cases.

    /usr/bin/python3 experiments/stiffness_table.py [--reduced] [--out DIR]

For the armature sweep (La over five decades) and the high-gain sweep (PIV
feedback gains x1, x10, x100): the largest spectral radius of the plant
Jacobian along 0.2 s of the run, the stiffness ratio, the fastest mode, and
for each explicit fixed-step method the largest stable step predicted by its
stability region beside the one found by bisection. Writes DIR/<table>.csv
and DIR/<table>.png (default DIR = results/stiffness). --reduced: one case per
table, into build/stiffness-reduced (CI).
"""
import argparse
import csv
import os
import subprocess
import sys

ROOT = os.path.normpath(os.path.join(os.path.dirname(os.path.abspath(__file__)), ".."))
PUMASIM = os.environ.get("PUMASIM", os.path.join(ROOT, "build", "release", "bin", "pumasim"))
T_END = 0.2
KP = [18.2583, 7.27722, 6.65612]
KI = [172.081, 68.5862, 62.7325]
KV = [0.252963, 0.066542, 0.0559978]


def gains(k):
    f = lambda v: "[" + ", ".join(f"{x * k:.6g}" for x in v) + "]"  # noqa: E731
    return [f"controller.kp={f(KP)}", f"controller.ki={f(KI)}", f"controller.kv={f(KV)}"]


TABLES = {
    "stiff_armature": [(f"La={la}", [f"motor.inductance={la}"]) for la in
                       ("2.1e-2", "2.1e-3", "2.1e-4", "2.1e-5", "2.1e-6")],
    "stiff_high_gain": [(f"gain_x{k}", gains(k)) for k in (1, 10, 100)],
}


def analyse(scene, sets, t_end):
    cmd = [PUMASIM, "stiffness", os.path.join(ROOT, "experiments", "scenes", scene + ".toml"),
           "--t-end", repr(t_end), "--samples", "20", "--bisect"]
    for s in sets:
        cmd += ["--set", s]
    p = subprocess.run(cmd, capture_output=True, text=True, cwd=ROOT)
    if p.returncode != 0:
        sys.exit(f"stiffness_table: {' '.join(cmd)} failed: {p.stderr.strip()}")
    blocks = [b for b in p.stdout.split("\n\n") if b.strip()]

    def table(block):
        lines = [line for line in block.splitlines() if not line.startswith("#")]
        head = lines[0].split("\t")
        return [dict(zip(head, line.split("\t"))) for line in lines[1:]]

    samples, steps = table(blocks[0]), table(blocks[1])
    worst = max(samples, key=lambda r: float(r["spectral radius [1/s]"]))
    return {
        "spectral_radius": worst["spectral radius [1/s]"],
        "stiffness_ratio": f"{max(float(r['stiffness ratio']) for r in samples):.6g}",
        "fastest_state": worst["fastest state"], "fastest_tau_s": worst["fastest tau [s]"],
    }, steps


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--reduced", action="store_true")
    ap.add_argument("--out", default=None)
    args = ap.parse_args()
    out = args.out or os.path.join(ROOT, "build", "stiffness-reduced") if args.reduced else \
        (args.out or os.path.join(ROOT, "results", "stiffness"))
    os.makedirs(out, exist_ok=True)
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    for scene, cases in TABLES.items():
        rows = []
        for case, sets in (cases[:1] if args.reduced else cases):
            info, steps = analyse(scene, sets, 0.02 if args.reduced else T_END)
            for s in steps:
                rows.append({"case": case, **info, "integrator": s["integrator"],
                             "predicted_s": s["predicted [s]"], "measured_s": s["measured [s]"], "note": s["note"]})
            print(f"{scene} {case}: spectral radius {info['spectral_radius']} 1/s", flush=True)
        path = os.path.join(out, scene + ".csv")
        with open(path + ".tmp", "w", newline="") as f:
            f.write(f"# pumasim stiffness experiments/scenes/{scene}.toml --t-end {T_END} --samples 20 --bisect "
                    "--set ... (per case)\n")
            w = csv.DictWriter(f, fieldnames=list(rows[0].keys()))
            w.writeheader()
            w.writerows(rows)
        os.replace(path + ".tmp", path)
        fig, ax = plt.subplots(figsize=(6.5, 4.5))
        for k, m in enumerate(sorted({r["integrator"] for r in rows})):
            rm = [r for r in rows if r["integrator"] == m]
            c = plt.cm.tab10(k)
            x = [float(r["spectral_radius"]) for r in rm]
            ax.plot(x, [float(r["predicted_s"]) for r in rm], "-", color=c, lw=1, label=f"{m} predicted")
            meas = [(xx, float(r["measured_s"])) for xx, r in zip(x, rm) if float(r["measured_s"]) > 0]
            if meas:
                ax.plot(*zip(*meas), "o", color=c, ms=4, label=f"{m} measured")
        ax.set(xscale="log", yscale="log", xlabel="largest |eigenvalue| of the Jacobian [1/s]",
               ylabel="largest stable step [s]", title=f"{scene}: stable step against spectral radius")
        ax.grid(True, lw=0.3)
        ax.legend(fontsize=6, ncol=2)
        fig.tight_layout()
        fig.savefig(os.path.join(out, scene + ".png"), dpi=80)
        plt.close(fig)
    print(f"stiffness tables: {os.path.relpath(out, ROOT)}/")


if __name__ == "__main__":
    main()
