#!/usr/bin/python3
"""Stiffness tables: `pumasim stiffness --bisect` over the stiff scenes' cases.

    /usr/bin/python3 experiments/stiffness_table.py [--reduced] [--out DIR]

For the armature sweep (La over four decades) and the high-gain sweep (PIV
feedback gains x1, x10, x100): the largest spectral radius of the plant
Jacobian along 0.2 s of the run, the stiffness ratio, the fastest mode, and
for each explicit fixed-step method the largest stable step predicted by its
stability region beside the one found by bisection. Writes DIR/<table>.csv
and DIR/<table>.png with DIR/<table>.pdf beside it (default DIR =
results/stiffness). Then the conditioning
table: `pumasim conditioning` along the paper's path, the path moved out to a
nearly stretched arm, and the six-joint path through the wrist singularity,
each with and without rotor inertia: DIR/conditioning.csv, .png and .pdf. The
plots are in the house style (pumasim_exp/style.py). --reduced: one case per
table, into build/stiffness-reduced (CI). Last, DIR/scenes.csv: every shipped
scene over its whole run, its spectral radius and stiffness ratio (median over
40 samples, and the range), and whether it is stiff (median >= 100).
"""
import argparse
import re
import csv
import os
import subprocess
import sys
import tempfile

from pumasim_exp import style

ROOT = os.path.normpath(os.path.join(os.path.dirname(os.path.abspath(__file__)), ".."))
PUMASIM = os.environ.get("PUMASIM", os.path.join(ROOT, "build", "release", "bin", "pumasim"))
T_END = 0.2
KP = [18.2583, 7.27722, 6.65612]
KI = [172.081, 68.5862, 62.7325]
KV = [0.252963, 0.066542, 0.0559978]
KVFF = [0.309963, 0.123542, 0.112998]


def gains(k):
    f = lambda v: "[" + ", ".join(f"{x * k:.6g}" for x in v) + "]"  # noqa: E731
    kvff = "[" + ", ".join(f"{a * k + (b - a):.6g}" for a, b in zip(KV, KVFF)) + "]"
    return [f"controller.kp={f(KP)}", f"controller.ki={f(KI)}", f"controller.kv={f(KV)}", f"controller.kvff={kvff}"]


TABLES = {
    "stiff_armature": [(f"La={la}", [f"motor.inductance={la}"]) for la in
                       ("2.1e-2", "2.1e-3", "2.1e-4", "2.1e-5", "2.1e-6")],
    "high_gain": [(f"gain_x{k}", gains(k)) for k in (1, 10, 100)],
}


def pumasim_csv(args, options):
    """Runs `pumasim <args>` with each CSV option in `options` (e.g. --csv)
    naming a temporary file; returns the rows of each file (dicts keyed by the
    header's column names)."""
    with tempfile.TemporaryDirectory() as tmp:
        cmd = [PUMASIM] + args
        for k, option in enumerate(options):
            cmd += [option, os.path.join(tmp, f"{k}.csv")]
        p = subprocess.run(cmd, capture_output=True, text=True, cwd=ROOT)
        if p.returncode != 0:
            sys.exit(f"stiffness_table: {' '.join(cmd)} failed: {p.stderr.strip()}")
        tables = []
        for k in range(len(options)):
            with open(os.path.join(tmp, f"{k}.csv"), newline="") as f:
                tables.append(list(csv.DictReader(f)))
        return tables


def printed(x, digits):
    """x (full precision in pumasim's CSV) as pumasim's text tables printed it
    (C's %.<digits>g), from which the committed tables were computed: the same
    rounding keeps them identical."""
    return f"{float(x):.{digits}g}"


def analyse(scene, sets, t_end):
    args = ["stiffness", os.path.join(ROOT, "experiments", "scenes", scene + ".toml"),
            "--t-end", repr(t_end), "--samples", "20", "--bisect"]
    for s in sets:
        args += ["--set", s]
    samples, steps = pumasim_csv(args, ["--csv", "--steps-csv"])
    samples = [{"radius": printed(r["spectral_radius [1/s]"], 4), "ratio": printed(r["stiffness_ratio [-]"], 4),
                "fastest_state": r["fastest_state"], "fastest_tau": printed(r["fastest_tau [s]"], 3)}
               for r in samples]
    steps = [{"integrator": r["integrator"], "predicted": printed(r["predicted_step [s]"], 4),
              "measured": printed(r["measured_step [s]"], 4), "note": r["note"]} for r in steps]
    worst = max(samples, key=lambda r: float(r["radius"]))
    return {
        "spectral_radius": worst["radius"],
        "stiffness_ratio": f"{max(float(r['ratio']) for r in samples):.6g}",
        "fastest_state": worst["fastest_state"], "fastest_tau_s": worst["fastest_tau"],
    }, steps


CONDITIONING = [
    ("paper path, 3 joints", "paper_slow", []),
    ("paper path, 3 joints, no rotor inertia", "paper_slow", ["scene.rotor_inertia=false"]),
    ("path moved out, arm nearly stretched", "paper_slow", ["reference.start=[0.52, -0.25]"]),
    ("path moved out, no rotor inertia", "paper_slow", ["reference.start=[0.52, -0.25]", "scene.rotor_inertia=false"]),
    ("6 joints through the wrist singularity", "stiff_singular", []),
    ("6 joints through the wrist singularity, no rotor inertia", "stiff_singular", ["scene.rotor_inertia=false"]),
]


def conditioning(out, reduced, plt):
    rows, curves = [], []
    for case, scene, sets in (CONDITIONING[:1] if reduced else CONDITIONING):
        args = ["conditioning", os.path.join(ROOT, "experiments", "scenes", scene + ".toml"),
                "--samples", "20" if reduced else "600"]
        for x in sets:
            args += ["--set", x]
        table, = pumasim_csv(args, ["--csv"])
        head = list(table[0].keys())
        backends = [h[len("qdd_error_"):-len(" [-]")] for h in head if h.startswith("qdd_error_")]
        data = []
        for r in table:
            row = {"t [s]": float(printed(r["t [s]"], 6)), "cond(H)": float(printed(r["cond_H [-]"], 6)),
                   "min eig(H)": float(printed(r["min_eig_H [kg m^2]"], 6))}
            row.update({h: float(printed(r[h], 6)) for h in head if h.startswith("q") and h.endswith(" [rad]")})
            row.update({b: float(printed(r[f"qdd_error_{b} [-]"], 3)) for b in backends})
            data.append(row)
        worst = max(data, key=lambda r: r["cond(H)"])
        row = {"case": case, "command": " ".join(["pumasim conditioning", scene] + [f"--set {x}" for x in sets]),
               "max_cond_H": f"{worst['cond(H)']:.6g}", "t_at_max_s": f"{worst['t [s]']:.4g}",
               "min_eig_H": f"{min(r['min eig(H)'] for r in data):.6g}"}
        if "q5 [rad]" in data[0]:
            row["min_abs_q5_rad"] = f"{min(abs(r['q5 [rad]']) for r in data):.3g}"
        else:
            row["min_abs_q5_rad"] = ""
        for b in backends:
            row[f"qdd_error_{b}"] = f"{max(r[b] for r in data):.3g}"
        rows.append(row)
        curves.append((case, [r["t [s]"] for r in data], [r["cond(H)"] for r in data]))
        print(f"conditioning {case}: max cond(H) {row['max_cond_H']}", flush=True)
    keys = []
    for r in rows:
        keys += [k for k in r if k not in keys]
    path = os.path.join(out, "conditioning.csv")
    with open(path + ".tmp", "w", newline="") as f:
        f.write("# pumasim conditioning <scene> --samples 600 [--set ...]: cond(H) along the reference and each "
                "back-end's worst relative qdd error\n")
        w = csv.DictWriter(f, fieldnames=keys)
        w.writeheader()
        w.writerows(rows)
    os.replace(path + ".tmp", path)
    # conditioning.png and .pdf: a case's colour from the palette (the dash
    # pattern too beyond eight cases; no markers on the dense curves).
    fig, ax = plt.subplots(figsize=(7, 4.2))
    for k, (case, t, c) in enumerate(curves):
        st = style.series(k)
        ax.plot(t, c, lw=1, color=st["color"], ls=st["ls"], label=case)
    ax.set(xlabel="t [s]", ylabel="cond(H)", yscale="log", title="Conditioning of H along the paths")
    ax.grid(True, lw=0.3)
    style.legend_right(ax)
    fig.tight_layout()
    style.save(fig, os.path.join(out, "conditioning.png"))


def scene_stiffness(out, reduced):
    """Every shipped scene over its whole run: the largest spectral radius and
    the stiffness ratio (largest over smallest |Re lambda| of the decaying
    modes), as the median over the samples and its range. The median, not the
    maximum, classifies a scene: while a hybrid-friction joint is stuck its
    speed and PIV integral form modes with |Re lambda| near zero, and the
    ratio of those samples (1e6 and more) says nothing about the stiffness of
    the motion. A scene is called stiff here when the median is >= 100."""
    rows = []
    scenes = sorted(f[:-5] for f in os.listdir(os.path.join(ROOT, "experiments", "scenes")) if f.endswith(".toml"))
    for scene in (scenes[:1] if reduced else scenes):
        path = os.path.join(ROOT, "experiments", "scenes", scene + ".toml")
        check = subprocess.run([PUMASIM, "check", path], capture_output=True, text=True, cwd=ROOT)
        if check.returncode != 0:
            sys.exit(f"stiffness_table: pumasim check {path} failed: {check.stderr.strip()}")
        # The resolved scene ends at its state layout; its [scene] table holds the run's duration.
        duration = float(re.search(r"^duration = (\S+)$", check.stdout, re.M).group(1))
        t_end = 0.02 if reduced else duration
        data, = pumasim_csv(["stiffness", path, "--samples", "5" if reduced else "40", "--t-end", repr(t_end)],
                            ["--csv"])
        data = [{"spectral radius [1/s]": printed(r["spectral_radius [1/s]"], 4),
                 "slowest tau [s]": printed(r["slowest_tau [s]"], 3), "fastest state": r["fastest_state"]}
                for r in data]
        t_end = float(printed(t_end, 6))
        # Modes slower than the run (and the undamped ones of a conservative
        # arm, Re lambda ~ 0) barely move within it: their rate is floored at
        # 1 / t_end (Shampine's view: stiffness is rho times the interval).
        def slowest_rate(r):
            tau = float(r["slowest tau [s]"])
            return 1.0 / tau if 0 < tau < float("inf") else 0.0  # no decaying mode: 0
        ratios = sorted(float(r["spectral radius [1/s]"]) / max(slowest_rate(r), 1.0 / t_end) for r in data)
        median = ratios[len(ratios) // 2] if len(ratios) % 2 else 0.5 * (ratios[len(ratios) // 2 - 1] +
                                                                          ratios[len(ratios) // 2])
        worst = max(data, key=lambda r: float(r["spectral radius [1/s]"]))
        rows.append({"scene": scene, "t_end_s": f"{t_end:g}", "samples": len(data),
                     "max_spectral_radius_per_s": worst["spectral radius [1/s]"],
                     "fastest_state": worst["fastest state"],
                     "median_stiffness_ratio": f"{median:.4g}",
                     "min_stiffness_ratio": f"{ratios[0]:.4g}", "max_stiffness_ratio": f"{ratios[-1]:.4g}",
                     "stiff": "yes" if median >= 100 else "no"})
        print(f"scene {scene}: median stiffness ratio {median:.4g}", flush=True)
    path = os.path.join(out, "scenes.csv")
    with open(path + ".tmp", "w", newline="") as f:
        f.write("# pumasim stiffness experiments/scenes/<scene>.toml --samples 40 --t-end <its duration>; stiffness ratio = "
                "spectral radius / max(slowest decay rate, 1/t_end); stiff = median >= 100\n")
        w = csv.DictWriter(f, fieldnames=list(rows[0].keys()))
        w.writeheader()
        w.writerows(rows)
    os.replace(path + ".tmp", path)


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--reduced", action="store_true")
    ap.add_argument("--out", default=None)
    args = ap.parse_args()
    out = args.out or os.path.join(ROOT, "build", "stiffness-reduced") if args.reduced else \
        (args.out or os.path.join(ROOT, "results", "stiffness"))
    os.makedirs(out, exist_ok=True)
    plt = style.pyplot()
    for scene, cases in TABLES.items():
        rows = []
        for case, sets in (cases[:1] if args.reduced else cases):
            info, steps = analyse(scene, sets, 0.02 if args.reduced else T_END)
            for s in steps:
                p, m = float(s["predicted"]), float(s["measured"])
                rows.append({"case": case, **info, "integrator": s["integrator"],
                             "predicted_s": s["predicted"], "measured_s": s["measured"],
                             "measured_over_predicted": f"{m / p:.4g}" if p > 0 and m > 0 else "",
                             "note": s["note"]})
            print(f"{scene} {case}: spectral radius {info['spectral_radius']} 1/s", flush=True)
        path = os.path.join(out, scene + ".csv")
        with open(path + ".tmp", "w", newline="") as f:
            f.write(f"# pumasim stiffness experiments/scenes/{scene}.toml --t-end {T_END} --samples 20 --bisect "
                    "--set ... (per case)\n")
            w = csv.DictWriter(f, fieldnames=list(rows[0].keys()))
            w.writeheader()
            w.writerows(rows)
        os.replace(path + ".tmp", path)
        # <table>.png and .pdf: line = predicted, markers = measured, a colour
        # per integrator (the palette; beyond eight the dash and marker too).
        fig, ax = plt.subplots(figsize=(6.5, 4.5))
        for k, m in enumerate(sorted({r["integrator"] for r in rows})):
            rm = [r for r in rows if r["integrator"] == m]
            st = style.series(k)
            c = st["color"]
            x = [float(r["spectral_radius"]) for r in rm]
            ax.plot(x, [float(r["predicted_s"]) for r in rm], ls=st["ls"], color=c, lw=1, label=f"{m} predicted")
            meas = [(xx, float(r["measured_s"])) for xx, r in zip(x, rm) if float(r["measured_s"]) > 0]
            if meas:
                ax.plot(*zip(*meas), st["marker"], color=c, ms=4, label=f"{m} measured")
        ax.set(xscale="log", yscale="log", xlabel="largest |eigenvalue| of the Jacobian [1/s]",
               ylabel="largest stable step [s]", title=f"{scene}: stable step against spectral radius")
        ax.grid(True, lw=0.3)
        style.legend_right(ax)
        fig.tight_layout()
        style.save(fig, os.path.join(out, scene + ".png"))
    conditioning(out, args.reduced, plt)
    scene_stiffness(out, args.reduced)
    print(f"stiffness tables: {os.path.relpath(out, ROOT)}/")


if __name__ == "__main__":
    main()
