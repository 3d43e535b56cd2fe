"""The merge step of a sweep: every run compared with its variant's
reference, and each reference with its cross-check, in every error measure
(measures), into the table's rows, with the friction modes' yardstick, the
distance of each variant's reference to sweep.limit_variant's and its creep
where sweep.stuck_variant's reference holds a joint stuck; report writes them
out. Trajectories are read from the run folders (io), never from text
pumasim printed."""
import math
import os
import re

import mode_sequence

from . import io as pumasim_io
from . import plots, report
from .measures import (MEASURES, WEAK_REFERENCE_FACTOR, below_reference_accuracy, compare, creep, disqualified_by,
                       reference_too_weak, rtol_of, stuck_intervals, variant_targets, wall_spread)
from .runner import complete_summaries
from .specs import SweepError, run_list, slug


def trajectory(run_dir):
    """{column name without its unit: list of floats} of a run folder's trajectory.csv."""
    try:
        return pumasim_io.read_trajectory(run_dir).lists()
    except pumasim_io.RunFolderError as e:
        raise SweepError(f"merge: {e}")


def _reference_vs_check(work, v, summaries):
    """(the variant's reference trajectory, compare() of its cross-check
    against it); SweepError if either of the two runs failed."""
    vdir = slug(v["label"])
    ref_sum, chk_sum = summaries[f"{vdir}/reference"], summaries[f"{vdir}/check"]
    for which, sm in (("reference", ref_sum), ("check", chk_sum)):
        if not sm["stats"]["ok"]:
            raise SweepError(f"variant {v['label']}: the {which} run failed: {sm['stats']['failure']}")
    ref = trajectory(os.path.join(work, vdir, "reference"))
    return ref, compare(ref, trajectory(os.path.join(work, vdir, "check")))


def _agreement_entry(s, c, ref_stats):
    """A variant's agreement entry from compare()'s result c of its reference
    and cross-check (every measure, the final state, the measures in which the
    reference is too weak, the reference's steps and tracking error), and the
    CSV columns in which it is too weak."""
    a = {col: c[col] for col, *_ in MEASURES.values()}
    a["final_state_error"] = c["final_state_error"]
    a["max_state_error"] = c["max_state_error"]
    too_weak = reference_too_weak(a, s["targets"])
    a["reference_too_weak"] = [m for m, spec in MEASURES.items() if spec[0] in too_weak]
    a["reference_steps"] = ref_stats["steps"]
    a["tracking_mm"] = ref_stats["max_path_error_mm"]
    return a, too_weak


def _run_row(work, run, sm, ref, columns, rcol, agreement_rank, targets):
    """One run's CSV row: its error measures against its variant's reference
    trajectory ref (nan in every one of `columns` if it failed), its global
    error over its rtol (adaptive runs), whether it is below the reference's
    accuracy (agreement_rank: reference vs check in the ranking measure
    rcol), whether it is within every target (and which it misses),
    wall-time spread, pinning, counters. The key '_pinning' (the pinning
    method) is for the summary, not the table."""
    st = sm["stats"]
    if st["ok"]:
        e = compare(ref, trajectory(os.path.join(work, run[0])))
    else:
        e = dict.fromkeys(columns, math.nan)
    flag = below_reference_accuracy(e[rcol], agreement_rank)
    rtol = rtol_of(run[4])
    missed = disqualified_by({"ok": st["ok"], **e}, targets)
    row = {
        "variant": run[1]["label"], "value": run[1]["value"], "integrator": sm["integrator"],
        "setting": re.sub(r"^(dt|rtol)", r"\1=", run[2][len(sm["integrator"]) + 1:]),
        "ok": st["ok"], "failure": st["failure"],
        **e,
        "error_over_rtol": "" if rtol is None else e["max_state_error"] / rtol,
        "below_reference_accuracy": "" if flag is None else flag,
        "within_targets": not missed, "disqualified_by": " ".join(missed),
        "max_path_error_mm": st["max_path_error_mm"] if st["ok"] else math.nan,
        **wall_spread(sm["wall_times_s"]),
        "wall_times_s": " ".join(f"{w:.6g}" for w in sm["wall_times_s"]),
        "repeats": len(sm["wall_times_s"]),
        "pinned_cpu": "" if sm.get("pinned_cpu") is None else sm["pinned_cpu"],
        "rhs_evaluations": st["rhs_evaluations"], "jacobian_evaluations": st["jacobian_evaluations"],
        "steps": st["steps"], "rejected_steps": st["rejected_steps"], "restarts": st["restarts"],
        "time_events": st["time_events"], "root_events": st["root_events"],
    }
    row["_pinning"] = sm.get("pinning")
    if "max_ledger_residual_J" in st:  # scenes with the energy ledger
        row["max_ledger_residual_J"] = st["max_ledger_residual_J"]
        row["ledger_energy_scale_J"] = st["ledger_energy_scale_J"]
    return row


def _variant_rows(s, work, v, summaries, ref, c, a, modes):
    """The CSV rows of a variant's runs (not its reference and cross-check),
    sorted by run id; ref, c, a: the variant's reference trajectory, compare()
    of its cross-check and its agreement entry; modes: _mode_reference()'s,
    whose mode columns each row gets (mode_sequence.columns) when it has one."""
    rcol = MEASURES[s["rank_by"]][0]
    rows = []
    for run in run_list(s):
        if run[1] is not v or run[2] in ("reference", "check"):
            continue
        rows.append(_run_row(work, run, summaries[run[0]], ref, c, rcol, a[rcol],
                             variant_targets(s["targets"], a, rcol)))
        if modes:
            events = mode_sequence.read_events(os.path.join(work, run[0])) if rows[-1]["ok"] else None
            # The hybrid model's own events against the reference's own; a
            # run classified by speed (the other laws, time-stepping) against
            # the reference classified the same way.
            own = summaries[run[0]].get("mode_log", "").startswith("hybrid")
            key = "" if own or not modes["events_speed"] else "_speed"
            rows[-1].update(mode_sequence.columns(modes["events" + key], modes["marks" + key], events))
    return rows


def _mode_reference(s, work):
    """The friction modes' yardstick: sweep.stuck_variant's reference events,
    its marginal decisions (mode_sequence.marginal against its cross-check),
    and each variant's own reference compared with it (the treatment itself,
    as finely integrated as the sweep has it); None without a stuck variant
    or without events."""
    if not s["stuck_variant"]:
        return None
    vdir = slug(s["stuck_variant"])
    try:
        ref = mode_sequence.read_events(os.path.join(work, vdir, "reference"))
        if ref is None:
            return None
        marks = mode_sequence.marginal(ref, mode_sequence.read_events(os.path.join(work, vdir, "check")) or [])
        speed = mode_sequence.read_events(os.path.join(work, vdir, "reference"), mode_sequence.EVENTS_SPEED)
        marks_speed = mode_sequence.marginal(speed, mode_sequence.read_events(
            os.path.join(work, vdir, "check"), mode_sequence.EVENTS_SPEED) or []) if speed else {}
        treatments = {}
        for v in s["variants"]:
            vref = mode_sequence.read_events(os.path.join(work, slug(v["label"]), "reference")) or []
            yardstick = ref if v["label"] == s["stuck_variant"] or not speed else speed
            treatments[v["label"]] = mode_sequence.compare(yardstick, vref)
    except mode_sequence.EventsError as e:
        raise SweepError(f"merge: {e}")
    return {"variant": s["stuck_variant"], "events": ref, "marks": marks, "treatments": treatments,
            "events_speed": speed, "marks_speed": marks_speed,
            "marginal_speed": [{"joint": j, "t": t, "why": w} for (j, t), w in sorted(marks_speed.items())],
            "reference_events_speed": len(speed or []),
            "min_duration_s": mode_sequence.MIN_DURATION, "torque_margin": mode_sequence.TORQUE_MARGIN,
            "marginal": [{"joint": j, "t": t, "why": w} for (j, t), w in sorted(marks.items())],
            "reference_events": len(ref)}


def _pinning(rows):
    """How many runs were pinned to a CPU, how, and to which CPUs; removes the
    rows' '_pinning' keys."""
    pinned = [r for r in rows if r["pinned_cpu"] != ""]
    pinning = {"pinned_runs": len(pinned), "runs": len(rows),
               "methods": sorted({r["_pinning"] for r in pinned if r["_pinning"]}),
               "cpus": sorted({r["pinned_cpu"] for r in pinned})}
    for r in rows:
        del r["_pinning"]
    return pinning


def _distance_to_limit(s, work):
    """{variant: its reference against sweep.limit_variant's, every measure}
    ({} without a limit variant)."""
    limit = {}
    if s["limit_variant"]:
        lim = trajectory(os.path.join(work, slug(s["limit_variant"]), "reference"))
        for v in s["variants"]:
            d = compare(lim, trajectory(os.path.join(work, slug(v["label"]), "reference")))
            limit[v["label"]] = {col: d[col] for col, *_ in MEASURES.values()}
    return limit


def _creep_by_variant(s, work):
    """{variant: creep() of its reference where sweep.stuck_variant's reference
    holds a joint stuck} ({} without a stuck variant)."""
    held_creep = {}
    if s["stuck_variant"]:
        held = stuck_intervals(trajectory(os.path.join(work, slug(s["stuck_variant"]), "reference")))
        for v in s["variants"]:
            held_creep[v["label"]] = creep(trajectory(os.path.join(work, slug(v["label"]), "reference")), held)
    return held_creep


def merge(s, work, out_dir):
    """Compares every run with its variant's reference, and each reference
    with its cross-check, and writes out_dir/<sweep>.csv, <sweep>.png,
    <sweep>_precision.md, <sweep>_cost.png (several variants only) and
    <sweep>_summary.json (experiments/sweep.py's docstring describes
    them); returns the summary. SweepError if a
    run is missing, stale (another key) or a reference or check failed."""
    plt = plots.pyplot()
    rows, agreement, weak = [], {}, {}
    summaries = complete_summaries(s, work)
    modes = _mode_reference(s, work)
    for v in s["variants"]:
        ref, c = _reference_vs_check(work, v, summaries)
        a, too_weak = _agreement_entry(s, c, summaries[f"{slug(v['label'])}/reference"]["stats"])
        agreement[v["label"]] = a
        if too_weak:
            weak[v["label"]] = {col: {"difference": a[col], "limit": s["targets"][col] / WEAK_REFERENCE_FACTOR}
                                for col in too_weak}
        rows += _variant_rows(s, work, v, summaries, ref, c, a, modes)
    pinning = _pinning(rows)
    limit = _distance_to_limit(s, work)
    held_creep = _creep_by_variant(s, work)
    return report.write_outputs(s, work, out_dir, plt, rows, agreement, weak, limit, held_creep, pinning, modes)
