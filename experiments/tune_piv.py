#!/usr/bin/python3
"""PIV gains tuned on the full nonlinear plant against scripts/design_piv.py's pole placement.

  experiments/tune_piv.py SCENE --out DIR [--force] [--set KEY=VALUE ...] [--unset KEY ...]
      [--headroom 0.95] [--abscissa 2.0] [--damping 0.3] [--iterations 30] [--module PATH]

The scene's gains are the starting point (the shipped scenes': design_piv.py's pole placement on the
decoupled, linearised joints). The search varies kp, ki and kv of every simulated joint (the
feed-forward gains kvff, kaff are the model's and are kept), in logarithms, to minimise the run's RMS
path error (stats.json rms_path_error_mm: the flange against the reference, every output row), by
scipy's SLSQP with
- the objective's gradient from the forward sensitivities (CVODES, `pumasim.run(sensitivity=...)`,
  d_rms_path_error_mm of each gain: one run per evaluation, at the run's rtol 1e-6);
- the drive's voltage limit: every joint's peak amplifier voltage at most `headroom` of its limit (the
  constraint's gradient by forward differences of plain runs);
- a stability margin of the full model: at the start state and at five states along the run, the
  linearised closed loop (the plant's exact Jacobian, every state: joints, currents, integrals) has
  every eigenvalue left of -`abscissa` [1/s] and every complex pair damped by at least `damping`
  (gradient by differences of the Jacobian's eigenvalues; no runs).
The scene must have a continuous PIV controller and no discrete state (sensitivities refuse it: give
a smooth friction law with --set, as the paper's scene with friction.model="viscous").

Writes DIR (a new folder, or with --force one it wrote): tune.json (both gain sets, their runs'
figures, the margins, the design's intended poles against the full model's, the search's history and
cost) and tuned.toml (the scene with the tuned gains, resolved: `pumasim run DIR/tuned.toml` re-runs it).
"""
import argparse
import json
import math
import os
import sys
import time

import numpy as np

from pumasim_exp import files

HERE = os.path.dirname(os.path.abspath(__file__))
MARKER = "tune.json"
GAINS = ("kp", "ki", "kv")
RUN = {"integrator": "cvode-bdf", "rtol": 1e-6}


class BadInput(Exception):
    pass


def forward_jacobian(f, x, h):
    """d f / d x by forward differences of step h in each component."""
    f0 = np.asarray(f(x), dtype=float)
    J = np.zeros((f0.size, len(x)))
    for k in range(len(x)):
        e = np.array(x, dtype=float)
        e[k] += h
        J[:, k] = (np.asarray(f(e), dtype=float) - f0) / h
    return J


class Tuner:
    def __init__(self, pumasim, scene_file, overrides, unset, args):
        self.pumasim, self.file, self.args = pumasim, scene_file, args
        self.overrides, self.unset = dict(overrides), list(unset)
        try:
            base = pumasim.Scene.load(scene_file, overrides=self.overrides, unset=self.unset)
        except (ValueError, TypeError) as e:
            raise BadInput(str(e))
        import tomllib

        doc = tomllib.loads(base.resolved_toml())
        ctl = doc.get("controller", {})
        if ctl.get("law", "piv") != "piv" or ctl.get("mode") != "continuous":
            raise BadInput(f"{scene_file}: tune_piv needs a continuous PIV controller ([controller] law \"piv\", "
                           "mode \"continuous\")")
        if base.discrete_state:
            raise BadInput(f"{scene_file}: the plant has discrete state ({base.discrete_state}); the sensitivities "
                           "refuse it (a smooth friction law: --set friction.model=\"viscous\")")
        self.n = int(doc["scene"]["joints"])
        missing = [g for g in GAINS if g not in ctl]
        if missing or "voltage_limit" not in doc.get("amplifier", {}):
            raise BadInput(f"{scene_file}: tune_piv needs [controller] kp, ki, kv and a drive with [amplifier] "
                           f"voltage_limit; missing: {', '.join(missing + (['voltage_limit'] if 'voltage_limit' not in doc.get('amplifier', {}) else []))}")
        self.g0 = np.array([float(np.broadcast_to(ctl[g], (self.n,))[j]) for g in GAINS for j in range(self.n)])
        if np.any(self.g0 <= 0):
            raise BadInput(f"{scene_file}: tune_piv searches log-gains: every kp, ki, kv must be > 0")
        self.keys = [f"controller.{g}[{j}]" for g in GAINS for j in range(self.n)]
        self.vmax = np.broadcast_to(np.asarray(doc["amplifier"]["voltage_limit"], dtype=float), (self.n,))
        self.runs, self.wall, self.cache, self.history = 0, 0.0, {}, []
        self.states = None
        self.best = None  # (objective, x) of the best feasible point the search evaluated

    def gains(self, x):
        return self.g0 * np.exp(np.asarray(x, dtype=float))

    def scene(self, x):
        o = dict(self.overrides)
        g = self.gains(x)
        for k, gain in enumerate(GAINS):
            o[f"controller.{gain}"] = [float(v) for v in g[k * self.n:(k + 1) * self.n]]
        return self.pumasim.Scene.load(self.file, overrides=o, unset=self.unset)

    def run(self, x, sensitivity=True):
        key = (tuple(np.round(np.asarray(x, dtype=float), 14)), sensitivity)
        if key in self.cache:
            return self.cache[key]
        started = time.perf_counter()
        r = self.pumasim.run(self.scene(x), sensitivity=self.keys if sensitivity else None, **RUN)
        self.wall += time.perf_counter() - started
        self.runs += 1
        if not r.ok or (sensitivity and not r.sensitivity["ok"]):
            raise RuntimeError(f"the run with gains {self.gains(x).tolist()} failed: "
                               f"{r.failure or r.sensitivity['failure']}")
        self.cache[key] = r
        return r

    def objective(self, x):
        r = self.run(x)
        d = r.stats["sensitivity"]["d_rms_path_error_mm"]
        grad = np.array([d[k] for k in self.keys]) * self.gains(x)  # d/dx of exp(x) g0
        ok = bool(np.all(self.args.headroom * self.vmax >= np.asarray(r.stats["peak_voltage_V"])) and
                  np.all(self.margins(x) >= 0))
        self.history.append({"rms_path_error_mm": r.stats["rms_path_error_mm"], "feasible": ok,
                             "gains": self.gains(x).tolist()})
        if ok and (self.best is None or r.stats["rms_path_error_mm"] < self.best[0]):
            self.best = (r.stats["rms_path_error_mm"], np.array(x, dtype=float))
        return float(r.stats["rms_path_error_mm"]), grad

    def voltage(self, x):
        r = self.run(x, sensitivity=False)
        return self.args.headroom * self.vmax - np.asarray(r.stats["peak_voltage_V"], dtype=float)

    def voltage_jac(self, x):
        return forward_jacobian(self.voltage, x, 1e-3)

    def poles(self, x):
        """The eigenvalues of the closed loop with gains x linearised at six states of the starting gains' run
        (its first row and five more, evenly spaced): the same states for every x."""
        sc = self.scene(x)
        if self.states is None:
            r = self.run(np.zeros_like(x), sensitivity=False)
            t, X = np.asarray(r.t), np.asarray(r.x)
            pick = np.linspace(0, t.size - 1, 6).astype(int)
            self.states = [(float(t[k]), X[k]) for k in pick]
        return [np.linalg.eigvals(np.asarray(sc.jacobian(t, xs))) for t, xs in self.states]

    def margins(self, x):
        """(-abscissa - the largest real part, the least damping - damping) over the linearisations."""
        worst_re, worst_zeta = -math.inf, math.inf
        for lam in self.poles(x):
            worst_re = max(worst_re, float(np.max(lam.real)))
            osc = lam[np.abs(lam.imag) > 1e-9 * np.abs(lam)]
            if osc.size:
                worst_zeta = min(worst_zeta, float(np.min(-osc.real / np.abs(osc))))
        return np.array([-self.args.abscissa - worst_re, (worst_zeta if math.isfinite(worst_zeta) else 1.0) -
                         self.args.damping])

    def margins_jac(self, x):
        return forward_jacobian(self.margins, x, 1e-4)


def figures(tuner, x):
    r = tuner.run(x, sensitivity=False)
    m = tuner.margins(x)
    lam = tuner.poles(x)[0]  # at the start state
    lam = lam[lam.imag >= 0]  # one of each conjugate pair
    return {"gains": {g: tuner.gains(x)[k * tuner.n:(k + 1) * tuner.n].tolist() for k, g in enumerate(GAINS)},
            "rms_path_error_mm": r.stats["rms_path_error_mm"], "max_path_error_mm": r.stats["max_path_error_mm"],
            "peak_voltage_V": r.stats["peak_voltage_V"], "saturated_fraction": r.stats["saturated_fraction"],
            "spectral_abscissa": -(m[0] + tuner.args.abscissa), "least_damping": m[1] + tuner.args.damping,
            "slowest_poles": sorted([[float(v.real), float(abs(v.imag))] for v in lam], key=lambda p: -p[0])[:3 * tuner.n]}


def design_poles(tuner, args):
    """The poles design_piv.py places (from the scene's comment): s^2 + 2 zeta wn s + wn^2 per joint and the
    integral's -wn/10; None when the scene does not say its bandwidth."""
    with open(tuner.file, encoding="utf-8") as f:
        text = f.read()
    import re

    m = re.search(r"design_piv\.py \S+ --bandwidth (\S+) --damping (\S+)", text)
    if not m:
        return None
    wn, z = 2 * math.pi * float(m.group(1)), float(m.group(2))
    return {"bandwidth_hz": float(m.group(1)), "damping": z,
            "poles": [[-z * wn, wn * math.sqrt(max(0.0, 1 - z * z))], [-wn / 10, 0.0]]}


def tune(tuner, args, log):
    from scipy import optimize

    x0 = np.zeros(tuner.g0.size)
    before = figures(tuner, x0)
    log(f"start: rms path error {before['rms_path_error_mm']:.4g} mm, peak voltage "
        f"{max(before['peak_voltage_V']):.3g} V, abscissa {before['spectral_abscissa']:.3g} 1/s")
    started = time.perf_counter()
    res = optimize.minimize(tuner.objective, x0, jac=True, method="SLSQP",
                            bounds=[(-args.range, args.range)] * x0.size,
                            constraints=[{"type": "ineq", "fun": tuner.voltage, "jac": tuner.voltage_jac},
                                         {"type": "ineq", "fun": tuner.margins, "jac": tuner.margins_jac}],
                            options={"maxiter": args.iterations, "ftol": 1e-6})
    wall = time.perf_counter() - started
    feasible = bool(np.all(tuner.voltage(res.x) >= -1e-9) and np.all(tuner.margins(res.x) >= -1e-9))
    # SLSQP's last iterate, or (stopped infeasible, or worse) the best feasible point it evaluated.
    x = res.x if feasible else x0
    if tuner.best is not None and (not feasible or tuner.best[0] < tuner.run(x).stats["rms_path_error_mm"]):
        x = tuner.best[1]
    after = figures(tuner, x)
    log(f"tuned: rms path error {after['rms_path_error_mm']:.4g} mm ({res.message}, {res.nit} iterations, "
        f"{tuner.runs} runs, {wall:.1f} s)")
    return x, before, after, {"message": str(res.message), "iterations": int(res.nit), "success": bool(res.success),
                              "feasible": feasible, "runs": tuner.runs, "wall_s": wall,
                              "run_wall_s": tuner.wall, "history": tuner.history}


def summary_md(doc):
    pp, tu, c = doc["pole_placement"], doc["tuned"], doc["constraints"]
    name = os.path.splitext(os.path.basename(doc["scene"]))[0]
    lines = [f"# PIV gains on {name}: pole placement against tuning on the full model", "",
             "Generated by experiments/tune_piv.py (do not edit); overrides: " +
             (", ".join(f"`{o}`" for o in doc["overrides"] + [f"unset {u}" for u in doc["unset"]]) or "none") + ".",
             "",
             f"Constraints: peak voltage at most {c['headroom']:g} of the limit; every pole of the linearised "
             f"closed loop (start state and five run states) left of -{c['abscissa_per_s']:g} 1/s, every complex "
             f"pair damped by at least {c['damping']:g}. Runs: {doc['run']['integrator']} at rtol "
             f"{doc['run']['rtol']:g}.", "",
             "| | pole placement | tuned |", "|---|---|---|"]
    row = lambda label, f: lines.append(f"| {label} | {f(pp)} | {f(tu)} |")
    row("RMS path error [mm]", lambda v: f"{v['rms_path_error_mm']:.4g}")
    row("max path error [mm]", lambda v: f"{v['max_path_error_mm']:.4g}")
    lines.append(f"| RMS path error / pole placement's | 1 | {tu['rms_path_error_mm'] / pp['rms_path_error_mm']:.3g} |")
    row("peak voltage [V]", lambda v: f"{max(v['peak_voltage_V']):.4g}")
    row("spectral abscissa [1/s]", lambda v: f"{v['spectral_abscissa']:.4g}")
    row("least damping", lambda v: f"{v['least_damping']:.3g}")
    for g in GAINS:
        row(g, lambda v, g=g: ", ".join(f"{x:.4g}" for x in v["gains"][g]))
    s = doc["search"]
    lines += ["", f"Search: SLSQP, {s['iterations']} iterations ({s['message']}), {s['runs']} runs, "
              f"{s['wall_s']:.1f} s; the result is {'its last iterate' if s['feasible'] else 'the best feasible point it evaluated'}."]
    d = doc["design"]
    if d:
        lines += ["", f"design_piv.py placed, per joint, {d['poles'][0][0]:.4g} ± {d['poles'][0][1]:.4g}j and "
                  f"{d['poles'][1][0]:.4g} (bandwidth {d['bandwidth_hz']:g} Hz, damping {d['damping']:g}, on the decoupled "
                  "joint without inductance); the full model's slowest poles with those gains at the start state: " +
                  ", ".join(f"{p[0]:.4g} ± {p[1]:.4g}j" if p[1] else f"{p[0]:.4g}" for p in pp["slowest_poles"]) + "."]
    return "\n".join(lines) + "\n"


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("scene")
    ap.add_argument("--out", required=True)
    ap.add_argument("--force", action="store_true")
    ap.add_argument("--set", action="append", default=[], metavar="KEY=VALUE", help="a scene override (TOML value)")
    ap.add_argument("--unset", action="append", default=[], metavar="KEY")
    ap.add_argument("--headroom", type=float, default=0.95, help="peak voltage at most this fraction of the limit")
    ap.add_argument("--abscissa", type=float, default=2.0, help="[1/s] every pole left of -abscissa")
    ap.add_argument("--damping", type=float, default=0.3, help="every complex pair damped at least this much")
    ap.add_argument("--range", type=float, default=3.0, help="each gain within exp(+-range) of its start")
    ap.add_argument("--iterations", type=int, default=30)
    ap.add_argument("--module", help="the folder holding the pumasim module (default build/release/python)")
    ap.add_argument("--quiet", action="store_true")
    a = ap.parse_args(argv)
    log = (lambda s: None) if a.quiet else (lambda s: print("tune_piv: " + s, file=sys.stderr, flush=True))
    out = os.path.abspath(a.out)
    try:
        if not (0 < a.headroom <= 1) or a.abscissa < 0 or not (0 <= a.damping < 1) or a.range <= 0 or \
                a.iterations < 1:
            raise BadInput("expected --headroom in (0, 1], --abscissa >= 0, --damping in [0, 1), --range > 0, "
                           "--iterations >= 1")
        folder = files.ProgramFolder(out, (MARKER, "tuned.toml", "summary.md"), MARKER, "tune_piv")
        why = folder.refusal(a.force)
        if why:
            raise BadInput(why)
        pumasim = files.import_pumasim(a.module, os.path.join(HERE, os.pardir, "build", "release", "python"))

        overrides = {}
        for s in a.set:
            if "=" not in s:
                raise BadInput(f"--set {s}: expected KEY=VALUE")
            k, v = s.split("=", 1)
            import tomllib

            try:
                overrides[k] = tomllib.loads("v = " + v)["v"]
            except tomllib.TOMLDecodeError:
                raise BadInput(f"--set {s}: the value is not TOML")
        tuner = Tuner(pumasim, os.path.abspath(a.scene), overrides, a.unset, a)
        x, before, after, search = tune(tuner, a, log)
        doc = {"program": "experiments/tune_piv.py", "scene": tuner.file, "overrides": a.set, "unset": a.unset,
               "run": RUN, "constraints": {"headroom": a.headroom, "abscissa_per_s": a.abscissa,
                                           "damping": a.damping, "range": a.range},
               "design": design_poles(tuner, a), "pole_placement": before, "tuned": after, "search": search}
        with folder as tmp:
            with open(os.path.join(tmp, MARKER), "w", encoding="utf-8") as f:
                json.dump(doc, f, indent=1)
                f.write("\n")
            with open(os.path.join(tmp, "summary.md"), "w", encoding="utf-8") as f:
                f.write(summary_md(doc))
            with open(os.path.join(tmp, "tuned.toml"), "w", encoding="utf-8") as f:
                f.write(f"# Generated by experiments/tune_piv.py (do not edit): {os.path.relpath(tuner.file)} with "
                        "the PIV gains tuned on the full model.\n")
                f.write(tuner.scene(x).resolved_toml())
    except BadInput as e:
        print(f"tune_piv: {e}", file=sys.stderr)
        return 2
    except RuntimeError as e:
        print(f"tune_piv: {e}", file=sys.stderr)
        return 1
    log(f"wrote {out}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
