"""A sweep's report: the merged rows as <sweep>.csv with its comment lines
(the sweep, its ranking and targets, the flags' definitions, each variant's
reference against its cross-check), <sweep>_precision.md
(experiments/precision_table.py), <sweep>_modes.md (experiments/mode_table.py)
and <sweep>_summary.json for experiments/report.py, written with the plots as
one output set (io.write_output_set) under the sweep's merge lock."""
import os

import mode_table
import precision_table

from . import io as pumasim_io
from . import plots
from .measures import (BELOW_REFERENCE_FACTOR, MEASURES, WEAK_REFERENCE_FACTOR, cost_to_target,
                       disqualified_cheapest, measures_text, ranking)
from .specs import SweepError


def _table_comments(s, agreement, weak, limit, held_creep, pinning):
    """The CSV's comment lines: the sweep, its ranking and targets, the flags'
    and wall times' definitions, and per variant its reference vs cross-check."""
    rcol, runit, rlabel, rtarget = ranking(s)
    targets_text = ", ".join(f"{t:g} {next(m[1] for m in MEASURES.values() if m[0] == col)} ({col})"
                             for col, t in s["targets"].items())
    comments = [
        f"sweep {s['file']}: scene {s['scene']}, reference {' '.join([s['reference'][0]] + s['reference'][1])}, "
        f"cross-check {' '.join([s['check'][0]] + s['check'][1])}",
        f"ranked by {rlabel} [{runit}] ({rcol}, sweep.rank_by = \"{s['rank_by']}\"), target {rtarget:g} "
        f"{runit}; targets: {targets_text}",
        f"below_reference_accuracy: the run's {rcol} is within {BELOW_REFERENCE_FACTOR}x its variant's "
        f"reference-vs-check difference in that measure (empty: not judged, failed run); a reference is too "
        f"weak where that difference exceeds target/{WEAK_REFERENCE_FACTOR}",
        f"within_targets: the run finished and is within every target above (disqualified_by: the measures "
        f"whose target it misses, or failed; a measure its variant has no states for, its reference vs check "
        f"nan, is not judged); error_over_rtol (adaptive runs): max_state_error, the max over the "
        f"output rows and the states q, qd, i_motor, z_piv of |x - x_ref| / max(1, |x_ref|), over the run's rtol; "
        f"per method the slope of log(error) against log(rtol) is in {s['name']}_precision.md",
        f"wall times: median [s] of the repeats (all in wall_times_s), min, max, interquartile range "
        f"(nan below 4 repeats); {pinning['pinned_runs']} of {pinning['runs']} runs pinned to one CPU "
        f"({', '.join(pinning['methods']) or 'none'}; pinned_cpu, empty: not pinned)"]
    for v in s["variants"]:
        lab, a = v["label"], agreement[v["label"]]
        comments.append(f"{lab}: reference {' '.join([v['reference'][0]] + v['reference'][1])} vs cross-check "
                        f"{' '.join([v['check'][0]] + v['check'][1])}: {measures_text(a)}"
                        + "".join(f"; REFERENCE TOO WEAK for {col}: {w['difference']:.3g} > target/"
                                  f"{WEAK_REFERENCE_FACTOR} = {w['limit']:.3g}" for col, w in weak.get(lab, {}).items())
                        + (f"; its reference vs {s['limit_variant']}'s: "
                           f"{limit[lab]['max_tool_position_error_mm']:.3g} mm" if limit else "")
                        + (f"; creep where {s['stuck_variant']} holds a joint stuck: {held_creep[lab]['rad']:.3g} rad"
                           if held_creep else ""))
    return comments


def _mode_comments(s, modes):
    """The CSV's comment lines on the mode columns (none without them)."""
    if not modes:
        return [f"variants left out: {', '.join(s['skipped_variants'])}"] if s.get("skipped_variants") else []
    lines = [f"mode columns: each run's friction modes (events.csv) against {modes['variant']}'s reference "
             "(the hybrid model's runs against its own events; runs classified by speed -- the other laws, "
             "time-stepping -- against the reference classified the same way, events_speed.csv) "
             f"({modes['reference_events']} events), modes held under {modes['min_duration_s']:g} s dropped "
             "(experiments/mode_sequence.py): sequence match, first divergence (time, joint; divergence_marginal: "
             "at a decision the reference's cross-check does not share or within "
             f"{modes['torque_margin']:g} Fs of the static level), event-time error max and RMS over the matched "
             "events, sticks at speed reversals missed / in the reference",
             f"marginal decisions of {modes['variant']}'s reference: " +
             (", ".join(f"joint {m['joint']} at {m['t']:.6g} s ({m['why']})" for m in modes["marginal"]) or "none")]
    if s.get("skipped_variants"):
        lines.append(f"variants left out: {', '.join(s['skipped_variants'])}")
    return lines


def _summary(s, rows, agreement, weak, limit, held_creep, pinning, cost, has_cost_plot):
    """<sweep>_summary.json's content, for the report."""
    rcol, runit, rlabel, rtarget = ranking(s)
    return {"name": s["name"], "title": s["title"], "file": s["file"], "scene": s["scene"], "x": s["x"],
            "target_mm": s["target_mm"], "findings": s["findings"],
            "rank_by": {"measure": s["rank_by"], "column": rcol, "label": rlabel, "unit": runit,
                        "target": rtarget},
            "measures": {m: {"column": col, "unit": unit, "label": label, "target": s["targets"].get(col)}
                         for m, (col, unit, _, label) in MEASURES.items()},
            "below_reference_factor": BELOW_REFERENCE_FACTOR, "weak_reference_factor": WEAK_REFERENCE_FACTOR,
            "agreement": agreement, "reference_too_weak": weak,
            "limit_variant": s["limit_variant"], "distance_to_limit": limit,
            "stuck_variant": s["stuck_variant"], "creep": held_creep,
            "variants": [{"label": v["label"], "value": v["value"]} for v in s["variants"]],
            "runs": len(rows), "failed": sum(1 for r in rows if not r["ok"]),
            "below_reference_accuracy": sum(1 for r in rows if r["below_reference_accuracy"] is True),
            "pinning": pinning,
            "cost_to_target": cost, "has_cost_plot": has_cost_plot}


def _merge_lock(work):
    """The sweep's merge lock (work/.merge.lock) once taken, so that two
    merges of one sweep write one after the other; None if the work folder is
    not writable (a read-only copy of the runs): two merges at once then
    still leave no undetected mismatch, as the summary carries its files'
    hashes."""
    lock = pumasim_io.FileLock(os.path.join(work, ".merge.lock"))
    try:
        return lock if lock.acquire() else None
    except OSError:
        return None


def _write_csv(path, text):
    with open(path, "w", newline="") as f:
        f.write(text)


def plot_files(plt, s, rows, agreement, plottable):
    """{file name: writer} of a sweep's plots, each as .png and .pdf:
    <sweep> (work-precision) and, given plottable (None: not drawn),
    <sweep>_cost."""
    name = s["name"]
    colors = plots.integrator_colors(sorted({r["integrator"] for r in rows}))
    files = {}
    for fmt in ("png", "pdf"):
        files[f"{name}.{fmt}"] = lambda p, f=fmt: plots.plot_work_precision(plt, s, rows, agreement, colors, p, f)
        if plottable is not None:
            files[f"{name}_cost.{fmt}"] = lambda p, f=fmt: plots.plot_cost(plt, s, plottable, colors, p, f)
    return files


def _typed(row):
    """A row of a committed sweep table (strings) with what the plots read
    typed: numbers as floats, ok as a bool, below_reference_accuracy as
    True, False or None (not judged)."""
    out = dict(row)
    for k, v in row.items():
        if k in ("variant", "integrator", "setting", "failure", "disqualified_by", "wall_times_s"):
            continue
        try:
            out[k] = float(v)
        except (TypeError, ValueError):
            pass
    out["ok"] = row["ok"] == "True"
    out["below_reference_accuracy"] = {"True": True, "False": False}.get(row["below_reference_accuracy"])
    return out


def replot(s, work, out_dir):
    """Redraws a sweep's plots (.png and .pdf) from its committed table and
    summary in out_dir, runs nothing: for a change of the plot style. The set
    must be whole (check_outputs); the table, precision table and modes are
    kept byte for byte, the summary's hashes renewed. The table holds six
    significant digits, which no plot can show the difference of. Returns the
    summary; SweepError if the set is missing or not whole, or the sweep
    file's variants, ranking or title are no longer those merged. Under the
    sweep's merge lock (work: its runs' folder), as a merge."""
    name = s["name"]
    summary_path = os.path.join(out_dir, name + "_summary.json")
    try:
        summary = pumasim_io.read_json(summary_path)
        pumasim_io.check_outputs(out_dir, summary)
    except (OSError, ValueError, pumasim_io.OutputsMismatch) as e:
        raise SweepError(f"replot: {summary_path}: {e}")
    drawn = {k: summary.get(k) for k in ("title", "rank_by", "skipped_variants")}
    drawn["variants"] = [v["label"] for v in summary.get("variants", [])]
    wanted = {k: s.get(k) for k in ("title", "rank_by", "skipped_variants")}
    wanted["variants"] = [v["label"] for v in s["variants"]]
    if drawn != wanted:
        changed = ", ".join(k for k in wanted if wanted[k] != drawn[k])
        raise SweepError(f"replot: {summary_path}: the sweep file now differs from the one merged ({changed}); "
                         "re-run the sweep, or merge, instead of redrawing")
    rows = [_typed(r) for r in pumasim_io.read_table(os.path.join(out_dir, name + ".csv")).rows]
    kept = {}
    for n in summary["outputs"]:
        if not n.endswith((".png", ".pdf")):
            with open(os.path.join(out_dir, n), newline="") as f:
                kept[n] = f.read()
    files = {n: (lambda p, t=t: _write_csv(p, t)) for n, t in kept.items()}
    plottable = None
    if summary["has_cost_plot"]:
        plottable = {n: [p for p in pts if plots.usable(p["value"])] for n, pts in summary["cost_to_target"].items()}
    files.update(plot_files(plots.pyplot(), s, rows, summary["agreement"], plottable))
    lock = _merge_lock(work)
    try:
        pumasim_io.remove_dead_temporaries(out_dir, [*files, name + "_summary.json"])
        return pumasim_io.write_output_set(out_dir, files, name + "_summary.json",
                                           {k: v for k, v in summary.items() if k != "outputs"})
    except OSError as e:
        raise SweepError(f"replot: cannot write {e.filename}: {e.strerror}")
    finally:
        if lock:
            lock.release()


def write_outputs(s, work, out_dir, plt, rows, agreement, weak, limit, held_creep, pinning, modes=None):
    """Writes out_dir/<sweep>.csv, <sweep>.png, <sweep>_precision.md,
    <sweep>_cost.png (several variants only) and <sweep>_summary.json together
    (pumasim_io.write_output_set: temporaries first, then renamed into place,
    the summary last with the others' SHA-256, which the report checks), so
    that a merge killed at any instant never leaves a table beside a summary
    of another merge undetected; under the sweep's merge lock. Returns the
    summary; SweepError naming the file that cannot be written."""
    name = s["name"]
    comments = _table_comments(s, agreement, weak, limit, held_creep, pinning) + _mode_comments(s, modes)
    text = pumasim_io.table_text(rows, comments=comments, fmt=pumasim_io.fmt_6g)
    integrators = sorted({r["integrator"] for r in rows})
    cost = cost_to_target(s, rows, agreement, integrators)
    disqualified = disqualified_cheapest(s, rows, integrators)
    slopes = precision_table.tolerance_slopes(rows, agreement, BELOW_REFERENCE_FACTOR)
    precision = precision_table.markdown(s, rows, slopes, cost, disqualified, MEASURES, BELOW_REFERENCE_FACTOR)
    plottable = {n: [p for p in pts if plots.usable(p["value"])] for n, pts in cost.items()}
    has_cost_plot = len(s["variants"]) > 1 and any(len(p) > 1 for p in plottable.values())
    files = {name + ".csv": lambda p: _write_csv(p, text), name + "_precision.md": lambda p: _write_csv(p, precision)}
    files.update(plot_files(plt, s, rows, agreement, plottable if has_cost_plot else None))
    summary = _summary(s, rows, agreement, weak, limit, held_creep, pinning, cost, has_cost_plot)
    summary["disqualified_cheapest"] = disqualified
    summary["tolerance_slopes"] = [{k: m[k] for k in ("variant", "integrator", "options", "slope", "used", "mark")}
                                   for m in slopes]
    summary["skipped_variants"] = s.get("skipped_variants", [])
    if modes:
        summary["modes"] = {k: v for k, v in modes.items() if k not in ("events", "marks", "events_speed", "marks_speed")}
        summary["modes"]["cheapest_match"] = mode_table.cheapest_matches(rows)
        md = mode_table.markdown(s, rows, summary["modes"])
        files[name + "_modes.md"] = lambda p: _write_csv(p, md)
    lock = _merge_lock(work)
    try:
        os.makedirs(out_dir, exist_ok=True)
        pumasim_io.remove_dead_temporaries(out_dir, [*files, name + "_summary.json"])
        return pumasim_io.write_output_set(out_dir, files, name + "_summary.json", summary)
    except OSError as e:
        raise SweepError(f"merge: cannot write {e.filename}: {e.strerror}")
    finally:
        if lock:
            lock.release()
