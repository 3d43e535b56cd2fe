"""The asymptotic range of a convergence ladder, and the observed order fitted over it (issue 31).

A ladder is one method's runs on one problem, coarse to fine (the step
halving, or the tolerance tightening). Each run brings its error e, its
resolution n (1/dt for a fixed step, the right-hand-side evaluations for an
adaptive method: n grows along the ladder) and its floor: the error below
which the run cannot be told from the reference's own error (the
reference-vs-check difference times a factor, or the rounding that
accumulates over the run's steps). The observed order is the least-squares
slope of -log e against log n; a pair's slope is that of two neighbouring runs.

A slope means an order only inside the asymptotic range, where e falls as
n^-p: above the floor, and at steps where the method is stable.
asymptotic_fit() finds that range and fits there, or marks the slope:

  1. Each run on its own: "failed" (it reported a failure), "unstable" (its
     error is not finite or at least `unstable`, 1 by default: no correct
     digit), "too coarse" (error at least `ceiling`, the experiment's upper end
     of the range, if it names one), "below floor" (error at most its floor).
  2. The range is the longest stretch of consecutive runs left (of two equally
     long, the finer); runs outside it are "not consecutive".
  3. Its fine end: while the finest pair's error does not fall (slope <= 0)
     the finest run has reached the floor, whatever the floor given says
     (rounding grows with the steps, a reference has its own error): "below
     floor"; if that happened, so is every run within PLATEAU times the
     lowest error reached.
     Its coarse end: while the coarsest pair's slope exceeds p + STEEP (the
     error grows with the step faster than order p allows, as it does past a
     method's stability limit) or does not exceed 0, the coarse run is
     "unstable" (fixed step) or "not accuracy-bound" (adaptive: its steps
     are set by stability, as an explicit method's on a stiff problem, or by
     overheads such as restarts, not by the tolerance, so the cost hardly
     follows the error). A fixed-step ladder (halving steps) also drops its coarse
     run as "pre-asymptotic" while the local order has not settled: the
     coarsest pair's slope lies on one side of p and the next pair's is more
     than SETTLED closer to it (RK4 near its stability limit, 4.85 then 4.32).
     Adaptive ladders are not trimmed so: their pairs' slopes scatter with the
     step-size controller.
  4. With at least MIN_POINTS runs left the slope is fitted over them (and the
     finest pair's slope reported beside it, marked if it does not exceed 0
     or exceeds p + STEEP: two runs of nearly one cost); with fewer there is
     no slope, and the reason says why: "too few points" and the marks of the
     others (the slope over every run that finished is kept as `raw_slope`,
     for the record, never as an order).

p is the method's theoretical order, the highest for a variable-order one
("1-5": 5). THEORY holds it per integrator, from the registry.
"""
import collections.abc
import json
import math
import subprocess


def theory_of(entry):
    """The theoretical order of a registry entry (an object of `pumasim integrators --json`): "p",
    or "1-p" for a variable-order method (CVODE's BDF 1-5 and Adams 1-12 start at order 1)."""
    p = int(entry["order"])
    return f"1-{p}" if entry["variable_order"] else str(p)


class _Theory(collections.abc.Mapping):
    """name -> theoretical order (theory_of) of every registry entry, read from `pumasim integrators
    --json` ($PUMASIM, else the release build's) on first use: the registry is the one list, so a new
    integrator needs no entry here."""

    def __init__(self):
        self._table = None

    def _load(self):
        if self._table is None:
            from pumasim_exp.io import PUMASIM
            p = subprocess.run([PUMASIM, "integrators", "--json"], capture_output=True, text=True)
            if p.returncode != 0:
                raise SystemExit(f"order_fit: {PUMASIM} integrators --json: exit status {p.returncode}: "
                                 f"{p.stderr.strip()}")
            self._table = {e["name"]: theory_of(e) for e in json.loads(p.stdout)}
        return self._table

    def __getitem__(self, name):
        return self._load()[name]

    def __iter__(self):
        return iter(self._load())

    def __len__(self):
        return len(self._load())


THEORY = _Theory()

STEEP = 1.0      # a pair steeper than order + STEEP: the coarser run is past the stability limit
SETTLED = 0.2    # fixed step: a coarse pair whose next pair's slope is this much closer to p: pre-asymptotic
MIN_POINTS = 2   # runs in the range needed for a slope
UNSTABLE = 1.0   # an error at or above this (or not finite): unstable
PLATEAU = 10.0   # once the error rises at the fine end: runs within this factor of its lowest are below floor

RULE_TEXT = (f"Asymptotic range: a run that failed, or whose error is not finite or ≥ {UNSTABLE:g}, is unstable; "
             "one whose error is within its floor is below floor. Of the longest stretch of consecutive runs left, "
             "the fine end is below floor while the error stops falling (and then every run within "
             f"{PLATEAU:g}× of the lowest error reached); the coarse end is unstable (adaptive: not accuracy-bound, "
             f"the cost not following the tolerance) while its pair's slope exceeds the order + {STEEP:g} or is "
             f"not positive, and, on a step ladder, pre-asymptotic while the next pair's "
             f"slope is more than {SETTLED:g} closer to the order. The slope is fitted over the runs left if at "
             f"least {MIN_POINTS}; else there is none, and the table gives the reason (\"too few points\", with the "
             "marks of the others) and the slope over every finished run, which is not an order.")


def max_order(theory):
    """The highest order of a THEORY entry ("1-5" -> 5.0, "4" -> 4.0)."""
    return float(str(theory).split("-")[-1])


def least_squares(ns, es):
    """Least-squares slope of -log e against log n (nan for fewer than 2
    points or no spread in n)."""
    pts = [(math.log(n), -math.log(e)) for n, e in zip(ns, es)]
    if len(pts) < 2:
        return math.nan
    mx = sum(p[0] for p in pts) / len(pts)
    my = sum(p[1] for p in pts) / len(pts)
    sxx = sum((p[0] - mx) ** 2 for p in pts)
    if sxx == 0:
        return math.nan
    return sum((p[0] - mx) * (p[1] - my) for p in pts) / sxx


def pair_slope(a, b):
    """Slope of -log e against log n between runs a and b (dicts with n, e):
    +inf where the error falls at equal cost, nan where neither changes."""
    dn = math.log(b["n"]) - math.log(a["n"])
    de = math.log(a["e"]) - math.log(b["e"])
    if dn == 0:
        return math.nan if de == 0 else math.copysign(math.inf, de)
    return de / dn


def _own_mark(r, unstable, ceiling):
    """Step 1's mark of one run (None: unmarked)."""
    if not r["ok"]:
        return "failed"
    if not (math.isfinite(r["e"]) and r["e"] < unstable) or not r["n"] > 0:
        return "unstable"
    if ceiling is not None and r["e"] >= ceiling:
        return "too coarse"
    if r["e"] <= r["floor"] or r["e"] <= 0:
        return "below floor"
    return None


def _longest_stretch(marks):
    """(first, last + 1) of the longest run of unmarked indices (the finer of equals)."""
    best, start = (0, 0), None
    for i, m in enumerate(marks + ["end"]):
        if m is None and start is None:
            start = i
        elif m is not None and start is not None:
            if i - start >= best[1] - best[0]:
                best = (start, i)
            start = None
    return best


def _trim_floor(runs, idx, marks):
    """Step 3's fine end: runs whose error rises as the step shrinks have
    reached the floor; so has every run within PLATEAU of the lowest error
    then. Marks what it drops from idx."""
    rose = False
    while len(idx) >= 2 and pair_slope(runs[idx[-2]], runs[idx[-1]]) <= 0:
        marks[idx.pop()] = "below floor"
        rose = True
    if rose:
        bottom = min(runs[i]["e"] for i in range(len(runs)) if marks[i] in (None, "below floor")
                     and runs[i]["ok"] and math.isfinite(runs[i]["e"]))
        while idx and runs[idx[-1]]["e"] < PLATEAU * bottom:
            marks[idx.pop()] = "below floor"
    return idx


def _settling(runs, idx, p):
    """True if the coarse end of a fixed-step range idx has not settled: its
    pair's slope moves toward p, by more than SETTLED, at the next pair."""
    if len(idx) < 3:
        return False
    s0, s1 = pair_slope(runs[idx[0]], runs[idx[1]]), pair_slope(runs[idx[1]], runs[idx[2]])
    return (s0 > p and s0 - s1 > SETTLED) or (s0 < p and s1 - s0 > SETTLED)


def _trim(runs, idx, marks, p, fixed):
    """Step 3 on the range idx (indices into runs), marking what it drops."""
    idx = _trim_floor(runs, idx, marks)
    while len(idx) >= 2:
        if not 0 < pair_slope(runs[idx[0]], runs[idx[1]]) <= p + STEEP:
            marks[idx.pop(0)] = "unstable" if fixed else "not accuracy-bound"
        elif fixed and _settling(runs, idx, p):
            marks[idx.pop(0)] = "pre-asymptotic"
        else:
            break
    return idx


def reason_text(marks):
    """'2 unstable, 1 below floor' of the marks (None: unmarked), in a fixed order."""
    counts = [(k, sum(m == k for m in marks)) for k in ("failed", "unstable", "not accuracy-bound", "too coarse",
                                                        "pre-asymptotic", "below floor", "not consecutive")]
    return ", ".join(f"{c} {k}" for k, c in counts if c)


def asymptotic_fit(runs, theory, fixed, unstable=UNSTABLE, ceiling=None):
    """The observed order over the asymptotic range of one ladder (the module
    docstring has the rule). runs: coarse to fine, dicts with ok (bool), e
    (error), n (resolution: 1/dt or RHS evaluations), floor (the error at or
    below which a run is below floor); theory: THEORY's entry; fixed: True for
    a fixed-step ladder. Returns {slope (nan unless fitted), used (indices of
    the runs fitted), marks (per run: None if used, else why not), finest_pair,
    finest_pair_mark (None, or why it is no order), raw_slope (every run that
    finished, for the record), reason ("" if fitted, else why not: 'too few
    points (1 in range; 3 unstable, 2 below floor)')}."""
    p = max_order(theory)
    marks = [_own_mark(r, unstable, ceiling) for r in runs]
    lo, hi = _longest_stretch(marks)
    for i in range(len(runs)):
        if marks[i] is None and not lo <= i < hi:
            marks[i] = "not consecutive"
    idx = _trim(runs, list(range(lo, hi)), marks, p, fixed)
    finished = [r for r in runs if r["ok"] and math.isfinite(r["e"]) and r["e"] > 0 and r["n"] > 0]
    out = {"marks": marks, "used": idx, "raw_slope": least_squares([r["n"] for r in finished],
                                                                    [r["e"] for r in finished]),
           "slope": math.nan, "finest_pair": math.nan, "finest_pair_mark": None, "reason": ""}
    if len(idx) < MIN_POINTS:
        out["reason"] = f"too few points ({len(idx)} in range" + (f"; {reason_text(marks)})" if any(marks) else ")")
        return out
    out["slope"] = least_squares([runs[i]["n"] for i in idx], [runs[i]["e"] for i in idx])
    out["finest_pair"] = pair_slope(runs[idx[-2]], runs[idx[-1]])
    if not 0 < out["finest_pair"] <= p + STEEP:
        out["finest_pair_mark"] = (f"steeper than order {p:g} allows" if out["finest_pair"] > 0
                                   else "error not falling")
    return out


def slope_cell(fit, digits=2):
    """A table's cell for a fit: the slope, or '– (reason; all runs: raw)'."""
    if math.isfinite(fit["slope"]):
        return f"{fit['slope']:.{digits}f}"
    raw = f"; all finished runs: {fit['raw_slope']:.{digits}f}, not an order" if math.isfinite(fit["raw_slope"]) else ""
    return f"– ({fit['reason']}{raw})"
