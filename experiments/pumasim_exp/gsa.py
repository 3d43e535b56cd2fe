"""Global sensitivity: Sobol indices (Saltelli sampling, Jansen's estimators, bootstrap confidence
intervals) and Morris elementary effects, with SALib's names and meanings (SALib is not in Debian):
first-order S1 and total ST with S1_conf and ST_conf; Morris mu, mu_star, sigma and mu_star_conf.

Sampling and estimators:
- Saltelli, Annoni, Azzini, Campolongo, Ratto and Tarantola, "Variance based sensitivity analysis
  of model output. Design and estimator for the total sensitivity index", Computer Physics
  Communications 181 (2010) 259-270: matrices A and B of N points each, and A_B^i (A with column
  i from B), N (d + 2) evaluations; A and B are the two halves of a scrambled Sobol' sequence in
  2d dimensions (scipy.stats.qmc.Sobol).
- First order, Jansen's form (Saltelli et al. 2010, Table 2, row f):
  V_i = V - 1/(2N) sum_j (f(B)_j - f(A_B^i)_j)^2.
- Total, Jansen (1999, "Analysis of variance designs for model output", Computer Physics
  Communications 117, 35-43; Saltelli et al. 2010, Table 2, row f): V_Ti = 1/(2N) sum_j (f(A)_j -
  f(A_B^i)_j)^2.
- V is the variance of f over A and B together. Confidence: 1.96 times the standard deviation of
  the estimate over bootstrap resamples of the N rows (SALib's conf_level 0.95).
- Morris, "Factorial sampling plans for preliminary computational experiments", Technometrics 33
  (1991) 161-174: r trajectories on a p-level grid, step Delta = p / (2 (p - 1)); mu_star (the mean
  of |EE|) from Campolongo, Cariboni and Saltelli, Environmental Modelling & Software 22 (2007)
  1509-1518.

Inputs are points of the unit hypercube; `to_factors` maps them onto an ensemble file's
distributions (uniform, log-uniform, normal by its inverse CDF, choice by equal intervals).
"""
import math

import numpy as np
from scipy.stats import norm, qmc

Z95 = 1.959963984540054  # norm.ppf(0.975)


class GsaError(ValueError):
    pass


def saltelli(d, n, seed):
    """(A, B, AB): A and B of shape (n, d), AB of shape (d, n, d) with AB[i] = A but column i from B;
    n a power of 2 (the Sobol' sequence's balance)."""
    if d < 1:
        raise GsaError(f"saltelli: expected at least one factor, got {d}")
    if n < 2 or n & (n - 1):
        raise GsaError(f"saltelli: expected n a power of 2 (>= 2), got {n}")
    x = qmc.Sobol(d=2 * d, scramble=True, seed=seed).random(n)
    a, b = x[:, :d], x[:, d:]
    ab = np.repeat(a[None, :, :], d, axis=0)
    for i in range(d):
        ab[i, :, i] = b[:, i]
    return a, b, ab


def _jansen(fa, fb, fab):
    v = np.var(np.concatenate([fa, fb]), ddof=1)
    if not v > 0:
        raise GsaError("sobol: the output does not vary over the samples (variance 0): no indices")
    s1 = (v - 0.5 * np.mean((fb[None, :] - fab) ** 2, axis=1)) / v
    st = 0.5 * np.mean((fa[None, :] - fab) ** 2, axis=1) / v
    return s1, st


def sobol_indices(fa, fb, fab, bootstrap=1000, seed=0):
    """{S1, S1_conf, ST, ST_conf} (arrays over the factors) from f at A, B and AB (shape (d, n))."""
    fa, fb, fab = np.asarray(fa, float), np.asarray(fb, float), np.asarray(fab, float)
    if not (np.all(np.isfinite(fa)) and np.all(np.isfinite(fb)) and np.all(np.isfinite(fab))):
        raise GsaError("sobol: the output has non-finite values (failed runs?): drop or fix them first")
    s1, st = _jansen(fa, fb, fab)
    rng = np.random.default_rng(seed)
    n = fa.size
    boot1, boott = [], []
    for _ in range(bootstrap):
        j = rng.integers(0, n, n)
        b1, bt = _jansen(fa[j], fb[j], fab[:, j])
        boot1.append(b1), boott.append(bt)
    return {"S1": s1, "S1_conf": Z95 * np.std(boot1, axis=0, ddof=1), "ST": st,
            "ST_conf": Z95 * np.std(boott, axis=0, ddof=1)}


def morris_trajectories(d, r, levels, seed):
    """r trajectories of d + 1 points each in the unit hypercube on a `levels`-level grid (Morris
    1991): shape (r, d + 1, d), and for each step the factor it moved and its signed Delta."""
    if levels < 2 or levels % 2:
        raise GsaError(f"morris: expected an even number of levels >= 2, got {levels}")
    rng = np.random.default_rng(seed)
    delta = levels / (2.0 * (levels - 1))
    grid = np.arange(levels // 2) / (levels - 1)  # starting values from which +Delta stays in [0, 1]
    traj = np.empty((r, d + 1, d))
    moves = np.empty((r, d), dtype=int)
    signs = np.empty((r, d))
    for k in range(r):
        x = rng.choice(grid, size=d)
        up = rng.integers(0, 2, d).astype(bool)
        x = np.where(up, x, x + delta)  # a point that then moves down stays in [0, 1]
        order = rng.permutation(d)
        traj[k, 0] = x
        for s, i in enumerate(order):
            x = x.copy()
            x[i] += delta if up[i] else -delta
            traj[k, s + 1] = x
            moves[k, s], signs[k, s] = i, (delta if up[i] else -delta)
    return traj, moves, signs


def morris_indices(f_traj, moves, signs, bootstrap=1000, seed=0):
    """{mu, mu_star, sigma, mu_star_conf} from f along the trajectories (shape (r, d + 1))."""
    f_traj = np.asarray(f_traj, float)
    r, d = moves.shape
    ee = np.empty((r, d))
    for k in range(r):
        for s in range(d):
            ee[k, moves[k, s]] = (f_traj[k, s + 1] - f_traj[k, s]) / signs[k, s]
    rng = np.random.default_rng(seed)
    boot = [np.mean(np.abs(ee[rng.integers(0, r, r)]), axis=0) for _ in range(bootstrap)]
    return {"mu": ee.mean(axis=0), "mu_star": np.abs(ee).mean(axis=0),
            "sigma": ee.std(axis=0, ddof=1) if r > 1 else np.zeros(d),
            "mu_star_conf": Z95 * np.std(boot, axis=0, ddof=1)}


def ishigami(x, a=7.0, b=0.1):
    """Ishigami and Homma (1990) on x in [-pi, pi]^3."""
    x = np.asarray(x, float)
    return np.sin(x[..., 0]) + a * np.sin(x[..., 1]) ** 2 + b * x[..., 2] ** 4 * np.sin(x[..., 0])


def ishigami_exact(a=7.0, b=0.1):
    """The closed-form indices (S1, ST) of the Ishigami function with inputs uniform on [-pi, pi]
    (Sobol' and Levitan 1999; Saltelli et al., Global Sensitivity Analysis: The Primer, 2008)."""
    p4, p8 = math.pi ** 4, math.pi ** 8
    v1 = 0.5 * (1 + b * p4 / 5) ** 2
    v2 = a * a / 8
    vt3 = 8 * b * b * p8 / 225  # V13; V3 = 0
    v = v1 + v2 + vt3
    return np.array([v1, v2, 0.0]) / v, np.array([v1 + vt3, v2, vt3]) / v


def to_factors(u, factors):
    """Unit-hypercube points u (shape (..., d)) as the values of an ensemble file's [[vary]] factors
    (dicts as the sidecar's 'factors' lists them): uniform and log-uniform by their bounds, normal by
    its inverse CDF (u clipped to [1e-12, 1 - 1e-12]), choice by k equal intervals."""
    u = np.asarray(u, float)
    out = []
    for i, f in enumerate(factors):
        col = u[..., i]
        kind = f["distribution"]
        if kind == "uniform":
            out.append(f["low"] + (f["high"] - f["low"]) * col)
        elif kind == "log-uniform":
            out.append(np.exp(np.log(f["low"]) + (np.log(f["high"]) - np.log(f["low"])) * col))
        elif kind == "normal":
            out.append(f["mean"] + f["sd"] * norm.ppf(np.clip(col, 1e-12, 1 - 1e-12)))
        else:
            raise GsaError(f"{f['key']}: a '{kind}' factor has no continuous map from [0, 1] here")
    return np.stack(out, axis=-1)
