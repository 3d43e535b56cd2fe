"""The error measures of a sweep's runs: a run against its variant's
reference (and the reference against its cross-check) at the output times,
whether a reference is too weak for a target, whether a run is below the
reference's accuracy or within every target, the cheapest run within them,
and a stuck joint's creep. Pure functions of trajectories ({column: list of
floats}) and table rows; no files, no pumasim."""
import math
import re
import statistics

import numpy as np

# The error measures of a run against its variant's reference (and of the
# reference against its cross-check): name (for `rank_by`), CSV column, unit,
# the sweep key of its accuracy target, and a label for tables and plots.
MEASURES = {
    "tool_position": ("max_tool_position_error_mm", "mm", "target_mm", "max tool position error"),
    "tool_orientation": ("max_tool_orientation_error_rad", "rad", "target_orientation_rad",
                         "max tool orientation error"),
    "joint": ("max_joint_error_rad", "rad", "target_joint_rad", "max joint-angle error"),
    "current": ("max_current_error_A", "A", "target_current_A", "max motor-current error"),
}
DEFAULT_RANK = "tool_position"
BELOW_REFERENCE_FACTOR = 10  # a run's ranking error within this factor of reference vs check: flagged
WEAK_REFERENCE_FACTOR = 100  # reference vs check must be this far below the target, or the reference is too weak
QUATERNION = ("tool_qw", "tool_qx", "tool_qy", "tool_qz")
STUCK_MARGIN = 2  # output samples trimmed from each end of a stuck interval


def rotation_angle(q1, q2):
    """Angle [rad] of the rotation between two unit quaternions (w, x, y, z):
    2 atan2(|vec(q1* q2)|, |scalar(q1* q2)|), in [0, pi], the same for q and -q
    and accurate near 0 (unlike 2 acos)."""
    w1, x1, y1, z1 = q1
    w2, x2, y2, z2 = q2
    # q1* q2 with q1* = (w1, -x1, -y1, -z1)
    w = w1 * w2 + x1 * x2 + y1 * y2 + z1 * z2
    x = w1 * x2 - x1 * w2 - y1 * z2 + z1 * y2
    y = w1 * y2 - y1 * w2 - z1 * x2 + x1 * z2
    z = w1 * z2 - z1 * w2 - x1 * y2 + y1 * x2
    return 2.0 * math.atan2(math.sqrt(x * x + y * y + z * z), abs(w))


def _max(values):
    """Largest value; nan if there is none or one is nan (an error that is
    not finite must not hide behind a smaller one)."""
    values = list(values)
    if not values or any(math.isnan(v) for v in values):
        return math.nan
    return max(values)


def compare(ref, run):
    """The error measures of `run` against `ref` on their common output times
    (the first min(len) rows of both; the runs share the scene's output grid):
    max and RMS tool (flange) position distance [mm] (columns x, y, z); max
    tool orientation angle [rad] (tool_qw..tool_qz; nan if absent); max
    joint-angle difference over every q column [rad]; max motor-current
    difference over every i_motor column [A] (nan without current states); and
    the final-state error max_i |dx_i| / max(1, |x_i|) over q, qd, i_motor,
    z_piv (nan unless both reached the same final time); the same over every
    common output row (max_state_error, the global error relative to the
    state's scale, which error_over_rtol divides by the tolerance). Keys: the
    CSV columns."""
    n = min(len(ref["t"]), len(run["t"]))
    d = [1e3 * math.dist((ref["x"][k], ref["y"][k], ref["z"][k]), (run["x"][k], run["y"][k], run["z"][k]))
         for k in range(n)]
    if all(c in ref and c in run for c in QUATERNION):
        rot = _max(rotation_angle([ref[c][k] for c in QUATERNION], [run[c][k] for c in QUATERNION])
                   for k in range(n))
    else:
        rot = math.nan
    joints = [h for h in ref if re.fullmatch(r"q\d+", h)]
    currents = [h for h in ref if re.fullmatch(r"i_motor\d+", h)]
    dq = _max(abs(ref[h][k] - run[h][k]) for h in joints for k in range(n))
    di = _max(abs(ref[h][k] - run[h][k]) for h in currents for k in range(n))
    states = [h for h in ref if re.fullmatch(r"(q|qd|i_motor|z_piv|z_fric)\d+", h) and h in run]
    final = math.nan
    if len(ref["t"]) == len(run["t"]) and abs(ref["t"][-1] - run["t"][-1]) < 1e-9:
        final = _max(abs(ref[h][-1] - run[h][-1]) / max(1.0, abs(ref[h][-1])) for h in states)
    return {"max_tool_position_error_mm": _max(d),
            "rms_tool_position_error_mm": math.sqrt(sum(e * e for e in d) / n) if n else math.nan,
            "max_tool_orientation_error_rad": rot, "max_joint_error_rad": dq, "max_current_error_A": di,
            "final_state_error": final, "max_state_error": _max_state_error(ref, run, states, n)}


def _max_state_error(ref, run, states, n):
    """The global error relative to the state's scale: max over the first n
    output rows and the states of |x - x_ref| / max(1, |x_ref|) (nan without
    rows or states; experiments/observed_order.py's error of a run)."""
    if not (n and states):
        return math.nan
    worst = []
    for h in states:
        x, x_ref = np.asarray(run[h][:n], dtype=float), np.asarray(ref[h][:n], dtype=float)
        worst.append(float(np.max(np.abs(x - x_ref) / np.maximum(1.0, np.abs(x_ref)))))
    return _max(worst)


def wall_spread(walls):
    """Median, min, max of the repeats' wall times [s] and the interquartile
    range (quartiles by linear interpolation, statistics 'inclusive'; nan for
    fewer than 4 repeats)."""
    iqr = math.nan
    if len(walls) >= 4:
        q1, _, q3 = statistics.quantiles(walls, n=4, method="inclusive")
        iqr = q3 - q1
    return {"wall_time_median_s": statistics.median(walls), "wall_time_min_s": min(walls),
            "wall_time_max_s": max(walls), "wall_time_iqr_s": iqr}


def reference_too_weak(agreement, targets):
    """Measures (CSV columns) for which the reference and its cross-check
    differ by more than target / WEAK_REFERENCE_FACTOR: the reference cannot
    resolve errors near the target there. A measure without a target, or
    whose difference is nan (no such states), is not judged."""
    return [col for col, target in targets.items()
            if math.isfinite(agreement.get(col, math.nan)) and agreement[col] > target / WEAK_REFERENCE_FACTOR]


def below_reference_accuracy(error, agreement):
    """True if a run's ranking error is within BELOW_REFERENCE_FACTOR of the
    reference-vs-check difference in the same measure (the reference cannot
    tell it from zero); None if either is not finite (failed run, no such
    states)."""
    if not (math.isfinite(error) and math.isfinite(agreement)):
        return None
    return error <= BELOW_REFERENCE_FACTOR * agreement


def stuck_intervals(run):
    """Per joint, the output-sample index ranges [a, b] over which the joint
    speed is exactly zero at every sample (the hybrid model holds a stuck
    joint at exactly zero speed), trimmed by STUCK_MARGIN samples at each end
    so that a model breaking away a little earlier or later is not counted."""
    out = {}
    n = len(run["t"])
    for h in run:
        if not re.fullmatch(r"qd\d+", h):
            continue
        qd, k, ivs = run[h], 0, []
        while k < n - 1:
            if qd[k] == 0.0 and qd[k + 1] == 0.0:
                a = k
                while k < n - 1 and qd[k + 1] == 0.0:
                    k += 1
                if k - STUCK_MARGIN > a + STUCK_MARGIN:
                    ivs.append((a + STUCK_MARGIN, k - STUCK_MARGIN))
            k += 1
        out["q" + h[2:]] = ivs
    return out


def creep(run, held):
    """Largest motion (max - min of the angle) of a joint of `run` over an
    interval in which the exact model holds that joint stuck: {rad, joint,
    from_s, to_s}, and the stuck time examined."""
    worst = {"rad": 0.0, "joint": None, "from_s": math.nan, "to_s": math.nan}
    total = 0.0
    for q, ivs in held.items():
        for a, b in ivs:
            seg = run[q][a:b + 1]
            total += run["t"][b] - run["t"][a]
            if max(seg) - min(seg) >= worst["rad"]:
                worst = {"rad": max(seg) - min(seg), "joint": q, "from_s": run["t"][a], "to_s": run["t"][b]}
    worst["stuck_time_s"] = total
    return worst


def measures_text(a):
    """'tool position 0.00226 mm, tool orientation 1e-07 rad, ...' of an agreement entry."""
    return ", ".join(f"{label[len('max '):-len(' error')]} {a[col]:.3g} {unit}"
                     for col, unit, _, label in MEASURES.values()) + f", final state {a['final_state_error']:.3g}"


def ranking(s):
    """(CSV column, unit, label, target) of the sweep's ranking measure (sweep.rank_by)."""
    rcol, runit, _, rlabel = MEASURES[s["rank_by"]]
    return rcol, runit, rlabel, s["targets"][rcol]


def rtol_of(opts):
    """A run's rtol, from its pumasim options; None for a fixed step."""
    return float(opts[opts.index("--rtol") + 1]) if "--rtol" in opts else None


def disqualified_by(row, targets):
    """The error measures (MEASURES' names, in its order) whose target
    (targets: {CSV column: target}) a finished run misses, its error above the
    target or not finite; ["failed"] for a run that did not finish. A run
    qualifies ("within target") only with none: within every target the
    sweep sets, not the ranking measure's alone."""
    if not row["ok"]:
        return ["failed"]
    return [m for m, (col, *_) in MEASURES.items()
            if col in targets and not (math.isfinite(row[col]) and row[col] <= targets[col])]


def variant_targets(targets, agreement, rcol):
    """The targets a variant's runs are judged on (disqualified_by): every
    target the sweep sets but those in a measure the variant has no states
    for, its reference-vs-check difference nan (agreement: its entry; the
    motor currents of a variant with La = 0), which, as in
    reference_too_weak, is not judged; the ranking measure's always."""
    return {col: t for col, t in targets.items() if col == rcol or math.isfinite(agreement.get(col, math.nan))}


def _cheapest(rows):
    """The row with the fewest RHS evaluations (None for no rows)."""
    return min(rows, key=lambda r: r["rhs_evaluations"]) if rows else None


def cost_to_target(s, rows, agreement, integrators):
    """{integrator: per variant, its cheapest run (fewest RHS evaluations)
    within every target the sweep sets (within_targets: the ranking measure's
    and every other one's)} (variants without one left out; a cheaper run
    that misses another target is in disqualified_cheapest)."""
    rcol = ranking(s)[0]
    cost = {}
    for n in integrators:
        for v in s["variants"]:
            best = _cheapest([r for r in rows if r["variant"] == v["label"] and r["integrator"] == n
                              and r["within_targets"]])
            if best:
                cost.setdefault(n, []).append({
                    "value": v["value"], "variant": v["label"], "rhs": best["rhs_evaluations"],
                    "setting": best["setting"], "wall_s": best["wall_time_median_s"],
                    "wall_min_s": best["wall_time_min_s"], "wall_max_s": best["wall_time_max_s"],
                    "error": best[rcol], "below_reference_accuracy": best["below_reference_accuracy"],
                    "reference_too_weak": s["rank_by"] in agreement[v["label"]]["reference_too_weak"]})
    return cost


def disqualified_cheapest(s, rows, integrators):
    """Per (integrator, variant) whose cheapest run within the ranking
    measure's target misses another target the sweep sets: that run's
    setting and RHS evaluations and the measures it misses, with its error
    and the target in each (a list: the summary's and the precision table's)."""
    rcol, _, _, rtarget = ranking(s)
    out = []
    for n in integrators:
        for v in s["variants"]:
            r = _cheapest([r for r in rows if r["variant"] == v["label"] and r["integrator"] == n and
                           r["ok"] and math.isfinite(r[rcol]) and r[rcol] <= rtarget])
            if r is not None and not r["within_targets"]:
                out.append({"integrator": n, "variant": v["label"], "setting": r["setting"],
                            "rhs": r["rhs_evaluations"],
                            "measures": [{"measure": m, "error": r[MEASURES[m][0]],
                                          "target": s["targets"][MEASURES[m][0]]}
                                         for m in r["disqualified_by"].split()]})
    return out
