#!/usr/bin/python3
"""pumasim identify: an arm's base parameters from a simulated experiment with a known truth.

  experiments/identify.py EXPERIMENT.toml --out DIR [--force] [--seeds N] [--methods ols,wls,iv,didim]

The experiment file names a scene (the plant: drive, controller, friction; its reference is replaced)
and says how to excite it, what is measured and how the data are filtered
(docs/user-guide/identification.md, experiments/identification/puma560.toml). Steps:
1. Excitation (Swevers, Ganseman, Tukel, De Schutter & Van Brussel, IEEE TRA 13(5), 1997): per joint
   a finite Fourier series of `harmonics` terms at the base frequency 1/period, at rest with zero
   acceleration at t = 0 (two coefficients per joint eliminated), its coefficients chosen (Powell's search) to
   minimise the condition number of the stacked base regressor on a grid, under the joint ranges (less
   a margin) and the speed limits. The drive's voltage limit is checked by running the closed-loop
   plant on it; where it saturates the amplitudes are scaled down and the run repeated.
2. The closed-loop run (the scene's integrator) on the excitation, given to the scene as knots of a
   C4 quintic spline (reference.joints).
3. Measurements (per noise seed): motor-side encoder angles quantised to `encoder_counts` per motor
   revolution, motor currents with Gaussian noise, at `sample_rate`; torques Z K i.
4. Filtering: zero-phase Butterworth (scipy.signal.filtfilt) of the angles and, in parallel, the
   torques (Gautier 1997's parallel filtering); speeds and accelerations by central differences of
   the filtered angles; the ends trimmed; every `decimate`-th sample kept.
5. Estimation of the base parameters:
   - ols: IDIM-OLS, linear least squares on the stacked base regressor (Gautier & Khalil);
   - wls: IDIM-WLS, each joint's rows weighted by 1 / its OLS residual's standard deviation
     (Gautier & Poignet 2001);
   - iv: IDIM-IV (Janot, Vandanjon & Gautier, IEEE TCST 22(1), 2014): the instruments are the base
     regressor of the closed loop simulated with the previous estimate, iterated from WLS;
   - didim: DIDIM (Gautier, Janot & Vandanjon, IEEE TCST 21(2), 2013): closed-loop output error on
     the torques by Gauss-Newton with the paper's Jacobian, the base regressor of the simulated
     motion (the dependence of that motion on the parameters neglected, as the paper does), from WLS.
   A simulation with an estimate needs a whole robot: the estimate's completion nearest the robot
   file's own parameters with the base parameters' own columns moved (K pi = beta). The simulated closed
   loop depends on beta only, so the completion's choice changes no estimate, only whether it is a
   robot a robot file can hold (an estimate whose completion has an inertia that is not positive
   semi-definite is not simulated: that seed's iv or didim is reported failed).
6. Monte Carlo over noise seeds: each method's estimates, their bias and spread against the truth,
   and the cost of each method.
The truth is the scene's plant: the links and rotors of its robot, and its friction on the joint side
(Fv = Z^2 B; the viscous law's; Fc = Fo = 0). Only friction "none" or "viscous" is accepted: another
law is not the regressor's Fv qd + Fc sign(qd) + Fo and the truth would not be exact.

Writes DIR (a new folder, or with --force one this program wrote; nothing half-written: the results
are made in a sibling temporary folder and renamed): identify.json (the summary: excitation, costs,
truth and estimates, feasibility), estimates.csv (every seed's estimates), excitation.csv (the knots;
not with --no-knots),
table.md (the Monte Carlo table), experiment.toml (the input). Exit 2 for a bad experiment file (its
file, line, key and what was expected), 1 for a failed run.
"""
import argparse
import csv
import io
import json
import math
import os
import sys
import time
import tomllib

import numpy as np

from pumasim_exp import files

HERE = os.path.dirname(os.path.abspath(__file__))
METHODS = ("ols", "wls", "iv", "didim")
MARKER = "identify.json"


class BadInput(Exception):
    pass


# ---------------------------------------------------------------- the experiment file

def _positive(x):
    return x > 0


def _nonneg(x):
    return x >= 0


# section -> key -> (required, kind, check, expected)
SCHEMA = {
    "experiment": {
        "name": (True, str, None, "a string"),
        "scene": (True, str, None, "a scene file's path, relative to the experiment file"),
    },
    "excitation": {
        "period": (True, float, _positive, "a number > 0 [s]"),
        "harmonics": (True, int, lambda x: 2 <= x <= 20, "a whole number in [2, 20]"),
        "periods": (False, int, lambda x: 1 <= x <= 100, "a whole number in [1, 100]"),
        "center": (True, list, None, "an array of n angles [rad], the trajectory's mean"),
        "margin": (False, float, _nonneg, "a number >= 0 [rad] kept from each joint limit"),
        "max_speed": (True, "array", _positive, "a number > 0 [rad/s], one per joint (an array) or one for all"),
        "grid": (False, int, lambda x: 10 <= x <= 10000, "a whole number in [10, 10000] of points per period"),
        "knot_interval": (False, float, _positive, "a number > 0 [s] between the spline's knots"),
        "evaluations": (False, int, lambda x: 0 <= x <= 1000000,
                        "a whole number in [0, 1e6]: the search's evaluations of cond(W_b)"),
        "seed": (False, int, _nonneg, "a whole number >= 0"),
    },
    "measurement": {
        "sample_rate": (True, float, _positive, "a number > 0 [Hz]"),
        "encoder_counts": (True, int, _positive, "a whole number > 0 of counts per motor revolution"),
        "current_noise": (True, float, _nonneg, "a number >= 0 [A], the standard deviation"),
    },
    "filter": {
        "cutoff": (True, float, _positive, "a number > 0 [Hz], below half the sample rate"),
        "order": (False, int, lambda x: 1 <= x <= 10, "a whole number in [1, 10]"),
        "decimate": (False, int, lambda x: 1 <= x <= 1000, "a whole number in [1, 1000]"),
        "trim": (False, float, _nonneg, "a number >= 0 [s] dropped at each end"),
    },
    "identification": {
        "methods": (False, "methods", None, "an array of: " + ", ".join(f'"{m}"' for m in METHODS)),
        "iterations": (False, int, lambda x: 1 <= x <= 100, "a whole number in [1, 100] (iv, didim)"),
        "tolerance": (False, float, lambda x: 0 < x < 1, "a number in (0, 1): the relative change that stops iv, didim"),
        "essential_ratio": (False, float, _nonneg, "a number >= 0: iv and didim keep the base parameters whose "
                            "WLS estimate exceeds this many standard errors"),
    },
    "monte_carlo": {
        "seeds": (False, int, lambda x: 1 <= x <= 100000, "a whole number in [1, 100000]"),
        "first_seed": (False, int, _nonneg, "a whole number >= 0"),
    },
}
DEFAULTS = {
    "excitation": {"periods": 1, "margin": 0.1, "grid": 100, "knot_interval": 0.01, "evaluations": 3000, "seed": 1},
    "filter": {"order": 4, "decimate": 10, "trim": 0.2},
    "identification": {"methods": list(METHODS), "iterations": 10, "tolerance": 1e-4, "essential_ratio": 3.0},
    "monte_carlo": {"seeds": 10, "first_seed": 1},
}


def _line_of(text, section, key):
    """The line (from 1) of `key` in [section], or of the section's header, or 1."""
    current, header = None, 1
    for k, line in enumerate(text.splitlines(), 1):
        s = line.strip()
        if s.startswith("[") and s.endswith("]"):
            current = s.strip("[]").strip()
            if current == section:
                header = k
            continue
        if current == section and key is not None and s.split("=")[0].strip() == key:
            return k
    return header


def _kind_ok(kind, v):
    if kind is float:
        return isinstance(v, (int, float)) and not isinstance(v, bool) and math.isfinite(v)
    if kind is int:
        return isinstance(v, int) and not isinstance(v, bool)
    if kind is str:
        return isinstance(v, str)
    if kind is list:
        return isinstance(v, list) and all(_kind_ok(float, x) for x in v)
    if kind == "array":
        return _kind_ok(float, v) or (isinstance(v, list) and len(v) > 0 and all(_kind_ok(float, x) for x in v))
    if kind == "methods":
        return isinstance(v, list) and len(v) > 0 and all(isinstance(x, str) and x in METHODS for x in v)
    return False


def read_experiment(path):
    """The experiment as a dict of sections, defaults filled in; BadInput naming file, line and key."""
    try:
        with open(path, "rb") as f:
            raw = f.read()
        text = raw.decode("utf-8")
        doc = tomllib.loads(text)
    except OSError as e:
        raise BadInput(f"{path}: cannot read the experiment file ({e.strerror})")
    except (UnicodeDecodeError, tomllib.TOMLDecodeError) as e:
        raise BadInput(f"{path}: not a TOML file ({e})")
    out = {}
    for section, value in doc.items():
        if section not in SCHEMA:
            raise BadInput(f"{path}:{_line_of(text, section, None)}: unknown section [{section}]; "
                           f"expected one of: " + ", ".join(f"[{s}]" for s in SCHEMA))
        if not isinstance(value, dict):
            raise BadInput(f"{path}:{_line_of(text, section, None)}: {section}: expected a table [{section}]")
    for section, keys in SCHEMA.items():
        given = doc.get(section, {})
        for key in given:
            if key not in keys:
                raise BadInput(f"{path}:{_line_of(text, section, key)}: [{section}] {key}: unknown key; expected "
                               "one of: " + ", ".join(keys))
        sec = dict(DEFAULTS.get(section, {}))
        for key, (required, kind, check, expected) in keys.items():
            where = f"{path}:{_line_of(text, section, key)}: [{section}] {key}"
            if key not in given:
                if required:
                    raise BadInput(f"{where}: required ({expected})")
                continue
            v = given[key]
            if not _kind_ok(kind, v):
                raise BadInput(f"{where}: expected {expected}, got {v!r}")
            values = v if isinstance(v, list) and kind == "array" else [v]
            if check is not None and not all(check(x) for x in values):
                raise BadInput(f"{where}: expected {expected}, got {v!r}")
            sec[key] = v
        out[section] = sec
    if out["filter"]["cutoff"] >= 0.5 * out["measurement"]["sample_rate"]:
        raise BadInput(f"{path}:{_line_of(text, 'filter', 'cutoff')}: [filter] cutoff: expected a number below "
                       f"half the sample rate ({0.5 * out['measurement']['sample_rate']:g} Hz), got "
                       f"{out['filter']['cutoff']!r}")
    out["file"] = os.path.abspath(path)
    out["text"] = text
    return out


# ---------------------------------------------------------------- the plant and its truth

def _per_joint(v, n):
    """A value given once for all joints or as an array of n (checked: check_joint_arrays)."""
    a = np.asarray(v if isinstance(v, list) else [v] * n, dtype=float)
    if a.size != n:
        raise ValueError(f"expected {n} values, got {a.size}")
    return a


def where(exp, section, key):
    return f"{exp['file']}:{_line_of(exp['text'], section, key)}: [{section}] {key}"


def check_against_plant(exp, plant):
    """The keys whose range depends on the scene: the joint count, the limits, the decimated Nyquist."""
    ex, n = exp["excitation"], plant.n
    for key in ("center", "max_speed"):
        v = ex[key]
        if isinstance(v, list) and len(v) != n:
            raise BadInput(f"{where(exp, 'excitation', key)}: expected {n} values (the scene's joints), got {len(v)}")
    center = np.asarray(ex["center"], dtype=float)
    lo, hi = plant.q_min + ex["margin"], plant.q_max - ex["margin"]
    if np.any(center <= lo) or np.any(center >= hi):
        raise BadInput(f"{where(exp, 'excitation', 'center')}: expected each angle inside its joint range less the "
                       f"margin ({ex['margin']} rad: {np.round(lo, 4).tolist()} .. {np.round(hi, 4).tolist()}), got "
                       f"{center.tolist()}")
    nyquist = 0.5 * exp["measurement"]["sample_rate"] / exp["filter"]["decimate"]
    if exp["filter"]["cutoff"] >= nyquist:
        raise BadInput(f"{where(exp, 'filter', 'cutoff')}: expected a number below the decimated samples' Nyquist "
                       f"frequency ({nyquist:g} Hz: sample_rate / 2 / decimate), got {exp['filter']['cutoff']!r}")


def pseudo_inertia(p):
    """A link's 4 x 4 pseudo-inertia [[tr(I_o)/2 1 - I_o, h], [h^T, m]] from its regressor parameters
    p (XX XY XZ YY YZ ZZ about the frame's origin, MX MY MZ, M): positive semi-definite exactly for a
    rigid body's (Wensing, Kim & Slotine 2017)."""
    Io = np.array([[p[0], p[1], p[2]], [p[1], p[3], p[4]], [p[2], p[4], p[5]]])
    J = np.zeros((4, 4))
    J[:3, :3] = 0.5 * np.trace(Io) * np.eye(3) - Io
    J[:3, 3] = J[3, :3] = p[6:9]
    J[3, 3] = p[9]
    return J


class Plant:
    """The experiment's scene: its robot, drive constants, friction and the truth pi, beta."""

    def __init__(self, pumasim, exp):
        self.pumasim = pumasim
        self.scene_file = os.path.normpath(os.path.join(os.path.dirname(exp["file"]), exp["experiment"]["scene"]))
        try:
            scene = pumasim.Scene.load(self.scene_file)
        except (ValueError, TypeError) as e:
            raise BadInput(str(e))
        doc = tomllib.loads(scene.resolved_toml())
        where = f"{self.scene_file}: "
        robot = doc["scene"]["robot"]
        # A shipped robot's name, or a file relative to the scene (as the scene reader takes it).
        self.robot = robot if "/" not in robot and "." not in robot else \
            os.path.normpath(os.path.join(os.path.dirname(self.scene_file), robot))
        n = int(doc["scene"]["joints"])
        self.n = n
        zero = np.zeros((1, n))
        try:
            reg = pumasim.regressor(robot=self.robot, q=zero, qd=zero, qdd=zero)
        except ValueError as e:
            raise BadInput(where + f"[scene] joints = {n}: identify needs every joint of the robot simulated ({e})")
        if "motor" not in doc or "amplifier" not in doc:
            raise BadInput(where + "identify needs a drive ([amplifier] and [motor]): the torques come from currents")
        if not np.all(_per_joint(doc["motor"]["inductance"], n) > 0):
            raise BadInput(where + "[motor] inductance: identify needs the currents as states (inductance > 0)")
        law = doc.get("friction", {}).get("model", "none")
        if law not in ("none", "viscous"):
            raise BadInput(where + f"[friction] model = \"{law}\": identify takes \"none\" or \"viscous\" (the regressor's "
                           "Fv qd + Fc sign(qd) + Fo is another law's truth only approximately)")
        self.names = reg["names"]
        self.Z = np.asarray(reg["gear_ratio"], dtype=float)
        self.K = _per_joint(doc["motor"]["torque_constant"], n)
        self.voltage_limit = _per_joint(doc["amplifier"].get("voltage_limit", math.inf), n)
        B = _per_joint(doc["friction"]["viscous"], n) if law == "viscous" else np.zeros(n)
        pi = np.array(reg["pi"], dtype=float)
        per = len(self.names) // n
        for j in range(n):
            pi[j * per + 11] = self.Z[j] ** 2 * B[j]  # Fv, joint side
            pi[j * per + 12] = 0.0                     # Fc
            pi[j * per + 13] = 0.0                     # Fo
            if not doc["scene"].get("rotor_inertia", True):
                pi[j * per + 10] = 0.0
        self.per = per
        self.pi = pi
        base = pumasim.base_parameters(robot=self.robot)
        self.base = list(base["base"])
        self.labels = list(base["labels"])
        self.definitions = list(base["definitions"])
        self.Kb = np.asarray(base["K"])
        from scipy import linalg

        self.null = linalg.null_space(self.Kb)
        self.scale = np.array([max(1e-9, abs(pi[j * per + 9]) + np.sum(np.abs(pi[j * per: j * per + 6])))
                               for j in range(n)])
        beta = self.Kb @ pi
        # K's rounding leaves 1e-19 where a base parameter is 0 (a wrist's YZ4R): zero below 1e-12 of the largest.
        self.beta = np.where(np.abs(beta) > 1e-12 * np.max(np.abs(beta)), beta, 0.0)
        made = pumasim.robot_with_parameters(robot=self.robot, pi=reg["pi"])
        if made["text"] is None:
            raise BadInput(where + "the robot's joint limits: its own parameters are no robot a file can hold")
        limits = tomllib.loads(made["text"])
        self.q_min = np.array([j.get("limits", [-math.inf, math.inf])[0] for j in limits.get("joint", [])] or
                              [-math.inf] * n)
        self.q_max = np.array([j.get("limits", [-math.inf, math.inf])[1] for j in limits.get("joint", [])] or
                              [math.inf] * n)
        self.state_names = scene.state_names

    def base_regressor(self, q, qd, qdd):
        Y = self.pumasim.regressor(robot=self.robot, q=q, qd=qd, qdd=qdd)["Y"]
        return np.asarray(Y)[:, self.base]

    def completion(self, beta):
        """A whole pi with K pi = beta, a rigid body per link where the search finds one: from the start
        pi0 (the robot file's and the scene's) with each base parameter's own column moved (K's base columns
        are the identity), moved along K's null space to make each link's pseudo-inertia positive
        semi-definite (Wensing, Kim & Slotine, IEEE RA-L 3(1), 2017: a body's mass, first moment and
        inertia) and each rotor's Ia >= 0. Whether the estimate is physically feasible at all is that
        question (Sousa & Cortesao, IJRR 33(6), 2014); a search that ends above zero is no proof. Where it
        does, the nearest body in the base parameters' scales is returned instead: its K pi is not beta
        (the closed-loop methods then simulate that projection; `feasible` says which)."""
        from scipy import optimize

        pi = self.pi.copy()
        pi[self.base] += beta - self.Kb @ self.pi
        if self.violation(pi) == 0.0:
            return pi
        res = optimize.minimize(lambda z: self.violation(pi + self.null @ z), np.zeros(self.null.shape[1]),
                                method="L-BFGS-B", options={"maxiter": 500})
        pi = pi + self.null @ res.x
        if self.violation(pi) == 0.0:
            return pi
        # No body found with these base parameters: the nearest pi that is one, in the base parameters'
        # own scales (beta moves: the caller sees K pi != beta).
        scale = np.maximum(np.abs(self.beta), 1e-6 * np.max(np.abs(self.beta)))
        res = optimize.minimize(lambda x: float(np.sum(((self.Kb @ x - beta) / scale) ** 2)) +
                                1e6 * self.violation(x), pi, method="L-BFGS-B", options={"maxiter": 2000})
        return self.repaired(res.x)

    def repaired(self, pi):
        """What a penalty leaves: each link's pseudo-inertia J shifted by (margin - its least eigenvalue)
        times the identity where that is negative (J + c 1: m + c and I_o + 2c 1), Ia < 0 set to 0."""
        pi = pi.copy()
        for j in range(self.n):
            p = pi[j * self.per: j * self.per + 11]
            c = 2e-9 * self.scale[j] - float(np.linalg.eigvalsh(pseudo_inertia(p))[0])
            if c > 0:
                p[[0, 3, 5]] += 2.0 * c  # Sigma = tr(I_o)/2 1 - I_o grows by a/2 when I_o grows by a 1
                p[9] += c
            p[10] = max(p[10], 0.0)
        return pi

    def violation(self, pi):
        """The sum of squares of the negative eigenvalues of each link's pseudo-inertia (relative to the
        start's scale) and of the negative Ia: zero for a rigid body with rotors."""
        total = 0.0
        for j in range(self.n):
            p = pi[j * self.per: j * self.per + 11]
            # A margin of 1e-9 of the scale: a robot file's check sees no rounding-level negative eigenvalue.
            e = np.linalg.eigvalsh(pseudo_inertia(p)) / self.scale[j] - 1e-9
            total += float(np.sum(np.minimum(e, 0.0) ** 2)) + min(0.0, p[10] / self.scale[j]) ** 2
        return total

    def friction_of(self, pi):
        """Motor-side viscous B = Fv / Z^2 of a pi (clamped at 0: a scene refuses B < 0)."""
        Fv = pi[11::self.per][: self.n]
        return np.maximum(Fv, 0.0) / self.Z ** 2


# ---------------------------------------------------------------- excitation

def fourier(coef, w, t):
    """q - center, qd, qdd of the series sum_l a_l/(w l) sin(w l t) - b_l/(w l) cos(w l t) per joint.

    coef: (n, 2, L) the a and b of each joint."""
    L = coef.shape[2]
    wl = w * np.arange(1, L + 1)
    arg = np.multiply.outer(t, wl)  # (T, L)
    s, c = np.sin(arg), np.cos(arg)
    a, b = coef[:, 0, :], coef[:, 1, :]
    q = s @ (a / wl).T - c @ (b / wl).T
    qd = c @ a.T + s @ b.T
    qdd = -s @ (a * wl).T + c @ (b * wl).T
    return q, qd, qdd


def coefficients(x, n, L):
    """The free coefficients x (n, 2, L - 1: a_l, b_l for l >= 2) completed so that qd(0) = qdd(0) = 0:
    a_1 = -sum a_l, b_1 = -sum l b_l."""
    free = x.reshape(n, 2, L - 1)
    coef = np.zeros((n, 2, L))
    coef[:, :, 1:] = free
    coef[:, 0, 0] = -free[:, 0, :].sum(axis=1)
    coef[:, 1, 0] = -(free[:, 1, :] * np.arange(2, L + 1)).sum(axis=1)
    return coef


def design_excitation(plant, ex):
    """Minimise cond(W_b) on the grid over the free coefficients. The limits hold by construction: each
    candidate joint's coefficients are scaled by the largest factor <= 1 that keeps its grid inside its range
    (less the margin) and its speed under its limit, so the search is unconstrained."""
    from scipy import optimize

    n, L, T = plant.n, ex["harmonics"], ex["period"]
    w = 2 * math.pi / T
    center = np.asarray(ex["center"], dtype=float)
    vmax = _per_joint(ex["max_speed"], n)
    lo, hi = plant.q_min + ex["margin"], plant.q_max - ex["margin"]
    t = np.arange(ex["grid"]) * (T / ex["grid"])

    def fitted(x, at=t):
        coef = coefficients(x, n, L) if x.ndim == 1 else x
        q, qd, _ = fourier(coef, w, at)
        with np.errstate(divide="ignore", invalid="ignore"):
            room = np.min([vmax / np.max(np.abs(qd), axis=0), (hi - center) / np.max(q, axis=0),
                           (center - lo) / np.max(-q, axis=0)], axis=0)
        room = np.where(np.isfinite(room) & (room > 0), np.minimum(room, 1.0), 1.0)
        return coef * room[:, None, None]

    def cond(coef):
        q, qd, qdd = fourier(coef, w, t)
        return float(np.linalg.cond(plant.base_regressor(q + center, qd, qdd)))

    rng = np.random.default_rng(ex["seed"])
    x0 = rng.uniform(-1, 1, size=n * 2 * (L - 1)) * np.repeat(vmax, 2 * (L - 1)) / L
    started = time.perf_counter()
    cond0 = cond(fitted(x0))
    # Powell's derivative-free search, for `evaluations` evaluations at most (a budget: it stops there
    # without a convergence test passed, as in the shipped experiments): the scaling puts kinks in the objective that stop a gradient
    # method's line search near its start (L-BFGS-B moved cond(W_b) by 0.1 % here, Powell by 19x).
    res = optimize.minimize(lambda x: math.log(cond(fitted(x))), x0, method="Powell",
                            options={"maxfev": max(1, ex["evaluations"])})
    # The grid's scaling, then again on a grid 20 times finer (between the grid's points the series can
    # exceed a limit the grid kept: by 0.5 % in a run of the shipped experiment).
    fine = np.arange(20 * ex["grid"]) * (T / (20 * ex["grid"]))
    coef = fitted(fitted(res.x), at=fine)
    q, qd, _ = fourier(coef, w, fine)
    return {"coef": coef, "w": w, "center": center, "cond_start": cond0, "cond": cond(coef),
            "optimiser": {"method": "Powell", "message": str(res.message), "evaluations": int(res.nfev),
                          "success": bool(res.success)},
            "wall_s": time.perf_counter() - started,
            "grid_peak_speed": np.max(np.abs(qd), axis=0).tolist(),
            "grid_range": [(np.min(q, axis=0) + center).tolist(), (np.max(q, axis=0) + center).tolist()]}


def scaled(design, factor):
    d = dict(design)
    d["coef"] = design["coef"] * factor
    return d


def knots(design, ex):
    """Rows t, q1 .. qn of the excitation at the knot interval over its periods."""
    span = ex["period"] * ex["periods"]
    m = max(2, int(round(span / ex["knot_interval"])))
    t = np.linspace(0.0, span, m + 1)
    q, _, _ = fourier(design["coef"], design["w"], t)
    return t, q + design["center"]


# ---------------------------------------------------------------- closed-loop runs

class Simulator:
    """Runs the scene on the excitation's knots, with the truth or with an estimate's completion."""

    def __init__(self, plant, exp, workdir, t, q):
        self.plant, self.exp, self.workdir = plant, exp, workdir
        self.csv = os.path.join(workdir, "excitation.csv")
        with open(self.csv, "w", encoding="utf-8") as f:
            f.write("t," + ",".join(f"q{j + 1}" for j in range(plant.n)) + "\n")
            for k in range(t.size):
                f.write(f"{t[k]:.12g}," + ",".join(f"{float(v):.12g}" for v in q[k]) + "\n")
        self.span = float(t[-1])
        doc = tomllib.loads(plant.pumasim.Scene.load(plant.scene_file).resolved_toml())
        self.unset = ["reference." + k for k in doc.get("reference", {})]
        self.runs = 0
        self.wall = 0.0

    def scene(self, pi=None):
        p = self.plant
        o = {"reference.joints": self.csv, "reference.interpolation": "joint-quintic", "reference.timing": "explicit",
             "scene.output_interval": 1.0 / self.exp["measurement"]["sample_rate"]}
        if pi is not None:
            pi = pi.copy()
            for j in range(p.n):  # the file's friction is not simulated (the scene's viscous law is); >= 0 for the file
                pi[j * p.per + 11: j * p.per + 13] = np.maximum(pi[j * p.per + 11: j * p.per + 13], 0.0)
            made = p.pumasim.robot_with_parameters(robot=p.robot, pi=pi,
                                                   comment="an estimate's completion (experiments/identify.py)")
            if made["text"] is None:
                return None, made["problems"]
            self.runs += 1
            path = os.path.join(self.workdir, "estimate_robot.toml")
            with open(path, "w", encoding="utf-8") as f:
                f.write(made["text"])
            o["scene.robot"] = path
            o["friction.model"] = "viscous"
            o["friction.viscous"] = [float(b) for b in p.friction_of(pi)]
        return p.pumasim.Scene.load(p.scene_file, overrides=o, unset=self.unset), []

    def run(self, pi=None, at=None):
        """(t, x, qdd, stats) at the sample times, qdd from f(t, x) at the samples `at` (default all, else
        zeros elsewhere); None and why for a failed run."""
        scene, problems = self.scene(pi)
        if scene is None:
            return None, "the estimate's completion is no robot a file can hold: " + "; ".join(
                f"link {q['link']} {q['key']} ({q['got']})" for q in problems if not q["excusable"])
        started = time.perf_counter()
        r = self.plant.pumasim.run(scene, t_end=self.span)
        self.wall += time.perf_counter() - started
        if not r.ok:
            return None, f"the closed-loop run failed: {r.failure}"
        t, x = np.asarray(r.t), np.asarray(r.x)
        names = list(r.state_names)
        iq = [names.index(f"qd{j + 1}") for j in range(self.plant.n)]
        qdd = np.zeros((t.size, self.plant.n))
        for k in range(t.size) if at is None else at:
            qdd[k] = np.asarray(scene.rhs(t[k], x[k]))[iq]
        return {"t": t, "x": x, "qdd": qdd, "names": names, "stats": r.stats}, None


def states(plant, run, prefix):
    return run["x"][:, [run["names"].index(f"{prefix}{j + 1}") for j in range(plant.n)]]


def check_drive(plant, run):
    """The closed-loop run's peak voltage and saturation per joint against the amplifier's limit."""
    peak = np.asarray(run["stats"]["peak_voltage_V"], dtype=float)
    sat = np.asarray(run["stats"]["saturated_fraction"], dtype=float)
    return {"peak_voltage_V": peak.tolist(), "voltage_limit_V": plant.voltage_limit.tolist(),
            "saturated_fraction": sat.tolist(), "ok": bool(np.all(sat == 0) and np.all(peak <= plant.voltage_limit))}


# ---------------------------------------------------------------- measurements and filtering

def measure(plant, run, meas, rng):
    """Quantised motor-side encoder angles (joint side) and noisy currents' torques Z K i."""
    q = states(plant, run, "q")
    i = states(plant, run, "i_motor")
    step = 2 * math.pi / meas["encoder_counts"]
    q_enc = np.round(q * plant.Z / step) * step / plant.Z
    i_meas = i + meas["current_noise"] * rng.standard_normal(i.shape)
    return q_enc, i_meas * plant.K * plant.Z


def process(plant, exp, t, q, tau):
    """Zero-phase Butterworth of q and tau, central differences, the ends trimmed, decimated."""
    from scipy import signal

    fs = exp["measurement"]["sample_rate"]
    flt = exp["filter"]
    b, a = signal.butter(flt["order"], flt["cutoff"] / (0.5 * fs))
    dt = 1.0 / fs
    qf = signal.filtfilt(b, a, q, axis=0)
    qd = np.gradient(qf, dt, axis=0)
    qdd = np.gradient(qd, dt, axis=0)
    tf = signal.filtfilt(b, a, tau, axis=0)
    keep = np.arange(t.size)
    keep = keep[(t >= t[0] + flt["trim"]) & (t <= t[-1] - flt["trim"])][:: flt["decimate"]]
    return keep, qf[keep], qd[keep], qdd[keep], tf[keep]


# ---------------------------------------------------------------- the estimators

def _lstsq(A, y):
    beta = np.linalg.lstsq(A, y, rcond=None)[0]
    r = y - A @ beta
    s2 = float(r @ r) / max(1, A.shape[0] - A.shape[1])
    return beta, s2


def _se(cov):
    return np.sqrt(np.maximum(np.diag(cov), 0.0))


def ols(W, y):
    beta, s2 = _lstsq(W, y)
    return {"beta": beta, "se": _se(s2 * np.linalg.inv(W.T @ W))}


def joint_weights(W, y, n):
    """1 / each joint's OLS residual standard deviation, one per row (Gautier & Poignet 2001)."""
    beta = np.linalg.lstsq(W, y, rcond=None)[0]
    r = (y - W @ beta).reshape(-1, n)
    sd = np.sqrt(np.sum(r * r, axis=0) / max(1, r.shape[0] - W.shape[1] / n))
    return np.tile(1.0 / np.where(sd > 0, sd, 1.0), r.shape[0])


def wls(W, y, n):
    w = joint_weights(W, y, n)
    Wt, yt = W * w[:, None], y * w
    beta, s2 = _lstsq(Wt, yt)
    return {"beta": beta, "se": _se(s2 * np.linalg.inv(Wt.T @ Wt))}


def essential(start, ratio):
    """The base parameters the starting estimate tells from zero: |beta| > ratio * its standard error.
    The others are left out of the closed-loop methods (set to 0 in their model and their regression),
    as Gautier's essential parameters are (Pham & Gautier, ICRA 1991): an estimate of them is mostly
    noise, and its completion often no body a robot file can hold."""
    return np.abs(start["beta"]) > ratio * start["se"]


def closed_loop(plant, sim, keep, W, y, n, start, idn, kind):
    """IDIM-IV (kind "iv") or DIDIM ("didim") on the essential parameters, from the WLS estimate
    `start`: each iteration simulates the closed loop with the estimate, takes the base regressor of the
    simulated motion at the kept samples, and solves iv: (Z^T W) beta = Z^T y, didim: min |y - Z beta|;
    rows weighted as WLS."""
    w = joint_weights(W, y, n)
    keep_cols = essential(start, idn["essential_ratio"])
    if not keep_cols.any():
        return {"beta": np.zeros(start["beta"].size), "se": np.full(start["beta"].size, math.nan), "iterations": 0,
                "essential": keep_cols, "projection": 0.0, "failure": "no essential parameter"}
    Wt, yt = (W * w[:, None])[:, keep_cols], y * w
    beta = np.where(keep_cols, start["beta"], 0.0)
    it, failure, change, moved = 0, None, math.inf, 0.0
    for it in range(1, idn["iterations"] + 1):
        pi = plant.completion(beta)
        moved = max(moved, float(np.linalg.norm(plant.Kb @ pi - beta) / np.linalg.norm(beta)))
        run, failure = sim.run(pi, at=keep)
        if run is None:
            break
        q, qd = states(plant, run, "q")[keep], states(plant, run, "qd")[keep]
        Zt = (plant.base_regressor(q, qd, run["qdd"][keep]) * w[:, None])[:, keep_cols]
        new = np.linalg.solve(Zt.T @ Wt, Zt.T @ yt) if kind == "iv" else np.linalg.lstsq(Zt, yt, rcond=None)[0]
        change = np.linalg.norm(new - beta[keep_cols]) / np.linalg.norm(new)
        beta = beta.copy()
        beta[keep_cols] = new
        if change < idn["tolerance"]:
            break
    out = {"beta": beta, "se": np.full(beta.size, math.nan), "iterations": it, "essential": keep_cols,
           "projection": moved}
    if run is None:
        return {**out, "failure": failure}
    if change >= idn["tolerance"]:
        out["failure"] = f"not converged in {idn['iterations']} iterations (last relative change {change:.3g})"
    A = Zt if kind == "didim" else Wt
    r = yt - A @ beta[keep_cols]
    s2 = float(r @ r) / max(1, A.shape[0] - A.shape[1])
    if kind == "iv":
        P = np.linalg.inv(Zt.T @ Wt)
        cov = s2 * P @ (Zt.T @ Zt) @ P.T
    else:
        cov = s2 * np.linalg.inv(Zt.T @ Zt)
    out["se"][keep_cols] = _se(cov)
    return out


def estimate(plant, sim, exp, t, q_meas, tau_meas):
    """Every method's estimate from one experiment's measurements, with its wall time."""
    n = plant.n
    keep, q, qd, qdd, tau = process(plant, exp, t, q_meas, tau_meas)
    W = plant.base_regressor(q, qd, qdd)
    y = tau.reshape(-1)
    idn = exp["identification"]
    out, start = {}, None
    for m in idn["methods"]:
        t0, runs0 = time.perf_counter(), sim.runs
        if m == "ols":
            e = ols(W, y)
        elif m == "wls":
            e = wls(W, y, n)
        else:
            if start is None:
                start = wls(W, y, n)
            e = closed_loop(plant, sim, keep, W, y, n, start, idn, m)
        e["wall_s"] = time.perf_counter() - t0
        e["simulations"] = sim.runs - runs0
        out[m] = e
    return out


def noise_free_ols(plant, run):
    """IDIM-OLS on the run's exact states: q, qd and the currents from x, qdd from f(t, x), every sample."""
    q, qd, i = states(plant, run, "q"), states(plant, run, "qd"), states(plant, run, "i_motor")
    W = plant.base_regressor(q, qd, run["qdd"])
    return ols(W, (i * plant.K * plant.Z).reshape(-1))["beta"]


# ---------------------------------------------------------------- the study

def excite(plant, exp, workdir, log):
    """The designed excitation, scaled down until the closed loop stays inside the voltage limit."""
    design = design_excitation(plant, exp["excitation"])
    log(f"excitation: cond(W_b) {design['cond_start']:.4g} -> {design['cond']:.4g} "
        f"({design['optimiser']['evaluations']} evaluations, Powell, {design['wall_s']:.1f} s)")
    factor = 1.0
    for _ in range(8):
        t, q = knots(scaled(design, factor), exp["excitation"])
        sim = Simulator(plant, exp, workdir, t, q)
        truth_run, failure = sim.run()
        if truth_run is None:
            raise RuntimeError(failure)
        drive = check_drive(plant, truth_run)
        if drive["ok"]:
            break
        log(f"excitation x {factor:.3g}: the drive saturates (peak {max(drive['peak_voltage_V']):.3g} V); scaled by 0.8")
        factor *= 0.8
    else:
        raise RuntimeError("the excitation saturates the drive even scaled by 0.8^7")
    if factor != 1.0:
        qq, qd, qdd = fourier(design["coef"] * factor, design["w"],
                              np.arange(exp["excitation"]["grid"]) * exp["excitation"]["period"] /
                              exp["excitation"]["grid"])
        design["cond"] = float(np.linalg.cond(plant.base_regressor(qq + design["center"], qd, qdd)))
    design["scale"] = factor
    design["drive"] = drive
    design["run_peak_speed"] = np.max(np.abs(states(plant, truth_run, "qd")), axis=0).tolist()
    return design, sim, truth_run, t, q


def study(pumasim, exp, workdir, seeds, log):
    plant = Plant(pumasim, exp)
    check_against_plant(exp, plant)
    design, sim, truth_run, t_knots, q_knots = excite(plant, exp, workdir, log)
    exact = noise_free_ols(plant, truth_run)
    exact_err = float(np.max(np.abs(exact - plant.beta)) / np.max(np.abs(plant.beta)))
    log(f"noise-free IDIM-OLS: largest error {exact_err:.3g} of the largest base parameter")
    rows = []
    for seed in seeds:
        rng = np.random.default_rng(seed)
        q_meas, tau_meas = measure(plant, truth_run, exp["measurement"], rng)
        est = estimate(plant, sim, exp, truth_run["t"], q_meas, tau_meas)
        for m, e in est.items():
            rows.append({"seed": seed, "method": m, **e})
        log(f"seed {seed}: " + ", ".join(f"{m} {e['wall_s']:.2f} s" + (f" ({e['failure']})" if e.get("failure") else "")
                                        for m, e in est.items()))
    return plant, design, truth_run, t_knots, q_knots, exact_err, rows


def completion_problems(plant, beta):
    """(links whose inertia is not positive semi-definite or mass impossible, links breaking only the
    triangle inequalities, |K pi - beta| / |beta|: 0 when a body was found with the estimate's base
    parameters, the projection's distance otherwise) of the estimate's completion."""
    pi = plant.completion(beta)
    made = plant.pumasim.robot_with_parameters(robot=plant.robot, pi=pi)["problems"]
    return (sum(1 for p in made if not p["excusable"]), sum(1 for p in made if p["excusable"]),
            float(np.linalg.norm(plant.Kb @ pi - beta) / np.linalg.norm(beta)))


def summarise(plant, exp, rows):
    """Per method and base parameter, over the seeds whose estimate kept it (iv and didim leave the
    non-essential out): the mean, the spread, z of the mean; the costs; the mean's completion."""
    out = {}
    b = plant.beta.size
    for m in exp["identification"]["methods"]:
        every = [r for r in rows if r["method"] == m]
        mine = [r for r in every if not r.get("failure")]
        B = np.array([r["beta"] for r in mine]).reshape(-1, b)
        kept = np.array([r.get("essential", np.ones(b, dtype=bool)) for r in mine]).reshape(-1, b)
        count = kept.sum(axis=0)
        mean, sd, z = np.full(b, math.nan), np.full(b, math.nan), np.full(b, math.nan)
        for i in range(b):
            v = B[kept[:, i], i]
            if v.size:
                mean[i] = v.mean()
            if v.size > 1:
                sd[i] = v.std(ddof=1)
                z[i] = (mean[i] - plant.beta[i]) / (sd[i] / math.sqrt(v.size)) if sd[i] > 0 else math.nan
        full = np.where(np.isfinite(mean), mean, 0.0)
        out[m] = {"estimates": len(mine), "failed": len(every) - len(mine),
                  "failures": sorted({r["failure"] for r in every if r.get("failure")}),
                  "kept": count.tolist(), "mean": mean.tolist(), "std": sd.tolist(), "z": z.tolist(),
                  "outside_3_se": int(np.sum(np.abs(z[np.isfinite(z)]) > 3)),
                  "tested": int(np.sum(np.isfinite(z))),
                  # kept by every estimate: z ~ t(M - 1) for an unbiased method, no selection
                  "outside_3_se_kept_by_all": int(np.sum(np.abs(z[(count == len(mine)) & np.isfinite(z)]) > 3)),
                  "kept_by_all": int(np.sum((count == len(mine)) & np.isfinite(z))),
                  "wall_s": float(np.mean([r["wall_s"] for r in every])),
                  "simulations": float(np.mean([r["simulations"] for r in every])),
                  "iterations": float(np.mean([r.get("iterations", 1) for r in every])),
                  "projection": max((r["projection"] for r in every if "projection" in r), default=None),
                  "mean_completion_problems": completion_problems(plant, full) if mine else None}
    return out


# ---------------------------------------------------------------- outputs

def _cell(bias, sd, truth):
    if not math.isfinite(bias):
        return "-"
    if abs(truth) > 0:
        return f"{100 * bias / abs(truth):+.3g} ± {100 * sd / abs(truth):.2g} %" if math.isfinite(sd) else \
            f"{100 * bias / abs(truth):+.3g} %"
    return f"{bias:+.3g} ± {sd:.2g}" if math.isfinite(sd) else f"{bias:+.3g}"


def table_md(plant, exp, design, summary, seeds, exact_err):
    methods = exp["identification"]["methods"]
    lines = [
        f"# Identification of {plant.robot}: {exp['experiment']['name']}",
        "",
        "Generated by experiments/identify.py (do not edit): "
        f"{len(seeds)} noise seeds ({seeds[0]}..{seeds[-1]}).",
        "",
        f"Excitation: {exp['excitation']['harmonics']} harmonics at 1/{exp['excitation']['period']:g} s, "
        f"cond(W_b) {design['cond']:.4g} on the design grid (from {design['cond_start']:.4g}), amplitudes x "
        f"{design['scale']:.3g}, peak voltage {max(design['drive']['peak_voltage_V']):.3g} V. Measurements: "
        f"{exp['measurement']['encoder_counts']} counts per motor revolution, current noise "
        f"{exp['measurement']['current_noise']:g} A, {exp['measurement']['sample_rate']:g} Hz; Butterworth order "
        f"{exp['filter']['order']} at {exp['filter']['cutoff']:g} Hz, decimated by {exp['filter']['decimate']}.",
        f"Noise-free IDIM-OLS (exact states, qdd from f): largest error {exact_err:.3g} of the largest base parameter.",
        "",
        "Each cell: the bias of the Monte Carlo mean against the truth and the spread (standard deviation over "
        "seeds), in % of |truth|; absolute (SI units) where the truth is 0.",
        "",
        "| parameter | truth | " + " | ".join(methods) + " |",
        "|---|---|" + "---|" * len(methods),
    ]
    for i, label in enumerate(plant.labels):
        cells = []
        for m in methods:
            k, M = summary[m]["kept"][i], summary[m]["estimates"]
            c = "left out" if k == 0 else _cell(summary[m]["mean"][i] - plant.beta[i], summary[m]["std"][i],
                                                   plant.beta[i])
            cells.append(c if k in (0, M) else f"{c} ({k} of {M})")
        lines.append(f"| {label} | {plant.beta[i]:.6g} | " + " | ".join(cells) + " |")
    row = lambda name, f: lines.append(f"| {name} | | " + " | ".join(f(summary[m]) for m in methods) + " |")
    row("estimates (failed)", lambda s: f"{s['estimates']} ({s['failed']})")
    row("&#124;z&#124; > 3", lambda s: f"{s['outside_3_se']} of {s['tested']}")
    row("&#124;z&#124; > 3, parameters kept by every estimate",
        lambda s: f"{s['outside_3_se_kept_by_all']} of {s['kept_by_all']}")
    row("wall per estimate [s]", lambda s: f"{s['wall_s']:.3g}")
    row("closed-loop runs per estimate", lambda s: f"{s['simulations']:.3g}")
    truth = completion_problems(plant, plant.beta)[2]
    row(f"mean's distance to the nearest body found (the truth's own: {truth:.2g})",
        lambda s: "-" if s["mean_completion_problems"] is None else "%.2g" % s["mean_completion_problems"][2])
    row("largest projection of an iterate (relative)",
        lambda s: "%.2g" % s["projection"] if s.get("projection") is not None else "-")
    lines.append("")
    lines.append("The distance: |K pi - beta| / |beta| of the completion simulated (0: a rigid body with exactly "
                 "these base parameters was found). The search is no proof: a nonzero distance, the truth's "
                 "included (the published set's first link has mass 0 and an inertia), may have a body nearer.")
    lines.append("Left out: a base parameter that iv and didim dropped as not essential (its WLS estimate "
                 f"within {exp['identification']['essential_ratio']:g} standard errors of 0); (k of M): kept "
                 "by k of the M estimates, the statistics over those.")
    lines.append("")
    lines.append("z: (Monte Carlo mean - truth) / (spread / sqrt(estimates)). A completion is the robot file's parameter "
                 "vector with the estimate's base parameters put in their own columns (Wensing, Kim & Slotine "
                 "2017's conditions per link); another completion may be a body where this one is not.")
    return "\n".join(lines) + "\n"


def write_outputs(tmp, plant, exp, design, summary, rows, seeds, exact_err, t_knots, q_knots, wall):
    with open(os.path.join(tmp, "experiment.toml"), "w", encoding="utf-8") as f:
        f.write(f"# Copied by experiments/identify.py from {os.path.relpath(exp['file'])}; its scene is "
                f"{os.path.relpath(plant.scene_file)}.\n" + exp["text"])
    with open(os.path.join(tmp, "table.md"), "w", encoding="utf-8") as f:
        f.write(table_md(plant, exp, design, summary, seeds, exact_err))
    with open(os.path.join(tmp, "estimates.csv"), "w", encoding="utf-8", newline="") as f:
        w = csv.writer(f)
        w.writerow(["seed", "method", "wall_s", "simulations", "failure"] + plant.labels)
        for r in rows:
            w.writerow([r["seed"], r["method"], f"{r['wall_s']:.6g}", r["simulations"], r.get("failure") or ""] +
                       [repr(float(b)) for b in r["beta"]])
    doc = {
        "program": "experiments/identify.py", "experiment": exp["file"], "scene": plant.scene_file,
        "robot": plant.robot, "seeds": list(seeds), "wall_time_s": wall,
        "base_parameters": [{"name": l, "definition": d, "truth": float(b)}
                            for l, d, b in zip(plant.labels, plant.definitions, plant.beta)],
        "excitation": {"cond": design["cond"], "cond_start": design["cond_start"], "scale": design["scale"],
                       "optimiser": design["optimiser"], "design_wall_s": design["wall_s"],
                       "coefficients_a_b": (design["coef"] * design["scale"]).tolist(),
                       "center": design["center"].tolist(), "drive": design["drive"]},
        "noise_free_ols_max_relative_error": exact_err,
        "methods": summary,
    }
    with open(os.path.join(tmp, MARKER), "w", encoding="utf-8") as f:
        json.dump(doc, f, indent=1, allow_nan=True)
        f.write("\n")


OUR_FILES = ("experiment.toml", "table.md", "estimates.csv", "excitation.csv", MARKER)


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("experiment")
    ap.add_argument("--out", required=True, help="a new folder (or, with --force, one identify wrote)")
    ap.add_argument("--force", action="store_true")
    ap.add_argument("--seeds", type=int, help="the Monte Carlo's seed count (default: the file's)")
    ap.add_argument("--methods", help="a comma-separated subset of " + ",".join(METHODS))
    ap.add_argument("--module", help="the folder holding the pumasim module (default build/release/python)")
    ap.add_argument("--no-knots", action="store_true",
                    help="leave excitation.csv (the spline's knots) out; identify.json's coefficients remake it")
    ap.add_argument("--quiet", action="store_true")
    a = ap.parse_args(argv)
    log = (lambda s: None) if a.quiet else (lambda s: print("identify: " + s, file=sys.stderr, flush=True))
    try:
        exp = read_experiment(a.experiment)
        if a.seeds is not None:
            if a.seeds < 1:
                raise BadInput(f"--seeds: expected a whole number >= 1, got {a.seeds}")
            exp["monte_carlo"]["seeds"] = a.seeds
        if a.methods is not None:
            ms = a.methods.split(",")
            bad = [m for m in ms if m not in METHODS]
            if bad or not ms:
                raise BadInput(f"--methods: expected a comma-separated subset of {','.join(METHODS)}, got {a.methods}")
            exp["identification"]["methods"] = ms
        folder = files.ProgramFolder(a.out, OUR_FILES, MARKER, "identify")
        why = folder.refusal(a.force)
        if why:
            raise BadInput(why)
        out = folder.out
        pumasim = files.import_pumasim(a.module, os.path.join(HERE, os.pardir, "build", "release", "python"))
        with folder as tmp:
            started = time.perf_counter()
            mc = exp["monte_carlo"]
            seeds = list(range(mc["first_seed"], mc["first_seed"] + mc["seeds"]))
            plant, design, _, t_knots, q_knots, exact_err, rows = study(pumasim, exp, tmp, seeds, log)
            summary = summarise(plant, exp, rows)
            write_outputs(tmp, plant, exp, design, summary, rows, seeds, exact_err, t_knots, q_knots,
                          time.perf_counter() - started)
            if a.no_knots:
                os.remove(os.path.join(tmp, "excitation.csv"))  # an earlier run's, if any, goes too
    except BadInput as e:
        print(f"identify: {e}", file=sys.stderr)
        return 2
    except RuntimeError as e:
        print(f"identify: {e}", file=sys.stderr)
        return 1
    log(f"wrote {out}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
