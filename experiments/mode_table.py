"""The friction treatments' work-precision table with their mode sequences:
<sweep>_modes.md, written by sweep.py's merge (experiments/sweep.py) from
its rows (each with mode_sequence.columns) and its summary's "modes" entry;
report.py puts its first table into results/README.md.
"""
import math

import mode_sequence

# A run has the right modes when its sequence is the reference's and every
# matched event lies within this of the reference's [s]: the resolution of the
# sequences themselves (modes shorter than this are dropped).
ON_TIME = mode_sequence.MIN_DURATION


def _ms(x):
    return "–" if not isinstance(x, (int, float)) or not math.isfinite(x) else f"{1e3 * x:.3g}"


def _g(x, fmt=".3g"):
    return "–" if not isinstance(x, (int, float)) or not math.isfinite(x) else format(x, fmt)


def cheapest_matches(rows):
    """Per variant and integrator: its runs, those that finished, those whose
    mode sequence matches the reference's, and the cheapest of these (fewest
    RHS evaluations) among those with every matched event within ON_TIME:
    setting, RHS, median wall time, event-time errors, tool error; without
    one, the run that kept the reference's sequence longest (latest first
    divergence, or the right sequence with the smallest time error) and its
    missed reversal sticks."""
    out = []
    for key in sorted({(r["variant"], r["integrator"]) for r in rows}):
        mine = [r for r in rows if (r["variant"], r["integrator"]) == key]
        ok = [r for r in mine if r["ok"]]
        seq = [r for r in ok if r.get("mode_sequence_match") == "yes"]
        right = [r for r in seq if r["max_event_time_error_s"] <= ON_TIME]
        e = {"variant": key[0], "integrator": key[1], "runs": len(mine), "ok": len(ok), "match": len(seq),
             "on_time": len(right)}
        if right:
            b = min(right, key=lambda r: r["rhs_evaluations"])
            e["cheapest"] = {k: b[k] for k in ("setting", "rhs_evaluations", "wall_time_median_s",
                                                 "max_event_time_error_s", "rms_event_time_error_s",
                                                 "max_tool_position_error_mm")}
        elif ok:
            b = max(ok, key=lambda r: (r["first_divergence_s"] if math.isfinite(r["first_divergence_s"]) else math.inf,
                                       -r["max_event_time_error_s"] if math.isfinite(r["max_event_time_error_s"])
                                       else -math.inf))
            e["longest"] = {k: b[k] for k in ("setting", "first_divergence_s", "first_divergence_joint",
                                                "divergence_marginal", "missed_reversal_sticks",
                                                "max_event_time_error_s")}
        out.append(e)
    return out


def summary_table(modes):
    """The condensed table (markdown lines) from the summary's modes entry."""
    lines = [f"| treatment | integrator | runs (finished) | right mode sequence (and every event within "
             f"{1e3 * ON_TIME:g} ms) | cheapest such run: setting, RHS, wall [s] | its event-time error max / RMS "
             "[ms] | its tool error [mm] | else the best: first divergence [s] (joint, marginal) or max "
             "event-time error [ms], missed reversal sticks |",
             "|---|---|---|---|---|---|---|---|"]
    for e in modes["cheapest_match"]:
        c, lo = e.get("cheapest"), e.get("longest")
        if c:
            tail = (f"{c['setting']}, {c['rhs_evaluations']}, {_g(c['wall_time_median_s'])} | "
                    f"{_ms(c['max_event_time_error_s'])} / {_ms(c['rms_event_time_error_s'])} | "
                    f"{_g(c['max_tool_position_error_mm'])} | – |")
        elif lo and not math.isfinite(lo["first_divergence_s"]):
            tail = (f"– | – | – | {lo['setting']}: sequence right, {_ms(lo['max_event_time_error_s'])} ms, "
                    f"{lo['missed_reversal_sticks']} |")
        elif lo:
            tail = (f"– | – | – | {lo['setting']}: {_g(lo['first_divergence_s'], '.4g')} "
                    f"({lo['first_divergence_joint']}, {lo['divergence_marginal'] or '–'}), "
                    f"{lo['missed_reversal_sticks']} |")
        else:
            tail = "– | – | – | no run finished |"
        lines.append(f"| {e['variant']} | {e['integrator']} | {e['runs']} ({e['ok']}) | {e['match']} "
                     f"({e['on_time']}) | " + tail)
    return lines


def treatments_table(modes):
    """Each treatment's own reference (its finest run) against the yardstick's reference."""
    lines = ["| treatment (its reference run) | mode sequence as the exact model's | first divergence [s] "
             "(joint) | matched events / reference's | event-time error max / RMS [ms] | missed reversal "
             "sticks |", "|---|---|---|---|---|---|"]
    for lab, c in modes["treatments"].items():
        lines.append(f"| {lab} | {'yes' if c['match'] else 'no'} | "
                     f"{_g(c['first_divergence_s'], '.4g')} ({c['first_divergence_joint'] or '–'}) | "
                     f"{c['matched_events']} / {c['reference_events']} | {_ms(c['max_event_time_error_s'])} / "
                     f"{_ms(c['rms_event_time_error_s'])} | {c['missed_reversal_sticks']} / "
                     f"{c['reversal_sticks']} |")
    return lines


def _run_lines(rows):
    lines = ["| treatment | integrator | setting | finished | RHS | wall [s] | tool error [mm] | mode sequence "
             "right | first divergence [s] (joint, marginal) | event-time error max / RMS [ms] | missed "
             "reversal sticks |", "|---|---|---|---|---|---|---|---|---|---|---|"]
    for r in rows:
        div = ("–" if not math.isfinite(r.get("first_divergence_s", math.nan)) else
               f"{r['first_divergence_s']:.4g} ({r['first_divergence_joint']}, {r['divergence_marginal']})")
        lines.append(f"| {r['variant']} | {r['integrator']} | {r['setting']} | {'yes' if r['ok'] else 'no'} | "
                     f"{r['rhs_evaluations']} | {_g(r['wall_time_median_s'])} | "
                     f"{_g(r['max_tool_position_error_mm'])} | {r.get('mode_sequence_match') or '–'} | {div} | "
                     f"{_ms(r.get('max_event_time_error_s'))} / {_ms(r.get('rms_event_time_error_s'))} | "
                     f"{r.get('missed_reversal_sticks') or '–'} |")
    return lines


def markdown(s, rows, modes):
    """<sweep>_modes.md: the condensed table, the treatments' references, every run."""
    marg = ", ".join(f"joint {m['joint']} at {m['t']:.6g} s ({m['why']})" for m in modes["marginal"]) or "none"
    marg_speed = ", ".join(f"joint {m['joint']} at {m['t']:.6g} s ({m['why']})"
                           for m in modes.get("marginal_speed", [])) or "none"
    text = [f"# {s['title']}: friction modes", "",
            f"Generated by `experiments/sweep.py {s['file']}` (merge). Every run's stick/slip sequence "
            f"(events.csv) against the exact model's ({modes['variant']}) reference run, "
            f"{modes['reference_events']} events; modes held under {modes['min_duration_s']:g} s dropped on both "
            "sides (experiments/mode_sequence.py). Marginal decisions of that reference (its cross-check "
            f"disagrees, or within {modes['torque_margin']:g} Fs of the static level): {marg}. The hybrid "
            "model's runs are compared with its events; the runs classified by speed (the other laws, and "
            "time-stepping, which solves the friction itself) with the same reference classified the same way "
            f"(events_speed.csv: stuck at |w_m| <= 1e-3 rad/s, {modes.get('reference_events_speed', 0)} events; "
            f"its marginal decisions: {marg_speed}), so that a joint the exact model keeps creeping below the "
            "threshold reads alike on both sides.", "",
            "## Cost of the right mode sequence", ""] + summary_table(modes) + [
            "", "## Each treatment's own reference against the exact model's", ""] + treatments_table(modes) + [
            "", "## Every run", ""] + _run_lines(rows)
    if s.get("skipped_variants"):
        text += ["", f"Left out: {', '.join(s['skipped_variants'])}."]
    return "\n".join(text) + "\n"
