"""A sweep's <sweep>_precision.md (experiments/sweep.py --merge writes it
beside <sweep>.csv): tolerance proportionality and the cheapest run within
every target (issue 31).

Tolerance proportionality: each adaptive run's error_over_rtol, its global
error relative to the state's scale (max_state_error: the max over the output
rows and the states q, qd, i_motor, z_piv of |x - x_ref| / max(1, |x_ref|),
the error experiments/observed_order.py fits) divided by its rtol; per method
(variant, integrator and its extra options) the least-squares slope of
log(error) against log(rtol) over its finished runs above the reference's
accuracy in that measure (error more than below_factor times the
reference-vs-check difference): 1 for an error proportional to the
tolerance. Fewer than MIN_RUNS runs: the slope is marked.

Cheapest within every target: a run qualifies only if it finished and is
within every target the sweep sets (sweep.disqualified_by); where the
cheapest run within the ranking measure's target misses another, the table
names the measure, the run's error in it and the target.
"""
import math
import re

import order_fit

MIN_RUNS = 3  # runs a tolerance slope needs to be unmarked
SETTING_RE = re.compile(r"^rtol=([^_\s]+)(.*)$")


def tolerance_slopes(rows, agreement, below_factor):
    """Per adaptive method (variant, integrator, options: what follows the
    rtol in the setting) in the order of the rows: its runs [(rtol, error,
    error_over_rtol, used in the slope)], the slope of log(error) against
    log(rtol) over the used ones (nan below 2), their number, and the mark
    ("" or why the slope is not to be trusted)."""
    methods = {}
    for r in rows:
        m = SETTING_RE.match(r["setting"])
        if not m or r["error_over_rtol"] == "":
            continue
        key = (r["variant"], r["integrator"], m.group(2).lstrip("_"))
        floor = below_factor * agreement[r["variant"]].get("max_state_error", math.nan)
        e = r["max_state_error"]
        used = bool(r["ok"]) and math.isfinite(e) and e > 0 and not e <= floor
        methods.setdefault(key, []).append((float(m.group(1)), e, r["error_over_rtol"], used))
    out = []
    for (variant, integrator, options), runs in methods.items():
        runs.sort(key=lambda x: -x[0])
        use = [x for x in runs if x[3]]
        slope = order_fit.least_squares([1.0 / x[0] for x in use], [x[1] for x in use])
        mark = "" if len(use) >= MIN_RUNS else f"fewer than {MIN_RUNS} runs"
        out.append({"variant": variant, "integrator": integrator, "options": options, "runs": runs,
                    "slope": slope, "used": len(use), "mark": mark})
    return out


def _ratio_cell(runs):
    """'1e-03: 2.7, 1e-04: 22*, …' (*: not in the slope; –: failed)."""
    cells = []
    for rtol, _, ratio, used in runs:
        v = "–" if not (isinstance(ratio, float) and math.isfinite(ratio)) else f"{ratio:.3g}"
        cells.append(f"{rtol:.0e}: {v}" + ("" if used else "*"))
    return ", ".join(cells)


def proportionality_section(slopes, below_factor):
    """The file's lines on error against tolerance."""
    L = ["## Error against tolerance", "",
         "Each adaptive run's global error relative to the state's scale (`max_state_error`: the max over the "
         "output rows and the states q, qd, i_motor, z_piv of |x − x_ref| / max(1, |x_ref|)) divided by its rtol "
         "(`error_over_rtol` in the CSV; atol = atol_factor × rtol); per method the least-squares slope of "
         "log(error) against log(rtol) over its finished runs above the reference's accuracy (error more than "
         f"{below_factor}× the reference-vs-check difference in that measure; the others marked *): 1 for an "
         f"error proportional to the tolerance. A slope over fewer than {MIN_RUNS} runs is marked †.", ""]
    if not slopes:
        return L + ["No adaptive runs.", ""]
    L += ["| variant | integrator | options | error ÷ rtol at each rtol | slope (runs) |", "|---|---|---|---|---:|"]
    for m in slopes:
        s = "–" if math.isnan(m["slope"]) else f"{m['slope']:.2f}"
        L.append(f"| {m['variant']} | {m['integrator']} | {m['options'] or '–'} | {_ratio_cell(m['runs'])} | "
                 f"{s} ({m['used']}){' †' if m['mark'] else ''} |")
    return L + [""]


def _missed_text(d, measures):
    """'dt=0.0005 (80,971 RHS) misses max motor-current error 48.3 A > 1 A'."""
    what = "; ".join(f"{measures[x['measure']][3]} {x['error']:.3g} {measures[x['measure']][1]} > "
                     f"{x['target']:g} {measures[x['measure']][1]}" for x in d["measures"])
    return f"{d['setting']} ({d['rhs']:,} RHS) misses {what}"


def targets_section(s, rows, cost, disqualified, measures):
    """The file's lines on the cheapest run within every target (measures:
    sweep.MEASURES; cost, disqualified: sweep's _cost_to_target and
    disqualified_cheapest)."""
    targets = ", ".join(f"{spec[3]} {s['targets'][spec[0]]:g} {spec[1]}" for spec in measures.values()
                        if spec[0] in s["targets"])
    rlabel = measures[s["rank_by"]][3]
    variants = [v["label"] for v in s["variants"]]
    L = ["## Cheapest run within every target", "",
         f"Targets: {targets}. A run qualifies only if it finished and is within every one of them. Per "
         "integrator and variant: the cheapest qualifying run's RHS evaluations (setting), `–` if none qualifies, "
         f"`fail` if every run failed; and where the cheapest run within the {rlabel} target (the ranking "
         "measure) misses another target: that run, the measure, its error and the target.", "",
         "| integrator | " + " | ".join(variants) + " |", "|---|" + "---|" * len(variants)]
    for n in sorted({r["integrator"] for r in rows}):
        cells = []
        for v in variants:
            best = next((c for c in cost.get(n, []) if c["variant"] == v), None)
            mine = [r for r in rows if r["integrator"] == n and r["variant"] == v]
            cell = (f"{best['rhs']:,} ({best['setting']})" if best else
                    "fail" if mine and not any(r["ok"] for r in mine) else "–")
            d = next((d for d in disqualified if d["integrator"] == n and d["variant"] == v), None)
            cells.append(cell + (f"; {_missed_text(d, measures)}" if d else ""))
        L.append(f"| {n} | " + " | ".join(cells) + " |")
    return L + [""]


def markdown(s, rows, slopes, cost, disqualified, measures, below_factor):
    """<sweep>_precision.md's text."""
    L = [f"# {s['title']}: error against tolerance, cheapest run within every target", "",
         f"Generated by `experiments/sweep.py {s['file']} --merge` with `{s['name']}.csv` beside it, whose rows "
         "hold every number below (experiments/precision_table.py); do not edit.", ""]
    L += proportionality_section(slopes, below_factor)
    L += targets_section(s, rows, cost, disqualified, measures)
    return "\n".join(L)
